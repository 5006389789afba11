"""Highlight desaturation: the algorithm of seed 000 section 4.2, step by step, against NumPy."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from hdrjax import REC709_WEIGHTS
from hdrjax.display import (
    DesaturateHighlights,
    desaturate_highlights,
    highlight_threshold,
)

from ..conftest import DATA, enable_x64

RNG = np.random.default_rng(4)


def _reference(rgb: np.ndarray, T: float, weights=REC709_WEIGHTS) -> np.ndarray:
    """Section 4.2 in float64: mean of the channels, differences, coefficient 0 at and below
    T and 1 at the image's maximum luminance (linear between), channels moved by it."""
    x = rgb.astype(np.float64)
    L = x @ np.asarray(weights, np.float64)
    L_max = L.max()
    s = np.clip((L - T) / (L_max - T), 0.0, 1.0) if L_max > T else np.zeros_like(L)
    mean = x.mean(axis=-1, keepdims=True)
    return x - s[..., None] * (x - mean)


def _hdr(shape, seed=0):
    return np.random.default_rng(seed).lognormal(0, 2, size=shape).astype(np.float32)


def test_manual_threshold_matches_the_paper_step_by_step():
    rgb = _hdr((40, 50, 3))
    T = 20.0
    with enable_x64():
        got = np.asarray(desaturate_highlights(rgb.astype(np.float64), T))
    np.testing.assert_allclose(got, _reference(rgb, T), rtol=1e-12)
    got32 = np.asarray(desaturate_highlights(rgb, T))
    np.testing.assert_allclose(got32, _reference(rgb, T), rtol=1e-5)


def test_brightest_pixel_becomes_grey_and_dim_pixels_are_unchanged():
    rgb = _hdr((30, 30, 3))
    rgb[7, 9] = [5000.0, 1000.0, 100.0]  # the maximum luminance
    out = np.asarray(desaturate_highlights(rgb, 5.0))
    np.testing.assert_allclose(out[7, 9], [rgb[7, 9].mean()] * 3, rtol=1e-6)
    L = rgb @ np.asarray(REC709_WEIGHTS, np.float32)
    dim = L <= 5.0
    np.testing.assert_array_equal(out[dim], rgb[dim])
    # threshold at or above the maximum: nothing changes
    np.testing.assert_array_equal(np.asarray(desaturate_highlights(rgb, 1e6)), rgb)


def test_automatic_threshold_is_twice_the_luminance_exceeded_by_ten_percent():
    rgb = _hdr((64, 80, 3), seed=1)
    L = rgb.astype(np.float64) @ np.asarray(REC709_WEIGHTS)
    L90 = np.percentile(L, 90)  # numpy's linear interpolation, all pixels positive here
    T, err = highlight_threshold(rgb)
    assert abs(float(T) / (2 * L90) - 1) <= float(err) + 1e-6
    assert 0 < float(err) < 0.005
    T_exact, err0 = highlight_threshold(rgb, method="exact")
    assert float(err0) == 0.0
    np.testing.assert_allclose(float(T_exact), 2 * L90, rtol=1e-5)
    np.testing.assert_allclose(
        np.asarray(desaturate_highlights(rgb, method="exact")),
        _reference(rgb, 2 * L90),
        rtol=1e-4,
        atol=1e-6,
    )


def test_automatic_threshold_counts_dark_and_zero_pixels():
    """'Only 10 % of the pixels exceed' counts all finite pixels, not only positive ones."""
    rgb = _hdr((50, 50, 3), seed=2)
    rgb[:25] = 0.0  # half the image is black
    L = rgb.astype(np.float64) @ np.asarray(REC709_WEIGHTS)
    T, _ = highlight_threshold(rgb, method="exact")
    np.testing.assert_allclose(float(T), 2 * np.percentile(L, 90), rtol=1e-4)
    rgb[:46] = 0.0  # fewer than 10 % positive: L90 is 0
    T, _ = highlight_threshold(rgb, method="exact")
    assert float(T) == 0.0


def test_threshold_of_images_at_the_float_maximum_is_the_float_maximum():
    """``2 · L₉₀`` past the largest float (it was +Inf, or NaN from the percentile of an
    image at the maximum) is clamped to it: finite, and still at or above every pixel's
    luminance, so nothing changes, as with any ``T ≥ L_max``."""
    big = np.finfo(np.float32).max
    # the shapes of the tests above for each method: their compiled functions are reused
    for shape, method in (((64, 80, 3), "histogram"), ((50, 50, 3), "exact")):
        for level in (1.0, 0.75):
            T, _ = highlight_threshold(np.full(shape, level * big, np.float32), method=method)
            assert float(T) == big, (method, level)


def test_non_finite_pixels_pass_through_and_do_not_spread():
    rgb = _hdr((20, 24, 3), seed=3)
    rgb[2, 3] = [np.nan, 1.0, 1.0]
    rgb[5, 6] = [np.inf, 1.0, 1.0]
    rgb[8, 9] = [-np.inf, 0.0, 0.0]
    out = np.asarray(desaturate_highlights(rgb))
    bad = ~np.all(np.isfinite(rgb), axis=-1)
    np.testing.assert_array_equal(out[bad], rgb[bad])
    assert np.isfinite(out[~bad]).all()
    clean = rgb.copy()
    clean[bad] = 0.0
    T, _ = highlight_threshold(rgb)
    np.testing.assert_allclose(out[~bad], _reference(clean, float(T))[~bad], rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("bad", [None, "lanes", "tail"])
def test_one_pass_threshold_over_many_blocks(monkeypatch, bad):
    """The automatic path reads the luminance once (histogram, maximum and the finiteness
    test together, in blocks of lanes plus a ragged tail): against NumPy, with a NaN pixel
    in a block or in the tail, and dark pixels counted in the 90 % rank."""
    import hdrjax._stats as S

    monkeypatch.setattr(S, "LANES", 1024)  # 5 blocks + a tail of 107 pixels
    rgb = _hdr((61, 86, 3), seed=7)  # a shape of its own: compiled afresh with small lanes
    rgb[:6] = 0.0
    rgb[10, 3] = -0.5
    flat = rgb.reshape(-1, 3)
    if bad:
        flat[2000 if bad == "lanes" else 5200] = [np.nan, 1.0, 2.0]
    ok = np.all(np.isfinite(flat), axis=-1)
    L = flat[ok].astype(np.float64) @ np.asarray(REC709_WEIGHTS)
    T_ref = 2 * np.percentile(L, 90, method="lower")  # the order statistic the bin holds
    out = np.asarray(desaturate_highlights(rgb)).reshape(-1, 3)
    T, err = highlight_threshold(rgb)
    assert abs(float(T) / T_ref - 1) <= float(err) + 1e-6
    np.testing.assert_array_equal(out[~ok], flat[~ok])  # NaN stays where it was
    expect = _reference(flat[ok], float(T))
    np.testing.assert_allclose(out[ok], expect, rtol=1e-4, atol=1e-6)


def test_differentiable_in_the_threshold_and_the_image():
    rgb = jnp.asarray(_hdr((16, 16, 3), seed=5))

    def f(t):
        return jnp.sum(desaturate_highlights(rgb, t) ** 2)

    t0 = 8.0
    g = jax.grad(f)(t0)
    fd = (f(t0 + 1e-2) - f(t0 - 1e-2)) / 2e-2
    np.testing.assert_allclose(float(g), float(fd), rtol=2e-2)
    gi = jax.grad(lambda x: jnp.sum(desaturate_highlights(x, t0)))(rgb)
    assert np.isfinite(np.asarray(gi)).all()
    ge = jax.grad(lambda x: jnp.sum(desaturate_highlights(x, method="exact")))(rgb)
    assert np.isfinite(np.asarray(ge)).all()


def test_automatic_path_is_differentiable_through_the_maximum(x64):
    # the one-pass statistics give L_max; its derivative (through the brightest pixel,
    # which the histogram threshold does not see move) against central differences
    rgb = _hdr((12, 14, 3), seed=6).astype(np.float64)
    i = np.unravel_index(np.argmax(rgb @ np.asarray(REC709_WEIGHTS)), rgb.shape[:2])

    def f(x):
        return jnp.sum(desaturate_highlights(x) ** 2)

    g = np.asarray(jax.grad(f)(jnp.asarray(rgb)))
    for c in range(3):
        e = np.zeros_like(rgb)
        e[i + (c,)] = 1e-4 * rgb[i + (c,)]
        fd = (float(f(rgb + e)) - float(f(rgb - e))) / (2 * e[i + (c,)])
        np.testing.assert_allclose(g[i + (c,)], fd, rtol=1e-5)


def test_batches_get_their_own_thresholds_and_modules_compose():
    a, b = _hdr((20, 20, 3), seed=6), _hdr((20, 20, 3), seed=7) * 50
    batch = np.stack([a, b])
    out = np.asarray(jax.jit(desaturate_highlights)(batch))
    np.testing.assert_allclose(out[0], np.asarray(desaturate_highlights(a)), rtol=1e-4)
    np.testing.assert_allclose(out[1], np.asarray(desaturate_highlights(b)), rtol=1e-4)
    T, _ = highlight_threshold(batch)
    assert T.shape == (2,) and float(T[1]) > 10 * float(T[0])
    per_image = np.asarray(desaturate_highlights(batch, jnp.asarray([3.0, 300.0])))
    np.testing.assert_allclose(per_image[1], _reference(b, 300.0), rtol=1e-4)
    mod = DesaturateHighlights(threshold=jnp.asarray(3.0))
    np.testing.assert_allclose(
        np.asarray(eqx.filter_jit(lambda m, x: m(x))(mod, a)),
        np.asarray(desaturate_highlights(a, 3.0)),
        rtol=1e-6,
    )


def test_on_the_repository_image():
    from hdrjax import io as hio

    img = hio.read(DATA / "cornell_box.exr")
    rgb = img.rgb()
    out = np.asarray(desaturate_highlights(rgb, weights=img.luminance_weights))
    T, _ = highlight_threshold(rgb, method="exact")
    finite = np.all(np.isfinite(rgb), axis=-1)
    np.testing.assert_allclose(out[finite], _reference(rgb, float(T))[finite], rtol=1e-3, atol=1e-6)
    spread_in = np.ptp(rgb, axis=-1)
    spread_out = np.ptp(out, axis=-1)
    assert (spread_out <= spread_in * (1 + 1e-6) + 1e-7).all()


def test_bad_arguments():
    rgb = np.ones((4, 4, 3), np.float32)
    with pytest.raises(ValueError):
        desaturate_highlights(np.ones((4, 4, 4), np.float32))
    with pytest.raises(ValueError):
        desaturate_highlights(rgb, method="sort")
    with pytest.raises(ValueError):
        highlight_threshold(rgb, bins=1)


@settings(deadline=None, max_examples=30)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 50.0))
def test_saturation_never_increases_and_luminance_order_is_kept(seed, T):
    rgb = _hdr((6, 7, 3), seed)
    out = np.asarray(desaturate_highlights(rgb, T))
    assert (np.ptp(out, axis=-1) <= np.ptp(rgb, axis=-1) * (1 + 1e-6) + 1e-6).all()
    np.testing.assert_allclose(out.mean(-1), rgb.mean(-1), rtol=1e-5)  # the mean is kept
