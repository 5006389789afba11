"""Radiance RGBE read speed: hdrjax.io.read against OpenCV's imread.

The test image tiles data/venice_sunset_1k.hdr (a real Poly Haven map) up to N × N (full mode
4096, quick mode 2048), written with hdrjax's run-length encoder (the RLE flavour every
Radiance writer uses). Both readers produce float32 RGB; the benchmark checks they agree bit
for bit, then times them alternately in one process (one warm-up call each, then the repeats)
and records the median times; the report gives their ratio.

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


def run(quick: bool = False, *, size: int | None = None, repeat: int | None = None) -> list[dict]:
    """Records of benchmark ``"rgbe_read"``: hdrjax.io.read and cv2.imread of one file."""
    import cv2

    n = size or (2048 if quick else 4096)
    reps = repeat or (5 if quick else 7)
    flags = cv2.IMREAD_ANYDEPTH | cv2.IMREAD_COLOR
    base = hio.read(ROOT / "data" / "venice_sunset_1k.hdr").image
    tiles = (-(-n // base.shape[0]), -(-n // base.shape[1]), 1)
    img = np.tile(base, tiles)[:n, :n]
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "bench.hdr"
        hio.write(p, img)
        mb = p.stat().st_size / 2**20
        ours = hio.read(p, sidecars=False).image
        theirs = cv2.imread(str(p), flags)[:, :, ::-1]
        if not np.array_equal(ours, theirs):
            raise AssertionError(f"{p}: hdrjax and OpenCV decode the file differently")

        def clock(fn) -> float:
            t = time.perf_counter()
            fn()
            return time.perf_counter() - t

        def read_ours():
            return hio.read(p, sidecars=False)

        def read_cv():
            return cv2.imread(str(p), flags)

        first_ours, first_cv = clock(read_ours), clock(read_cv)
        t_ours, t_cv = [], []
        for _ in range(reps):  # alternately, so both see the same machine load
            t_ours.append(clock(read_ours))
            t_cv.append(clock(read_cv))
    case = f"RLE {n}x{n}"
    common = {"pixels": n * n, "file_mb": round(mb, 1), "bit_identical": True}
    return [
        H.record(BENCH, case, "hdrjax", timing=H.summarize(t_ours, first_ours), **common),
        H.record(BENCH, case, "cv2.imread", timing=H.summarize(t_cv, first_cv), **common),
    ]


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="2048×2048, 5 repeats")
    ap.add_argument("--size", type=int, default=None, help="image side (default 4096)")
    ap.add_argument("--repeat", type=int, default=None)
    a = ap.parse_args()
    run(a.quick, size=a.size, repeat=a.repeat)
