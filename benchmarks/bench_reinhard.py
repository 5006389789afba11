"""Reinhard 2002 with automatic key and white point at 4096×4096 RGB float32, in one process.

Compared against:
  * a NumPy float32 implementation of the same operator and JGT parameters
    (``np.percentile`` for P1/P99);
  * OpenCV's ``createTonemapReinhard`` (its own global photoreceptor operator, defaults);
  * colour-hdri's ``tonemapping_operator_Reinhard2004`` (defaults);
  * a memory-bandwidth bound: ``np.copyto`` of the image's bytes (one read + one write).

hdrjax is timed three ways: the full call (statistics + mapping, fresh output buffer), the
same with the input buffer donated (``donate_argnums``: no page faults for the output), and
the statistics pass alone. Compile time is reported separately. Each figure is the median
of ``--repeats`` runs after one warm-up.

Usage: ``python benchmarks/bench_reinhard.py [--size 4096] [--repeats 7] [--json PATH]``
"""

import argparse
import json
import os
import platform
import statistics
import time

import jax
import numpy as np

import hdrjax
from hdrjax.operators import Reinhard2002

W = np.array([0.2126, 0.7152, 0.0722], np.float32)


def numpy_reinhard_auto(rgb: np.ndarray) -> np.ndarray:
    """NumPy float32 peer: the same JGT parameters and global curve."""
    L = rgb @ W
    pos = L[L > 0]
    l1, l99 = np.percentile(pos, [1, 99])
    lbar_t = np.exp(np.mean(np.log(pos[pos <= l99])))
    key = 0.18 * 4 ** (
        (2 * np.log2(lbar_t) - np.log2(l1) - np.log2(l99)) / (np.log2(l99) - np.log2(l1))
    )
    lbar = np.exp(np.mean(np.log(np.float32(1e-6) + np.maximum(L, 0))))
    zones = np.log2(pos.max()) - np.log2(pos.min())
    white = 1.5 * 2 ** (zones - 5)
    Ls = np.float32(key / lbar) * L
    Ld = Ls * (1 + Ls / np.float32(white) ** 2) / (1 + Ls)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(L > 0, Ld / L, 0).astype(np.float32)
    return rgb * ratio[..., None]


def timeit(fn, repeats: int) -> tuple[float, float]:
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), (max(ts) - min(ts)) / 2


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=4096)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--json", default="benchmarks/results/reinhard.json")
    ap.add_argument("--skip-peers", action="store_true", help="hdrjax only (quick)")
    args = ap.parse_args()

    n = args.size
    rng = np.random.default_rng(0)
    L = rng.lognormal(0.0, 2.5, (n, n)).astype(np.float32)
    rgb = (L[..., None] * rng.uniform(0.6, 1.4, (n, n, 3))).astype(np.float32)
    mb = rgb.nbytes / 1e6
    results: dict[str, dict] = {}

    def record(name, fn, repeats=args.repeats, compile_s=None):
        fn()  # warm-up
        med, spread = timeit(fn, repeats)
        results[name] = {"median_s": med, "spread_s": spread}
        if compile_s is not None:
            results[name]["compile_s"] = compile_s
        extra = f"  (compile {compile_s:.2f} s)" if compile_s is not None else ""
        print(f"{name:<44s} {med * 1e3:9.1f} ms ± {spread * 1e3:5.1f}{extra}", flush=True)

    dst = np.empty_like(rgb)
    record("bandwidth bound (np.copyto, 1 read + 1 write)", lambda: np.copyto(dst, rgb))

    x = jax.device_put(rgb)
    op = Reinhard2002()
    full = jax.jit(lambda img: op(img))
    t0 = time.perf_counter()
    full.lower(x).compile()
    c_full = time.perf_counter() - t0
    record("hdrjax reinhard2002 auto", lambda: full(x).block_until_ready(), compile_s=c_full)

    donated = jax.jit(lambda img: op(img), donate_argnums=0)
    t0 = time.perf_counter()
    donated.lower(x).compile()
    c_don = time.perf_counter() - t0
    bufs = [jax.device_put(rgb) for _ in range(args.repeats + 1)]
    it = iter(bufs)
    record(
        "hdrjax reinhard2002 auto (donated input)",
        lambda: donated(next(it)).block_until_ready(),
        compile_s=c_don,
    )

    measure = jax.jit(lambda img: op.measure(img))
    t0 = time.perf_counter()
    measure.lower(x).compile()
    c_meas = time.perf_counter() - t0
    record(
        "hdrjax statistics only (JGT key, white)",
        lambda: jax.block_until_ready(measure(x)),
        compile_s=c_meas,
    )

    exact = Reinhard2002(percentile_method="exact")
    if n <= 1024:
        ex = jax.jit(lambda img: exact(img))
        record(
            "hdrjax reinhard2002 auto, exact percentiles",
            lambda: ex(x).block_until_ready(),
            repeats=3,
        )

    if not args.skip_peers:
        record("NumPy float32 (same operator)", lambda: numpy_reinhard_auto(rgb), repeats=3)
        try:
            import cv2

            tm = cv2.createTonemapReinhard()
            record("OpenCV createTonemapReinhard", lambda: tm.process(rgb), repeats=3)
        except ImportError:
            print("OpenCV not installed: skipped")
        try:
            from colour_hdri import tonemapping_operator_Reinhard2004

            record(
                "colour-hdri Reinhard2004",
                lambda: tonemapping_operator_Reinhard2004(rgb),
                repeats=3,
            )
        except ImportError:
            print("colour-hdri not installed: skipped")

    bound = results["bandwidth bound (np.copyto, 1 read + 1 write)"]["median_s"]
    ours = results["hdrjax reinhard2002 auto"]["median_s"]
    print(f"\nimage {n}x{n} RGB float32 ({mb:.0f} MB); ratios (time / hdrjax full call):")
    for name, r in results.items():
        print(f"  {name:<44s} {r['median_s'] / ours:6.2f}x")
    print(f"hdrjax / bandwidth bound for two passes: {ours / (2 * bound):.2f}x")
    meta = {
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "machine": platform.platform(),
        "processor": platform.processor(),
        "cpus": os.cpu_count(),
        "jax": jax.__version__,
        "backend": jax.default_backend(),
        "device": str(jax.devices()[0]),
        "numpy": np.__version__,
        "hdrjax": hdrjax.__version__,
        "size": n,
        "repeats": args.repeats,
    }
    os.makedirs(os.path.dirname(args.json) or ".", exist_ok=True)
    with open(args.json, "w") as f:
        json.dump({"meta": meta, "results": results}, f, indent=2)
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
