"""Radiance RGBE read speed: hdrjax.io.read against OpenCV's imread.

Two kinds of case: the shipped 1024×512 maps (data/rooitou_park_1k.hdr and
data/venice_sunset_1k.hdr, real Poly Haven files, read as they are: the per-frame cost of a
batch of 1k maps), and data/venice_sunset_1k.hdr tiled up to N × N (full mode 4096, quick
mode 2048) and written with hdrjax's run-length encoder (the RLE flavour every Radiance
writer uses). Both readers produce float32 RGB; the benchmark checks they agree bit for bit,
then times them alternately in one process (one warm-up call each, then the repeats) and
records the median times; the report gives their ratio, and a run of this file alone prints
it for each case.

Run: ``.venv/bin/python benchmarks/bench_rgbe_read.py [--quick] [--size N] [--repeat R]``.
"""

import argparse
import tempfile
import time
from pathlib import Path

import _harness as H
import numpy as np

import hdrjax.io as hio

ROOT = Path(__file__).resolve().parents[1]
BENCH = "rgbe_read"
SHIPPED = ("rooitou_park_1k.hdr", "venice_sunset_1k.hdr")


def _clock(fn) -> float:
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def _compare(p: Path, case: str, reps: int, **extra) -> list[dict]:
    """Records of hdrjax.io.read and cv2.imread of ``p``, timed alternately."""
    import cv2

    flags = cv2.IMREAD_ANYDEPTH | cv2.IMREAD_COLOR
    ours = hio.read(p, sidecars=False).image
    theirs = cv2.imread(str(p), flags)[:, :, ::-1]
    if not np.array_equal(ours, theirs):
        raise AssertionError(f"{p}: hdrjax and OpenCV decode the file differently")

    def read_ours():
        return hio.read(p, sidecars=False)

    def read_cv():
        return cv2.imread(str(p), flags)

    first_ours, first_cv = _clock(read_ours), _clock(read_cv)
    t_ours, t_cv = [], []
    for _ in range(reps):  # alternately, so both see the same machine load
        t_ours.append(_clock(read_ours))
        t_cv.append(_clock(read_cv))
    common = {
        "pixels": ours.shape[0] * ours.shape[1],
        "file_mb": round(p.stat().st_size / 2**20, 1),
        "bit_identical": True,
        **extra,
    }
    return [
        H.record(BENCH, case, "hdrjax", timing=H.summarize(t_ours, first_ours), **common),
        H.record(BENCH, case, "cv2.imread", timing=H.summarize(t_cv, first_cv), **common),
    ]


def run(quick: bool = False, *, size: int | None = None, repeat: int | None = None) -> list[dict]:
    """Records of benchmark ``"rgbe_read"``: hdrjax.io.read and cv2.imread of each file."""
    records = []
    for name in SHIPPED:
        reps = repeat or (11 if quick else 21)
        records += _compare(ROOT / "data" / name, f"{name} 1024x512", reps)
    n = size or (2048 if quick else 4096)
    base = hio.read(ROOT / "data" / "venice_sunset_1k.hdr").image
    tiles = (-(-n // base.shape[0]), -(-n // base.shape[1]), 1)
    img = np.tile(base, tiles)[:n, :n]
    with tempfile.TemporaryDirectory() as d:
        p = hio.write(Path(d) / "bench.hdr", img)
        records += _compare(p, f"RLE {n}x{n}", repeat or (5 if quick else 7))
    return records


def _print_ratios(records: list[dict]) -> None:
    by_case: dict[str, dict[str, float]] = {}
    for r in records:
        by_case.setdefault(r["case"], {})[r["impl"]] = r["median_s"]
    for case, t in by_case.items():
        print(
            f"[{BENCH}] {case:<40} hdrjax / cv2.imread = {t['hdrjax'] / t['cv2.imread']:.2f}"
            f"  ({t['hdrjax'] * 1e3:.2f} ms / {t['cv2.imread'] * 1e3:.2f} ms, medians)"
        )


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="2048×2048, fewer repeats")
    ap.add_argument("--size", type=int, default=None, help="tiled image side (default 4096)")
    ap.add_argument("--repeat", type=int, default=None)
    a = ap.parse_args()
    _print_ratios(run(a.quick, size=a.size, repeat=a.repeat))
