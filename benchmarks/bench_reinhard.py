"""Reinhard 2002 with automatic key and white point on RGB float32, in one process.

Full mode: 4096×4096, 7 repeats; quick mode: 1024×1024, 5 repeats (peers 3 repeats).
Compared against:
  * a NumPy float32 implementation of the same operator and JGT parameters
    (``np.percentile`` for P1/P99);
  * OpenCV's ``createTonemapReinhard`` (its own global photoreceptor operator, defaults);
  * colour-hdri's ``tonemapping_operator_Reinhard2004`` (defaults);
  * a memory-bandwidth bound: ``np.copyto`` of the image's bytes (one read + one write).

hdrjax is timed three ways: the full call (statistics + mapping, fresh output buffer), the
same with the input buffer donated (``donate_argnums``: no page faults for the output), and
the statistics pass alone (its own case: it has no peer). Compile time (``lower().compile()``)
is reported separately. Each figure is the median of the repeats after one warm-up. The
hdrjax output is checked against the NumPy peer of the same operator (``max_rel_err``).

Usage: ``python benchmarks/bench_reinhard.py [--quick] [--size N] [--repeats R] [--skip-peers]``
"""

import argparse
import time

import _harness as H
import jax
import numpy as np

from hdrjax.operators import Reinhard2002

W = np.array([0.2126, 0.7152, 0.0722], np.float32)
BENCH = "reinhard"


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


def _compile_time(fn, x) -> float:
    t0 = time.perf_counter()
    fn.lower(x).compile()
    return time.perf_counter() - t0


def run(
    quick: bool = False,
    *,
    size: int | None = None,
    repeats: int | None = None,
    skip_peers: bool = False,
) -> list[dict]:
    """Records of benchmark ``"reinhard"`` (see the module docstring)."""
    n = size or (1024 if quick else 4096)
    reps = repeats or (5 if quick else 7)
    peer_reps = 3
    rng = np.random.default_rng(0)
    L = rng.lognormal(0.0, 2.5, (n, n)).astype(np.float32)
    rgb = (L[..., None] * rng.uniform(0.6, 1.4, (n, n, 3))).astype(np.float32)
    mb = rgb.nbytes / 1e6
    case = f"auto key+white {n}x{n} RGB"
    common = {"pixels": n * n, "megabytes": round(mb, 1)}
    out: list[dict] = []

    dst = np.empty_like(rgb)
    out.append(
        H.record(
            BENCH,
            case,
            "bandwidth bound (np.copyto, 1 read + 1 write)",
            lambda: np.copyto(dst, rgb),
            repeats=reps,
            **common,
        )
    )

    x = jax.device_put(rgb)
    op = Reinhard2002()
    full = jax.jit(lambda img: op(img))
    c_full = _compile_time(full, x)
    ours = np.asarray(full(x))
    ref = numpy_reinhard_auto(rgb)
    err = float(np.max(np.abs(ours - ref) / np.maximum(np.abs(ref), 1e-6)))
    out.append(
        H.record(
            BENCH,
            case,
            "hdrjax",
            lambda: full(x),
            repeats=reps,
            compile_s=c_full,
            max_rel_err_vs_numpy=err,
            **common,
        )
    )

    donated = jax.jit(lambda img: op(img), donate_argnums=0)
    c_don = _compile_time(donated, x)
    it = iter([jax.device_put(rgb) for _ in range(reps + 1)])  # warm-up + repeats
    out.append(
        H.record(
            BENCH,
            case,
            "hdrjax (donated input)",
            lambda: donated(next(it)),
            repeats=reps,
            compile_s=c_don,
            **common,
        )
    )

    if n <= 1024:
        exact = Reinhard2002(percentile_method="exact")
        ex = jax.jit(lambda img: exact(img))
        out.append(
            H.record(
                BENCH, case, "hdrjax (exact percentiles)", lambda: ex(x), repeats=3, compiled=True
            )
        )

    measure = jax.jit(lambda img: op.measure(img))
    c_meas = _compile_time(measure, x)
    out.append(
        H.record(
            BENCH,
            f"statistics only (JGT key, white) {n}x{n}",
            "hdrjax",
            lambda: measure(x),
            repeats=reps,
            compile_s=c_meas,
            **common,
        )
    )

    if not skip_peers:
        out.append(
            H.record(
                BENCH,
                case,
                "NumPy float32 (same operator)",
                lambda: numpy_reinhard_auto(rgb),
                repeats=peer_reps,
            )
        )
        try:
            import cv2

            tm = cv2.createTonemapReinhard()
            out.append(
                H.record(
                    BENCH,
                    case,
                    "OpenCV createTonemapReinhard",
                    lambda: tm.process(rgb),
                    repeats=peer_reps,
                )
            )
        except ImportError:
            print("OpenCV not installed: skipped")
        try:
            from colour_hdri import tonemapping_operator_Reinhard2004

            out.append(
                H.record(
                    BENCH,
                    case,
                    "colour-hdri Reinhard2004",
                    lambda: tonemapping_operator_Reinhard2004(rgb),
                    repeats=peer_reps,
                )
            )
        except ImportError:
            print("colour-hdri not installed: skipped")
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1024×1024, 5 repeats")
    ap.add_argument("--size", type=int, default=None, help="image side (default 4096, quick 1024)")
    ap.add_argument("--repeats", type=int, default=None)
    ap.add_argument("--skip-peers", action="store_true", help="hdrjax only")
    a = ap.parse_args()
    run(a.quick, size=a.size, repeats=a.repeats, skip_peers=a.skip_peers)
