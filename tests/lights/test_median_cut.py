"""Debevec 2005 median cut: a partition of the map into regions of equal energy."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import hdrjax.lights as hl

from ._synth import H, W, angle_deg, disc_map, pixel_solid_angles


def coverage(region: np.ndarray, h: int, w: int) -> np.ndarray:
    count = np.zeros((h, w), int)
    for x0, y0, x1, y1 in region:
        count[y0:y1, x0:x1] += 1
    return count


def test_partition_conserves_energy_and_colour():
    img, (t,) = disc_map([(-40.0, 20.0, 4.0, (2e4, 1e4, 5e3))], background=(0.3, 0.4, 0.5))
    mc = hl.median_cut(img, n_lights=16)
    assert mc.direction.shape == (16, 3)
    np.testing.assert_array_equal(coverage(np.asarray(mc.region), H, W), 1)
    dw = pixel_solid_angles()
    total_rgb = (img.astype(np.float64) * dw[..., None]).sum((0, 1))
    np.testing.assert_allclose(np.asarray(mc.irradiance).sum(0), total_rgb, rtol=1e-5)
    assert float(np.sum(mc.energy_share)) == pytest.approx(1.0, abs=1e-6)
    # the disc holds 97 % of the energy, so the cuts crowd onto it (measured: 13 lights
    # within 5° carrying 0.82; the others' regions mix disc and background)
    on_disc = np.array([angle_deg(d, t["centroid"]) < 5.0 for d in np.asarray(mc.direction)])
    assert on_disc.sum() >= 8
    assert float(np.asarray(mc.energy_share)[on_disc].sum()) >= 0.75


def test_uniform_map_gives_equal_energies():
    img = np.ones((H, W, 3), np.float32)
    mc = hl.median_cut(img, n_lights=16)
    share = np.asarray(mc.energy_share)
    np.testing.assert_allclose(share, 1 / 16, rtol=0.05)
    # regions are cut along their longer side (cos-weighted width): no sliver regions
    r = np.asarray(mc.region)
    assert (r[:, 2] - r[:, 0]).min() >= 8 and (r[:, 3] - r[:, 1]).min() >= 8


@settings(deadline=None, max_examples=10)
@given(seed=st.integers(0, 2**31 - 1), spread=st.floats(0.0, 8.0))
def test_energy_is_conserved_for_any_map(seed, spread):
    rng = np.random.default_rng(seed)
    img = np.exp(spread * rng.standard_normal((H, W, 3))).astype(np.float32)
    mc = hl.median_cut(img, n_lights=16)
    np.testing.assert_array_equal(coverage(np.asarray(mc.region), H, W), 1)
    e = (img.astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])) * pixel_solid_angles()
    np.testing.assert_allclose(np.asarray(mc.energy).sum(), e.sum(), rtol=1e-4)
    assert np.all(np.isfinite(np.asarray(mc.direction)))


def test_regions_that_cannot_be_split_and_bad_input():
    img = np.zeros((4, 8, 3), np.float32)
    img[1, 2] = [10.0, 10.0, 10.0]
    img[0, 0] = np.nan
    mc = hl.median_cut(img, n_lights=32)
    assert float(np.sum(mc.energy_share)) == pytest.approx(1.0, abs=1e-6)
    assert np.all(np.isfinite(np.asarray(mc.direction)))
    assert np.sum(np.asarray(mc.energy) > 0) == 1  # one pixel holds everything
    with pytest.raises(ValueError, match="power of two"):
        hl.median_cut(img, n_lights=12)
    with pytest.raises(ValueError, match="pixels"):
        hl.median_cut(img, n_lights=64)
