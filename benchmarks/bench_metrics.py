"""What the quality metrics cost: TMQI (Yeganeh & Wang 2013) and its gradient, in one process.

Issue 22's goals, on a 2048×1024 pair (quick mode 512×256): ``hdrjax.metrics.tmqi`` warm
≤ 50 ms on the 2-core development machine, and its gradient with respect to the LDR image
(what a fit needs) ≤ 3× the forward time. The peer row is TMQI in float64 NumPy/SciPy
written step by step as the authors' MATLAB code computes it
(``tests/metrics/tmqi_numpy.py``: 2-D 11×11 correlations, SciPy's distributions), run once.
PU-SSIM (Mantiuk & Azimi 2021) on the same pair is timed too (no peer), and a fit of
``drago2003``'s bias that maximises TMQI (:class:`hdrjax.targets.TMQI`) on
``data/venice_sunset_1k.hdr`` (2048×1024 by pixel repetition; quick mode as shipped),
at the fit's default size (goal ≤ 1 s; no peer).

The images: a smooth random log-normal HDR field (cd/m²) and its Reinhard-style rendition,
``L / (1 + L)`` encoded with gamma 1/2.2.

Usage: ``python benchmarks/bench_metrics.py [--quick]``
"""

import argparse
import sys
from pathlib import Path

import jax
import numpy as np

import hdrjax
import hdrjax.metrics as hm
import hdrjax.targets as ht

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import _harness as H  # noqa: E402

from tests.metrics.tmqi_numpy import tmqi as tmqi_numpy  # noqa: E402

BENCH = "metrics"
REPO = Path(__file__).resolve().parents[1]


def _pair(h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    coarse = rng.normal(0.0, 2.0, (h // 16 + 1, w // 16 + 1))
    field = np.kron(coarse, np.ones((16, 16)))[:h, :w] + rng.normal(0.0, 0.3, (h, w))
    hdr = np.exp(field)[..., None] * rng.uniform(0.8, 1.2, (h, w, 3))
    ldr = (hdr / (1 + hdr)) ** (1 / 2.2)
    return hdr.astype(np.float32), ldr.astype(np.float32)


def run(quick: bool = False) -> list[dict]:
    """Records of benchmark ``"metrics"`` (see the module docstring)."""
    h, w = (256, 512) if quick else (1024, 2048)
    reps = 5 if quick else 7
    hdr_np, ldr_np = _pair(h, w)
    hdr, ldr = jax.device_put(hdr_np), jax.device_put(ldr_np)
    common = {"pixels": h * w}
    case = f"TMQI {w}x{h}"
    forward = jax.jit(lambda a, b: hm.tmqi(a, b).q)
    grad = jax.jit(jax.grad(lambda b, a: hm.tmqi(a, b).q))
    fwd = H.record(BENCH, case, "hdrjax", lambda: forward(hdr, ldr), repeats=reps, compiled=True)
    q_numpy = []
    peer = H.record(
        BENCH,
        case,
        "NumPy/SciPy (as the authors' MATLAB code)",
        lambda: q_numpy.append(tmqi_numpy(hdr_np, ldr_np * 255.0)),
        repeats=1,
        **common,
    )
    diff = abs(float(forward(hdr, ldr)) - q_numpy[-1][0])
    fwd["extra"].update(common, abs_diff_Q_vs_numpy=diff)
    g = H.record(
        BENCH,
        f"TMQI gradient {w}x{h}",
        "hdrjax",
        lambda: grad(ldr, hdr),
        repeats=reps,
        compiled=True,
        **common,
    )
    g["extra"]["times_forward"] = g["median_s"] / fwd["median_s"]
    cd = hdr * 100.0
    ssim = jax.jit(lambda a, b: hm.pu_ssim(a, b))
    s = H.record(
        BENCH,
        f"PU-SSIM {w}x{h}",
        "hdrjax",
        lambda: ssim(cd * 0.9, cd),
        repeats=reps,
        compiled=True,
        **common,
    )
    # a TMQI-maximising fit of drago2003's bias (goal ≤ 1 s) on a real image, 2048×1024 (its
    # pixels repeated 2×; quick: 1024×512 as shipped): the timed call measures the operator
    # on the full image, box-filters it to 64×32 (the fit's default size) and solves; the
    # target's source image is that box-filtered HDR image
    venice = np.asarray(hdrjax.io.read(REPO / "data" / "venice_sunset_1k.hdr").rgb(), np.float32)
    if not quick:
        venice = np.repeat(np.repeat(venice, 2, axis=0), 2, axis=1)
    venice = jax.device_put(venice)
    vh, vw = venice.shape[:2]
    fit = H.record(
        BENCH,
        f"fit drago2003 bias to max TMQI, {vw}x{vh} input (venice_sunset_1k.hdr)",
        "hdrjax",
        lambda: hdrjax.fit("drago2003", venice, ht.TMQI(), params="bias"),
        repeats=reps,
        compiled=True,
        pixels=vh * vw,
    )
    res = hdrjax.fit("drago2003", venice, ht.TMQI(), params="bias")
    fit["extra"].update(
        fit_resolution="64x32",
        steps=int(res.steps),
        converged=bool(res.success),
        bias=float(res.params["bias"]),
        tmqi=float(res.statistics[0]),
    )
    return [fwd, peer, g, s, fit]


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    run(ap.parse_args().quick)
