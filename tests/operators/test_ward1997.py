"""ward1997 (Ward Larson, Rushmeier, Piatko 1997 histogram adjustment): against HDR Toolbox's
``WardHistAdjTMO`` under GNU Octave (fixtures/hdrtoolbox/make_ward1997.py), against a
float64 NumPy transcription of the paper's histogram, ceiling and tone curve, and its
gradients through the ceiling loop and the curve's interpolation.

Parity criterion with HDR Toolbox, per image: both outputs clipped to [0, 1] and sRGB
encoded, the 99th percentile of the absolute difference is at most 0.01. The fixture inputs
are in cd/m²; the Toolbox's outputs are display-linear, not clamped.
"""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax.operators._ward1997 import TOLERANCE

from .cases import natural

FIXTURES = Path(__file__).parent / "fixtures" / "hdrtoolbox" / "ward1997.npz"
PARITY = 0.01
"""99th percentile of |difference| after clipping to [0, 1] and sRGB encoding, per image."""
MEASURED = 3e-3
"""What hdrjax reaches (largest p99 over the eight comparisons: 1.9e-3, studio_small_03;
the fixed-grid histogram moves a pixel by at most half a fine bin, and HDR Toolbox adds
10⁻⁶ cd/m² to the luminance before its logarithm)."""
WEIGHTS = np.array(hdrjax.REC709_WEIGHTS)


@pytest.fixture(scope="module")
def toolbox():
    with np.load(FIXTURES) as d:
        return {k: d[k] for k in d.files}


def _srgb(x):
    """IEC 61966-2-1 encoding of linear values clipped to [0, 1] (NumPy, float64)."""
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


@pytest.mark.parametrize(
    "key, kw",
    [("default", {}), ("custom", dict(n_bins=50, L_dmin=5.0, L_dmax=300.0))],
)
def test_matches_hdrtoolbox(toolbox, key, kw):
    """``compat="hdrtoolbox"`` against ``WardHistAdjTMO(img)`` and
    ``WardHistAdjTMO(img, 50, 5, 300)`` on four real images (one batch each)."""
    op = hdrjax.make_operator("ward1997", compat="hdrtoolbox", **kw)
    out = np.asarray(op(toolbox["input"]))
    ref = toolbox[key]
    diff = np.abs(_srgb(out) - _srgb(ref)).reshape(len(ref), -1)
    p99 = np.percentile(diff, 99, axis=1)
    assert np.all(p99 <= PARITY), f"{key}: p99 {p99}"
    assert np.all(p99 <= MEASURED), f"{key}: p99 {p99}"
    # the comparison covers a real range of outputs (not dark images only)
    assert np.all(np.ptp(_srgb(ref).reshape(len(ref), -1), axis=1) > 0.5)


def _tvi(L_a):
    """Ferwerda et al. 1996's combined threshold as Radiance's pcond writes it (float64)."""
    x = np.log10(np.maximum(L_a, 1.148e-4))
    y = np.where(
        x < -1.44,
        (0.405 * np.maximum(x, -3.94) + 1.6) ** 2.18 - 2.86,
        np.where(x < -0.0184, x - 0.395, (0.249 * np.clip(x, -0.0184, 1.9) + 0.65) ** 2.7 - 0.72),
    )
    y = np.where(x < 1.9, y, x - 1.255)
    return np.where(L_a < 1.148e-4, 1.38e-3, 10.0**y)


def _paper_cdf(L, n_bins, L_dmin, L_dmax, human=False):
    """The paper's histogram, ceiling (linear or human-contrast) and cumulative
    distribution in float64 NumPy, from the pixels (bins of ``ln L`` over
    ``[ln min, ln max]``)."""
    b = np.log(L[L > 0])
    lo, hi = b.min(), b.max()
    hist = np.histogram(b, bins=n_bins, range=(lo, hi))[0].astype(np.float64)
    db = (hi - lo) / n_bins
    B_d = np.log(L_dmax / L_dmin)
    L_w = np.exp(lo + (np.arange(n_bins) + 0.5) * db)
    tol = TOLERANCE * hist.sum()
    while True:
        total = hist.sum()
        if total < tol:
            break
        if human:
            L_d = L_dmin * np.exp(B_d * (np.cumsum(hist) - 0.5 * hist) / total)
            ceiling = total * db * _tvi(L_d) / _tvi(L_w) * L_w / (L_d * B_d)
        else:
            ceiling = total * db / B_d
        trimmed = np.maximum(hist - ceiling, 0.0).sum()
        hist = np.minimum(hist, ceiling)
        if trimmed <= tol:
            break
    cum = np.concatenate([[0.0], np.cumsum(hist)])
    return cum / cum[-1], lo, hi, hist.sum() / (len(b) * TOLERANCE)


@pytest.mark.parametrize("kw", [{}, dict(n_bins=40, L_dmin=0.5, L_dmax=400.0)])
def test_curve_is_the_papers(x64, kw):
    """The measured table and the mapped luminance against the NumPy transcription: the
    table within a few pixels (the fixed grid's bins move a pixel by at most half a fine bin
    across a bin edge; after truncation one pixel weighs more than 1 / N), the display luminance
    ``(L_dmin^(1 − P) L_dmax^P − L_dmin) / (L_dmax − L_dmin)`` accordingly."""
    img = natural((48, 64), seed=3, dtype=np.float64) * 50.0
    L = img @ WEIGHTS
    op = hdrjax.make_operator("ward1997", **kw)
    m = op.measure(img)
    cdf, lo, hi, _ = _paper_cdf(L, m.n_bins, float(m.L_dmin), float(m.L_dmax))
    assert m.cdf.shape == (m.n_bins + 1,)
    np.testing.assert_allclose(np.log(float(m.L_min)), lo, rtol=1e-12)
    np.testing.assert_allclose(np.log(float(m.L_max)), hi, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(m.cdf), cdf, atol=4.0 / L.size)
    # the ceiling bites on this image (17 stops onto a 100:1 display)
    assert np.max(np.diff(cdf)) < np.max(np.histogram(np.log(L), m.n_bins)[0]) / L.size
    P = np.interp(np.log(L), np.linspace(lo, hi, m.n_bins + 1), cdf)
    lo_d, hi_d = float(m.L_dmin), float(m.L_dmax)
    Ld = (lo_d ** (1 - P) * hi_d**P - lo_d) / (hi_d - lo_d)
    out = np.asarray(op(img)) @ WEIGHTS
    np.testing.assert_allclose(out, Ld, rtol=0, atol=0.01)
    np.testing.assert_allclose(out.max(), 1.0, rtol=1e-12)  # L_max → L_dmax
    np.testing.assert_allclose(out.min(), 0.0, atol=1e-12)  # L_min → L_dmin


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_human_ceiling_is_the_papers(x64, scale):
    """``ceiling="human"`` against the NumPy transcription of the human-contrast ceiling at
    three scene levels; in the dark scene (rods, thresholds far above Weber's) it is not the linear
    ceiling (the dark half of the curve is compressed much more)."""
    img = natural((48, 64), seed=4, dtype=np.float64) * scale
    L = img @ WEIGHTS
    m = hdrjax.make_operator("ward1997", ceiling="human").measure(img)
    cdf = _paper_cdf(L, m.n_bins, 1.0, 100.0, human=True)[0]
    np.testing.assert_allclose(np.asarray(m.cdf), cdf, atol=4.0 / L.size)
    if scale < 1:
        linear = _paper_cdf(L, m.n_bins, 1.0, 100.0)[0]
        assert np.max(np.abs(cdf - linear)) > 0.02


def test_ceiling_limits_the_slope():
    """No contrast is exaggerated: the curve's slope ``d ln L_d / d ln L_w`` stays at most
    1 on a scene wider than the display, whose untruncated histogram would be steeper, to
    what the last truncation step may leave: it trims at most 2.5 % of the original total
    ``T_0``, so a bin may exceed the final ceiling by ``0.025 T_0 / T``."""
    rng = np.random.default_rng(1)
    L = np.exp(rng.normal(0.0, 1.0, (64, 64))).astype(np.float32)  # ln range about 7
    img = L[..., None] * np.ones(3, np.float32)
    m = hdrjax.make_operator("ward1997").measure(img)
    span = np.log(float(m.L_max) / float(m.L_min))
    assert span > np.log(100.0)  # the ceiling can be met (a narrower scene empties it)
    slope = np.diff(np.asarray(m.cdf)) * np.log(100.0) / (span / m.n_bins)
    remaining = _paper_cdf(L, m.n_bins, 1.0, 100.0)[3]  # T / (0.025 T_0)
    assert np.max(slope) <= 1.0 + 1.0 / remaining + 1e-3
    hist = np.histogram(np.log(L), m.n_bins)[0] / L.size
    assert np.max(hist) * np.log(100.0) / (span / m.n_bins) > 1.5  # the ceiling was needed


def test_statistics_merge():
    """The histogram comes from mergeable statistics: two halves merged give the whole's."""
    img = natural((24, 32), seed=5)
    op = hdrjax.make_operator("ward1997")
    merged = op.statistics(img[:12]).merge(op.statistics(img[12:]))
    whole = op.measure(img)
    bound = op.bind(merged)
    np.testing.assert_allclose(np.asarray(bound.cdf), np.asarray(whole.cdf), atol=1e-6)
    np.testing.assert_allclose(np.asarray(bound(img)), np.asarray(op(img)), atol=1e-6)


def test_gradients_match_finite_differences(x64):
    """Through the ceiling loop (``L_dmin``, ``L_dmax``) and through each pixel's
    interpolation in the curve (image, table fixed), against central differences."""
    img = jnp.asarray(natural((16, 16), seed=7, dtype=np.float64) * 20.0)

    def f(L_dmin, L_dmax):
        return jnp.sum(hdrjax.operators.Ward1997(L_dmin=L_dmin, L_dmax=L_dmax)(img) ** 2)

    g = jax.grad(f, argnums=(0, 1))(1.0, 100.0)
    for i, (a, h) in enumerate(((1.0, 1e-6), (100.0, 1e-4))):
        args = [1.0, 100.0]
        args[i] = a + h
        up = f(*args)
        args[i] = a - h
        down = f(*args)
        np.testing.assert_allclose(g[i], (up - down) / (2 * h), rtol=1e-5)
    m = hdrjax.make_operator("ward1997").measure(img)
    fixed = m.__class__(**{**m.parameters(), "L_min": m.L_min, "L_max": m.L_max})
    gi = jax.grad(lambda x: jnp.sum(fixed(x)))(img)
    assert np.all(np.isfinite(gi))
    e = np.zeros(img.shape)
    e[5, 6, 1] = 1e-6 * float(img[5, 6, 1])
    fd = (jnp.sum(fixed(img + e)) - jnp.sum(fixed(img - e))) / (2 * e[5, 6, 1])
    np.testing.assert_allclose(gi[5, 6, 1], fd, rtol=1e-5)
    assert abs(float(gi[5, 6, 1])) > 0


def test_bad_settings_are_named():
    with pytest.raises(ValueError, match="^L_dmin: expected less than L_dmax"):
        hdrjax.make_operator("ward1997", L_dmin=200.0)
    with pytest.raises(ValueError, match="^n_bins"):
        hdrjax.make_operator("ward1997", n_bins=1)
    with pytest.raises(ValueError, match="^ceiling"):
        hdrjax.make_operator("ward1997", ceiling="pcond")
    with pytest.raises(ValueError, match="^compat"):
        hdrjax.make_operator("ward1997", compat="pcond")
