"""hdrjax.panorama.equirect_to_perspective: pinhole views against a float64 NumPy reference
of the ray geometry (rotation matrices about the frame's axes, an independent derivation of
the module docstring's camera basis), and the identities a view must satisfy."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.panorama as hp

ATOL_DIR = 1e-5
"""float32 directions against the float64 reference (unit vectors)."""
ATOL_SAMPLE = 2e-3
"""Bilinear resampling of a smooth 32 x 64 map: its interpolation error at the centre."""

H, W = 32, 64  # the panorama
VH, VW = 9, 12  # the view (odd height: a centre row)


def _rx(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def reference_directions(h, w, fov, yaw, pitch, roll):
    """float64: the camera looks along -Z; roll about its axis (clockwise: -roll about +Z),
    pitch about +X, yaw about -Y (to the right); pixel centres on the plane z = -1 at
    focal length (w / 2) / tan(fov / 2)."""
    f = (w / 2) / math.tan(math.radians(fov) / 2)
    i, j = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    cam = np.stack([(i - w / 2) / f, (h / 2 - j) / f, -np.ones_like(i)], -1)
    rot = _ry(-math.radians(yaw)) @ _rx(math.radians(pitch)) @ _rz(-math.radians(roll))
    d = cam @ rot.T
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def _smooth():
    """A panorama whose value is its direction: a view must show its own directions."""
    return 0.5 + 0.5 * np.asarray(hp.equirect_directions(H, W))


VIEWS = [(90.0, 0.0, 0.0, 0.0), (60.0, 30.0, 20.0, 0.0), (120.0, -135.0, -40.0, 25.0)]


@pytest.mark.parametrize("fov, yaw, pitch, roll", VIEWS)
def test_directions_match_the_rotation_matrix_reference(fov, yaw, pitch, roll):
    got = hp.perspective_directions(
        VH, VW, fov_deg=fov, yaw_deg=yaw, pitch_deg=pitch, roll_deg=roll
    )
    ref = reference_directions(VH, VW, fov, yaw, pitch, roll)
    np.testing.assert_allclose(np.asarray(got), ref, atol=ATOL_DIR)


def test_centre_pixel_looks_at_yaw_and_pitch_and_views_sample_the_panorama():
    pano = _smooth()
    view = jax.jit(
        lambda p, a: hp.equirect_to_perspective(
            p, VH, VW + 1, fov_deg=a[0], yaw_deg=a[1], pitch_deg=a[2], roll_deg=a[3]
        )
    )  # angles traced: one compile for every view
    for fov, yaw, pitch, roll in VIEWS:
        out = np.asarray(view(pano, jnp.array([fov, yaw, pitch, roll])))
        y, p = math.radians(yaw), math.radians(pitch)
        axis = [math.cos(p) * math.sin(y), math.sin(p), -math.cos(p) * math.cos(y)]
        # odd view: (VH, VW + 1) has a centre pixel (4, 6)
        np.testing.assert_allclose(
            out[VH // 2, (VW + 1) // 2], 0.5 + 0.5 * np.array(axis), atol=ATOL_SAMPLE
        )
        ref = 0.5 + 0.5 * reference_directions(VH, VW + 1, fov, yaw, pitch, roll)
        assert np.abs(out - ref).max() < 10 * ATOL_SAMPLE


def test_a_bright_feature_lands_at_the_predicted_pixel():
    pano = np.zeros((H, W, 1), np.float32)
    row, col = 12, 40  # az = 360 (40.5) / 64 - 180 = 47.8°, el = 90 - 180 (12.5) / 32 = 19.7°
    pano[row, col] = 1.0
    az = math.radians(360 * (col + 0.5) / W - 180)
    el = math.radians(90 - 180 * (row + 0.5) / H)
    fov, yaw, pitch, roll = 70.0, 35.0, 10.0, 15.0
    # predicted pixel: the feature's direction in camera coordinates, projected
    d = np.array([math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)])
    rot = _ry(-math.radians(yaw)) @ _rx(math.radians(pitch)) @ _rz(-math.radians(roll))
    c = rot.T @ d
    f = (48 / 2) / math.tan(math.radians(fov) / 2)
    x, y = 48 / 2 + f * c[0] / -c[2], 36 / 2 - f * c[1] / -c[2]
    out = np.asarray(
        hp.equirect_to_perspective(
            pano, 36, 48, fov_deg=fov, yaw_deg=yaw, pitch_deg=pitch, roll_deg=roll
        )
    )[..., 0]
    j, i = np.unravel_index(np.argmax(out), out.shape)
    # the peak pixel is within the footprint of one panorama pixel (about 5.6°, 4 px here)
    assert math.hypot(i + 0.5 - x, j + 0.5 - y) < 3.0, (i, j, x, y)


def test_identities_roll_half_turn_full_yaw_turn_and_linearity():
    pano = np.random.default_rng(0).random((H, W, 3)).astype(np.float32)
    base = dict(fov_deg=80.0, yaw_deg=20.0, pitch_deg=-15.0)
    a = np.asarray(hp.equirect_to_perspective(pano, VH, VW, **base))
    # a half turn of roll turns the view upside down
    b = np.asarray(hp.equirect_to_perspective(pano, VH, VW, **base, roll_deg=180.0))
    np.testing.assert_allclose(b, a[::-1, ::-1], atol=1e-4)
    # a full turn of yaw is the same view
    c = np.asarray(hp.equirect_to_perspective(pano, VH, VW, **{**base, "yaw_deg": 380.0}))
    np.testing.assert_allclose(c, a, atol=1e-4)
    # linear in the panorama: the gradient of the view's sum is the bilinear weights,
    # which sum to one per output value
    g = jax.jit(jax.grad(lambda p: hp.equirect_to_perspective(p, VH, VW, **base).sum()))(pano)
    g = np.asarray(g)
    assert np.all(g >= 0) and np.isclose(g.sum(), VH * VW * 3, rtol=1e-5)


def test_nan_stays_local_and_bad_arguments_name_themselves():
    pano = np.ones((H, W, 1), np.float32)
    pano[16, 32] = np.nan  # straight ahead, on the horizon
    ahead = np.asarray(hp.equirect_to_perspective(pano, VH, VW, fov_deg=60.0))
    behind = np.asarray(hp.equirect_to_perspective(pano, VH, VW, fov_deg=60.0, yaw_deg=180.0))
    # NaN exactly where a bilinear weight touches it: the view of its indicator image
    touched = np.asarray(hp.equirect_to_perspective(np.isnan(pano) * 1.0, VH, VW, fov_deg=60.0))
    np.testing.assert_array_equal(np.isnan(ahead), touched > 0)
    assert 0 < np.isnan(ahead).sum() < 9 and np.all(behind == 1.0)
    for kw, name in (({"fov_deg": 180.0}, "fov_deg"), ({"fov_deg": -1.0}, "fov_deg")):
        with pytest.raises(ValueError, match=name):
            hp.equirect_to_perspective(pano, VH, VW, **kw)
    with pytest.raises(ValueError, match="pitch_deg"):
        hp.perspective_directions(VH, VW, pitch_deg=float("nan"))
    with pytest.raises(ValueError, match="height"):
        hp.equirect_to_perspective(pano, 0, VW)
