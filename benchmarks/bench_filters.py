"""Filters and highlight desaturation: hdrjax against OpenCV and SciPy, in one process.

Single-channel float32 with edges replicated (OpenCV ``BORDER_REPLICATE`` and
``medianBlur``'s own replication, SciPy ``mode="nearest"``). Each time is the best of several
runs after a warm-up call; the warm-up's extra time over a run is reported as compile time.
Every hdrjax result is checked against the peer before it is timed (medians bit-identical,
the mean's float32 error against float64 printed). Ratios are hdrjax / peer: below 1 means
hdrjax is faster. Both sides allocate their outputs afresh, as a caller would.

    .venv/bin/python benchmarks/bench_filters.py            # 1366×768 and 4096×4096
    .venv/bin/python benchmarks/bench_filters.py --big      # also 15000×15000 (~6 GB RAM)

The load average is printed: other processes on a small machine move the numbers (both
sides run in the same process, one after the other, so the ratios move less).
"""

import argparse
import os
import time

import jax
import jax.numpy as jnp
import numpy as np

import hdrjax.filters as F
from hdrjax.display import desaturate_highlights

ROWS: list[tuple] = []


def best_of(fn, n: int) -> float:
    """Best wall time (s) of n calls of fn (results blocked on)."""
    best = float("inf")
    for _ in range(n):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        best = min(best, time.perf_counter() - t0)
    return best


def first_call(fn) -> float:
    t0 = time.perf_counter()
    jax.block_until_ready(fn())
    return time.perf_counter() - t0


def report(op: str, size: str, ours: float, peer_name: str, peer: float, compile_s: float):
    ROWS.append((op, size, ours, peer_name, peer, compile_s))
    print(
        f"{op:<22} {size:>11}  hdrjax {ours * 1e3:9.1f} ms   {peer_name:<21} "
        f"{peer * 1e3:9.1f} ms   ratio {ours / peer:6.2f}   compile {compile_s:5.2f} s",
        flush=True,
    )


def bench_size(h: int, w: int, runs: int, rng) -> None:
    import cv2
    import scipy.ndimage as ndi

    x = rng.lognormal(0.0, 2.0, size=(h, w)).astype(np.float32)
    xj = jnp.asarray(x)
    size = f"{w}x{h}"
    small = h * w < 2e6  # SciPy and the larger windows only at the small size
    big = h * w > 5e7
    n = 2 if big else runs
    for k in (3, 5, 7, 15) if small else (5,) if big else (3, 5):

        def med(k=k):
            return F.median_filter(xj, k, channel_axis=None)

        first = first_call(med)
        ours = best_of(med, n)
        got = np.asarray(med())
        if k <= 5:  # OpenCV's float median supports 3 and 5 only
            assert np.array_equal(got, cv2.medianBlur(x, k)), "median differs from OpenCV"
            peer = best_of(lambda k=k: cv2.medianBlur(x, k), n)
            report(f"median {k}x{k}", size, ours, "cv2.medianBlur", peer, first - ours)
        if small:
            assert np.array_equal(got, ndi.median_filter(x, k, mode="nearest"))
            peer = best_of(lambda k=k: ndi.median_filter(x, k, mode="nearest"), 1)
            report(f"median {k}x{k}", size, ours, "scipy median_filter", peer, first - ours)

    def mean():
        return F.mean_filter(xj, 5, channel_axis=None)

    first = first_call(mean)
    ours = best_of(mean, n)
    if not big:
        ref = ndi.uniform_filter(x.astype(np.float64), 5, mode="nearest")
        err = float(np.max(np.abs(np.asarray(mean()) - ref) / ref))
        print(f"  mean 5x5 at {size}: float32 max relative error against float64 {err:.1e}")
    peer = best_of(lambda: cv2.blur(x, (5, 5), borderType=cv2.BORDER_REPLICATE), n)
    report("mean 5x5", size, ours, "cv2.blur", peer, first - ours)
    if not big:
        peer = best_of(lambda: ndi.uniform_filter(x, 5, mode="nearest"), n)
        report("mean 5x5", size, ours, "scipy uniform_filter", peer, first - ours)


def bench_desaturation(runs: int, rng) -> None:
    """Automatic threshold on 4096² RGB against one read-and-write pass of the image."""
    rgb = jnp.asarray(rng.lognormal(0.0, 2.0, size=(4096, 4096, 3)).astype(np.float32))

    def desat():
        return desaturate_highlights(rgb)

    first = first_call(desat)
    ours = best_of(desat, runs)
    copy = jax.jit(lambda v: v * 1.0001)
    first_call(lambda: copy(rgb))
    peer = best_of(lambda: copy(rgb), runs)
    report("desaturate auto (RGB)", "4096x4096", ours, "read+write pass", peer, first - ours)


def main() -> None:
    import cv2

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--big", action="store_true", help="include 15000×15000")
    ap.add_argument("--runs", type=int, default=5, help="timed runs per case (best is kept)")
    args = ap.parse_args()
    print(
        f"jax {jax.__version__} ({jax.devices()[0].platform}), opencv {cv2.__version__} "
        f"({cv2.getNumThreads()} threads), {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    rng = np.random.default_rng(0)
    sizes = [(768, 1366), (4096, 4096)] + ([(15000, 15000)] if args.big else [])
    for h, w in sizes:
        bench_size(h, w, args.runs, rng)
    bench_desaturation(args.runs, rng)
    print("\n| operation | size | hdrjax (ms) | peer | peer (ms) | ratio | compile (s) |")
    print("|---|---|---:|---|---:|---:|---:|")
    for op, size, ours, peer_name, peer, comp in ROWS:
        print(
            f"| {op} | {size} | {ours * 1e3:.1f} | {peer_name} | {peer * 1e3:.1f} "
            f"| {ours / peer:.2f} | {comp:.2f} |"
        )
    print(f"\nload average at the end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
