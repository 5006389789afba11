"""pattanaik2000 (Pattanaik et al. 2000) against pfstmo 2.2.0's ``pfstmo_pattanaik00``, and
its time course (:func:`hdrjax.operators.pattanaik2000_sequence`).

Fixtures: fixtures/pfstmo/pattanaik2000.npz, written by fixtures/pfstmo/make_pattanaik2000.py
(its docstring: the commands, the pfstmo version, the crops, scales and sequence).

Issue 20's parity criterion: after clipping both to [0, 1] and sRGB encoding, the 99th
percentile of the absolute difference is at most 0.01 on every image (:data:`CRITERION`).
Measured in float32 with pfstmo's luminance weights (p99 / largest difference):
CandleGlass (log-average 1.2e-3 cd/m²) 1.5e-6 / 1.9e-6, rooitou_park (0.13) 4.1e-7 / 1.0e-6,
venice_sunset × 100 (26) 1.2e-6 / 2.0e-6, MtTamNorth × 1000 (100) 6.5e-6 / 8.5e-6; the
24-frame sequence of pfstmo's time-dependent mode, with ``compat="pfstmo"``: 4.5e-7 / 7.5e-7
(:data:`TIGHT` bounds the largest difference, so a regression well inside the criterion
shows).
"""

import functools
import math
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax.operators import Pattanaik2000, pattanaik2000_sequence
from hdrjax.operators._pattanaik2000 import (
    I0_CONE,
    I0_ROD,
    T0_CONE,
    T0_ROD,
    TAU_CONE,
    TAU_ROD,
    steady_state,
)

from ..conftest import RTOL32
from .cases import natural

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "pfstmo" / "pattanaik2000.npz"
PFSTMO_WEIGHTS = (0.212656, 0.715158, 0.072186)
"""Luminance weights of pfstools' RGB-to-XYZ matrix (its Y row): pfstmo's luminance."""
CRITERION = 0.01
TIGHT = 3e-5
"""Largest absolute difference (encoded) allowed: about 3 times the largest measured."""


@functools.cache
def fixtures() -> dict[str, np.ndarray]:
    with np.load(FIXTURES) as f:
        return {k: f[k] for k in f.files}


def encoded(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB encoding after clipping to [0, 1] (float64 NumPy)."""
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def _check(got: np.ndarray, ref: np.ndarray, what: str) -> None:
    diff = np.abs(encoded(got) - encoded(ref))
    assert np.percentile(diff, 99) <= CRITERION, what
    assert diff.max() <= TIGHT, f"{what}: {diff.max():.2e}"


def test_static_mode_matches_pfstmo():
    """Four real images at four levels from dim to bright daylight, in one batch."""
    f = fixtures()
    op = hdrjax.make_operator("pattanaik2000", weights=PFSTMO_WEIGHTS)
    out = np.asarray(op(f["input"]))
    assert out.dtype == np.float32
    for name, got, ref in zip(f["names"], out, f["output"], strict=True):
        _check(got, ref, str(name))


def test_time_dependent_mode_matches_pfstmo():
    """pfstmo's ``-t --fps 16`` on a step of the scene's luminance (×100 after 0.25 s):
    ``compat="pfstmo"`` follows it frame by frame."""
    f = fixtures()
    op = hdrjax.make_operator("pattanaik2000", weights=PFSTMO_WEIGHTS)
    out, _ = pattanaik2000_sequence(
        f["sequence_input"], float(f["sequence_fps"]), op, compat="pfstmo"
    )
    for i, (got, ref) in enumerate(zip(np.asarray(out), f["sequence_output"], strict=True)):
        _check(got, ref, f"frame {i}")


def _uniform_frames(levels, shape=(4, 4)) -> np.ndarray:
    return np.stack([np.full(shape + (3,), v) for v in levels])


def test_step_adapts_with_the_papers_time_constants(x64):
    """A step from 1 to 1000 cd/m²: one second (16 frames at 16 fps) after it, the state
    is the exact solution of the paper's equations for a constant goal: ``A`` relaxed
    through ``e^(−t/t₀)`` (80 ms cones, 150 ms rods), bleaching ``dB/dt = (1 − B)/τ −
    G B/I₀`` (τ 110 s and 400 s)."""
    fps, low, high = 16.0, 1.0, 1000.0
    frames = _uniform_frames([low] + [high] * 16)
    _, st = pattanaik2000_sequence(frames, fps)
    op = Pattanaik2000()
    G0 = float(op.measure(frames[0]).A_cone)
    G1 = float(op.measure(frames[-1]).A_cone)
    np.testing.assert_allclose(G1, 5 * high, rtol=1e-9)  # 5 × the log-average
    B0 = steady_state(G0, G0)
    t = 1.0
    for name, t0, tau, I0, B in (
        ("cone", T0_CONE, TAU_CONE, I0_CONE, B0.B_cone),
        ("rod", T0_ROD, TAU_ROD, I0_ROD, B0.B_rod),
    ):
        A = G1 + (G0 - G1) * math.exp(-t / t0)
        np.testing.assert_allclose(getattr(st, f"A_{name}")[-1], A, rtol=1e-9, err_msg=name)
        r = 1 / tau + G1 / I0
        B_inf = 1 / (tau * r)
        B_t = B_inf + (float(B) - B_inf) * math.exp(-r * t)
        np.testing.assert_allclose(getattr(st, f"B_{name}")[-1], B_t, rtol=1e-9, err_msg=name)
    # the first frame is mapped adapted to itself, and the state moves towards the goal
    np.testing.assert_allclose(st.A_cone[0], G0, rtol=1e-12)
    assert np.all(np.diff(np.asarray(st.A_cone)[1:]) > 0)
    assert np.all(np.diff(np.asarray(st.B_cone)[1:]) < 0)  # the bright light bleaches


def test_constant_sequence_stays_at_the_static_result():
    frame = natural((8, 8)) * 50.0
    frames = np.stack([frame] * 5)
    op = Pattanaik2000()
    out, st = pattanaik2000_sequence(frames, 25.0, op)
    static = np.asarray(op(frame))
    for got in np.asarray(out):
        np.testing.assert_allclose(got, static, rtol=RTOL32, atol=1e-7)
    A = float(op.measure(frame).A_cone)
    np.testing.assert_allclose(st.A_cone, A, rtol=RTOL32)
    np.testing.assert_allclose(st.B_rod, 0.04 / (0.04 + A), rtol=RTOL32)


def test_sequence_is_differentiable():
    """Finite, non-zero gradients with respect to the frames, the frame rate and the
    display adaptation, through the scan."""
    frames = jnp.asarray(np.stack([natural((6, 6), seed=s) * 10.0**s for s in range(4)]))
    op = Pattanaik2000()
    params, static = eqx.partition(op, eqx.is_inexact_array)

    def loss(p, x, fps):
        out, _ = pattanaik2000_sequence(x, fps, eqx.combine(p, static))
        return jnp.sum(out)

    gp, gx, gf = jax.jit(jax.grad(loss, argnums=(0, 1, 2)))(params, frames, 8.0)
    for g in (gp.display_adaptation, gx, gf):
        assert np.all(np.isfinite(np.asarray(g)))
    assert np.any(np.asarray(gx) != 0) and float(gf) != 0.0


def test_sequence_arguments_are_checked():
    frames = np.ones((2, 4, 4, 3), np.float32)
    with pytest.raises(ValueError, match="^compat"):
        pattanaik2000_sequence(frames, 16.0, compat="fast")
    with pytest.raises(ValueError, match="^frames"):
        pattanaik2000_sequence(frames[0], 16.0)


def test_absolute_level_changes_the_appearance():
    """The model is absolute: the same image at 1/1000 the luminance looks darker, and
    greyer (rods take over), not the same (a relative operator would map both alike)."""
    frame = natural((8, 8))
    op = Pattanaik2000()
    bright, dim = np.asarray(op(np.stack([frame * 100.0, frame * 0.1])))
    assert bright.mean() > dim.mean()

    def chroma(x):
        return np.mean(np.std(x, axis=-1) / np.maximum(np.mean(x, axis=-1), 1e-12))

    assert chroma(dim) < chroma(bright)
