"""Absolute calibration: ISO 12232 exposure settings end to end through a simulated bracket,
and Lagarde et al. (2016) against colour-hdri (called directly)."""

import math

import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.merge as hm
from hdrjax.io import read
from hdrjax.operators import Q_FACTOR, saturation_luminance

from ..conftest import DATA, RTOL32, RTOL64, enable_x64

MEDIAN_REL_ERROR = 0.02
"""Issue 23's bound for merged radiance, here in cd/m² after calibration."""


def test_absolute_scale_is_the_iso_12232_saturation_luminance_at_one_second():
    # 78 N² / (q S), q = (π/4) · 0.9 · 0.98 · cos⁴(10°) (colour-hdri's defaults)
    q = math.pi / 4 * 0.9 * 0.98 * math.cos(math.radians(10)) ** 4
    assert float(hm.absolute_scale(8.0, 100)) == pytest.approx(78 * 64 / (q * 100), rel=RTOL32)
    assert float(hm.absolute_scale(2.8, 400, q=0.65)) == pytest.approx(
        78 * 2.8**2 / (0.65 * 400), rel=RTOL32
    )
    t = 1 / 125
    assert float(hm.absolute_scale(4.0, 200)) == pytest.approx(
        float(saturation_luminance(t, 4.0, 200) * t), rel=RTOL32
    )
    for kwargs in ({"f_number": 0.0, "iso": 100}, {"f_number": 8.0, "iso": -1}):
        with pytest.raises(ValueError, match=f"^{next(k for k, v in kwargs.items() if v <= 0)}"):
            hm.absolute_scale(**kwargs)


def test_bracket_of_a_scene_in_cd_m2_calibrates_back_to_cd_m2():
    """A scene in cd/m², photographed at f/8, ISO 100, 1/1024–1/4 s (2 EV apart).

    The camera: a pixel seeing luminance ``L`` for ``t`` seconds gets the sensor exposure
    ``X = L t / L_sat(1 s)`` with ``L_sat(1 s) = 78 N² / (q S)`` (X = 1 saturates: ISO
    12232). :func:`hdrjax.merge.simulate_bracket` scales the scene by
    ``k = fill / (p99 · t_mid)`` (``p99`` the 99th percentile of the channel mean); choosing
    ``fill = p99 · t_mid / L_sat(1 s)`` makes ``k = 1 / L_sat(1 s)``: that camera.
    """
    img = np.asarray(read(DATA / "venice_sunset_1k.hdr").rgb(), np.float64)[::8, ::8]
    scene = img * (3000.0 / np.percentile(img.mean(-1), 99))  # p99 at 3000 cd/m²
    n, s = 8.0, 100.0
    l_sat_1s = 78 * n**2 / (Q_FACTOR * s)
    times = 2.0 ** np.arange(-10, -1, 2)  # 1/1024 … 1/4 s
    fill = np.percentile(scene.mean(-1), 99) * times[2] / l_sat_1s
    b = hm.simulate_bracket(scene, times, curve="srgb", fill=fill)
    np.testing.assert_allclose(b.radiance, scene / l_sat_1s, rtol=1e-12)
    out = np.asarray(hm.calibrate(hm.merge(b.codes, times, b.response), f_number=n, iso=s))
    ok = scene > 0
    err = np.median(np.abs(out[ok] - scene[ok]) / scene[ok])
    assert err < MEDIAN_REL_ERROR, err


def test_calibrate_illuminance_matches_colour_hdri_lagarde2016():
    colour_hdri = pytest.importorskip("colour_hdri")
    env = np.asarray(read(DATA / "rooitou_park_1k.hdr").rgb(), np.float64)[::8, ::8]
    ours = hm.calibrate_illuminance(env, 12000.0)
    theirs = colour_hdri.absolute_luminance_calibration_Lagarde2016(env, 12000.0)
    # colour-hdri derives the luminance weights from the sRGB primaries; hdrjax uses
    # Rec. 709's rounded ones (0.2126, 0.7152, 0.0722): a 1e-5 difference
    np.testing.assert_allclose(ours, theirs, rtol=RTOL32)
    with enable_x64():
        ours64 = hm.calibrate_illuminance(env, 12000.0)
        assert ours64.dtype == jnp.float64
        np.testing.assert_allclose(ours64, theirs, rtol=2e-5)
        assert float(hm.absolute_scale(8.0, 100)) == pytest.approx(
            78 * 64 / (Q_FACTOR * 100), rel=RTOL64
        )


def test_calibrate_errors_are_one_line_and_name_the_argument():
    env = np.ones((8, 16, 3))
    env[:4] = 0.0  # black sky: nothing to scale
    cases = [
        (lambda: hm.calibrate_illuminance(env, 100.0), "^radiance"),
        (lambda: hm.calibrate_illuminance(np.ones((8, 16, 3)), -1.0), "^illuminance_lux"),
        (lambda: hm.calibrate_illuminance(np.ones((8, 16)), 1.0), "^radiance"),
        (lambda: hm.calibrate(np.ones((4, 4, 2)), f_number=8, iso=100), "^radiance"),
        (lambda: hm.calibrate(np.ones((4, 4, 3)), f_number=8, iso=0), "^iso"),
    ]
    for call, match in cases:
        with pytest.raises(ValueError, match=match) as info:
            call()
        assert "\n" not in str(info.value)
    out = hm.calibrate(np.full((2, 2, 3), 0.5), f_number=8.0, iso=100)
    np.testing.assert_allclose(out, 0.5 * 78 * 64 / (Q_FACTOR * 100), rtol=RTOL32)
