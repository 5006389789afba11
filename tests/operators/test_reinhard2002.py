"""Reinhard 2002: the paper's curve, JGT automatic parameters against a float64 NumPy
reference written here (formulas.md §1.3), the local operator against a scipy reference,
the automatic switch, and monotonicity (hypothesis)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.ndimage as ndi
from hypothesis import given, settings, strategies as st

import hdrjax
from hdrjax.operators import Reinhard2002, Reinhard2002Auto, Reinhard2002Local
from hdrjax.operators._reinhard2002_local import ALPHA1, scales

from ..conftest import DATA, RTOL32, RTOL64
from .cases import natural

W = np.array([0.2126, 0.7152, 0.0722])


def jgt_reference(rgb):
    """Float64 NumPy reference of the JGT 2002 automatic parameters (formulas.md §1.3), with
    hdritools' white-point guard in scaled units (Eq. 5's white against the trimmed
    log-average times ``key / lbar``; see hdrjax/operators/_reinhard2002.py)."""
    L = rgb @ W
    pos = L[np.isfinite(L) & (L > 0)]
    l1, l99 = np.percentile(pos, [1, 99])
    lbar_t = np.exp(np.mean(np.log(pos[pos <= l99])))
    key = 0.18 * 4 ** (
        (2 * np.log2(lbar_t) - np.log2(l1) - np.log2(l99)) / (np.log2(l99) - np.log2(l1))
    )
    lbar = np.exp(np.mean(np.log(1e-6 + np.maximum(L, 0))))
    zones = np.log2(pos.max()) - np.log2(pos.min())
    if 1.5 * 2 ** (zones - 5) <= lbar_t * key / lbar:
        white = 1.5 * pos.max() * key / lbar
    else:
        white = 1.5 * 2 ** (zones - 5)
    return key, white, lbar


@pytest.mark.parametrize("seed,sigma", [(0, 2.0), (1, 0.7), (2, 3.0)])
def test_automatic_parameters_match_numpy_reference(x64, seed, sigma):
    rng = np.random.default_rng(seed)
    rgb = rng.lognormal(0.0, sigma, (40, 50, 1)) * rng.uniform(0.5, 1.5, (40, 50, 3))
    key, white, lbar = jgt_reference(rgb)
    op = Reinhard2002(percentile_method="exact").measure(rgb)
    np.testing.assert_allclose(float(op.key), key, rtol=RTOL64)
    np.testing.assert_allclose(float(op.L_white), white, rtol=RTOL64)
    np.testing.assert_allclose(float(op.log_average), lbar, rtol=RTOL64)
    # the histogram default stays within its stated bound (key depends on log ratios)
    fast = Reinhard2002().measure(rgb)
    np.testing.assert_allclose(float(fast.key), key, rtol=5e-3)
    np.testing.assert_allclose(float(fast.L_white), white, rtol=RTOL64)


@pytest.mark.parametrize("bad", [None, "tail"])
def test_statistics_pass_decides_the_clean_path(monkeypatch, bad):
    """The automatic operator measures and checks for NaN/Inf in one pass over the
    luminance (blocks of lanes plus a ragged tail): the parameters against the NumPy
    reference of the finite pixels, and a NaN pixel in the tail (the lanes' own NaN test:
    tests/core/test_stats_encode.py) stays NaN without reaching its neighbours or the
    statistics."""
    import hdrjax._stats as S

    monkeypatch.setattr(S, "LANES", 1024)  # 4 blocks + a tail of 479 pixels
    rng = np.random.default_rng(5)
    rgb = (rng.lognormal(0.0, 2.0, (75, 61, 1)) * rng.uniform(0.5, 1.5, (75, 61, 3))).astype(
        np.float32
    )
    flat = rgb.reshape(-1, 3)
    flat[7] = 0.0
    if bad:
        flat[4400] = [1.0, np.nan, 1.0]
    ok = np.all(np.isfinite(flat), axis=-1)
    key, white, lbar = jgt_reference(flat[ok].astype(np.float64))
    op = Reinhard2002().measure(rgb)
    np.testing.assert_allclose(float(op.key), key, rtol=5e-3)  # the histogram's bound
    np.testing.assert_allclose(float(op.L_white), white, rtol=1e-5)
    np.testing.assert_allclose(float(op.log_average), lbar, rtol=1e-5)
    out = np.asarray(jax.jit(Reinhard2002())(rgb)).reshape(-1, 3)
    assert np.isnan(out[~ok]).all() and np.isfinite(out[ok]).all()
    # the mapping (luminance recomputed from RGB in its loop): the paper's curve in NumPy
    Lw = flat[ok].astype(np.float64) @ W
    Ls = float(op.key) / float(op.log_average) * Lw
    Ld = Ls * (1 + Ls / float(op.L_white) ** 2) / (1 + Ls)
    ratio = np.where(Lw > 0, Ld / np.where(Lw > 0, Lw, 1.0), 0.0)
    np.testing.assert_allclose(out[ok], flat[ok] * ratio[:, None], rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("k", [1.0, 2.0**-12])
def test_white_point_guard_branch(x64, k):
    # narrow range: Eq. 5's white would be below the log-average -> 1.5 * max (scaled), at
    # any exposure k (hdritools' image-unit comparison picks Eq. 5 at k = 2^-12)
    rgb = k * np.linspace(1.0, 3.0, 60).reshape(6, 10, 1) * np.ones(3)
    key, white, lbar = jgt_reference(rgb)
    op = Reinhard2002(percentile_method="exact").measure(rgb)
    np.testing.assert_allclose(float(op.L_white), white, rtol=RTOL64)
    np.testing.assert_allclose(white, 1.5 * 3.0 * k * key / lbar, rtol=RTOL64)


def test_global_curve_is_the_papers(x64):
    rgb = natural(dtype=np.float64)
    a, Lw, lbar = 0.3, 2.5, 0.9
    out = np.asarray(hdrjax.tonemap(rgb, "reinhard2002", key=a, L_white=Lw, log_average=lbar))
    L_w = rgb @ W
    L = a * L_w / lbar
    L_d = L * (1 + L / Lw**2) / (1 + L)
    np.testing.assert_allclose(out, rgb * (L_d / L_w)[..., None], rtol=RTOL64)


def test_seed_003_white_is_the_largest_luminance(x64):
    """Seed 003: key 0.18, L_white = the largest scaled luminance -> the brightest pixel
    maps to exactly 1 and everything else below."""
    rgb = natural(dtype=np.float64)
    L = rgb @ W
    lbar = np.exp(np.mean(np.log(1e-6 + L)))
    white = 0.18 * L.max() / lbar
    out = np.asarray(hdrjax.tonemap(rgb, "reinhard2002", key=0.18, L_white=white))
    Ld = out @ W
    np.testing.assert_allclose(Ld.max(), 1.0, rtol=RTOL64)
    assert np.unravel_index(Ld.argmax(), Ld.shape) == np.unravel_index(L.argmax(), L.shape)


@settings(deadline=None, max_examples=25)
@given(
    st.lists(st.floats(1e-6, 1e6), min_size=2, max_size=40),
    st.floats(0.05, 1.0),
    st.floats(0.5, 1e4),
)
def test_global_curve_is_monotone(values, key, white):
    L = np.sort(np.asarray(values))
    rgb = np.repeat(L[None, :, None], 3, axis=2).astype(np.float32)
    out = np.asarray(hdrjax.tonemap(rgb, "reinhard2002", key=key, L_white=white, log_average=1.0))[
        0, :, 0
    ]
    assert np.all(np.diff(out) >= -1e-7 * np.abs(out[1:]))


def local_reference(rgb, key, lbar, phi=8.0, eps=0.05):
    """scipy reference of the dodging-and-burning operator with the same normalised,
    zero-padded convolution (formulas.md §1.2, reference-code scale selection)."""
    L_w = rgb @ W
    Ls = key / lbar * L_w
    ss = scales(1.0, 43.0, 8)
    V1 = []
    ones = np.ones_like(Ls)
    for s in ss:
        r = max(1, int(np.ceil(4 * ALPHA1 * s)))
        x = np.arange(-r, r + 1)
        from scipy.special import erf

        c = 1 / (ALPHA1 * s)
        k = erf(c * (x + 0.5)) - erf(c * (x - 0.5))
        k2 = np.outer(k, k) / 4
        num = ndi.convolve(Ls, k2, mode="constant")
        den = ndi.convolve(ones, k2, mode="constant")
        V1.append(num / den)
    V1 = np.stack(V1)
    m = np.full(Ls.shape, len(ss) - 1)
    for i in reversed(range(len(ss) - 1)):
        act = (V1[i] - V1[i + 1]) / (2**phi * key / ss[i] ** 2 + V1[i])
        m = np.where(np.abs(act) > eps, i, m)
    V1m = np.take_along_axis(V1, m[None], 0)[0]
    L_d = Ls / (1 + V1m)
    return rgb * (L_d / L_w)[..., None]


def test_local_operator_matches_scipy_reference(x64):
    rgb = natural((24, 30), seed=3, dtype=np.float64)
    out = np.asarray(hdrjax.tonemap(rgb, "reinhard2002_local", key=0.18, log_average=0.5))
    ref = local_reference(rgb, 0.18, 0.5)
    np.testing.assert_allclose(out, ref, rtol=1e-6, atol=1e-9)


def test_local_operator_isolates_nan_pixels():
    rgb = natural((24, 30), seed=4)
    bad = rgb.copy()
    bad[10, 10] = np.nan
    op = Reinhard2002Local(key=0.18, log_average=0.5)
    out = np.asarray(op(bad))
    assert np.all(np.isnan(out[10, 10]))
    assert np.all(np.isfinite(np.delete(out.reshape(-1, 3), 10 * 30 + 10, axis=0)))
    # far from the bad pixel (beyond the largest kernel) nothing changes
    far = np.asarray(op(rgb))
    assert np.isfinite(out).sum() == out.size - 3
    np.testing.assert_allclose(out[0, 0], far[0, 0], rtol=0.05)


def test_auto_switches_on_eleven_zones():
    narrow = np.ones((16, 16, 3), np.float32)  # 2 zones: global
    narrow[0, 0] *= 4.0
    wide = natural((16, 16), seed=6)
    wide[0, 0] = 1e-5
    wide[1, 1] = 1e4  # > 11 zones: local
    auto = Reinhard2002Auto()
    for img, local in ((narrow, False), (wide, True)):
        assert bool(auto.measure(jnp.asarray(img)).local > 0.5) is local
        want = (Reinhard2002Local() if local else Reinhard2002())(img)
        np.testing.assert_allclose(np.asarray(auto(img)), np.asarray(want), rtol=RTOL32)


def test_eager_calls_compile_once(caplog):
    """``op(x)`` and ``op.measure(x)`` outside jit run one cached compiled function: a second
    call on another image of the same shape compiles nothing (an eager ``lax.cond`` would
    recompile both branches every call, ~1.5 s each)."""
    import logging

    op = hdrjax.make_operator("reinhard2002")
    rng = np.random.default_rng(3)
    x1, x2 = (jnp.asarray(rng.random((6, 7, 3)), jnp.float32) for _ in range(2))
    np.testing.assert_allclose(op(x1), hdrjax.tonemap(x1, "reinhard2002"), rtol=1e-6)
    op.measure(x1)
    with caplog.at_level(logging.WARNING, logger="jax"), jax.log_compiles():
        y2 = op(x2)
        m2 = op.measure(x2)
    compiled = [r.getMessage() for r in caplog.records if "Compiling" in r.getMessage()]
    assert compiled == []
    np.testing.assert_allclose(y2, hdrjax.tonemap(x2, "reinhard2002"), rtol=1e-6)
    assert float(m2.key) == float(op.measure(x2).key)


def test_image_gradients_finite_beside_a_bad_pixel():
    """Issue 16.1: one NaN or ±Inf value in a real crop (rooitou_park_1k.hdr, shipped in
    data/) left the default (histogram) path's gradient NaN at every pixel: the statistics
    pass, run on the assumption that the image is finite, produced a NaN log sum whose
    derivative (times the zero cotangent of the branch not taken) reached every pixel.

    Reference: the finite pixels alone, as one row (the statistics are order-free and the
    operator global), give the same gradient at each of them."""
    x = np.asarray(hdrjax.io.read(DATA / "rooitou_park_1k.hdr").rgb())[100:116, 200:224]
    frames = np.stack([x] * 3)
    for k, bad in enumerate([np.nan, np.inf, -np.inf]):
        frames[k, 3, 4, 1] = bad
    fin = np.all(np.isfinite(frames[0]), axis=-1)

    def nansum(v):
        return jnp.nansum(hdrjax.tonemap(v, "reinhard2002"))

    def masked(v):
        out = hdrjax.tonemap(v, "reinhard2002")
        return jnp.sum(jnp.where(jnp.isfinite(out), out, 0.0))

    ref = np.asarray(jax.jit(jax.grad(nansum))(jnp.asarray(x[fin][None])))[0]
    for loss in (nansum, masked):
        g = np.asarray(jax.jit(jax.vmap(jax.grad(loss)))(jnp.asarray(frames)))
        for k in range(3):
            assert np.all(np.isfinite(g[k][fin])), f"{loss.__name__}/{k}"
            np.testing.assert_allclose(g[k][fin], ref, rtol=RTOL32, atol=1e-6)
