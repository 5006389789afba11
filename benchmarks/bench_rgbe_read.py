"""Radiance RGBE read speed: hdrjax.io.read against OpenCV's imread, 4096 x 4096.

The test image tiles data/venice_sunset_1k.hdr (a real Poly Haven map) 4 x 8 times, written
with hdrjax's run-length encoder (the RLE flavour every Radiance writer uses). Both readers
produce float32 RGB; the script checks they agree bit for bit, then times them alternately
in one process and prints the median times and their ratio.

Run: ``.venv/bin/python benchmarks/bench_rgbe_read.py [--size 4096] [--repeat 7]``.
"""

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import hdrjax.io as hio

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=4096)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    import cv2

    base = hio.read(ROOT / "data" / "venice_sunset_1k.hdr").image
    reps = (-(-args.size // base.shape[0]), -(-args.size // base.shape[1]), 1)
    img = np.tile(base, reps)[: args.size, : args.size]
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "bench.hdr"
        hio.write(p, img)
        mb = p.stat().st_size / 2**20
        ours = hio.read(p, sidecars=False).image
        theirs = cv2.imread(str(p), cv2.IMREAD_ANYDEPTH | cv2.IMREAD_COLOR)[:, :, ::-1]
        assert np.array_equal(ours, theirs), "hdrjax and OpenCV disagree"
        t_ours, t_cv = [], []
        for _ in range(args.repeat):
            t = time.perf_counter()
            hio.read(p, sidecars=False)
            t_ours.append(time.perf_counter() - t)
            t = time.perf_counter()
            cv2.imread(str(p), cv2.IMREAD_ANYDEPTH | cv2.IMREAD_COLOR)
            t_cv.append(time.perf_counter() - t)
    a, b = statistics.median(t_ours), statistics.median(t_cv)
    print(f"RGBE {args.size}x{args.size} RLE, {mb:.1f} MB, median of {args.repeat}:")
    print(f"  hdrjax.io.read  {a * 1e3:8.1f} ms")
    print(f"  cv2.imread      {b * 1e3:8.1f} ms")
    print(f"  ratio hdrjax/OpenCV: {a / b:.2f}")


if __name__ == "__main__":
    main()
