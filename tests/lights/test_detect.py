"""hdrjax.lights.detect on synthetic maps with known lights, and on degenerate input.

Every synthetic map is 256×512 (one compiled plan); the lights are uniform discs, so the
expected direction is the energy centroid of the disc's pixels, its solid angle the sum of
their solid angles, its colour the disc's RGB and its share of ∑ L dω exact.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import hdrjax.lights as hl
from tests.conftest import enable_x64

from ._synth import PIXEL_DEG, H, W, angle_deg, direction, disc_map


def finite_outputs(res: hl.Lights) -> None:
    """No NaN anywhere; Inf only in the threshold (meaning "no light to find")."""
    for name, leaf in vars(res).items():
        if isinstance(leaf, jax.Array) and jnp.issubdtype(leaf.dtype, jnp.floating):
            if name == "threshold":
                assert not bool(jnp.any(jnp.isnan(leaf))), name
            else:
                assert bool(jnp.all(jnp.isfinite(leaf))), name


def check_light(res: hl.Lights, k: int, t: dict, rgb_tol: float = 1e-3) -> None:
    assert angle_deg(res.direction[k], t["centroid"]) <= PIXEL_DEG
    assert angle_deg(res.direction[k], t["dir"]) <= PIXEL_DEG
    assert float(res.solid_angle[k]) == pytest.approx(t["solid_angle"], rel=1e-4)
    assert float(res.energy_share[k]) == pytest.approx(t["share"], rel=1e-3)
    np.testing.assert_allclose(res.colour[k], t["rgb"], rtol=rgb_tol)
    np.testing.assert_array_equal(np.asarray(res.labels) == k, t["mask"])


def test_one_disc_direction_size_colour_energy_and_mask():
    img, (t,) = disc_map([(40.0, 25.0, 3.0, (300.0, 200.0, 100.0))])
    res = hl.detect(img)
    assert int(res.count) == 1 and not bool(res.truncated)
    check_light(res, 0, t)
    # the disc's nominal size: 6° wide
    assert float(res.angular_diameter[0]) == pytest.approx(6.0, abs=PIXEL_DEG)
    assert float(res.azimuth[0]) == pytest.approx(40.0, abs=PIXEL_DEG)
    assert float(res.elevation[0]) == pytest.approx(25.0, abs=PIXEL_DEG)
    assert float(res.peak_luminance[0]) == pytest.approx(0.2126 * 300 + 0.7152 * 200 + 7.22)
    # pixel position: the centroid in pixel coordinates, a twentieth of a pixel from the
    # direction's (the mean on the sphere and in the image differ slightly)
    x, y = np.asarray(res.pixel[0])
    assert (x + 0.5) / W * 360 - 180 == pytest.approx(float(res.azimuth[0]), abs=PIXEL_DEG / 20)
    assert 90 - (y + 0.5) / H * 180 == pytest.approx(float(res.elevation[0]), abs=PIXEL_DEG / 20)
    assert int(res.n_samples[0]) >= 1
    assert int(res.sample_light[0]) == 0  # the brightest candidate joined the light
    finite_outputs(res)
    assert not bool(res.valid[1]) and float(res.energy[1]) == 0.0


def test_light_across_the_seam_is_one_light():
    img, (t,) = disc_map([(180.0, 10.0, 4.0, (50.0, 50.0, 50.0))])
    assert t["mask"][:, 0].any() and t["mask"][:, -1].any()  # it does cross
    res = hl.detect(img)
    assert int(res.count) == 1
    check_light(res, 0, t)
    assert abs(float(res.azimuth[0])) == pytest.approx(180.0, abs=PIXEL_DEG)


def test_two_close_lights_stay_two_and_are_sorted_by_energy():
    # 5° apart, 2° gap between the discs (about 3 pixels)
    img, truth = disc_map([(0.0, 0.0, 1.5, (80.0,) * 3), (5.0, 0.0, 1.5, (40.0,) * 3)])
    res = hl.detect(img)
    assert int(res.count) == 2
    for k in range(2):
        check_light(res, k, truth[k])


def test_several_lights_exact_count_and_colours():
    spec = [
        (-120.0, 30.0, 2.0, (900.0, 600.0, 300.0)),
        (60.0, -20.0, 5.0, (20.0, 40.0, 80.0)),
        (150.0, 60.0, 3.0, (200.0, 200.0, 150.0)),
        (-30.0, 5.0, 1.0, (500.0, 500.0, 500.0)),
    ]
    img, truth = disc_map(spec)
    res = hl.detect(img)
    assert int(res.count) == 4
    order = np.argsort([-t["share"] for t in truth])
    for k, j in enumerate(order):
        check_light(res, k, truth[j])
    assert float(jnp.sum(res.energy_share)) == pytest.approx(
        sum(t["share"] for t in truth), rel=1e-3
    )


def test_light_at_high_elevation():
    img, (t,) = disc_map([(10.0, 75.0, 3.0, (100.0,) * 3)])
    res = hl.detect(img)
    assert int(res.count) == 1
    check_light(res, 0, t)


def test_light_at_the_zenith_is_one_light_but_its_mask_is_clipped():
    # Documented limitation: the mask window is max_radius high and twice that wide in
    # pixels, so near a pole, where a disc spans many columns, part of it is cut off.
    img, (t,) = disc_map([(10.0, 87.0, 3.0, (100.0,) * 3)])
    res = hl.detect(img)
    assert int(res.count) == 1
    assert angle_deg(res.direction[0], t["centroid"]) <= 3.0
    assert 0.3 * t["share"] < float(res.energy_share[0]) <= t["share"] * 1.001


@settings(deadline=None, max_examples=12)
@given(
    az=st.floats(-180.0, 179.9),
    el=st.floats(-60.0, 60.0),
    radius=st.floats(0.8, 4.0),
    level=st.floats(5.0, 1e4),
)
def test_any_disc_is_found_within_a_pixel(az, el, radius, level):
    img, (t,) = disc_map([(az, el, radius, (level,) * 3)])
    res = hl.detect(img)
    assert int(res.count) == 1
    assert angle_deg(res.direction[0], t["centroid"]) <= PIXEL_DEG
    assert float(res.energy_share[0]) == pytest.approx(t["share"], rel=1e-3)


# ----------------------------------------------------------------------------- degenerate


def test_black_and_constant_maps_have_no_light():
    for img in (np.zeros((H, W, 3), np.float32), np.full((H, W, 3), 3.0, np.float32)):
        res = hl.detect(img)
        assert int(res.count) == 0
        assert math.isinf(float(res.threshold))
        assert bool(jnp.all(res.labels == -1)) and bool(jnp.all(res.sample_light == -1))
        finite_outputs(res)


def test_nan_and_inf_pixels_are_excluded():
    img, (t,) = disc_map([(-70.0, 15.0, 3.0, (400.0, 300.0, 200.0))])
    rng = np.random.default_rng(1)
    ys, xs = rng.integers(0, H, 300), rng.integers(0, W, 300)
    img[ys[:100], xs[:100], 0] = np.nan
    img[ys[100:200], xs[100:200]] = np.inf
    img[ys[200:], xs[200:], 2] = -np.inf
    bad = ~np.isfinite(img).all(-1)
    res = hl.detect(img)
    finite_outputs(res)
    assert int(res.count) == 1
    assert angle_deg(res.direction[0], t["centroid"]) <= PIXEL_DEG
    # the share counts finite pixels only
    lum = np.where(bad, 0.0, img @ np.array([0.2126, 0.7152, 0.0722]))
    from ._synth import pixel_solid_angles

    dw = pixel_solid_angles()
    expected = (lum * dw * t["mask"]).sum() / (lum * dw).sum()
    assert float(res.energy_share[0]) == pytest.approx(expected, rel=1e-3)


def test_all_nan_map():
    res = hl.detect(np.full((H, W, 3), np.nan, np.float32))
    assert int(res.count) == 0
    finite_outputs(res)


def test_ldr_map_with_a_clipped_sun():
    # sky from 0.2 (horizon) to 0.6 (zenith), ground 0.1, a sun clipped at 1.0
    el = 90 - 180 * (np.arange(H) + 0.5) / H
    sky = np.where(el > 0, 0.2 + 0.4 * el / 90, 0.1)
    base = np.repeat(sky[:, None], W, axis=1)[..., None] * np.ones(3)
    img, (t,) = disc_map([(100.0, 30.0, 2.0, (1.0, 1.0, 1.0))])
    img = np.where(t["mask"][..., None], img, base).astype(np.float32)
    res = hl.detect(img)
    assert float(res.threshold) == pytest.approx(0.8)  # the listing's LDR threshold
    assert int(res.count) == 1
    assert angle_deg(res.direction[0], t["centroid"]) <= PIXEL_DEG


def test_only_light_clipped_flat():
    img, (t,) = disc_map([(-150.0, 40.0, 4.0, (4096.0,) * 3)], background=0.5)
    res = hl.detect(img)
    assert int(res.count) == 1
    check_light(res, 0, t)
    assert float(res.peak_luminance[0]) == pytest.approx(4096.0)


def test_explicit_threshold():
    spec = [
        (-100.0, 0.0, 2.0, (300.0,) * 3),
        (0.0, 0.0, 2.0, (200.0,) * 3),
        (100.0, 0.0, 2.0, (100.0,) * 3),
    ]
    img, _ = disc_map(spec)
    assert int(hl.detect(img, threshold=1e4).count) == 0
    assert int(hl.detect(img, threshold=150.0).count) == 2
    assert int(hl.detect(img, threshold=jnp.float32(50.0)).count) == 3


def test_more_lights_than_max_lights():
    # 40 small lights, brightest first by longitude; max_lights is 32
    spec = [(-175.0 + 9 * i, 20.0 * (i % 3) - 20.0, 1.0, (1000.0 - 10 * i,) * 3) for i in range(40)]
    img, _ = disc_map(spec)
    res = hl.detect(img)
    assert int(res.count) == 32 and int(res.n_found) == 40 and bool(res.truncated)
    # the 32 brightest local maxima are kept
    assert float(jnp.min(res.peak_luminance)) >= 1000.0 - 10 * 31 - 1e-3


def test_batch_is_one_vmapped_call_with_per_map_thresholds():
    a, _ = disc_map([(30.0, 10.0, 2.0, (100.0,) * 3)])
    b, _ = disc_map([(-60.0, -10.0, 3.0, (50.0,) * 3), (90.0, 20.0, 2.0, (60.0,) * 3)])
    both = hl.detect(np.stack([a, b]))
    assert both.count.shape == (2,) and both.labels.shape == (2, H, W)
    for i, img in enumerate((a, b)):
        one = hl.detect(img)
        assert int(both.count[i]) == int(one.count)
        np.testing.assert_allclose(both.direction[i], one.direction, atol=1e-6)
        np.testing.assert_array_equal(both.labels[i], one.labels)
    thr = hl.detect(np.stack([a, b]), threshold=jnp.array([1e9, 1.0]))
    assert np.asarray(thr.count).tolist() == [0, 2]


def test_float64_under_x64():
    img, (t,) = disc_map([(20.0, -30.0, 3.0, (70.0, 80.0, 90.0))])
    img = img.astype(np.float64)
    # the expected share, in float64 from the same (float32-rounded) values
    from ._synth import pixel_solid_angles

    e = (img @ np.array([0.2126, 0.7152, 0.0722])) * pixel_solid_angles()
    share = e[t["mask"]].sum() / e.sum()
    with enable_x64():
        res = hl.detect(img)
        assert res.direction.dtype == jnp.float64 and res.energy_share.dtype == jnp.float64
        assert int(res.count) == 1
        assert angle_deg(res.direction[0], t["centroid"]) <= PIXEL_DEG
        assert float(res.energy_share[0]) == pytest.approx(share, rel=1e-9)


def test_directions_in_renderer_conventions():
    img, (t,) = disc_map([(90.0, 0.0, 2.0, (100.0,) * 3)])  # straight to the right: +X
    res = hl.detect(img)
    np.testing.assert_allclose(res.directions()[0], [1, 0, 0], atol=2e-3)
    np.testing.assert_allclose(res.directions("z_up")[0], [1, 0, 0], atol=2e-3)
    np.testing.assert_allclose(res.directions("mitsuba")[0], [-1, 0, 0], atol=2e-3)
    np.testing.assert_allclose(res.directions("blender")[0], [0, -1, 0], atol=2e-3)
    assert bool(jnp.all(res.directions("pbrt")[1:] == 0))  # padding stays zero


def test_records_and_json():
    img, _ = disc_map([(40.0, 25.0, 3.0, (300.0, 200.0, 100.0))])
    res = hl.detect(img)
    (rec,) = res.to_records()
    assert rec["azimuth_deg"] == pytest.approx(40.0, abs=PIXEL_DEG)
    assert set(rec) >= {"direction", "solid_angle_sr", "energy_share", "colour", "pixel"}
    import json

    doc = json.loads(res.to_json(file="x"))
    assert doc["count"] == 1 and doc["file"] == "x" and "Y-up" in doc["convention"]
    full = res.labels_at()
    assert full.shape == (H, W) and (full == 0).sum() == (np.asarray(res.labels) == 0).sum()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(width=2), "width"),
        (dict(blur=-1.0), "blur"),
        (dict(max_radius=0.0), "max_radius"),
        (dict(max_lights=0), "max_lights"),
        (dict(threshold=-1.0), "threshold"),
        (dict(n_samples=0), "n_samples"),
        (dict(weights=(1.0, 2.0)), "weights"),
    ],
)
def test_bad_options_raise_value_errors(kwargs, match):
    img = np.zeros((H, W, 3), np.float32)
    with pytest.raises(ValueError, match=match):
        hl.detect(img, **kwargs)


def test_bad_shapes_raise_value_errors():
    with pytest.raises(ValueError, match="RGB"):
        hl.detect(np.zeros((H, W), np.float32))
    with pytest.raises(ValueError, match="at least"):
        hl.detect(np.zeros((1, 8, 3), np.float32))


# ----------------------------------------------------------------------------- variants


def test_plain_image_with_halton_samples():
    h, w = 200, 300
    yy, xx = np.mgrid[0:h, 0:w]
    img = np.full((h, w, 3), 0.1, np.float32)
    blobs = [((80.0, 50.0), 6.0, 500.0), ((230.0, 150.0), 4.0, 200.0)]
    masks = []
    for (cx, cy), r, v in blobs:
        m = (xx - cx) ** 2 + (yy - cy) ** 2 <= r * r
        img[m] = v
        masks.append(m)
    res = hl.detect_image(img)
    assert res.projection == "plane" and int(res.count) == 2
    for k, ((cx, cy), _, _) in enumerate(blobs):
        np.testing.assert_allclose(res.pixel[k], [cx, cy], atol=0.5)
        np.testing.assert_array_equal(np.asarray(res.labels) == k, masks[k])
        assert float(res.area[k]) == masks[k].sum()
    assert bool(jnp.all(res.direction == 0)) and bool(jnp.all(res.solid_angle == 0))
    with pytest.raises(ValueError, match="no directions"):
        res.directions()
    finite_outputs(res)


def test_cube_map_lights_in_the_cube_maps_frame():
    s = 48
    faces = np.full((6, s, s, 3), 0.05, np.float32)
    faces[2, 22:26, 22:26] = 300.0  # +Y face centre: straight up (about 5° across)
    faces[5, 22:26, 10:14] = 900.0  # -Z face (ahead), left of centre
    res = hl.detect_cubemap(faces)
    assert int(res.count) == 2 and res.input_shape == (2 * s, 4 * s)
    ups = np.asarray(res.direction)
    up = ups[np.argmax(ups[:, 1])]
    np.testing.assert_allclose(up, [0, 1, 0], atol=0.02)
    ahead = ups[np.argmin(ups[:, 2])]
    # the -Z square covers columns 10-13 and rows 22-25 of 48: its centre is at face
    # coordinates u = 12 / 24 - 1, v = 24 / 24 - 1; direction (-u, -v, -1) normalised
    # (hdrjax.panorama's face table)
    u, v = 12 / 24 - 1, 24 / 24 - 1
    expected = np.array([-u, -v, -1.0]) / np.linalg.norm([u, v, 1.0])
    assert angle_deg(ahead, expected) < 1.0


def test_larger_maps_are_reduced_and_keep_the_peak():
    img, (t,) = disc_map([(-20.0, 35.0, 2.0, (100.0,) * 3)], h=2 * H, w=2 * W)
    img[t["mask"].nonzero()[0][0], t["mask"].nonzero()[1][0]] = 5000.0  # one hot pixel
    res = hl.detect(img)  # width 512: reduced 2x
    assert int(res.count) == 1 and res.labels.shape == (H, W)
    assert float(res.peak_luminance[0]) == pytest.approx(5000.0)
    assert angle_deg(res.direction[0], t["centroid"]) <= PIXEL_DEG
    assert res.labels_at().shape == (2 * H, 2 * W)


def test_direction_is_sharper_than_the_working_pixel():
    # a 1-pixel light between two working pixels of a 2x reduced map
    img = np.full((2 * H, 2 * W, 3), 0.01, np.float32)
    img[201, 601] = 1e4
    res = hl.detect(img)
    az, el = 360 * 601.5 / (2 * W) - 180, 90 - 180 * 201.5 / (2 * H)
    assert int(res.count) == 1
    assert angle_deg(res.direction[0], direction(az, el)) <= PIXEL_DEG
