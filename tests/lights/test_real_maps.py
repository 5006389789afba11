"""Detection on real environment maps against the hand-checked lights of SOURCES.md.

Positions in SOURCES.md are the blobs' brightest pixels at full resolution; hdrjax reports
the energy centroid, so a small light agrees to within one pixel (0.35° at 1024 wide)
and a large one to within a fraction of its size. ``rooitou_park_1k.hdr`` ships in
``data/`` and always runs; the others are read from ../shared and skip when absent.
"""

import numpy as np
import pytest

import hdrjax.io
import hdrjax.lights as hl
from tests.conftest import shared_file

from ._synth import angle_deg, direction, rooitou

PIX_1K = 360.0 / 1024  # one input pixel, degrees


def read(path):
    img = hdrjax.io.read(path)
    return img.rgb(), img.luminance_weights


def near(res: hl.Lights, az: float, el: float, tol: float) -> int:
    """Index of the light within ``tol`` degrees (plus its own radius) of (az, el), or -1."""
    d = direction(az, el)
    for k in range(int(res.count)):
        if angle_deg(res.direction[k], d) <= tol + float(res.angular_diameter[k]) / 2:
            return k
    return -1


def test_rooitou_sun():
    rgb, w = read(rooitou())
    res = hl.detect(rgb, weights=w)
    assert int(res.count) == 1  # the sun and nothing else: no sky patch
    # SOURCES.md: (+36.0, +10.4, peak 6.489e4, 6 px, share 0.633)
    assert float(res.azimuth[0]) == pytest.approx(36.0, abs=PIX_1K)
    assert float(res.elevation[0]) == pytest.approx(10.4, abs=PIX_1K)
    assert float(res.peak_luminance[0]) == pytest.approx(6.489e4, rel=1e-3)
    # at the default 512-wide working resolution the sun's pixels are 2x2 blocks that
    # also hold some bright sky: its share is 0.633 + 0.03 (measured 0.659)
    assert float(res.energy_share[0]) == pytest.approx(0.633, abs=0.04)
    assert float(res.threshold) == pytest.approx(1298, rel=1e-3)  # SOURCES.md's T
    assert 0.5 < float(res.angular_diameter[0]) < 4.0


def test_rooitou_median_cut_conserves_energy_and_cuts_through_the_sun():
    rgb, _ = read(rooitou())
    mc = hl.median_cut(rgb, n_lights=32)
    assert float(np.sum(mc.energy_share)) == pytest.approx(1.0, abs=1e-5)
    h, w = rgb.shape[:2]
    theta = np.pi * np.arange(h + 1) / h
    dw = 2 * np.pi * (np.cos(theta[:-1]) - np.cos(theta[1:])) / w
    total = (rgb.astype(np.float64) * dw[:, None, None]).sum((0, 1))
    np.testing.assert_allclose(np.asarray(mc.irradiance).sum(0), total, rtol=1e-4)
    # the sun holds 63 % of the energy: the cuts crowd onto it, and the lights within 2°
    # of it carry at least its share (measured: 12 of 32 lights, 0.66)
    sun = direction(36.0, 10.4)
    close = np.array([angle_deg(d, sun) < 2.0 for d in np.asarray(mc.direction)])
    assert close.sum() >= 8
    assert float(np.asarray(mc.energy_share)[close].sum()) >= 0.6


def test_venice_sun_on_the_horizon():
    rgb, w = read(shared_file("venice_sunset_1k.hdr"))
    res = hl.detect(rgb, weights=w)
    assert int(res.count) == 1
    assert float(res.azimuth[0]) == pytest.approx(36.0, abs=PIX_1K)
    assert float(res.elevation[0]) == pytest.approx(3.3, abs=PIX_1K)
    assert float(res.energy_share[0]) == pytest.approx(0.024, abs=0.005)
    assert float(res.colour[0, 0]) > 2 * float(res.colour[0, 2])  # a red sun


def test_studio_two_lights():
    rgb, w = read(shared_file("studio_small_03_1k.hdr"))
    res = hl.detect(rgb, weights=w)
    assert int(res.count) == 2
    # the round light: 937 px, 70 % of the energy; its peak is 2° from its centre
    assert near(res, -97.2, 43.1, 1.0) == 0
    assert float(res.energy_share[0]) == pytest.approx(0.70, abs=0.02)
    assert near(res, 60.6, 0.5, 1.0) == 1  # the softbox


def test_warehouse_ceiling_lamps():
    rgb, w = read(shared_file("empty_warehouse_01_1k.hdr"))
    res = hl.detect(rgb, weights=w)
    assert 15 <= int(res.count) <= 32
    for az, el in [(30.4, 50.1), (-117.6, 47.3), (101.4, 47.3)]:
        assert near(res, az, el, 1.0) >= 0, (az, el)
    # lamps are small and many: no light takes a third of the energy
    assert float(res.energy_share[0]) < 0.2
    assert float(np.sum(res.energy_share)) == pytest.approx(0.61, abs=0.08)


def test_stage_clipped_lamps():
    rgb, w = read(shared_file("StageEnvLatLong.exr"))
    res = hl.detect(rgb, weights=w)
    assert int(res.count) >= 4
    k = near(res, 23.6, 50.9, 1.0)
    assert k >= 0 and float(res.peak_luminance[k]) == 4096.0  # the flat-topped lamp
    assert near(res, 32.2, 3.8, 1.0) >= 0
    assert near(res, 96.7, 2.7, 1.0) >= 0
