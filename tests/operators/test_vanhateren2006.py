"""vanhateren2006 against HDR Toolbox's ``VanHaterenTMO`` (GNU Octave, the fixtures of
fixtures/hdrtoolbox/make_vanhateren2006.py) and against the cone model's steady state solved
in float64 NumPy (``numpy.roots`` of the paper's fifth-degree polynomial); its dynamics
(:func:`hdrjax.operators.vanhateren2006_sequence`) against the model's differential
equations integrated by SciPy (``solve_ivp``, Radau, float64). HDR Toolbox has no temporal
mode (``VanHaterenTMO`` is "the stable version ... not suitable for HDR videos"), so the
dynamics have no peer fixture.

Parity criterion, per image: both outputs clipped to [0, 1] and sRGB encoded, the 99th
percentile of the absolute difference is at most 0.01. HDR Toolbox returns the display
signal (no gamma to apply), so its output is compared as already encoded: clipped to
[0, 1] only.
"""

from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import hdrjax
from hdrjax._srgb import srgb_encode
from hdrjax.operators import VanHateren2006, vanhateren2006_sequence
from hdrjax.operators._vanhateren2006 import TAU_C, TAU_E, TAU_R

from ..conftest import RTOL32, RTOL64
from .cases import natural

FIXTURES = Path(__file__).parent / "fixtures" / "hdrtoolbox" / "vanhateren2006.npz"
PARITY = 0.01
"""99th percentile of |difference| after clipping to [0, 1] and sRGB encoding, per image."""
SAME_FUNCTION = 2e-6
"""Largest difference of the encoded outputs: hdrjax computes the Toolbox's function
(measured: 3.9e-7, float32 against the Toolbox's float64 rounded to float32)."""
WEIGHTS = np.array(hdrjax.REC709_WEIGHTS)


@pytest.fixture(scope="module")
def toolbox():
    with np.load(FIXTURES) as d:
        return {k: d[k] for k in d.files}


def steady_state_signal(L, pupil_area=10.0, k_beta=1.6e-4, c_beta=2.8e-3, a_C=9e-2):
    """``1 − I_os / I_os,max`` with ``I_os`` the positive real root of
    ``a_C x^5 + x^4 − 1 / (c_β + k_β A L)`` (van Hateren 2006), float64."""

    def root(inv_beta):
        r = np.roots([a_C, 1.0, 0.0, 0.0, 0.0, -inv_beta])
        return max(z.real for z in r if abs(z.imag) < 1e-9 and z.real > 0)

    x_max = root(1.0 / c_beta)
    return np.array([1.0 - root(1.0 / (c_beta + k_beta * pupil_area * v)) / x_max for v in L])


def test_vanhateren2006_matches_hdrtoolbox(toolbox):
    """HDR Toolbox's ``VanHaterenTMO`` with its default pupil (10 mm²) on four scenes from
    a sunny park to a dim interior: the same function (display light whose sRGB encoding
    is the Toolbox's signal, colour scaled in the encoded domain as there)."""
    out = np.asarray(hdrjax.make_operator("vanhateren2006")(toolbox["input"]))
    enc = np.asarray(srgb_encode(out))
    ref = np.clip(toolbox["output"], 0.0, 1.0)
    diff = np.abs(enc - ref).reshape(len(out), -1)
    p99 = np.percentile(diff, 99, axis=1)
    assert np.all(p99 <= PARITY), p99
    assert diff.max() <= SAME_FUNCTION, diff.max(axis=1)
    # the comparison covers a real range of outputs in every scene
    assert np.all(np.ptp(ref.reshape(len(ref), -1), axis=1) > 0.5)


def test_vanhateren2006_signal_is_the_steady_state(x64):
    """The signal solves the paper's steady state (float64 against ``numpy.roots``), for
    the default constants and others, from the dark to far beyond daylight."""
    L = np.logspace(-6, 9, 31)
    for kw in ({}, dict(pupil_area=3.0, k_beta=2e-4, c_beta=1e-3, a_C=0.2)):
        op = hdrjax.make_operator("vanhateren2006", **kw)
        got = np.asarray(op.signal(L))
        np.testing.assert_allclose(got, steady_state_signal(L, **kw), rtol=RTOL64, atol=1e-12)
    assert float(hdrjax.make_operator("vanhateren2006").signal(np.float64(0.0))) == 0.0


def test_vanhateren2006_grey_pixels_encode_to_the_signal():
    """A grey pixel's output, sRGB encoded, is the model's signal ``D`` (its display light
    is the signal decoded), and the curve rises with luminance."""
    L = np.logspace(-3, 6, 19).astype(np.float32)
    op = hdrjax.make_operator("vanhateren2006")
    rgb = np.repeat(L[None, :, None], 3, axis=2)
    out = np.asarray(op(rgb))[0]
    D = steady_state_signal(L.astype(np.float64))
    np.testing.assert_allclose(np.asarray(srgb_encode(out)), np.repeat(D[:, None], 3, 1), atol=2e-6)
    assert np.all(np.diff(out[:, 1]) > 0)


# --- dynamics ------------------------------------------------------------------------------

ODE_AGREEMENT = 5e-4
"""Largest difference of the display signal ``D`` from SciPy's solution of the model's
equations at the frame times (measured: 1.8e-4 for a step from 0.01 to 10⁴ cd/m² at 60 fps
with the integrator's 0.5 ms steps, either exponents; a fifth of an 8-bit code value)."""
POLYNOMIALS = {
    "hdrtoolbox": lambda a_C, b: [a_C, 1, 0, 0, 0, -1 / b],  # a_C I⁵ + I⁴ = 1/β
    "paper": lambda a_C, b: [a_C**4, 0, 0, 0, 1, -1 / b],  # a_C⁴ I⁵ + I = 1/β
}
EXPONENTS = {"hdrtoolbox": (0.25, 1.0), "paper": (1.0, 4.0)}  # (n_X, n_C): I_os = X^n_X


def _current(beta, compat, a_C=9e-2):
    """The steady-state current: the positive real root of the compat's polynomial."""
    r = np.roots(POLYNOMIALS[compat](a_C, beta))
    return max(z.real for z in r if abs(z.imag) < 1e-9 and z.real > 0)


def _ode_signal(L0, L1, fps, n, compat, pupil_area=10.0, k_beta=1.6e-4, c_beta=2.8e-3, a_C=9e-2):
    """``D`` at frames 1 … n−1 after a step from ``L0`` (adapted) to ``L1`` cd/m² at frame 1,
    the model's equations (``vanhateren2006_sequence`` docstring) solved in float64."""
    n_X, n_C = EXPONENTS[compat]

    def f(t, y):
        R, E, X, C = y
        beta = c_beta + k_beta * pupil_area * E
        dX = 1 / (1 + (a_C * C) ** n_C) - beta * X
        return [(L1 - R) / TAU_R, (R - E) / TAU_E, dX, (X**n_X - C) / TAU_C]

    I0 = _current(c_beta + k_beta * pupil_area * L0, compat, a_C)
    t = 1000.0 / fps * np.arange(1, n)
    y0 = [L0, L0, I0 ** (1 / n_X), I0]
    sol = solve_ivp(f, (0.0, t[-1]), y0, "Radau", t, rtol=1e-11, atol=1e-14)
    return 1.0 - sol.y[2] ** n_X / _current(c_beta, compat, a_C)


@pytest.fixture(scope="module")
def steps_in_luminance():
    """Steps up and down over six decades, at 16 and 60 fps: grey pixels, one per step."""
    return [(1.0, 100.0), (100.0, 1.0), (1000.0, 0.01), (0.01, 1e4)]


@pytest.mark.parametrize("compat", ["hdrtoolbox", "paper"])
@pytest.mark.parametrize("fps", [16.0, 60.0])
def test_vanhateren2006_sequence_solves_the_model_equations(x64, steps_in_luminance, fps, compat):
    n = 10
    L0 = np.array([a for a, _ in steps_in_luminance])
    L1 = np.array([b for _, b in steps_in_luminance])
    frames = np.repeat(L1[None, None, :, None], n, axis=0).repeat(3, axis=3)
    frames[0] = L0[None, :, None]
    out, _ = vanhateren2006_sequence(frames, fps, compat=compat)
    D = np.asarray(srgb_encode(jnp.asarray(out)))[1:, 0, :, 1]
    ref = np.stack([_ode_signal(a, b, fps, n, compat) for a, b in steps_in_luminance], axis=1)
    np.testing.assert_allclose(D, ref, rtol=0, atol=ODE_AGREEMENT)
    # cones adapt to a brighter scene within a frame, to a darker one over several (the cGMP
    # loop's time constant 1/β is long in dim light): a real transient, compared frame by frame
    assert np.all(np.ptp(ref[:, 1:3], axis=0) > 0.1)


def test_vanhateren2006_sequence_of_a_still_scene_is_the_static_operator():
    frame = natural((8, 8)) * 50.0
    op = VanHateren2006(pupil_area=5.0)
    out, st = vanhateren2006_sequence(np.stack([frame] * 4), 25.0, op)
    static = np.asarray(op(frame))
    for got in np.asarray(out):
        np.testing.assert_allclose(got, static, rtol=RTOL32, atol=1e-6)
    np.testing.assert_allclose(st.R[-1], st.E[-1], rtol=RTOL32)
    assert isinstance(op, hdrjax.operators.AbstractTimeDependentOperator)


def test_vanhateren2006_paper_steady_state(x64):
    """``compat="paper"``: the first frame (adapted) shows the model's own steady state,
    ``a_C⁴ I_os⁵ + I_os = 1/β`` (float64 against ``numpy.roots``), from the dark to far
    beyond daylight; it departs from HDR Toolbox's equation by up to 0.2 (near 560 cd/m²)."""
    L = np.logspace(-4, 8, 25)
    frames = np.repeat(L[None, None, :, None], 3, axis=3)
    out, st = vanhateren2006_sequence(frames, 16.0, compat="paper")
    D = np.asarray(srgb_encode(jnp.asarray(out)))[0, 0, :, 1]
    k = 2.8e-3 + 1.6e-3 * L
    ref = 1.0 - np.array([_current(b, "paper") for b in k]) / _current(2.8e-3, "paper")
    np.testing.assert_allclose(D, ref, rtol=RTOL64, atol=1e-12)
    np.testing.assert_allclose(st.C[0], st.X[0], rtol=RTOL64)  # n_X = 1: C = I_os = X
    toolbox = steady_state_signal(L)
    assert 0.1 < np.abs(D - toolbox).max() < 0.5


def test_vanhateren2006_sequence_in_chunks_equals_one_scan():
    frames = np.stack([natural((6, 6), seed=s) * 10.0 ** (s - 1) for s in range(5)])
    whole, states = vanhateren2006_sequence(frames, 16.0)
    first, st = VanHateren2006().sequence(frames[:2], 16.0)
    carried = jax.tree.map(lambda v: v[-1], st)
    rest, _ = VanHateren2006().sequence(frames[2:], 16.0, initial=carried)
    np.testing.assert_allclose(np.concatenate([first, rest]), whole, rtol=RTOL32, atol=1e-7)


def test_vanhateren2006_sequence_is_differentiable():
    """Finite, non-zero gradients with respect to the frames and the model's parameters."""
    frames = jnp.asarray(np.stack([natural((4, 4), seed=s) * 10.0**s for s in range(3)]))
    params, static = eqx.partition(VanHateren2006(), eqx.is_inexact_array)

    def loss(p, x):
        return jnp.sum(vanhateren2006_sequence(x, 16.0, eqx.combine(p, static), max_step=2.0)[0])

    gp, gx = jax.jit(jax.grad(loss, argnums=(0, 1)))(params, frames)
    for g in (gp.pupil_area, gp.k_beta, gp.c_beta, gp.a_C, gx):
        assert np.all(np.isfinite(np.asarray(g))) and np.any(np.asarray(g) != 0)


def test_vanhateren2006_sequence_bad_pixels_and_arguments():
    frames = np.stack([natural((4, 4), seed=s) * 10.0 for s in range(3)]).astype(np.float32)
    frames[:, 0, 0] = np.nan
    frames[:, 1, 1] = np.inf
    out = np.asarray(vanhateren2006_sequence(frames, 16.0)[0])
    assert np.all(np.isnan(out[:, 0, 0])) and np.all(out[:, 1, 1] == 1.0)
    rest = np.ones(out.shape[:3], bool)
    rest[:, :2, :2] = False
    assert np.all(np.isfinite(out[rest]))
    with pytest.raises(ValueError, match="^frames"):
        vanhateren2006_sequence(frames[0], 16.0)
    with pytest.raises(ValueError, match="^fps"):
        vanhateren2006_sequence(frames, 0.0)
    with pytest.raises(ValueError, match="^compat"):
        vanhateren2006_sequence(frames, 16.0, compat="pfstmo")
