"""hdrjax.panorama: projections with documented axes, bilinear sampling in JAX."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.panorama as pano

ATOL = 1e-5


def test_sample_bilinear_centres_midpoints_and_wrap():
    img = jnp.arange(12.0).reshape(3, 4, 1)
    x = jnp.array([0.5, 1.0, 3.5, 4.0, 0.0])
    y = jnp.array([0.5, 0.5, 2.5, 1.5, 0.5])
    clamp = pano.sample_bilinear(img, x, y)[:, 0]
    np.testing.assert_allclose(clamp, [0.0, 0.5, 11.0, 7.0, 0.0], atol=ATOL)
    wrap = pano.sample_bilinear(img, x, y, wrap_x=True)[:, 0]
    # x = 4.0 lies half way between the last column (7) and, wrapped, the first (4)
    np.testing.assert_allclose(wrap, [0.0, 0.5, 11.0, 5.5, 1.5], atol=ATOL)


def test_equirect_axes_match_sources_md():
    h, w = 8, 16
    d = np.asarray(pano.equirect_directions(h, w))
    # SOURCES.md: az = 360 (x + 0.5) / W - 180, el = 90 - 180 (y + 0.5) / H
    for x, y in [(0, 0), (7, 3), (12, 5), (15, 7)]:
        az = math.radians(360 * (x + 0.5) / w - 180)
        el = math.radians(90 - 180 * (y + 0.5) / h)
        expect = [math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)]
        np.testing.assert_allclose(d[y, x], expect, atol=ATOL)
    xs, ys = pano.direction_to_equirect(jnp.array([[0.0, 0, -1], [1, 0, 0], [0, 1, 0]]), h, w)
    np.testing.assert_allclose(xs[:2], [w / 2, 3 * w / 4], atol=ATOL)  # ahead, right
    np.testing.assert_allclose(ys, [h / 2, h / 2, 0.0], atol=ATOL)  # horizon, zenith


def test_cubemap_faces_and_round_trip():
    faces_d = np.asarray(pano.cubemap_directions(9))
    axes = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    for k, a in enumerate(axes):
        np.testing.assert_allclose(faces_d[k, 4, 4], a, atol=ATOL)
    # +X face: right of the face is -Z, up is +Y (OpenGL)
    assert faces_d[0, 4, 8, 2] < -0.5 and faces_d[0, 0, 4, 1] > 0.5
    h = 64
    d = pano.equirect_directions(h, 2 * h)
    smooth = 0.5 + 0.5 * d  # direction as colour: smooth over the sphere
    cube = pano.equirect_to_cubemap(smooth, 32)
    np.testing.assert_allclose(cube, 0.5 + 0.5 * np.asarray(pano.cubemap_directions(32)), atol=2e-3)
    back = pano.cubemap_to_equirect(cube, h)
    assert back.shape == (h, 2 * h, 3)
    err = np.abs(np.asarray(back) - np.asarray(smooth))
    assert err.mean() < 1e-3 and err.max() < 1e-2


def test_fisheye_both_ways():
    h = 64
    d = pano.equirect_directions(h, 2 * h)
    smooth = 0.5 + 0.5 * d
    fish = pano.equirect_to_fisheye(smooth, 48, fov_deg=180)
    fd, inside = pano.fisheye_directions(48, 48, fov_deg=180)
    assert float(fd[24, 24, 2]) < -0.99  # the centre looks ahead (-Z)
    assert float(fd[24, 47, 0]) > 0.99 and float(fd[0, 24, 1]) > 0.99  # right edge +X, top +Y
    np.testing.assert_allclose(
        np.where(inside[..., None], fish, 0),
        np.where(inside[..., None], 0.5 + 0.5 * fd, 0),
        atol=2e-3,
    )
    assert float(fish[0, 0, 0]) == 0.0  # outside the image circle: fill
    eq = pano.fisheye_to_equirect(fish, h, fov_deg=180)
    front = np.asarray(-d[..., 2] > math.cos(math.radians(75)))  # away from the rim
    np.testing.assert_allclose(np.asarray(eq)[front], np.asarray(smooth)[front], atol=2e-2)
    assert float(eq[h // 2, 0, 0]) == 0.0  # behind the viewer: outside the fov


def test_polar_to_disc():
    h, w = 30, 72  # theta rows 0..90 deg, phi columns 0..360 deg
    theta = (np.arange(h) + 0.5) / h * 90
    phi = (np.arange(w) + 0.5) / w * 360
    img = np.stack(np.broadcast_arrays(theta[:, None], np.cos(np.radians(phi))[None, :]), axis=2)
    disc = np.asarray(pano.polar_to_cartesian(jnp.asarray(img, jnp.float32), 61, theta_max_deg=90))
    c = 30
    assert disc[c, c, 0] < 3  # centre: theta ~ 0
    rim = ((59 + 0.5) / 61 * 2 - 1) * 90  # theta at the centre of output pixel 59
    assert disc[c, 59, 0] == pytest.approx(rim, abs=1.0)
    assert disc[c, 50, 1] == pytest.approx(1.0, abs=0.02)  # right: phi = 0
    assert disc[10, c, 1] == pytest.approx(0.0, abs=0.05)  # up: phi = 90
    assert disc[c, 10, 1] == pytest.approx(-1.0, abs=0.02)  # left: phi = 180
    assert disc[0, 0, 0] == 0.0  # outside the disc
    half = np.asarray(pano.polar_to_cartesian(img, 61, theta_max_deg=90, theta_view_deg=45))
    assert half[c, 59, 0] == pytest.approx(rim / 2, abs=1.0)


def test_jit_and_grad():
    img = jnp.ones((8, 16, 3))
    f = jax.jit(lambda im: pano.equirect_to_cubemap(im, 4).sum())
    assert float(f(img)) == pytest.approx(6 * 16 * 3)
    g = jax.grad(lambda im: pano.equirect_to_cubemap(im, 4).sum())(img)
    assert np.isfinite(np.asarray(g)).all() and float(g.sum()) == pytest.approx(
        6 * 16 * 3, rel=1e-5
    )


def test_flat_float64_images_resample_to_themselves(x64):
    """Issue 16.3: float32 sample coordinates with a float64 image rounded ``1 - f`` in
    float32, so the bilinear weights summed to up to ``1 + 2e-8``: a flat image at the
    float64 maximum came out +Inf, and a flat image of ones up to 3e-8 off 1."""
    for v in (np.finfo(np.float64).max, 1.0):
        img = np.full((8, 8, 3), v)
        fish = np.asarray(pano.fisheye_to_equirect(img, 8))
        disc = np.asarray(pano.polar_to_cartesian(img, 8))
        for out in (fish, disc):  # the view is v, the rest is the fill 0
            assert out.dtype == np.float64
            assert np.all((out == v) | (out == 0.0)) and np.any(out == v), (v, out[..., 0])
