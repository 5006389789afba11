"""Batch throughput: frames/s for a sequence of 1024×512 Radiance frames tone-mapped with
Reinhard 2002 (automatic key and white, per frame) and written as 8-bit sRGB PNG.

The frames are copies of data/venice_sunset_1k.hdr and data/rooitou_park_1k.hdr (real Poly
Haven maps, alternating) in a temporary folder: 200 frames in full mode, 24 in quick mode.
Every implementation reads the files, tone-maps, encodes and writes every frame:

* ``hdrjax`` — :func:`hdrjax.batch.run` in-process: batches of 8 through one compiled
  function (``lax.map`` over the frames, the CPU default), reading and writing in threads
  overlapped with the computation; ``hdrjax-vmap`` — the same with ``vectorize="vmap"``;
* ``hdrjax-dask-1w`` / ``hdrjax-dask-2w`` — the same work on a ``dask.distributed``
  LocalCluster with 1 and 2 worker processes (one thread each; quick mode: 2 only), started
  and warmed up (compiled) before the timing; the start-up time is reported in ``startup_s``.
  Each worker runs on its own cores, as ``batch.run(workers=N)`` pins them
  (hdrjax/batch/_cores.py); ``hdrjax-dask-2w-shared-cores`` (full mode) is 2 workers left to
  share every core, the difference that pinning makes;
* ``one-at-a-time loop`` — the plain hdrjax loop: ``hdrjax.io.read``, ``hdrjax.tonemap``,
  ``display.encode`` + ``quantize``, ``io.write_display`` per frame;
* ``numpy+opencv`` — the peer script: ``cv2.imread`` of the .hdr, the same operator in NumPy
  float32 (``bench_reinhard.numpy_reinhard_auto``, ``np.percentile`` for P1/P99), sRGB in
  NumPy, ``cv2.imwrite`` PNG at its default zlib level 1 (hdrjax's default too: Sub-filtered
  rows, run-length matching).

A second case repeats hdrjax, the loop and the peer at PNG zlib level 6
(``Pipeline(compression=6)`` / ``--zlib-level 6``), where the encoder is most of a frame's
CPU time. ``cpu_ms_per_frame`` is the process CPU time per frame (all threads): on
this 2-core machine no schedule can make a run shorter than half its CPU time, which bounds
what overlapping I/O with compute can gain over the one-at-a-time loop.

hdrjax is warmed up (compiled) on one batch of frames first; each figure is then one full
pass over the sequence. ``frames_per_s`` = frames / time.

Usage: ``python benchmarks/bench_batch.py [--quick] [--frames N] [--skip-dask]``
"""

import argparse
import logging
import os
import shutil
import tempfile
import time
from pathlib import Path

import _harness as H
import numpy as np
from bench_reinhard import numpy_reinhard_auto

import hdrjax
from hdrjax import batch, display, io as hio

ROOT = Path(__file__).resolve().parents[1]
SOURCES = (ROOT / "data" / "venice_sunset_1k.hdr", ROOT / "data" / "rooitou_park_1k.hdr")
BENCH = "batch"
BATCH = 8


def _frames(folder: Path, n: int) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for i in range(n):
        p = folder / f"frame_{i:04d}.hdr"
        shutil.copyfile(SOURCES[i % 2], p)
        paths.append(p)
    return paths


def _fresh(folder: Path) -> Path:
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    return folder


def _srgb_np(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x > 0.0031308, 1.055 * np.power(x, 1 / 2.4) - 0.055, 12.92 * x)


def peer_numpy_opencv(paths: list[Path], out: Path, level: int = 1) -> None:
    """The NumPy + OpenCV script: read, tone-map, encode, write, one frame after another."""
    import cv2

    for p in paths:
        bgr = cv2.imread(str(p), cv2.IMREAD_ANYDEPTH | cv2.IMREAD_COLOR)
        rgb = np.ascontiguousarray(bgr[:, :, ::-1])
        mapped = numpy_reinhard_auto(rgb)
        code = np.rint(_srgb_np(mapped) * 255).astype(np.uint8)
        cv2.imwrite(
            str(out / (p.stem + ".png")), code[:, :, ::-1], [cv2.IMWRITE_PNG_COMPRESSION, level]
        )


def hdrjax_loop(paths: list[Path], out: Path, level: int = hio.DEFAULT_COMPRESSION) -> None:
    """One frame at a time with the public single-image API."""
    for p in paths:
        rgb = hio.read(p, sidecars=False).rgb()
        mapped = hdrjax.tonemap(rgb, "reinhard2002")
        code = display.quantize(display.encode(mapped), 8)
        hio.write_display(out / (p.stem + ".png"), code, bits=8, compression=level)


def _timed(fn, repeats: int) -> dict:
    """Timing, plus the process CPU seconds of the last repeat (``cpu_s``): with 2 cores a
    batched run can be at most ``cpu_s / 2`` long, whatever overlaps with what."""
    c0 = time.process_time()
    t = H.measure(fn, repeats=repeats, warmup=False)
    t["cpu_s"] = (time.process_time() - c0) / max(repeats, 1)
    return t


def _rate(case: str, impl: str, t: dict, n: int, **extra) -> dict:
    """A record of ``n`` frames in ``t``: frames/s and process CPU time per frame."""
    return H.record(
        BENCH,
        case,
        impl,
        timing=t,
        frames=n,
        frames_per_s=n / t["median_s"],
        cpu_ms_per_frame=1e3 * t["cpu_s"] / n,
        **extra,
    )


def _slow_png(recs, paths, warm, out, n, reps) -> None:
    """The same three ways at PNG zlib level 6 (hdrjax ``compression=6``)."""
    case = f"reinhard2002 {n} frames 1024x512 hdr->png (zlib level 6)"
    pipe = batch.Pipeline("reinhard2002", compression=6)

    def batched():
        s = batch.run(paths, pipe, _fresh(out), batch_size=BATCH, progress=False, resume=False)
        assert len(s.done) == n, s

    batch.run(warm, pipe, _fresh(out), batch_size=BATCH, progress=False, resume=False)
    for impl, fn in (
        ("hdrjax", batched),
        ("one-at-a-time loop", lambda: hdrjax_loop(paths, _fresh(out), 6)),
        ("numpy+opencv", lambda: peer_numpy_opencv(paths, _fresh(out), 6)),
    ):
        recs.append(_rate(case, impl, _timed(fn, reps), n))


def run(quick: bool = False, *, frames: int | None = None, skip_dask: bool = False) -> list[dict]:
    """Records of benchmark ``"batch"`` (see the module docstring)."""
    n = frames or (24 if quick else 200)
    reps = 1
    recs: list[dict] = []
    case = f"reinhard2002 {n} frames 1024x512 hdr->png"
    pipe = batch.Pipeline("reinhard2002")
    with tempfile.TemporaryDirectory(prefix="hdrjax-bench-batch-") as d:
        d = Path(d)
        paths = _frames(d / "in", n)
        warm = paths[:BATCH]
        out = d / "out"

        def batched():
            s = batch.run(paths, pipe, _fresh(out), batch_size=BATCH, progress=False, resume=False)
            assert len(s.done) == n, s

        batch.run(warm, pipe, _fresh(out), batch_size=BATCH, progress=False, resume=False)
        recs.append(_rate(case, "hdrjax", _timed(batched, reps), n, batch_size=BATCH))

        # the same batches vectorised across frames (vmap) instead of lax.map
        pipe_vmap = batch.Pipeline("reinhard2002", vectorize="vmap")

        def batched_vmap():
            s = batch.run(
                paths, pipe_vmap, _fresh(out), batch_size=BATCH, progress=False, resume=False
            )
            assert len(s.done) == n, s

        batch.run(warm, pipe_vmap, _fresh(out), batch_size=BATCH, progress=False, resume=False)
        t = _timed(batched_vmap, reps)
        recs.append(
            H.record(
                BENCH,
                case,
                "hdrjax-vmap",
                timing=t,
                frames=n,
                frames_per_s=n / t["median_s"],
                batch_size=BATCH,
            )
        )

        def loop():
            hdrjax_loop(paths, _fresh(out))

        hdrjax_loop(warm[:2], _fresh(out))
        recs.append(_rate(case, "one-at-a-time loop", _timed(loop, reps), n))

        def peer():
            peer_numpy_opencv(paths, _fresh(out))

        recs.append(_rate(case, "numpy+opencv", _timed(peer, reps), n))
        _slow_png(recs, paths, warm, out, n, reps)

        if not skip_dask:
            from distributed import Client, LocalCluster

            from hdrjax.batch._cores import pin_workers

            # the cluster batch.run(workers=N) makes (each worker on its own cores), and for
            # 2 workers the same without pinning: XLA processes sharing every core
            variants = [(w, True) for w in ((2,) if quick else (1, 2))]
            variants += [] if quick else [(2, False)]
            for workers, pinned in variants:
                t0 = time.perf_counter()
                cluster = LocalCluster(
                    n_workers=workers,
                    threads_per_worker=1,
                    processes=True,
                    host="127.0.0.1",
                    dashboard_address=":0",
                    silence_logs=logging.ERROR,
                )
                client = Client(cluster)
                if pinned:
                    pin_workers(client, workers)
                startup = time.perf_counter() - t0
                try:
                    # warm-up: every worker compiles the pipeline once
                    batch.run(
                        paths[: BATCH * workers],
                        pipe,
                        _fresh(out),
                        batch_size=BATCH,
                        scheduler=client,
                        progress=False,
                        resume=False,
                    )

                    def on_dask(c=client):
                        s = batch.run(
                            paths,
                            pipe,
                            _fresh(out),
                            batch_size=BATCH,
                            scheduler=c,
                            progress=False,
                            resume=False,
                        )
                        assert len(s.done) == n, s

                    t = _timed(on_dask, reps)
                finally:
                    client.close()
                    cluster.close()
                recs.append(
                    H.record(
                        BENCH,
                        case,
                        f"hdrjax-dask-{workers}w" + ("" if pinned else "-shared-cores"),
                        timing=t,
                        frames=n,
                        frames_per_s=n / t["median_s"],
                        workers=workers,
                        pinned=pinned,
                        startup_s=startup,
                        cores=os.cpu_count(),
                    )
                )
    return recs


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="24 frames")
    ap.add_argument("--frames", type=int, default=None, help="number of frames (200, quick 24)")
    ap.add_argument("--skip-dask", action="store_true", help="in-process implementations only")
    a = ap.parse_args()
    run(a.quick, frames=a.frames, skip_dask=a.skip_dask)
