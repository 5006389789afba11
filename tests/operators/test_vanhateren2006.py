"""vanhateren2006 against HDR Toolbox's ``VanHaterenTMO`` (GNU Octave, the fixtures of
fixtures/hdrtoolbox/make_vanhateren2006.py) and against the cone model's steady state solved
in float64 NumPy (``numpy.roots`` of the paper's fifth-degree polynomial).

Parity criterion, per image: both outputs clipped to [0, 1] and sRGB encoded, the 99th
percentile of the absolute difference is at most 0.01. HDR Toolbox returns the display
signal (no gamma to apply), so its output is compared as already encoded: clipped to
[0, 1] only.
"""

from pathlib import Path

import numpy as np
import pytest

import hdrjax
from hdrjax._srgb import srgb_encode

from ..conftest import RTOL64

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
