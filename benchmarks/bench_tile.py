"""Tiled processing of a huge image: 5×5 luminance median + Reinhard 2002 (global).

The pipeline: ``hdrjax.tile.apply(Median(5))`` → first pass ``statistics`` of the filtered
image → ``apply(Tonemap(Reinhard2002()))`` in place with the key, white and log-average of
that pass. Two ways of running it:

- **in-process tiled**: the image in RAM (NumPy), the result in a second preallocated
  array, 2048² tiles one at a time;
- **dask**: the same steps as ``dask.array`` graphs (``to_dask``, ``map_overlap``) on a
  2-worker ``LocalCluster`` (processes, one thread each), 2048² chunks. The workers make
  the input chunks themselves (the same synthetic image; a real job would read them from
  files), keep the filtered image in worker memory (``persist``) for the three statistics
  sub-passes and Reinhard, and write the result into an ``.npy`` file chunk by chunk.

Reference time (a case of its own, against the in-process median step): OpenCV
``medianBlur`` (5×5) of the luminance plane alone (a single-channel median, not the
luminance-selected RGB median).

Memory: the peak resident set size (RSS) of this process — and for dask the sum over this
process and all its children (nannies, workers), sampled every 20 ms — minus the RSS before
the image was made, also as a multiple of the RGB float32 image size. RSS counts pages of
memory-mapped files while they are mapped, and shared pages once per process.

    .venv/bin/python benchmarks/bench_tile.py --quick   # 4096×4096 (0.19 GiB image)
    .venv/bin/python benchmarks/bench_tile.py           # 15000×15000 (2.5 GiB image, ~6 GiB RAM)

``--operator durand2002`` runs Durand & Dorsey 2002 (pfstmo's defaults, ``sigma_s`` 40) on
the same image in tiles instead, in place (``out`` is the input: the rows that later windows
read are kept before they are overwritten): its first pass merges the tiles' statistics, the
second maps each tile with a halo of its bilateral filter's radius.
Its peak RSS is set against the median + Reinhard pipeline's above (issue: a huge image
through a local operator within the memory the tiled pipeline already uses).

    .venv/bin/python benchmarks/bench_tile.py --operator durand2002 [--quick]
"""

import argparse
import logging
import os
import tempfile
import threading
import time

import _harness as H
import numpy as np

import hdrjax.tile as T
from hdrjax.operators import Reinhard2002

BENCH = "tile"
TILE = 2048
GIB = 1024**3


class PeakRSS:
    """Peak RSS (bytes) of this process (and, with ``children``, its descendants)."""

    def __init__(self, children: bool = False, interval: float = 0.02):
        import psutil

        self._proc = psutil.Process()
        self._children, self._interval = children, interval
        self.peak = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    def rss(self) -> int:
        procs = [self._proc] + (self._proc.children(recursive=True) if self._children else [])
        total = 0
        for p in procs:
            try:
                total += p.memory_info().rss
            except Exception:  # a process that just ended
                pass
        return total

    def _loop(self):
        while not self._stop.is_set():
            self.peak = max(self.peak, self.rss())
            time.sleep(self._interval)

    def __enter__(self):
        self.peak = self.rss()
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, self.rss())


def synth_block(y0: int, x0: int, h: int, w: int, n: int) -> np.ndarray:
    """Rows ``y0..y0+h`` × columns ``x0..x0+w`` of a synthetic ``n×n`` HDR image (float32
    RGB, about 26 stops: smooth light and shadow and hashed pixel noise)."""
    yy = np.arange(y0, y0 + h, dtype=np.uint32)[:, None]
    xx = np.arange(x0, x0 + w, dtype=np.uint32)[None, :]
    y = yy.astype(np.float32) / np.float32(n)
    x = xx.astype(np.float32) / np.float32(n)
    stops = 9.0 * np.sin(6.3 * x) * np.cos(4.1 * y) + 4.0 * np.sin(25.0 * (x + y))
    base = np.exp2(stops.astype(np.float32))
    hsh = (yy * np.uint32(2654435761)) ^ (xx * np.uint32(40503) + np.uint32(12345))
    hsh = hsh ^ (hsh >> np.uint32(13))
    noise = (hsh & np.uint32(0xFFFF)).astype(np.float32) / np.float32(65535.0)
    lum = base * (0.6 + 0.8 * noise)
    out = np.empty((h, w, 3), np.float32)
    out[..., 0] = lum * 1.1
    out[..., 1] = lum
    out[..., 2] = lum * (0.7 + 0.5 * noise)
    return out


def synth(n: int) -> np.ndarray:
    """The whole synthetic image, made in bands of 512 rows (small temporaries)."""
    img = np.empty((n, n, 3), np.float32)
    for y0 in range(0, n, 512):
        h = min(512, n - y0)
        img[y0 : y0 + h] = synth_block(y0, 0, h, n, n)
    return img


def _chunk(empty, block_info=None, n: int = 0):
    """One input chunk, made in the worker (``empty``: a placeholder chunk of its shape)."""
    (r0, r1), (c0, c1), _ = block_info[None]["array-location"]
    return synth_block(r0, c0, r1 - r0, c1 - c0, n)


class NpyTarget:
    """``da.store`` target writing into an existing ``.npy`` file from any worker."""

    def __init__(self, path: str):
        self.path = path

    def __setitem__(self, index, value):
        mm = np.load(self.path, mmap_mode="r+")
        mm[index] = value
        mm.flush()
        del mm


def in_process(img: np.ndarray) -> tuple[np.ndarray, dict]:
    times = {}
    t0 = time.perf_counter()
    out = T.apply(T.Median(5), img, tile=TILE)
    times["median_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    st = T.operator_statistics(Reinhard2002(), out, tile=TILE)
    times["stats_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    T.apply(T.Tonemap(Reinhard2002()), out, tile=TILE, stats=st, out=out)
    times["reinhard_s"] = time.perf_counter() - t0
    return out, times


def durand_in_process(img: np.ndarray, tile: int = TILE) -> tuple[np.ndarray, dict]:
    """Durand 2002 in tiles: statistics pass, then the mapping pass in place."""
    from hdrjax import make_operator

    op = make_operator("durand2002", sigma_s=40.0)
    times = {}
    t0 = time.perf_counter()
    st = T.operator_statistics(op, img, tile=tile)
    times["stats_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    T.apply(T.Tonemap(op), img, tile=tile, stats=st, out=img)
    times["map_s"] = time.perf_counter() - t0
    return img, times


def run_durand(quick: bool = False, tile: int = TILE) -> list[dict]:
    """Harness record: Durand 2002 over the synthetic image in ``tile``² tiles, with
    its time (compilation included) and peak RSS over the baseline."""
    n = 4096 if quick else 15000
    image_bytes = n * n * 3 * 4
    probe = PeakRSS()
    base = probe.rss()
    img = synth(n)
    with PeakRSS() as peak:
        t0 = time.perf_counter()
        res, parts = durand_in_process(img, tile)
        total = time.perf_counter() - t0
    delta = peak.peak - base
    sample = res[n // 2 : n // 2 + 64, n // 3 : n // 3 + 64]
    finite = bool(np.all(np.isfinite(res[:: max(1, n // 512), :: max(1, n // 512)])))
    return [
        _rec(
            f"durand2002 {n}x{n} tile {tile}",
            "hdrjax tile in-process, in place",
            total,
            **{k: round(v, 3) for k, v in parts.items()},
            peak_rss_delta_gib=round(delta / GIB, 3),
            peak_over_image=round(delta / image_bytes, 3),
            image_gib=round(image_bytes / GIB, 3),
            sample_mean=float(np.mean(sample)),
            finite_on_a_grid=finite,
            includes_compile=True,
        )
    ]


def with_dask(n: int, path: str) -> dict:
    import dask.array as da
    from distributed import wait

    times = {}
    t0 = time.perf_counter()
    src = da.empty((n, n, 3), chunks=(TILE, TILE, 3), dtype=np.float32)
    src = src.map_blocks(_chunk, n=n, dtype=np.float32)
    med = T.to_dask(T.Median(5), src).persist()
    wait(med)
    times["median_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    st = T.dask_operator_statistics(Reinhard2002(), med)
    times["stats_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = T.to_dask(T.Tonemap(Reinhard2002()), med, stats=st)
    da.store(res, NpyTarget(path), lock=False)
    times["reinhard_store_s"] = time.perf_counter() - t0
    del med
    return times


def _rec(case, impl, seconds, **extra):
    t = {"median_s": seconds, "spread_s": 0.0, "repeats": 1, "first_s": float("nan")}
    return H.record(BENCH, case, impl, timing=t, **extra)


def run(quick: bool = False) -> list[dict]:
    """Harness records: the pipeline in-process and on dask, and the median against OpenCV
    (4096² in quick mode, 15000² otherwise; one run each, compilation included)."""
    import cv2

    n = 4096 if quick else 15000
    case = f"median5 lum + reinhard2002 {n}x{n}"
    image_bytes = n * n * 3 * 4
    out: list[dict] = []

    # ---- in-process tiled; compile included (one window shape per step)
    probe = PeakRSS()
    base = probe.rss()
    t0 = time.perf_counter()
    img = synth(n)
    gen_s = time.perf_counter() - t0
    with PeakRSS() as peak:
        t0 = time.perf_counter()
        res, parts = in_process(img)
        total = time.perf_counter() - t0
    delta = peak.peak - base
    check = res[n // 2 : n // 2 + 4, n // 3 : n // 3 + 4].copy()
    out.append(
        _rec(
            case,
            "hdrjax tile in-process",
            total,
            **{k: round(v, 3) for k, v in parts.items()},
            synth_s=round(gen_s, 2),
            peak_rss_delta_gib=round(delta / GIB, 3),
            peak_over_image=round(delta / image_bytes, 3),
            image_gib=round(image_bytes / GIB, 3),
            includes_compile=True,
        )
    )

    # ---- OpenCV reference: 5×5 median of the luminance plane only
    lum = img[..., 0] * np.float32(0.2126)
    lum += img[..., 1] * np.float32(0.7152)
    lum += img[..., 2] * np.float32(0.0722)
    del img, res
    t = H.measure(lambda: cv2.medianBlur(lum, 5), repeats=1, warmup=False)
    lum = None
    # its own case, so the suite's ratio compares medians only: hdrjax's tiled luminance
    # median of RGB (compile included) against OpenCV's median of one plane
    mcase = f"median5 {n}x{n} (tiled RGB luminance median vs 1-plane medianBlur)"
    out.append(_rec(mcase, "hdrjax tile in-process", parts["median_s"], includes_compile=True))
    out.append(H.record(BENCH, mcase, "cv2.medianBlur luminance plane", timing=t))

    # ---- dask on a 2-worker LocalCluster
    out.append(_dask_record(case, n, image_bytes, check))
    return out


def _dask_record(case: str, n: int, image_bytes: int, check: np.ndarray) -> dict:
    from distributed import Client, LocalCluster

    for name in ("distributed", "distributed.worker", "distributed.scheduler"):
        logging.getLogger(name).setLevel(logging.CRITICAL)
    with tempfile.TemporaryDirectory(dir=os.environ.get("HDRJAX_BENCH_TMP")) as tmp:
        path = os.path.join(tmp, "out.npy")
        np.lib.format.open_memmap(path, "w+", np.float32, (n, n, 3)).flush()
        probe = PeakRSS(children=True)
        t0 = time.perf_counter()
        with (
            LocalCluster(
                n_workers=2,
                processes=True,
                threads_per_worker=1,
                dashboard_address=None,
                silence_logs=logging.CRITICAL,
            ) as cluster,
            Client(cluster),
        ):
            start_s = time.perf_counter() - t0
            base = probe.rss()
            with PeakRSS(children=True) as peak:
                t0 = time.perf_counter()
                parts = with_dask(n, path)
                total = time.perf_counter() - t0
        got = np.load(path, mmap_mode="r")[n // 2 : n // 2 + 4, n // 3 : n // 3 + 4]
        max_diff = float(np.max(np.abs(got - check)))
    delta = peak.peak - base
    return _rec(
        case,
        "hdrjax tile dask 2 workers",
        total,
        **{k: round(v, 3) for k, v in parts.items()},
        cluster_start_s=round(start_s, 2),
        peak_rss_delta_gib=round(delta / GIB, 3),
        peak_over_image=round(delta / image_bytes, 3),
        max_diff_vs_in_process=max_diff,
        includes_compile=True,
        includes_synth=True,
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="4096×4096 instead of 15000²")
    parser.add_argument(
        "--operator",
        choices=("reinhard2002", "durand2002"),
        default="reinhard2002",
        help="the median + Reinhard 2002 pipeline (default) or Durand 2002 alone",
    )
    parser.add_argument("--tile", type=int, default=TILE, help="durand2002's tile size (2048)")
    args = parser.parse_args()
    if args.operator == "durand2002":
        run_durand(args.quick, args.tile)
    else:
        run(args.quick)
