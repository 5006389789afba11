"""Vision formulas against float64 NumPy recomputations of the published equations.

Sources (formulas.md §3): Ferwerda et al. 1996 TVI (HDR Toolbox TpFerwerda/TsFerwerda),
Radiance pcond (htcontrs, hacuity fit, scotscan, cielum), Jensen et al. 2001 (knight
tonemap.c), Ward 1994, Spencer et al. 1995.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import hdrjax.vision as hv
from hdrjax._photometry import rgb_to_xyz_matrix

from ..conftest import RTOL32, RTOL64
from ._reference import np_tvi


@np.errstate(invalid="ignore")  # the unused branches of np.where
def np_tp(La):  # Ferwerda 1996 cones
    x = np.log10(La)
    return 10.0 ** np.where(
        x <= -2.6, -0.72, np.where(x >= 1.9, x - 1.255, (0.249 * x + 0.65) ** 2.7 - 0.72)
    )


@np.errstate(invalid="ignore")
def np_ts(La):  # Ferwerda 1996 rods
    x = np.log10(La)
    return 10.0 ** np.where(
        x <= -3.94, -2.86, np.where(x >= -1.44, x - 0.395, (0.405 * x + 1.6) ** 2.18 - 2.86)
    )


@pytest.mark.usefixtures("x64")
def test_tvi_photopic_and_scotopic_at_breakpoints_and_between():
    # each breakpoint approached from both sides (exactly at it, log10 rounding decides)
    e = np.array([1 - 1e-7, 1 + 1e-7])
    La = np.concatenate([[1e-6, 1e-2, 1.0, 50.0, 1e4], 10**-2.6 * e, 10**1.9 * e])
    np.testing.assert_allclose(hv.tvi_photopic(La), np_tp(La), rtol=RTOL64)
    Ls = np.concatenate([[1e-7, 1e-3, 1e-2, 0.1, 10.0], 10**-3.94 * e, 10**-1.44 * e])
    np.testing.assert_allclose(hv.tvi_scotopic(Ls), np_ts(Ls), rtol=RTOL64)
    # flat branches: the absolute thresholds of the paper
    assert float(hv.tvi_photopic(1e-5)) == pytest.approx(10**-0.72, rel=RTOL64)
    assert float(hv.tvi_scotopic(1e-6)) == pytest.approx(10**-2.86, rel=RTOL64)
    # the branches meet only to the paper's 3-digit constants: jumps of 0.6 % (cones,
    # 10^1.9) and 2.8 % (rods, 10^-1.44), both reproduced above on each side


@pytest.mark.usefixtures("x64")
def test_pcond_combined_tvi():
    e = np.array([1 - 1e-7, 1 + 1e-7])
    La = np.concatenate(
        [[0.0, 1e-5, 1e-3, 0.1, 0.5, 1.0, 1e3, 1e6]]
        + [b * e for b in (1.148e-4, 10**-1.44, 10**-0.0184, 10**1.9)]
    )
    np.testing.assert_allclose(hv.tvi(La), np_tvi(La), rtol=RTOL64)
    # rods hand over to cones at 10**-0.0184 = 0.958 cd/m² (formulas.md §3.8)
    assert float(hv.tvi(10**-0.0184 * 0.999)) == pytest.approx(0.958 * 0.999 * 10**-0.395, 1e-3)


@pytest.mark.usefixtures("x64")
def test_acuity_formula_and_table():
    La = np.array([1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0, 1e4])
    expect = 17.25 * np.arctan(1.4 * np.log10(La) + 0.35) + 25.72
    np.testing.assert_allclose(hv.acuity(La), expect, rtol=RTOL64)
    table = [1.87, 3.01, 5.31, 11.75, 31.5, 43.9, 47.5, 49.9]  # formulas.md §3.3
    np.testing.assert_allclose(np.asarray(hv.acuity(La)), table, atol=0.06)
    # clamped at pcond's LMIN instead of going negative
    r_min = 17.25 * math.atan(1.4 * -7 + 0.35) + 25.72
    assert float(hv.acuity(0.0)) == pytest.approx(r_min, rel=RTOL64)
    assert r_min == pytest.approx(0.45, abs=0.01)


@pytest.mark.usefixtures("x64")
def test_mesopic_weight_thresholds():
    lo, hi = 5.62e-3, 5.62
    assert hv.BOT_MESOPIC == lo and hv.TOP_MESOPIC == hi
    L = np.array([0.0, 1e-3, lo, 0.5 * (lo + hi), 1.0, hi, 100.0])
    expect = np.clip((L - lo) / (hi - lo), 0, 1)
    np.testing.assert_allclose(hv.mesopic_weight(L), expect, rtol=RTOL64, atol=1e-15)
    assert float(hv.mesopic_weight(lo)) == 0.0 and float(hv.mesopic_weight(hi)) == 1.0


@pytest.mark.usefixtures("x64")
def test_blue_shift_weight_smoothstep():
    Y = np.array([1e-4, 0.01, 0.1, 1.0, 10**0.6, 100.0])
    x = np.clip((np.log10(Y) + 2) / 2.6, 0, 1)
    np.testing.assert_allclose(
        hv.blue_shift_weight(Y), 3 * x**2 - 2 * x**3, rtol=RTOL64, atol=1e-15
    )
    assert float(hv.blue_shift_weight(0.0)) == pytest.approx(0.0, abs=1e-15)


@pytest.mark.usefixtures("x64")
def test_scotopic_luminance_cielum():
    rgb = np.array([[1.0, 1.0, 1.0], [0.2, 0.5, 0.9], [3.0, 0.1, 0.05], [0.0, 0.0, 0.0]])
    m = rgb_to_xyz_matrix()
    X, Y, Z = (rgb @ m.T).T
    with np.errstate(divide="ignore", invalid="ignore"):
        V = np.where(X > 0, Y * (1.33 * (1 + (Y + Z) / X) - 1.68), 0.0)
    np.testing.assert_allclose(hv.scotopic_luminance(rgb), V, rtol=RTOL64)
    # the Y row is hdrjax's luminance weights, and the X/Z rows colour-science's NPM
    np.testing.assert_allclose(m[1], (0.2126, 0.7152, 0.0722))
    np.testing.assert_allclose(m[0], (0.4123908, 0.35758434, 0.18048079), rtol=1e-6)


@pytest.mark.usefixtures("x64")
def test_ward1994_and_pcond_contrast_scale():
    Lwa = np.array([1e-3, 0.1, 10.0, 1000.0])
    Lda = 50.0
    expect = ((1.219 + Lda**0.4) / (1.219 + Lwa**0.4)) ** 2.5
    np.testing.assert_allclose(hv.ward1994_scale(Lwa, Lda), expect, rtol=RTOL64)
    np.testing.assert_allclose(
        hv.contrast_scale(Lwa, model="ward1994", display_max=100.0), expect, rtol=RTOL64
    )
    # pcond: L_da = geometric mean of the display range, default 100 cd/m² over 32:1
    Lda_p = 100.0 / math.sqrt(32.0)
    assert hv.display_adaptation("pcond") == pytest.approx(Lda_p)
    np.testing.assert_allclose(hv.contrast_scale(Lwa), np_tvi(Lda_p) / np_tvi(Lwa), rtol=RTOL64)
    # above the cone Weber onset, the visibility scale is the luminance scale times a constant
    m1, m2 = (float(hv.contrast_scale(L)) for L in (100.0, 1000.0))
    assert m1 / m2 == pytest.approx(10.0, rel=RTOL64)


@pytest.mark.usefixtures("x64")
def test_spencer_weights_and_psf():
    for name, w in hv.SPENCER1995_WEIGHTS.items():
        assert sum(w) == pytest.approx(1.0, abs=1e-12), name
    t = np.array([0.0, 0.01, 0.1, 1.0, 3.0, 10.0])
    a = 0.02
    f0 = 2.61e6 * np.exp(-((t / a) ** 2))
    f1 = 20.91 / (t + a) ** 3
    f2 = 72.37 / (t + a) ** 2
    f3 = 436.9 * (568 / 550.0) * np.exp(-19.75 * (t - 3 * 550.0 / 568) ** 2)
    np.testing.assert_allclose(
        hv.spencer1995_psf(t, "photopic"), 0.384 * f0 + 0.478 * f1 + 0.138 * f2, rtol=RTOL64
    )
    np.testing.assert_allclose(
        hv.spencer1995_psf(t, "scotopic", 550.0),
        0.282 * f0 + 0.478 * f1 + 0.207 * f2 + 0.033 * f3,
        rtol=RTOL64,
    )
    # components are normalised per steradian: f0, f1 integrate to 1 sr⁻¹·sr
    sr = (math.pi / 180) ** 2
    assert 2.61e6 * math.pi * a**2 * sr == pytest.approx(1.0, abs=2e-3)
    assert 20.91 * 2 * math.pi / (2 * a) * sr == pytest.approx(1.0, abs=2e-3)
    with pytest.raises(ValueError, match="variant"):
        hv.spencer1995_psf(t, "twilight")


def test_glare_kernel_sums_to_one_and_is_symmetric():
    for view, variant in [
        (hv.View(hfov=40.0).resolve(33, 65), "photopic"),
        (hv.View(hfov=40.0).resolve(33, 65), "mesopic"),
        (hv.View(pixel_deg=0.005).resolve(41, 41), "scotopic"),  # f0 spans pixels
        (hv.View(pixel_deg=2.0).resolve(9, 15), "photopic"),  # coarse pixels
    ]:
        k = hv.glare_kernel(view, variant)
        assert k.shape[1:] == (2 * view.height - 1, 2 * view.width - 1)
        np.testing.assert_allclose(k.sum(axis=(1, 2)), 1.0, rtol=1e-12)
        np.testing.assert_allclose(k, k[:, ::-1, ::-1], rtol=1e-12, atol=1e-18)
        assert (k >= 0).all()


def test_glare_kernel_matches_psf_integral_away_from_centre():
    view = hv.View(pixel_deg=0.1).resolve(101, 101)
    k = hv.glare_kernel(view, "photopic")[0]
    # 40 pixels (4°) right of the centre: weight = P(θ) × pixel solid angle
    sr = (math.pi / 180) ** 2
    expect = float(hv.spencer1995_psf(4.0, "photopic")) * 0.1 * 0.1 * sr
    assert k[100, 140] == pytest.approx(expect, rel=1e-3)
    # a truncated kernel keeps the near field and puts the rest in the centre pixel
    kt = hv.glare_kernel(view, "photopic", radius_deg=2.0)[0]
    assert kt.shape == (41, 41)  # radius 2° = 20 pixels
    np.testing.assert_array_equal(kt[20, 21:], k[100, 101:121])
    theta = 0.1 * np.hypot(*np.mgrid[-100:101, -100:101])
    assert kt[20, 20] - k[100, 100] == pytest.approx(k[theta > 2.0].sum(), rel=1e-9)
    assert kt.sum() == pytest.approx(1.0, abs=1e-12)


@pytest.mark.usefixtures("x64")
def test_fechner_brightness_and_inverse():
    L = np.array([1e-3, 0.1, 1.0, 10.0, 1e4])
    La = 2.0
    expect = La / np_tvi(La) * np.log(L / np_tvi(La))  # JNDs above the threshold
    np.testing.assert_allclose(hv.fechner_brightness(L, La), expect, rtol=RTOL64)
    np.testing.assert_allclose(hv.fechner_luminance(expect, La), L, rtol=RTOL64)


@settings(deadline=None, max_examples=40)
@given(st.floats(-9.0, 7.0), st.floats(1.0, 3.0))
def test_tvi_curves_are_monotone(logL, factor):
    L = 10.0**logL
    for f in (hv.tvi, hv.tvi_photopic, hv.tvi_scotopic, hv.acuity):
        assert float(f(L * factor)) >= float(f(L)) * (1 - RTOL32)
