"""What the quality metrics cost: TMQI (Yeganeh & Wang 2013) and its gradient, in one process.

Issue 22's goals, on a 2048×1024 pair (quick mode 512×256): ``hdrjax.metrics.tmqi`` warm
≤ 50 ms on the 2-core development machine, and its gradient with respect to the LDR image
(what a fit needs) ≤ 3× the forward time. The peer row is TMQI in float64 NumPy/SciPy
written step by step as the authors' MATLAB code computes it
(``tests/metrics/tmqi_numpy.py``: 2-D 11×11 correlations, SciPy's distributions), run once.
PU-SSIM (Mantiuk & Azimi 2021) on the same pair is timed too (no peer).

The images: a smooth random log-normal HDR field (cd/m²) and its Reinhard-style rendition,
``L / (1 + L)`` encoded with gamma 1/2.2.

Usage: ``python benchmarks/bench_metrics.py [--quick]``
"""

import argparse
import sys
from pathlib import Path

import jax
import numpy as np

import hdrjax.metrics as hm

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import _harness as H  # noqa: E402

from tests.metrics.tmqi_numpy import tmqi as tmqi_numpy  # noqa: E402

BENCH = "metrics"


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
    return [fwd, peer, g, s]


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    run(ap.parse_args().quick)
