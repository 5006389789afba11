"""Target statistics: values against NumPy / colour-science, soft limits, composition."""

import colour
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax import targets as ht

from ..conftest import RTOL64


def _display(seed=0, shape=(16, 16, 3)):
    return np.random.default_rng(seed).uniform(0.0, 1.2, shape)


def _lum(x):
    return np.clip(x, 0, 1) @ np.asarray(hdrjax.REC709_WEIGHTS)


def test_mean_luminance_matches_numpy(x64):
    d = _display()
    t = ht.MeanLuminance(0.4, weight=2.0)
    np.testing.assert_allclose(
        eqx.filter_jit(type(t).statistics)(t, jnp.asarray(d))[0], _lum(d).mean(), rtol=RTOL64
    )
    np.testing.assert_allclose(
        t.residuals(jnp.asarray(d))[0], 2.0 * (_lum(d).mean() - 0.4), rtol=RTOL64
    )


def test_percentiles_match_numpy_and_are_differentiable(x64):
    d = _display(1)
    t = ht.Percentiles((1, 50, 99), (0.02, 0.3, 0.95))
    np.testing.assert_allclose(
        eqx.filter_jit(type(t).statistics)(t, jnp.asarray(d)),
        np.percentile(_lum(d), [1, 50, 99]),
        rtol=RTOL64,
    )
    g = jax.grad(lambda s: t.statistics(s * jnp.asarray(d) * 0.5)[1])(1.0)
    # the median of 0.5·s·L is linear in s (no clipping below 1): derivative = median/2
    np.testing.assert_allclose(g, np.percentile(_lum(d * 0.5), 50), rtol=1e-9)
    with pytest.raises(ValueError):
        ht.Percentiles((1, 99), (0.5,))


def test_percentiles_by_selection_match_numpy_even_after_q_changes(x64):
    # 40 × 40 pixels: the percentiles come from jax.lax.top_k of the 42 smallest/largest (not a
    # sort); zero pixels are excluded, as numpy sees only the positive ones below
    d = _display(7, (40, 40, 3))
    d[:5] = 0.0
    L = _lum(d)
    t = ht.Percentiles((1, 2.5, 97.5, 99), (0.0,) * 4)
    assert t.select == (2.5, 97.5)
    got = eqx.filter_jit(type(t).statistics)(t, jnp.asarray(d))
    np.testing.assert_allclose(got, np.percentile(L[L > 0], [1, 2.5, 97.5, 99]), rtol=RTOL64)
    # P99 of the display s·d/2 (≤ 0.6: nothing clips) is s·P99(lum(d/2)): derivative at s = 1
    half = _lum(d * 0.5)
    g = jax.grad(lambda s: t.statistics(s * jnp.asarray(d * 0.5))[3])(1.0)
    np.testing.assert_allclose(g, np.percentile(half[half > 0], 99), rtol=1e-9)
    # a q moved outside the selection after construction falls back to the sort
    moved = eqx.tree_at(lambda t: t.q, t, jnp.asarray([1.0, 30.0, 60.0, 99.0]))
    np.testing.assert_allclose(
        eqx.filter_jit(type(t).statistics)(moved, jnp.asarray(d)),
        np.percentile(L[L > 0], [1, 30, 60, 99]),
        rtol=RTOL64,
    )


def test_clipped_fraction_tends_to_the_hard_count(x64):
    d = _display(2)
    hard = np.mean(d.max(-1) >= 1.0)
    soft = ht.ClippedFraction(0.0, softness=1e-6).statistics(jnp.asarray(d))[0]
    np.testing.assert_allclose(soft, hard, atol=1e-3)


def test_histogram_sums_to_one_and_tends_to_numpy(x64):
    d = _display(3, (32, 32, 3))
    t = ht.Histogram(np.ones(8), softness=1e-4)
    s = np.asarray(eqx.filter_jit(type(t).statistics)(t, jnp.asarray(d)))
    np.testing.assert_allclose(s.sum(), 1.0, rtol=1e-12)
    v = np.asarray(hdrjax.display.srgb_encode(_lum(d)))
    ref, _ = np.histogram(v, bins=8, range=(0, 1))
    np.testing.assert_allclose(s, ref / v.size, atol=2e-3)
    np.testing.assert_allclose(t.value, np.full(8, 1 / 8))


def test_reference_lab_matches_colour_science(x64):
    a, b = _display(4, (4, 4, 3)).clip(0, 1), _display(5, (4, 4, 3)).clip(0, 1)
    t = ht.Reference(jnp.asarray(b), space="lab")
    lab = lambda x: colour.XYZ_to_Lab(colour.sRGB_to_XYZ(x, apply_cctf_decoding=False))  # noqa: E731
    rmse = np.sqrt(np.sum((lab(a) - lab(b)) ** 2) / 16) / 100
    # colour uses the exact-precision sRGB matrix; ours is the 4-digit IEC one
    np.testing.assert_allclose(t.statistics(jnp.asarray(a))[0], rmse, rtol=2e-3)
    np.testing.assert_allclose(ht.Reference(jnp.asarray(a)).statistics(jnp.asarray(a)), [0.0])
    with pytest.raises(ValueError):
        t.residuals(jnp.zeros((2, 2, 3)))


def test_composition_concatenates_and_scales():
    d = jnp.asarray(_display(6))
    a, b = ht.MeanLuminance(0.2), ht.Percentiles((50,), (0.5,))
    c = a + 3.0 * b
    assert isinstance(c, ht.Combined) and len((c + a).targets) == 3
    np.testing.assert_allclose(
        c.residuals(d), np.concatenate([a.residuals(d), 3.0 * b.residuals(d)]), rtol=1e-6
    )
    np.testing.assert_allclose(
        c.statistics(d), np.concatenate([a.statistics(d), b.statistics(d)]), rtol=1e-6
    )
