"""OpenEXR layouts built by the tests with the OpenEXR bindings (no ../shared needed):
multi-view single part, multi-part with differing data windows, tiled, attributes.
"""

import numpy as np
import OpenEXR
import pytest

import hdrjax.io as hio
from hdrjax.layers import LayeredImage, MissingLayerError


def _win(x0, y0, x1, y1):
    return (np.array([x0, y0], np.int32), np.array([x1, y1], np.int32))


def test_multiview_single_part_y_only(tmp_path):
    """Like Fog.exr: Y is the default view 'left', right.Y the other view."""
    rng = np.random.default_rng(0)
    left = rng.random((6, 8)).astype(np.float16)
    right = rng.random((6, 8)).astype(np.float16)
    header = {
        "compression": OpenEXR.PIZ_COMPRESSION,
        "type": OpenEXR.scanlineimage,
        "multiView": ["left", "right"],
    }
    p = tmp_path / "fog.exr"
    OpenEXR.File(header, {"Y": left, "right.Y": right}).write(str(p))
    img = hio.read(p)
    assert img.channels == ("Y",) and img.attributes["multiView"] == ["left", "right"]
    np.testing.assert_array_equal(img.image[:, :, 0], left.astype(np.float32))
    np.testing.assert_array_equal(img.rgb()[:, :, 2], left.astype(np.float32))
    np.testing.assert_array_equal(img.layers["right"], right.astype(np.float32))
    r = hio.read(p, layer="right")
    np.testing.assert_array_equal(r.image[:, :, 0], right.astype(np.float32))
    np.testing.assert_array_equal(r.layers["left"], left.astype(np.float32))


def test_multiview_rgb_with_view_layers(tmp_path):
    """Like singlepart.0001.exr: default view R,G,B,A,Z plus left.* and layer.view.* ."""
    rng = np.random.default_rng(1)
    ch = {n: rng.random((4, 5)).astype(np.float16) for n in ("R", "G", "B", "A", "Z")}
    ch.update({f"left.{n}": rng.random((4, 5)).astype(np.float16) for n in ("R", "G", "B", "Z")})
    ch["forward.left.u"] = rng.random((4, 5)).astype(np.float16)
    ch["forward.left.v"] = rng.random((4, 5)).astype(np.float16)
    header = {"compression": OpenEXR.ZIPS_COMPRESSION, "type": OpenEXR.scanlineimage}
    header["multiView"] = ["right", "left"]
    p = tmp_path / "sp.exr"
    OpenEXR.File(header, dict(ch)).write(str(p))  # the bindings replace dict values
    img = hio.read(p)
    np.testing.assert_array_equal(img.image[:, :, 1], ch["G"].astype(np.float32))
    np.testing.assert_array_equal(img.layers["alpha"], ch["A"].astype(np.float32))
    np.testing.assert_array_equal(img.layers["depth"], ch["Z"].astype(np.float32))
    assert img.layer_channels["left"] == ("R", "G", "B", "Z")
    assert img.layer_channels["forward.left"] == ("u", "v")
    left = hio.read(p, layer="left")
    np.testing.assert_array_equal(left.image[:, :, 0], ch["left.R"].astype(np.float32))
    np.testing.assert_array_equal(left.layers["depth"], ch["left.Z"].astype(np.float32))
    assert left.layer_channels["right"] == ("R", "G", "B", "A", "Z")


def test_multipart_differing_data_windows(tmp_path):
    """Like multipart.0001.exr: parts with their own data windows inside one display window."""
    rgb = {n: np.full((3, 5), v, np.float16) for n, v in (("R", 1), ("G", 2), ("B", 3))}
    head0 = {
        "compression": OpenEXR.ZIP_COMPRESSION,
        "type": OpenEXR.scanlineimage,
        "dataWindow": _win(2, 3, 6, 5),
        "displayWindow": _win(0, 0, 9, 9),
        "view": "right",
    }
    head1 = dict(head0, dataWindow=_win(4, 3, 8, 5), view="left")
    depth = np.arange(15, dtype=np.float32).reshape(3, 5)
    ids = np.arange(15, dtype=np.uint32).reshape(3, 5)
    parts = [
        OpenEXR.Part(head0, dict(rgb), "rgba_right"),
        OpenEXR.Part(dict(head1), {"Z": depth}, "depth_left"),
        OpenEXR.Part(dict(head1), {"object_id": ids}, "ids"),
    ]
    p = tmp_path / "mp.exr"
    OpenEXR.File(parts).write(str(p))
    img = hio.read(p)
    assert img.attributes["parts"] == ["rgba_right", "depth_left", "ids"]
    assert img.data_window == (2, 3, 6, 5) and img.display_window == (0, 0, 9, 9)
    d = img.layers["depth_left"]
    # x 2..3 lie outside depth_left's window (4..8): NaN, never a silent zero
    assert np.isnan(d[:, :2]).all()
    np.testing.assert_array_equal(d[:, 2:], depth[:, :3])
    oid = img.layers["object_id"]
    assert oid.dtype == np.uint32 and (oid[:, :2] == 0xFFFFFFFF).all()
    np.testing.assert_array_equal(oid[:, 2:], ids[:, :3])
    depth_part = hio.read(p, part="depth_left")
    assert depth_part.data_window == (4, 3, 8, 5) and depth_part.attributes["view"] == "left"
    np.testing.assert_array_equal(depth_part.image[:, :, 0], depth)
    with pytest.raises(MissingLayerError, match="mp.exr has no 'x' part; parts present: "):
        hio.read(p, part="x")
    with pytest.raises(MissingLayerError, match="has no part 7; it has 3 part"):
        hio.read(p, part=7)


def test_tiled_file(tmp_path):
    tiles = OpenEXR.TileDescription()
    tiles.xSize, tiles.ySize = 16, 16
    tiles.mode, tiles.roundingMode = OpenEXR.ONE_LEVEL, OpenEXR.ROUND_DOWN
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.tiledimage, "tiles": tiles}
    a = np.random.default_rng(2).random((40, 50)).astype(np.float16)
    p = tmp_path / "tiled.exr"
    OpenEXR.File(header, {"R": a, "G": a, "B": a}).write(str(p))
    img = hio.read(p)
    np.testing.assert_array_equal(img.image[:, :, 2], a.astype(np.float32))


def test_xyz_primaries_white_luminance_and_envmap(tmp_path):
    """XYZ.exr / Tree.exr style attributes, on a written file."""
    xyz = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1 / 3, 1 / 3)
    img = LayeredImage(
        image=np.random.default_rng(3).random((4, 8, 3)).astype(np.float32),
        chromaticities=xyz,
        white_luminance=621.0,
        projection="equirectangular",
    )
    got = hio.read(hio.write(tmp_path / "xyz.exr", img))
    np.testing.assert_allclose(got.luminance_weights, (0.0, 1.0, 0.0), atol=1e-6)
    np.testing.assert_array_equal(got.luminance(), img.image[:, :, 1])
    assert got.white_luminance == 621.0 and got.projection == "equirectangular"
    assert str(got.attributes["envmap"]) == "ENVMAP_LATLONG"
    np.testing.assert_allclose(got.to_absolute().image, img.image * np.float32(621), rtol=1e-7)


def test_spectral_round_trip(tmp_path):
    wl = np.array([380.0, 450.5, 550.0, 700.25], np.float32)
    img = LayeredImage(
        image=np.random.default_rng(4).random((3, 4, 4)).astype(np.float32),
        layers={"wavelengths": wl},
        quantity="radiance",
    )
    p = hio.write(tmp_path / "spec.exr", img)
    with OpenEXR.File(str(p), separate_channels=True) as f:
        names = sorted(f.parts[0].channels)
        assert f.parts[0].header["spectralLayoutVersion"] == "1.0"
    assert names == ["S0.380,000000nm", "S0.450,500000nm", "S0.550,000000nm", "S0.700,250000nm"]
    got = hio.read(p)
    assert got.kind == "spectral" and got.unit == "W/(sr·m²)"
    np.testing.assert_array_equal(got.wavelengths, wl)
    np.testing.assert_array_equal(got.image, img.image)
    # 4 irregular bands: the cubic spline's minimum; read back, they integrate as written
    np.testing.assert_array_equal(got.rgb(), img.rgb())
    assert got.rgb().shape == (3, 4, 3) and np.isfinite(got.rgb()).all()
    with pytest.raises(ValueError, match="Radiance files hold RGB"):
        hio.write(tmp_path / "spec.hdr", LayeredImage(image=img.image, layers=img.layers))


def test_reflective_spectral_t_channels(tmp_path):
    """Fichet et al. 2021's reflective bands ``T.<λ>nm`` (decimal comma or dot, as another
    program writes them) are the spectral main image; the ``T.`` prefix stays in the channel
    names, so writing keeps them reflective (``T.`` channels, no ``emissiveUnits``)."""
    rng = np.random.default_rng(8)
    planes = {w: rng.random((3, 5)).astype(np.float32) for w in (400.5, 450.0, 500.25)}
    names = {400.5: "T.400,5nm", 450.0: "T.450nm", 500.25: "T.500.25nm"}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    header["spectralLayoutVersion"] = "1.0"
    p = tmp_path / "refl.exr"
    OpenEXR.File(header, {names[w]: a for w, a in planes.items()}).write(str(p))
    got = hio.read(p)
    assert got.kind == "spectral" and not got.layers.keys() - {"wavelengths"}
    assert got.channels == ("T.400,5nm", "T.450nm", "T.500.25nm")
    np.testing.assert_array_equal(got.wavelengths, np.array([400.5, 450.0, 500.25], np.float32))
    np.testing.assert_array_equal(got.image, np.stack(list(planes.values()), axis=2))
    again = hio.write(tmp_path / "refl2.exr", got)
    with OpenEXR.File(str(again), separate_channels=True) as f:
        assert sorted(f.parts[0].channels) == ["T.400,500000nm", "T.450,000000nm", "T.500,250000nm"]
        assert "emissiveUnits" not in f.parts[0].header
    back = hio.read(again)
    assert back.channels == ("T.400,500000nm", "T.450,000000nm", "T.500,250000nm")
    np.testing.assert_array_equal(back.image, got.image)
