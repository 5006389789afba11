"""Perceptual fit targets (TMQI, Naturalness, PUSSIM): values, composition, gradients
against float64 central finite differences, and fits that maximise TMQI.

References are independent of the code under test: the metric values come from
:mod:`hdrjax.metrics` called on the encoded (or displayed) rendition written out here, the
derivatives from central differences in float64, and the optimum of a fit from a grid scan
with :func:`hdrjax.study.sweep` (whose values are checked against the metric itself).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
import hdrjax.fit as hf
import hdrjax.metrics as hm
import hdrjax.targets as ht
from hdrjax import study

from ..conftest import DATA, RTOL32, RTOL64, enable_x64

START = 0.85
"""drago2003's default bias: the fit's starting value."""
GRID = np.linspace(0.5, 1.0, 26)
"""A grid of bias values, step 0.02."""
STEP = float(GRID[1] - GRID[0])
FD_RTOL = 1e-5
"""float64 central differences (h = 1e-6 · p) against autodiff."""
PU_PEAK, PU_BLACK = 100.0, 0.1
"""PUSSIM's default display (cd/m²)."""


@pytest.fixture(scope="module")
def venice():
    """data/venice_sunset_1k.hdr (1024 × 512, float32): the fit works on 64 × 32."""
    return jnp.asarray(np.asarray(hdrjax.io.read(DATA / "venice_sunset_1k.hdr").rgb(), np.float32))


@pytest.fixture(scope="module")
def small():
    """The Venice image box-filtered to 32 × 16 (float64 NumPy), for value and FD tests."""
    rgb = np.asarray(hdrjax.io.read(DATA / "venice_sunset_1k.hdr").rgb(), np.float64)
    return rgb.reshape(16, 32, 32, 32, 3).mean(axis=(1, 3))


def _display(hdr, bias=0.8):
    return hdrjax.tonemap(jnp.asarray(hdr), "drago2003", bias=bias)


def _srgb(x):
    """IEC 61966-2-1 encoding of [0, 1]-clipped values, in NumPy float64."""
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


# ----------------------------------------------------------------------------- values


def test_tmqi_target_is_the_metric_of_the_srgb_rendition(small, x64):
    d = np.asarray(_display(small))
    want = hm.tmqi(small, _srgb(d))
    t = ht.TMQI(weight=2.0)
    got = t.statistics(jnp.asarray(d), source=jnp.asarray(small))
    np.testing.assert_allclose(got, [want.q, want.s, want.n], rtol=RTOL64)
    np.testing.assert_allclose(
        t.residuals_for(jnp.asarray(d), small), [2 * (1 - want.q)], rtol=1e-9
    )
    # gamma: x^(1/γ) instead of sRGB
    g = ht.TMQI(gamma=2.2).statistics(jnp.asarray(d), source=jnp.asarray(small))
    np.testing.assert_allclose(g[0], hm.tmqi(small, np.clip(d, 0, 1) ** (1 / 2.2)).q, rtol=RTOL64)
    assert not np.isclose(g[0], got[0], rtol=1e-6)
    with pytest.raises(ValueError, match="^source: TMQI needs"):
        t.residuals(jnp.asarray(d))


def test_naturalness_is_tmqis_naturalness(small, x64):
    d = np.asarray(_display(small, 0.7))
    t = ht.Naturalness(weight=0.5)
    np.testing.assert_allclose(
        t.statistics(jnp.asarray(d)), [hm.tmqi(small, _srgb(d)).n], rtol=RTOL64
    )
    np.testing.assert_allclose(
        t.residuals(jnp.asarray(d)), [0.5 * (1 - hm.tmqi(small, _srgb(d)).n)], rtol=1e-9
    )
    assert not ht.Naturalness.takes_source and ht.Naturalness.maximises


def test_pussim_shows_the_rendition_on_the_display(small, x64):
    d = np.asarray(_display(small, 0.8))
    ref = PU_BLACK + (PU_PEAK - PU_BLACK) * np.clip(np.asarray(_display(small, 0.7)), 0, 1)
    t = ht.PUSSIM(ref, weight=3.0)
    shown = PU_BLACK + (PU_PEAK - PU_BLACK) * np.clip(d, 0.0, 1.0)
    want = hm.pu_ssim(shown, ref)
    np.testing.assert_allclose(t.statistics(jnp.asarray(d)), [want], rtol=RTOL64)
    np.testing.assert_allclose(t.residuals(jnp.asarray(d)), [3 * (1 - want)], rtol=1e-9)
    # the reference rendition itself: SSIM 1, residual 0
    same = ht.PUSSIM(ref).residuals(jnp.asarray(np.asarray(_display(small, 0.7))))
    np.testing.assert_allclose(same, [0.0], atol=1e-12)
    # a brighter display: the same rendition is other light, and another score
    bright = ht.PUSSIM(ref * 10, peak=1000.0, black=1.0).statistics(jnp.asarray(d))
    want = hm.pu_ssim(1.0 + 999.0 * np.clip(d, 0, 1), ref * 10)
    np.testing.assert_allclose(bright, [want], rtol=RTOL64)
    with pytest.raises(ValueError, match="^display: expected the shape"):
        t.residuals(jnp.asarray(d[:-1]))
    with pytest.raises(ValueError, match="^black"):
        ht.PUSSIM(ref, peak=50.0, black=50.0)


def test_combines_with_the_statistic_targets(small):
    d, src = _display(small), jnp.asarray(small, jnp.float32)
    tm, mean, hist = ht.TMQI(), ht.MeanLuminance(0.3), ht.Histogram(np.ones(4))
    c = tm + 2.0 * mean + 0.5 * ht.Naturalness() + hist
    assert c.takes_source and len(c.targets) == 4
    r = c.residuals_for(d, src)
    want = np.concatenate(
        [
            tm.residuals(d, source=src),
            2.0 * mean.residuals(d),
            0.5 * ht.Naturalness().residuals(d),
            hist.residuals(d),
        ]
    )
    np.testing.assert_allclose(r, want, rtol=RTOL32)
    s = c.statistics_for(d, src)
    np.testing.assert_allclose(s[:3], tm.statistics(d, source=src), rtol=RTOL32)
    assert s.shape == (3 + 1 + 1 + 4,)
    # a weighted TMQI alone: the source goes through Scaled
    np.testing.assert_allclose(
        (3.0 * tm).residuals_for(d, src), 3.0 * tm.residuals(d, source=src), rtol=RTOL32
    )
    # display-only targets ignore the source; a combination without the source refuses
    np.testing.assert_allclose(mean.residuals_for(d, src), mean.residuals(d), rtol=0)
    np.testing.assert_allclose((mean + hist).residuals_for(d, None), (mean + hist).residuals(d))
    with pytest.raises(ValueError, match="^source"):
        c.residuals(d)


# ----------------------------------------------------------------------------- gradients


def _loss_of_bias(target, hdr):
    op = hdrjax.make_operator("drago2003").measure(hdr)

    def f(bias):
        o = hdrjax.make_operator("drago2003", bias=bias, log_average=op.log_average, L_max=op.L_max)
        return target.residuals_for(o(hdr), hdr)[0]

    return f


@pytest.mark.parametrize("name", ["TMQI", "Naturalness", "PUSSIM"])
def test_gradient_with_respect_to_the_bias_matches_central_differences(small, name):
    with enable_x64():
        hdr = jnp.asarray(small)
        ref = PU_BLACK + (PU_PEAK - PU_BLACK) * np.clip(np.asarray(_display(small, 0.65)), 0, 1)
        target = {"TMQI": ht.TMQI(), "Naturalness": ht.Naturalness(), "PUSSIM": ht.PUSSIM(ref)}
        f = _loss_of_bias(target[name], hdr)
        b = 0.8
        # forward mode (the fit's Jacobian) and reverse mode, in one compiled call
        fwd, rev = jax.jit(lambda b: (jax.jvp(f, (b,), (1.0,))[1], jax.grad(f)(b)))(b)
        h = 1e-6 * b
        fd = (f(b + h) - f(b - h)) / (2 * h)
        assert abs(float(fd)) > 1e-3, "a flat point checks nothing"
        np.testing.assert_allclose(fwd, fd, rtol=FD_RTOL)
        np.testing.assert_allclose(rev, fd, rtol=FD_RTOL)


# ----------------------------------------------------------------------------- fits


@pytest.fixture(scope="module")
def tmqi_fit(venice):
    return hdrjax.fit("drago2003", venice, ht.TMQI(), params="bias")


@pytest.fixture(scope="module")
def tmqi_sweep(venice, tmqi_fit):
    """TMQI over GRID, the start and the fitted bias ± 0.005 (study.sweep: Q = 1 − √loss)."""
    b = float(tmqi_fit.params["bias"])
    values = np.concatenate([GRID, [START, b, b - 0.005, b + 0.005]])
    res = study.sweep("drago2003", venice, {"bias": values}, ht.TMQI())
    return values, 1.0 - np.sqrt(np.asarray(res.loss, np.float64))


def test_fit_maximises_tmqi(tmqi_fit, tmqi_sweep):
    values, q = tmqi_sweep
    assert bool(tmqi_fit.success)
    b = float(tmqi_fit.params["bias"])
    q_fit = q[len(GRID) + 1]
    # the sweep's loss is the fit's: the same Q at the fitted bias
    np.testing.assert_allclose(q_fit, tmqi_fit.statistics[0], rtol=RTOL32)
    np.testing.assert_allclose(tmqi_fit.loss, (1 - tmqi_fit.statistics[0]) ** 2, rtol=RTOL32)
    # better than the start, and than its neighbours and every point of the grid
    assert q_fit > q[len(GRID)] + 1e-4
    assert q_fit >= q[len(GRID) + 2 :].max() - 1e-6
    assert q_fit >= q[: len(GRID)].max() - 1e-6
    # the grid's optimum agrees with the fit within the grid step
    best = GRID[int(np.argmax(q[: len(GRID)]))]
    assert abs(best - b) <= STEP, (best, b)
    assert 0.55 < b < 0.95  # an interior optimum (the grid scan is a real check)


def test_sweep_maps_the_metric(venice, tmqi_sweep):
    """The sweep's Q at a grid point is hdrjax.metrics.tmqi of that rendition of the
    box-filtered image (the source the target sees)."""
    values, q = tmqi_sweep
    x = hf.downscale(venice, 64)
    op = hdrjax.make_operator("drago2003", bias=float(values[5])).measure(venice)
    want = hm.tmqi(x, hdrjax.display.srgb_encode(op(x))).q
    np.testing.assert_allclose(q[5], want, rtol=1e-5)


def test_fit_batch_maximises_tmqi_per_frame(venice, tmqi_fit):
    """Each frame's fit equals the single fit of that frame (its own source image)."""
    park = np.asarray(hdrjax.io.read(DATA / "rooitou_park_1k.hdr").rgb(), np.float32)
    frames = jnp.stack([venice, venice[:, ::-1] * 8.0, jnp.asarray(park)])
    res = hf.fit_batch("drago2003", frames, ht.TMQI(), params="bias")
    assert bool(jnp.all(res.success))
    np.testing.assert_allclose(res.params["bias"][0], tmqi_fit.params["bias"], rtol=1e-3)
    for i in (1, 2):
        one = hdrjax.fit("drago2003", frames[i], ht.TMQI(), params="bias")
        assert bool(one.success)
        np.testing.assert_allclose(res.params["bias"][i], one.params["bias"], rtol=1e-3)
        np.testing.assert_allclose(res.statistics[i], one.statistics, rtol=RTOL32)
    # the park is another scene: its own source, its own optimum (0.74 against 0.79)
    assert abs(float(res.params["bias"][2] - res.params["bias"][0])) > 0.02
