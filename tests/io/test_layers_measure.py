"""hdrjax.layers (the model) and hdrjax.measure (distances, readouts, regions)."""

import json
import math

import numpy as np
import pytest

import hdrjax.io as hio
import hdrjax.measure as hm
from hdrjax import luminance_weights
from hdrjax.layers import (
    KNOWN_LAYERS,
    POSITION,
    LayeredImage,
    MissingLayerError,
    ReadError,
)


def test_model_defaults_and_missing_layer_message():
    img = LayeredImage(image=np.ones((2, 3)), quantity="illuminance")
    assert img.image.shape == (2, 3, 1) and img.image.dtype == np.float32
    assert img.channels == ("Y",) and img.unit == "lx" and img.kind == "y"
    assert img.luminance_weights == luminance_weights(None)
    with pytest.raises(MissingLayerError) as e:
        img.layer("position")
    assert str(e.value) == "image has no 'position' layer; layers present: none"
    assert {"error", "hits", "position", "object_id", "grid", "wavelengths"} <= set(KNOWN_LAYERS)
    with pytest.raises(ReadError, match="unknown quantity 'brightness'"):
        LayeredImage(image=np.ones((1, 1, 3)), quantity="brightness")
    assert (
        LayeredImage(image=np.ones((1, 1, 3)), quantity="luminance", unit="cd/m2").unit == "cd/m²"
    )


def test_rgb_of_luminance_chroma_matches_formula():
    y = np.array([[1.0, 2.0]], np.float32)
    ry = np.array([[0.5, -0.25]], np.float32)
    by = np.array([[-0.5, 0.1]], np.float32)
    img = LayeredImage(image=np.stack([y, ry, by], axis=2), channels=("Y", "RY", "BY"))
    rgb = img.rgb()
    wr, wg, wb = img.luminance_weights
    r, b = (ry + 1) * y, (by + 1) * y
    np.testing.assert_allclose(rgb[..., 0], r, rtol=1e-6)
    np.testing.assert_allclose(rgb[..., 2], b, rtol=1e-6)
    np.testing.assert_allclose(rgb[..., 1], (y - wr * r - wb * b) / wg, rtol=1e-6)
    np.testing.assert_array_equal(img.luminance(), y)


def test_rgb_raises_for_unknown_channels():
    img = LayeredImage(image=np.ones((1, 1, 2)), channels=("u", "v"))
    with pytest.raises(ValueError, match="channels u, v"):
        img.rgb()


def test_with_layer_select_and_describe():
    img = LayeredImage(image=np.ones((2, 2, 3)))
    img2 = img.with_layer("position", np.arange(12, dtype=np.float32).reshape(2, 2, 3))
    assert not img.has_layer("position") and img2.is_grid_layer("position")
    sel = img2.select(POSITION)
    assert sel.channels == ("X", "Y", "Z") and sel.image[1, 1, 2] == 11
    assert "layer position: grid float32 (2, 2, 3)" in img2.describe()


# -- measurement -----------------------------------------------------------------------


def _measured(tmp_path):
    h, w = 6, 8
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    pos = np.stack([xx * 0.5, yy * 0.25, np.full_like(xx, 2.0)], axis=2)  # a plane
    pos[0, 0] = np.nan  # no scene point behind pixel (0, 0)
    img = LayeredImage(
        image=np.stack([xx, yy, xx + yy], axis=2),
        quantity="luminance",
        layers={
            "position": pos,
            "error": np.full((h, w), 0.1, np.float32),
            "hits": np.full((h, w), 3, np.uint32),
            "object_id": (xx > 3).astype(np.uint32),
        },
        sensor_size=(0.008, 0.006),
    )
    p = hio.write(tmp_path / "Scene.exr", img)
    return hio.read(p)


def test_distance_3d_2d_and_scale(tmp_path):
    img = _measured(tmp_path)
    d = hm.distance(img, (1, 1), (5, 4))
    assert d.mode == "3d" and d.unit == "scene units"
    assert d.value == pytest.approx(math.hypot(4 * 0.5, 3 * 0.25))
    assert d.point_a == (0.5, 0.25, 2.0)
    # forced 2D: sensor 8 mm x 6 mm over 8 x 6 pixels -> 1 mm pitch
    d2 = hm.distance(img, (1, 1), (5, 4), mode="2d")
    assert d2.mode == "2d" and d2.unit == "m" and d2.value == pytest.approx(0.005)
    assert "forced" in d2.note
    # coordinates picked on a 200 % view: (2, 2)-(10, 8) are pixels (1, 1)-(5, 4)
    d3 = hm.distance(img, (2, 2), (10, 8), scale_percent=200)
    assert (d3.a, d3.b) == ((1, 1), (5, 4)) and d3.value == pytest.approx(d.value)
    # a pixel without a scene point falls back to 2D and says so
    d4 = hm.distance(img, (0, 0), (3, 4))
    assert d4.mode == "2d" and "has no scene point" in d4.note
    with pytest.raises(ValueError, match="has no scene point"):
        hm.distance(img, (0, 0), (3, 4), mode="3d")
    with pytest.raises(ValueError, match="outside the 8 x 6 image"):
        hm.distance(img, (0, 0), (8, 0))


def test_distance_without_positions_is_2d_in_pixels():
    img = LayeredImage(image=np.zeros((10, 10, 3)))
    d = hm.distance(img, (0, 0), (3, 4))
    assert (d.mode, d.unit, d.value) == ("2d", "px", 5.0)
    assert d.note.startswith("no 'position' layer")
    with pytest.raises(MissingLayerError, match="image has no 'position' layer"):
        hm.distance(img, (0, 0), (3, 4), mode="3d")


def test_readout(tmp_path):
    img = _measured(tmp_path)
    r = hm.readout(img, (5, 2))
    assert r["pixel"] == (5, 2) and r["channels"] == {"R": 5.0, "G": 2.0, "B": 7.0}
    assert r["value"] == pytest.approx(0.2126 * 5 + 0.7152 * 2 + 0.0722 * 7, rel=1e-6)
    assert r["unit"] == "cd/m²" and r["hits"] == 3 and r["object_id"] == 1
    assert r["error"] == pytest.approx(0.1) and r["position"] == (2.5, 0.5, 2.0)
    bare = hm.readout(LayeredImage(image=np.ones((2, 2, 1))), (1, 1))
    assert bare["error"] is None and bare["position"] is None and bare["value"] == 1.0


def test_region_stats_and_json_round_trip(tmp_path):
    img = _measured(tmp_path)
    rect = hm.Region.rect(2, 1, 4, 3)  # pixels x 2..3, y 1..2
    s = hm.region_stats(img, rect)
    y = img.luminance()[1:3, 2:4]
    assert s["pixels"] == 4 and s["total_hits"] == 12
    assert s["mean"] == pytest.approx(float(y.mean())) and s["max"] == pytest.approx(float(y.max()))
    assert s["mean_error"] == pytest.approx(0.1)
    tri = hm.Region.polygon([(0, 0), (8, 0), (0, 6)])
    m = tri.mask(6, 8)
    yy, xx = np.mgrid[0:6, 0:8] + 0.5
    np.testing.assert_array_equal(m, xx / 8 + yy / 6 < 1)
    out = hm.save_region(tmp_path / "region.json", img, tri)
    doc = json.loads(out.read_text())
    assert doc["image_size"] == [8, 6] and doc["stats"]["pixels"] == int(m.sum())
    assert hm.load_region(out) == tri
    with pytest.raises(FileExistsError):
        hm.save_region(out, img, tri, overwrite=False)
    with pytest.raises(ValueError, match="contains no pixel"):
        hm.region_stats(img, hm.Region.rect(20, 20, 30, 30))
