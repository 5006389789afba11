"""ward1994 and ferwerda1996 against HDR Toolbox (banterle/HDR_Toolbox under GNU Octave, the
fixtures of fixtures/hdrtoolbox/make_fixtures.py), and every formula of the three operators
(tumblin_rushmeier1993 included, which HDR Toolbox does not have: its ``TumblinTMO`` is the
1999 revision, hdrjax's ``tumblin1999``) against float64 NumPy transcriptions of the papers.

Parity criterion with HDR Toolbox, per image: both outputs clipped to [0, 1] and sRGB
encoded, the 99th percentile of the absolute difference is at most 0.01. The fixture
inputs are in cd/m² (the scales are in make_fixtures.py); HDR Toolbox's outputs are
display-linear, clamped to [0, 1] (no gamma).
"""

from pathlib import Path

import colour
import numpy as np
import pytest

import hdrjax

from ..conftest import RTOL32, RTOL64

FIXTURES = Path(__file__).parent / "fixtures" / "hdrtoolbox" / "hdrtoolbox.npz"
PARITY = 0.01
"""99th percentile of |difference| after clipping to [0, 1] and sRGB encoding, per image."""
SAME_FUNCTION = 1e-5
"""Largest difference of the clipped linear outputs where hdrjax computes HDR Toolbox's
function (measured: 7.2e-7, float32 against the Toolbox's float64)."""
WEIGHTS = np.array(hdrjax.REC709_WEIGHTS)
LAMBERT = 1e4 / np.pi  # cd/m² per lambert


@pytest.fixture(scope="module")
def toolbox():
    with np.load(FIXTURES) as d:
        return {k: d[k] for k in d.files}


def _srgb(x):
    """IEC 61966-2-1 encoding of linear values clipped to [0, 1] (NumPy, float64)."""
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def _parity(out, ref):
    """Per image, the 99th percentile of |sRGB(out) − sRGB(ref)| (the criterion)."""
    diff = np.abs(_srgb(out) - _srgb(ref)).reshape(len(out), -1)
    return np.percentile(diff, 99, axis=1)


def _compare(name, out, ref, same_function=True):
    p99 = _parity(out, ref)
    assert np.all(p99 <= PARITY), f"{name}: p99 {p99}"
    # the comparison covers a real range of outputs (not dark images only)
    assert np.all(np.ptp(_srgb(ref).reshape(len(ref), -1), axis=1) > 0.25), name
    if same_function:
        np.testing.assert_allclose(np.clip(out, 0, 1), ref, rtol=0, atol=SAME_FUNCTION)
    return p99


def test_ward1994_matches_hdrtoolbox(toolbox):
    """HDR Toolbox's ``WardGlobalTMO`` with its defaults (L_dmax = 100 cd/m², L_wa the
    log-mean with 1e-6 inside the logarithm): the same function."""
    op = hdrjax.make_operator("ward1994")
    _compare("ward1994", np.asarray(op(toolbox["input"])), toolbox["ward"])


def test_ferwerda1996_hdrtoolbox_compat_matches_hdrtoolbox(toolbox):
    """``compat="hdrtoolbox"`` is HDR Toolbox's ``FerwerdaTMO`` with its defaults (rods'
    term from the photopic luminance, tinted (1.05, 0.97, 1.27); L_wa half the maximum)."""
    op = hdrjax.make_operator("ferwerda1996", compat="hdrtoolbox")
    _compare("ferwerda1996/hdrtoolbox", np.asarray(op(toolbox["input"])), toolbox["ferwerda"])


def test_ferwerda1996_departs_from_hdrtoolbox_through_the_rods_only(toolbox):
    """The paper's form (scotopic luminance, achromatic rods' term) is HDR Toolbox's where
    the rods are saturated (k = 0: rooitou_park, daylight) and differs where they see
    (the mesopic and scotopic scenes), by more than the parity criterion in MtTamNorth
    (k = 0.8) and CandleGlass (a candle at night)."""
    out = np.asarray(hdrjax.make_operator("ferwerda1996")(toolbox["input"]))
    names = list(toolbox["names"])
    day = names.index("rooitou_park_1k")
    _compare("ferwerda1996/paper", out[day : day + 1], toolbox["ferwerda"][day : day + 1])
    p99 = _parity(out, toolbox["ferwerda"])
    assert p99[names.index("MtTamNorth")] > PARITY
    assert p99[names.index("CandleGlass")] > PARITY


# ----------------------------------------------------------------- paper transcriptions


def _tvi(L, flat, knee, lo, hi, a, b, p, c):
    """A Ferwerda et al. 1996 threshold curve: ``10^t(log10 L)``, t piecewise (paper)."""
    x = np.log10(L)
    mid = (a * np.clip(x, lo, hi) + b) ** p - c  # (clipped: a negative base is NaN)
    t = np.where(x <= lo, flat, np.where(x >= hi, x - knee, mid))
    return 10.0**t


def t_p(L):
    return _tvi(L, -0.72, 1.255, -2.6, 1.9, 0.249, 0.65, 2.7, 0.72)


def t_s(L):
    return _tvi(L, -2.86, 0.395, -3.94, -1.44, 0.405, 1.6, 2.18, 2.86)


def _scotopic(rgb):
    """Ward Larson et al. 1997's scotopic luminance of linear Rec.709 RGB (cd/m²)."""
    xy = np.array([0.64, 0.33, 0.30, 0.60, 0.15, 0.06]).reshape(3, 2)
    M = colour.normalised_primary_matrix(xy, np.array([0.3127, 0.329]))
    M[1] = WEIGHTS  # hdrjax's luminance is the standard's rounded weights
    X, Y, Z = np.moveaxis(rgb @ M.T, -1, 0)
    V = Y * (1.33 * (1 + (Y + Z) / np.where(X > 0, X, 1.0)) - 1.68)
    return np.where(X > 0, np.maximum(V, 0.0), 0.0)


def ferwerda_reference(rgb, L_wa, L_dmax=100.0):
    """The paper's Ferwerda et al. 1996 operator, k of Walraven & Valeton (float64)."""
    L_da = L_dmax / 2
    k = max((100.0 - L_wa / 4) / (100.0 + L_wa), 0.0)
    m_p, m_s = t_p(L_da) / t_p(L_wa), t_s(L_da) / t_s(L_wa)
    return (m_p * rgb + k * m_s * _scotopic(rgb)[..., None]) / L_dmax


def ward_reference(rgb, L_wa, L_dmax=100.0):
    """Ward 1994 (float64): ``m L / L_dmax``."""
    m = ((1.219 + (L_dmax / 2) ** 0.4) / (1.219 + L_wa**0.4)) ** 2.5
    return rgb * m / L_dmax


def stevens(L):
    """Stevens' (α, β) at L in cd/m² (Tumblin & Rushmeier 1993: L in lamberts)."""
    x = np.log10(L / LAMBERT)
    return 0.4 * x + 2.92, -0.4 * x**2 - 2.584 * x + 2.0208


def log_average(rgb, delta):
    return np.exp(np.mean(np.log(rgb @ WEIGHTS + delta)))


def tumblin_rushmeier_reference(rgb, L_wa, L_dmax=100.0, C_max=100.0):
    """Tumblin & Rushmeier 1993 (float64), all luminances in lamberts."""
    L = rgb @ WEIGHTS
    a_w, b_w = stevens(L_wa)
    a_d, b_d = stevens(L_dmax / np.sqrt(C_max))
    L_d = (L / LAMBERT) ** (a_w / a_d) * 10 ** ((b_w - b_d) / a_d)
    n = np.maximum(L_d / (L_dmax / LAMBERT) - 1 / C_max, 0.0)
    return rgb * (n / L)[..., None]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_ward1994_and_ferwerda1996_follow_the_papers(toolbox, dtype, request):
    """Both operators equal the NumPy transcriptions on the four scenes (daylight to a
    candle at night: every branch of the rod curve but the flat one), with the
    adaptation luminance HDR Toolbox measured: Ward's log-mean (1e-6 inside the
    logarithm), Ferwerda's half maximum."""
    if dtype == np.float64:
        request.getfixturevalue("x64")
    rtol, atol = (RTOL32, 1e-7) if dtype == np.float32 else (RTOL64, 1e-13)
    x = toolbox["input"].astype(dtype)
    rgb = x.astype(np.float64)
    for name, reference, key in (
        ("ward1994", ward_reference, "ward_L_wa"),
        ("ferwerda1996", ferwerda_reference, "ferwerda_L_wa"),
    ):
        out = np.asarray(hdrjax.make_operator(name)(x))  # L_wa measured
        assert out.dtype == dtype
        ref = np.stack([reference(img, L_wa) for img, L_wa in zip(rgb, toolbox[key], strict=True)])
        np.testing.assert_allclose(out, ref, rtol=rtol, atol=atol, err_msg=name)


def test_rod_curve_is_the_papers_not_luminancehdrs():
    """The rods' middle branch is ``(0.405 x + 1.6)^2.18``; LuminanceHDR's port swaps the
    power's arguments (``2.18^(0.405 x + 1.6)``), which is 2.6 times larger at x = -2."""
    from hdrjax.operators._ferwerda1996 import ferwerda1996_factors

    L_wa, L_dmax = 0.01, 100.0  # x = -2, the rods' and the cones' middle branches
    cones, rods = (float(f) for f in ferwerda1996_factors(L_wa, L_dmax))
    k = (100.0 - L_wa / 4) / (100.0 + L_wa)
    np.testing.assert_allclose(cones, t_p(50.0) / t_p(L_wa) / L_dmax, rtol=RTOL32)
    np.testing.assert_allclose(rods, k * t_s(50.0) / t_s(L_wa) / L_dmax, rtol=RTOL32)
    swapped = 10.0 ** (2.18 ** (0.405 * -2 + 1.6) - 2.86)
    assert abs(float(t_s(L_wa)) / swapped - 1) > 0.5


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_tumblin_rushmeier1993_follows_the_paper(toolbox, dtype, request):
    """The 1993 equations in lamberts, L_wa measured (the log-average with 2.3e-5 inside
    the logarithm, as tumblin1999's), on the three scenes whose adaptation lies in
    Stevens' range (α > 0). The display's minimum 1/C_max is subtracted from
    ``L_d / L_dmax``, so the tolerance of a pixel is relative to ``n + 1/C_max``."""
    if dtype == np.float64:
        request.getfixturevalue("x64")
    rtol = RTOL32 if dtype == np.float32 else RTOL64
    names = list(toolbox["names"])
    keep = [names.index(n) for n in ("rooitou_park_1k", "venice_sunset_1k", "MtTamNorth")]
    x = toolbox["input"][keep].astype(dtype)
    out = np.asarray(hdrjax.make_operator("tumblin_rushmeier1993")(x))
    assert out.dtype == dtype
    rgb = x.astype(np.float64)
    for img, got in zip(rgb, out, strict=True):
        L_wa = log_average(img, 2.3e-5)
        assert stevens(L_wa)[0] > 0
        ref = tumblin_rushmeier_reference(img, L_wa)
        offset = img / (img @ WEIGHTS)[..., None] / 100.0  # 1/C_max in each channel
        np.testing.assert_array_less(np.abs(got - ref), rtol * (np.abs(ref) + offset))
        assert np.ptp(np.clip(ref, 0, 1)) > 0.5  # a real range of display values


def test_tumblin_rushmeier1993_holds_alpha_where_stevens_law_inverts(toolbox):
    """CandleGlass at night adapts below 1.6e-4 cd/m², where the paper's α is negative
    and its curve decreasing (shown on a display of contrast 10⁴, whose small offset
    leaves its dark end above black); hdrjax holds α at 1e-3: a positive exponent, a non-decreasing
    curve (so flat and dim here that it is black)."""
    from hdrjax.operators._tumblin_rushmeier1993 import tumblin_rushmeier1993_terms

    img = toolbox["input"][list(toolbox["names"]).index("CandleGlass")]
    L_wa = log_average(img.astype(np.float64), 2.3e-5)
    assert stevens(L_wa)[0] < 0
    grey = np.repeat(np.logspace(-6, 2, 50)[None, :, None], 3, axis=2)
    paper = tumblin_rushmeier_reference(grey, L_wa, C_max=1e4)[0, :, 1]
    assert np.all(np.diff(paper) <= 0) and paper[0] > paper[-1]  # darkest pixels brightest
    exponent, _ = tumblin_rushmeier1993_terms(np.float32(L_wa), np.float32(100), np.float32(1e4))
    assert float(exponent) > 0
    out = hdrjax.tonemap(grey.astype(np.float32), "tumblin_rushmeier1993", L_wa=L_wa, C_max=1e4)
    assert np.all(np.diff(np.asarray(out)[0, :, 1]) >= 0)
