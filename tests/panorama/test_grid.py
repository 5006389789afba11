"""The angular grid (hdrjax.plot.angular_grid / with_angular_grid): its lines are where the
panorama module's projections put those angles."""

import math

import numpy as np
import pytest
from matplotlib.figure import Figure

import hdrjax.panorama as hp
import hdrjax.plot as hplot
from hdrjax._angular_grid import grid_lines, project


@pytest.mark.parametrize(
    "view",
    [
        {"fov_deg": 70.0, "yaw_deg": 30.0, "pitch_deg": -10.0, "roll_deg": 0.0},
        {"fov_deg": 100.0, "yaw_deg": -120.0, "pitch_deg": 35.0, "roll_deg": 25.0},
    ],
)
def test_perspective_grid_projects_the_views_own_directions(view):
    """Each pixel centre's direction (as equirect_to_perspective samples it) projects back
    onto that pixel centre."""
    h, w = 24, 40
    d = np.asarray(hp.perspective_directions(h, w, **view), np.float64)
    x, y = project(d, h, w, projection="perspective", **view)
    cx, cy = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    np.testing.assert_allclose(x, cx, atol=2e-4)
    np.testing.assert_allclose(y, cy, atol=2e-4)


def test_equirectangular_and_fisheye_grid_lines_sit_at_their_angles():
    h, w = 90, 180
    lines = grid_lines(h, w, step_deg=30.0)
    horizon = [ln for ln in lines if ln[0] == "elevation" and ln[1] == 0.0]
    assert len(horizon) == 1
    np.testing.assert_allclose(horizon[0][3][np.isfinite(horizon[0][3])], h / 2)
    az = {deg: x for kind, deg, x, _ in lines if kind == "azimuth"}
    # the seam once, as −180° (at x = 0)
    assert sorted(az) == [30.0 * k for k in range(-6, 6)]
    np.testing.assert_allclose(np.nanmean(az[90.0]), w * 0.75)
    # fisheye (equidistant, 180°, looking along −Z): the angle from the axis maps linearly
    # to the radius, and the fisheye's own pixel directions project back onto their pixels
    el = np.radians(30.0)
    x, y = project(np.array([0.0, math.sin(el), -math.cos(el)]), 64, 64, projection="fisheye")
    np.testing.assert_allclose([x, y], [32.0, 32.0 - 32.0 * 30 / 90], atol=1e-9)
    d, inside = hp.fisheye_directions(64, 64, fov_deg=180.0)
    x, y = project(np.asarray(d, np.float64), 64, 64, projection="fisheye")
    cx, cy = np.meshgrid(np.arange(64) + 0.5, np.arange(64) + 0.5)
    inside = np.asarray(inside)
    np.testing.assert_allclose(x[inside], cx[inside], atol=2e-4)
    np.testing.assert_allclose(y[inside], cy[inside], atol=2e-4)


def test_angular_grid_draws_labelled_lines_and_with_angular_grid_keeps_the_size():
    fig = Figure(figsize=(4, 2), dpi=50)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.imshow(np.zeros((50, 100, 3)))
    artists = hplot.angular_grid(ax, 50, 100, step_deg=45.0)
    gids = [a.get_gid() for a in artists]
    assert gids.count("elevation") == 3 and gids.count("azimuth") == 8
    assert any(g == "azimuth_label" for g in gids)
    labels = {a.get_text() for a in artists if a.get_gid() == "azimuth_label"}
    assert "0°" in labels and "\u221245°" in labels
    img = np.full((40, 80, 3), 0.2, np.float32)
    out = hplot.with_angular_grid(img, step_deg=45.0, labels=False)
    assert out.shape == img.shape and out.dtype == np.float32
    # the horizon (row 20) is drawn white over the grey image; rows between lines are not
    assert out[19:21].max() > 0.9
    assert np.allclose(out[5, 5], 0.2, atol=0.01)
    with pytest.raises(ValueError, match="step_deg"):
        grid_lines(10, 20, step_deg=0.0)
    with pytest.raises(ValueError, match="image: expected"):
        hplot.with_angular_grid(np.zeros((4, 4)))
    assert math.isclose(float(np.nanmax(project(np.array([0.0, 0.0, -1.0]), 10, 20)[0])), 10.0)
