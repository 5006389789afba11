"""Field-of-view resolution (pcond's default view and sampling rate)."""

import math

import pytest

import hdrjax.vision as hv


def test_default_view_is_pcond_40_degrees_on_the_longer_side():
    v = hv.View().resolve(512, 1024)  # landscape: 40° horizontal
    assert v.hfov == 40.0 and v.projection == "perspective"
    assert v.vfov == pytest.approx(2 * math.degrees(math.atan(0.3639702 * 512 / 1024)), rel=1e-6)
    p = hv.View().resolve(1024, 512)  # portrait: 40° vertical
    assert p.vfov == 40.0
    assert p.hfov == pytest.approx(2 * math.degrees(math.atan(0.3639702 * 512 / 1024)), rel=1e-6)
    # pcond check2do: (xres/sqrt(hn2) + yres/sqrt(vn2)) / (2·180/π), sqrt(hn2) = 2 tan(h/2)
    rate = 1024 / (2 * math.tan(math.radians(20))) + 512 / (2 * math.tan(math.radians(v.vfov / 2)))
    assert v.samples_per_degree == pytest.approx(rate / (2 * 180 / math.pi), rel=1e-9)
    assert v.pixel_deg_x == pytest.approx(v.pixel_deg_y, rel=1e-9)  # square pixels


def test_equiangular_and_pixel_size_views():
    pano = hv.View(hfov=360.0, vfov=180.0, projection="equiangular").resolve(1024, 2048)
    assert pano.pixel_deg_x == pytest.approx(360 / 2048) and pano.pixel_deg_y == 180 / 1024
    assert pano.fovea_block == (6, 6)  # round(1° / 0.176°)
    tiny = hv.View(pixel_deg=1e-3).resolve(10, 20)
    assert (tiny.hfov, tiny.vfov) == pytest.approx((0.02, 0.01))
    assert tiny.fovea_block == (10, 20)  # one foveal sample covers the whole image
    assert hv.View(hfov=60.0).resolve(1, 1).fovea_block == (1, 1)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"hfov": 180.0},
        {"hfov": 0.0},
        {"hfov": float("nan")},
        {"pixel_deg": -1.0},
        {"hfov": 361.0, "projection": "equiangular"},
        {"hfov": 10.0, "pixel_deg": 0.1},
        {"projection": "fisheye"},
    ],
)
def test_bad_views_raise(kwargs):
    with pytest.raises(ValueError):
        hv.View(**kwargs)


def test_very_wide_and_very_narrow_perspective_views():
    wide = hv.View(hfov=170.0).resolve(2000, 100)  # vfov from the aspect stays under 180°
    assert 179.0 < wide.vfov < 180.0
    narrow = hv.View(hfov=0.01).resolve(100, 100)
    assert narrow.pixel_deg_x == pytest.approx(1e-4, rel=1e-6)
    with pytest.raises(ValueError, match="equiangular view needs"):
        hv.View(projection="equiangular").resolve(10, 10)
