"""delta_e_itp (ITU-R BT.2124) against colour-science 0.4's ``delta_E_ITP`` of
``RGB_to_ICtCp`` (BT.2100 PQ; colour takes its RGB in cd/m²), called directly."""

import colour
import jax
import numpy as np
import pytest

import hdrjax.metrics as hm

ATOL = 1e-6
"""Issue 22's criterion (ΔE_ITP units), float64."""


def test_matches_colour_science(x64):
    rng = np.random.default_rng(0)
    a = rng.lognormal(2.0, 2.5, (64, 3)).clip(0, 10000)
    b = a * rng.lognormal(0.0, 0.1, (64, 3))
    b[:4] = a[:4]  # identical pixels: 0
    b[4:8] *= 0.0  # black
    want = colour.difference.delta_E_ITP(colour.RGB_to_ICtCp(a), colour.RGB_to_ICtCp(b))
    got = np.asarray(hm.delta_e_itp(a, b))
    np.testing.assert_allclose(got, want, rtol=0, atol=ATOL)
    assert np.all(got[:4] == 0)


def test_float32_gradient_and_errors():
    a = np.array([[100.0, 50.0, 10.0], [0.0, 0.0, 0.0]], np.float32)
    g = jax.grad(lambda x: hm.delta_e_itp(x, a).sum())(a)  # identical: ΔE 0, gradient 0
    assert np.all(np.isfinite(g))
    with pytest.raises(ValueError, match="^b: expected the shape of a"):
        hm.delta_e_itp(a, a[:1])
    with pytest.raises(ValueError, match="^a: expected channels-last RGB"):
        hm.delta_e_itp(a[:, :2], a[:, :2])
