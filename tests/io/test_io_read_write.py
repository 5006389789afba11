"""hdrjax.io.read / write / write_display: the entry points the command line uses.

Golden statistics come from ../shared/data/hdr/SOURCES.md (real files, skipped when absent)
and from data/cornell_box.exr (shipped, same numbers in SOURCES.md); every feature is also
checked on files the tests write themselves.
"""

import os
import zlib

import numpy as np
import pytest

import hdrjax.io as hio
from hdrjax import luminance_weights
from hdrjax.layers import LayeredImage, MissingLayerError

from .._png import decode_png
from ..conftest import DATA, shared_file

RTOL_STATS = 2e-3  # SOURCES.md prints 4 significant digits


def _stats(y):
    return float(y.min()), float(y.max()), float(y.mean())


# -- reading real files ------------------------------------------------------------------


def test_read_cornell_box_shipped():
    img = hio.read(DATA / "cornell_box.exr")
    assert img.image.dtype == np.float32 and img.image.shape == (512, 512, 3)
    assert img.pixel_types["image"] == "half"
    assert img.chromaticities is None and img.luminance_weights == (0.2126, 0.7152, 0.0722)
    assert img.quantity == "relative" and img.unit is None
    assert img.path == DATA / "cornell_box.exr"
    lo, hi, mean = _stats(img.luminance())
    # SOURCES.md: min 0, max 12.1, mean 0.1324
    assert lo == 0.0
    assert hi == pytest.approx(12.1, rel=1e-3)
    assert mean == pytest.approx(0.1324, rel=RTOL_STATS)
    assert img.rgb() is img.image


def test_read_carrots_ap0_weights():
    img = hio.read(DATA / "Carrots.exr")
    np.testing.assert_allclose(img.luminance_weights, [0.34397, 0.72817, -0.07213], atol=1e-5)
    assert img.luminance_weights == luminance_weights(img.chromaticities)
    lo, hi, mean = _stats(img.luminance())
    assert (lo, hi, mean) == pytest.approx((-0.04611, 0.9726, 0.1432), rel=RTOL_STATS)
    assert "alpha" in img.layers and img.layers["alpha"].shape == (400, 600)


def test_read_tree_white_luminance_and_primaries():
    img = hio.read(shared_file("Tree.exr"))
    assert img.white_luminance == 621.0
    np.testing.assert_allclose(img.luminance_weights, [0.24994, 0.66502, 0.08504], atol=1e-5)
    absolute = img.to_absolute()
    assert absolute.quantity == "luminance" and absolute.unit == "cd/m²"
    assert float(absolute.luminance().max()) == pytest.approx(621 * 10.62, rel=RTOL_STATS)


def test_read_luminance_chroma_mttamnorth():
    img = hio.read(DATA / "MtTamNorth.exr")
    assert img.channels == ("Y", "RY", "BY") and img.image.shape == (796, 1198, 3)
    rgb = img.rgb()
    y = img.image[:, :, 0]
    # R = (RY + 1) Y, B = (BY + 1) Y, G solved from the Y weights: Y is reproduced exactly
    w = img.luminance_weights
    y_back = rgb[..., 0] * w[0] + rgb[..., 1] * w[1] + rgb[..., 2] * w[2]
    np.testing.assert_allclose(y_back, y, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(rgb[..., 0], (img.image[..., 1] + 1) * y, rtol=1e-6)
    assert _stats(y) == pytest.approx((0.0002975, 7.875, 0.791), rel=RTOL_STATS)
    assert rgb.min() > -0.05  # a plausible photo, not garbage from a bad chroma layout


def test_read_fog_multiview_y_only():
    img = hio.read(shared_file("Fog.exr"))
    assert img.channels == ("Y",)
    rgb = img.rgb()
    assert rgb.shape == (672, 1000, 3) and np.array_equal(rgb[..., 0], rgb[..., 2])
    assert _stats(img.luminance()) == pytest.approx((0.0001301, 50.69, 0.03042), rel=RTOL_STATS)
    right = hio.read(shared_file("Fog.exr"), layer="right")
    assert right.channels == ("Y",) and "left" in right.layers
    assert not np.array_equal(right.image, img.image)


def test_read_multipart_parts_and_windows():
    p = shared_file("multipart.0001.exr")
    img = hio.read(p)
    assert img.attributes["parts"] == [
        "rgba_right",
        "depth_left",
        "forward_left",
        "whitebarmask_left",
        "rgba_left",
        "depth_right",
        "forward_right",
        "disparityL",
        "disparityR",
        "whitebarmask_right",
    ]
    assert img.data_window == (654, 245, 1530, 1120)
    assert img.display_window == (0, 0, 2047, 1555)
    assert img.image.shape == (876, 877, 3)
    assert float(img.luminance().max()) == 0.5
    assert img.luminance().mean() == pytest.approx(0.1973, rel=RTOL_STATS)
    # depth_left has data window x 688..1564: columns left of 688 are outside it (NaN)
    d = img.layers["depth_left"]
    assert d.shape == (876, 877) and np.isnan(d[:, : 688 - 654]).all()
    assert np.isfinite(d[:, 688 - 654 :]).all()
    left = hio.read(p, part="rgba_left")
    assert left.data_window == (688, 245, 1564, 1120) and left.attributes["view"] == "left"
    with pytest.raises(MissingLayerError, match="multipart.0001.exr has no 'nope' part"):
        hio.read(p, part="nope")


def test_read_singlepart_views_and_layers():
    img = hio.read(shared_file("singlepart.0001.exr"))
    assert img.image.shape == (876, 911, 3)
    assert {"alpha", "depth", "left", "forward.left", "disparityL"} <= set(img.layers)
    assert img.layer_channels["left"] == ("R", "G", "B", "A", "Z")
    assert img.luminance().mean() == pytest.approx(0.19, rel=5e-3)
    left = hio.read(shared_file("singlepart.0001.exr"), layer="left")
    np.testing.assert_array_equal(left.image, img.layers["left"][:, :, :3])


def test_read_composited_data_window_and_xyz():
    img = hio.read(shared_file("composited.exr"))
    assert img.data_window == (1, 1, 1022, 574) and img.display_window == (0, 0, 1023, 575)
    assert img.image.shape == (574, 1022, 3)
    xyz = hio.read(shared_file("XYZ.exr"))
    np.testing.assert_allclose(xyz.luminance_weights, [0, 1, 0], atol=1e-6)
    np.testing.assert_array_equal(xyz.luminance(), xyz.image[:, :, 1])


def test_read_tiled_mipmap_latlong():
    img = hio.read(shared_file("StageEnvLatLong.exr"))
    assert img.image.shape == (500, 1000, 3) and img.projection == "equirectangular"
    assert float(img.image.max()) == 4096.0
    assert img.luminance().mean() == pytest.approx(2.712, rel=RTOL_STATS)


@pytest.mark.parametrize(
    "name,stats",
    [
        ("venice_sunset_1k.hdr", (3.344e-5, 2091, 0.4251)),
        ("rooitou_park_1k.hdr", (0.00526, 6.489e4, 0.5237)),
        ("studio_small_03_1k.hdr", (6.131e-5, 3352, 1.848)),
    ],
)
def test_read_radiance_real(name, stats):
    shipped = DATA / name
    img = hio.read(shipped if shipped.exists() else shared_file(name))
    assert img.image.shape == (512, 1024, 3)
    # the Photoshop header says PRIMARIES=0 0 0 0 0 0 0 0: ignored, Rec.709 is used
    assert img.chromaticities is None
    assert _stats(img.luminance()) == pytest.approx(stats, rel=RTOL_STATS)


# -- round trips on files the tests write ------------------------------------------------


def _layered(rng, h=6, w=9):
    return LayeredImage(
        image=rng.normal(size=(h, w, 3)).astype(np.float32) * 50,
        quantity="luminance",
        chromaticities=(0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.077, 0.32168, 0.33767),
        layers={
            "error": rng.random((h, w), dtype=np.float32),
            "hits": rng.integers(0, 2**31, (h, w)).astype(np.uint32),
            "position": rng.normal(size=(h, w, 3)).astype(np.float32),
            "object_id": rng.integers(0, 7, (h, w)).astype(np.uint32),
            "grid": rng.random((h, w, 3), dtype=np.float32),
            "view": {"fov_deg": 60.0, "model": "pinhole"},
            "objects": np.linspace(0, 1, 10).reshape(5, 2),
        },
    )


@pytest.mark.parametrize("pixel_type", ["float", "half"])
def test_exr_round_trip_bit_exact(tmp_path, pixel_type):
    rng = np.random.default_rng(1)
    src = _layered(rng)
    p = hio.write(tmp_path / "scene.exr", src, pixel_type=pixel_type)
    got = hio.read(p)
    cast = (
        (lambda a: a)
        if pixel_type == "float"
        else (lambda a: a.astype(np.float16).astype(np.float32))
    )
    np.testing.assert_array_equal(got.image, cast(src.image))
    assert got.pixel_types["image"] == pixel_type
    assert got.quantity == "luminance" and got.unit == "cd/m²"
    np.testing.assert_allclose(got.chromaticities, src.chromaticities, rtol=1e-7)
    for key in ("error", "position", "grid"):
        np.testing.assert_array_equal(got.layers[key], cast(src.layers[key]))
    for key in ("hits", "object_id"):
        assert got.layers[key].dtype == np.uint32
        np.testing.assert_array_equal(got.layers[key], src.layers[key])
    assert got.layers["view"] == src.layers["view"]
    np.testing.assert_array_equal(got.layers["objects"], src.layers["objects"])
    assert got.layers["objects"].dtype == np.float64
    # re-writing what was read keeps the stored types (half stays half, bit for bit)
    again = hio.read(hio.write(tmp_path / "again.exr", got))
    np.testing.assert_array_equal(again.image, got.image)
    assert again.pixel_types == got.pixel_types


def test_exr_channel_names_follow_conventions(tmp_path):
    import OpenEXR

    p = hio.write(tmp_path / "scene.exr", _layered(np.random.default_rng(2)))
    with OpenEXR.File(str(p), header_only=True) as f:
        names = sorted(f.parts[0].header["channels"], key=str)
    text = " ".join(str(c) for c in names)
    for ch in ('"P.X"', '"P.Y"', '"P.Z"', '"object_id"', '"error"', '"hits"', '"R"', '"G"', '"B"'):
        assert ch in text
    f = OpenEXR.File(str(p), separate_channels=True)
    assert f.parts[0].channels["object_id"].pixels.dtype == np.uint32


def test_exr_multipart_write_and_read(tmp_path):
    src = _layered(np.random.default_rng(3))
    p = hio.write(tmp_path / "mp.exr", src, multipart=True)
    got = hio.read(p)
    assert got.attributes["parts"][0] == "image"
    assert set(got.attributes["parts"][1:]) == {"error", "hits", "position", "object_id", "grid"}
    np.testing.assert_array_equal(got.layers["position"], src.layers["position"])
    np.testing.assert_array_equal(got.layers["object_id"], src.layers["object_id"])
    pos = hio.read(p, part="position")
    assert pos.channels == ("X", "Y", "Z") or pos.image.shape[2] == 3


def test_exr_data_window_round_trip(tmp_path):
    img = LayeredImage(
        image=np.arange(12, dtype=np.float32).reshape(3, 4, 1),
        data_window=(5, 7, 8, 9),
        display_window=(0, 0, 19, 19),
    )
    got = hio.read(hio.write(tmp_path / "dw.exr", img))
    assert got.data_window == (5, 7, 8, 9) and got.display_window == (0, 0, 19, 19)
    np.testing.assert_array_equal(got.image, img.image)


def test_read_layer_selection_and_missing_layer_message(tmp_path):
    src = LayeredImage(
        image=np.ones((2, 3, 3), np.float32),
        layers={"error": np.zeros((2, 3), np.float32), "hits": np.ones((2, 3), np.uint32)},
    )
    p = hio.write(tmp_path / "Scene.exr", src)
    with pytest.raises(MissingLayerError) as e:
        hio.read(p, layer="position")
    assert str(e.value) == "Scene.exr has no 'position' layer; layers present: error, hits"
    assert isinstance(e.value, hio.ReadError) and isinstance(e.value, ValueError)
    err = hio.read(p, layer="error")
    assert err.image.shape == (2, 3, 1) and float(err.image.max()) == 0.0


def test_radiance_round_trip_precision(tmp_path):
    rng = np.random.default_rng(4)
    rgb = np.exp(rng.normal(0, 3, (37, 50, 3))).astype(np.float32)
    for rle in (True, False):
        p = hio.write(tmp_path / f"x{rle}.hdr", rgb, rle=rle)
        got = hio.read(p).image
        # RGBE: 8-bit mantissa shared by the channels -> error < 2^-7 of the largest channel
        bound = rgb.max(axis=2, keepdims=True) * 2.0**-7
        assert np.all(np.abs(got - rgb) <= bound)
        assert np.all(got <= rgb)  # truncation on encode, no offset on decode
    # decode -> encode -> decode is exact
    got = hio.read(tmp_path / "xTrue.hdr").image
    np.testing.assert_array_equal(hio.read(hio.write(tmp_path / "y.hdr", got)).image, got)


def test_pfm_round_trip_and_layout(tmp_path):
    rng = np.random.default_rng(5)
    rgb = rng.normal(size=(4, 5, 3)).astype(np.float32)
    p = hio.write(tmp_path / "a.pfm", rgb)
    np.testing.assert_array_equal(hio.read(p).image, rgb)
    raw = p.read_bytes()
    assert raw.startswith(b"PF\n5 4\n-1.0\n")
    # first stored row is the bottom image row, little-endian
    first = np.frombuffer(raw[len(b"PF\n5 4\n-1.0\n") :][: 5 * 3 * 4], "<f4").reshape(5, 3)
    np.testing.assert_array_equal(first, rgb[-1])
    # big-endian 'Pf' (grey) with scale +1
    grey = rgb[:, :, 0]
    (tmp_path / "b.pfm").write_bytes(b"Pf\n5 4\n1.0\n" + grey[::-1].astype(">f4").tobytes())
    got = hio.read(tmp_path / "b.pfm")
    assert got.channels == ("Y",)
    np.testing.assert_array_equal(got.image[:, :, 0], grey)
    np.testing.assert_array_equal(got.rgb()[:, :, 1], grey)


def test_rgb_of_spectral_images():
    """A flat emissive spectrum of 1 W/(sr·m²·nm) over 400–700 nm (held constant beyond, as
    colour-science extrapolates) has Y = 683 lm/W × ΣV(λ) over 360–830 nm at 1 nm; its RGB
    with the working-space weights gives that luminance back. Too few bands to interpolate
    raise a one-line error naming the image."""
    import colour

    img = LayeredImage(
        image=np.ones((2, 2, 31), np.float32),
        layers={"wavelengths": np.arange(400, 701, 10, dtype=np.float32)},
    )
    assert img.kind == "spectral"
    v = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].values[:, 1].sum()
    np.testing.assert_allclose(img.luminance(), 683.0 * v, rtol=1e-5)
    y = img.rgb() @ np.asarray(img.luminance_weights_in())
    np.testing.assert_allclose(y, 683.0 * v, rtol=1e-5)
    four = LayeredImage(
        image=np.ones((2, 2, 4), np.float32),
        layers={"wavelengths": np.array([400, 500, 600, 700], np.float32)},
    )
    with pytest.raises(ValueError, match=r"^image: wavelengths: expected at least 6 regularly"):
        four.rgb()


# -- display export ----------------------------------------------------------------------


@pytest.mark.parametrize("bits", [8, 16])
def test_write_display_png(tmp_path, bits):
    rng = np.random.default_rng(6)
    d = rng.random((7, 11, 3)).astype(np.float32)
    d[0, 0] = [-0.5, 1.5, np.nan]  # clipped / zeroed
    p = hio.write_display(tmp_path / "o.png", d, bits=bits)
    px, chunks = decode_png(p.read_bytes())
    top = (1 << bits) - 1
    want = np.round(np.clip(np.nan_to_num(d), 0, 1) * top).astype(np.uint16)
    np.testing.assert_array_equal(px.astype(np.uint16), want)
    assert chunks[b"sRGB"] == b"\x00"


def test_write_display_compression_level(tmp_path):
    """The zlib level changes the size of the IDAT stream, never the pixels; the level
    written is the one asked for (zlib's header records levels 0-1 / 2-5 / 6 / 7-9)."""
    rng = np.random.default_rng(8)
    gx, gy = np.meshgrid(np.linspace(0, 1, 96), np.linspace(0, 1, 64))
    d = np.stack([gx, gy, 0.5 + 0.01 * rng.standard_normal(gx.shape)], axis=2).astype(np.float32)
    sizes, want = {}, np.round(np.clip(d, 0, 1) * 255)
    for level, flevel in ((0, 0), (1, 0), (2, 0), (6, 2), (9, 3)):
        p = hio.write_display(tmp_path / f"o{level}.png", d, compression=level)
        px, chunks = decode_png(p.read_bytes())
        np.testing.assert_array_equal(px, want)
        assert chunks[b"IDAT"][1] >> 6 == flevel  # FLEVEL bits of the zlib header
        sizes[level] = len(chunks[b"IDAT"])
        filt = zlib.decompress(chunks[b"IDAT"])[0]
        assert filt == (0 if level == 0 else 1)  # None when stored, else Sub
    assert sizes[0] > sizes[1] > sizes[9]
    # the default: what OpenCV writes (level 1, Sub rows, run-length matching)
    import cv2  # installed by `make test` (the bench extra)

    code = (want[..., ::-1]).astype(np.uint8)
    ok, ref = cv2.imencode(".png", code)
    assert ok
    p = hio.write_display(tmp_path / "default.png", d)
    _, chunks = decode_png(p.read_bytes())
    assert abs(len(chunks[b"IDAT"]) - len(ref.tobytes())) < 0.05 * len(ref.tobytes())
    pt = hio.write_display(tmp_path / "o.tif", d, compression=1)
    from PIL import Image

    with Image.open(pt) as im:
        np.testing.assert_array_equal(np.asarray(im), want)
    for bad in (-1, 10, 2.5, True, "6"):
        with pytest.raises(ValueError, match="compression"):
            hio.write_display(tmp_path / "bad.png", d, compression=bad)
    assert not (tmp_path / "bad.png").exists()


def test_write_display_jpeg_tiff_and_integers(tmp_path):
    from PIL import Image

    rng = np.random.default_rng(7)
    code8 = rng.integers(0, 256, (8, 10, 3)).astype(np.uint8)
    p = hio.write_display(tmp_path / "o.tif", code8)
    with Image.open(p) as im:
        np.testing.assert_array_equal(np.asarray(im), code8)
        assert "icc_profile" in im.info
    code16 = rng.integers(0, 65536, (8, 10, 3)).astype(np.uint16)
    p16 = hio.write_display(tmp_path / "o16.tif", code16, bits=16)
    raw = p16.read_bytes()
    assert raw[:4] == b"II*\x00"
    cv2 = pytest.importorskip("cv2")
    np.testing.assert_array_equal(cv2.imread(str(p16), cv2.IMREAD_UNCHANGED)[:, :, ::-1], code16)
    gx, gy = np.meshgrid(np.linspace(0, 1, 40), np.linspace(0.2, 0.8, 24))
    smooth = np.stack([gx, gy, np.full_like(gx, 0.5)], axis=2)
    pj = hio.write_display(tmp_path / "o.jpg", smooth)
    with Image.open(pj) as im:
        assert im.size == (40, 24) and "icc_profile" in im.info
        assert np.abs(np.asarray(im) / 255.0 - smooth).max() < 0.03
    with pytest.raises(ValueError, match="JPEG holds 8 bits"):
        hio.write_display(tmp_path / "o2.jpg", code8, bits=16)
    # uint8 promoted to 16 bits exactly (x 257)
    px, _ = decode_png(hio.write_display(tmp_path / "p.png", code8, bits=16).read_bytes())
    np.testing.assert_array_equal(px, code8.astype(np.uint16) * 257)


def test_write_display_overwrite_refusal(tmp_path):
    p = tmp_path / "o.png"
    hio.write_display(p, np.zeros((2, 2, 3)))
    before = p.read_bytes()
    with pytest.raises(FileExistsError):
        hio.write_display(p, np.ones((2, 2, 3)), overwrite=False)
    assert p.read_bytes() == before


# -- atomic writes -----------------------------------------------------------------------


def test_failed_write_keeps_old_file(tmp_path, monkeypatch):
    p = tmp_path / "keep.hdr"
    hio.write(p, np.ones((4, 9, 3), np.float32))
    before = p.read_bytes()

    from hdrjax.io import _rgbe

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(_rgbe, "encode_rgbe", boom)
    with pytest.raises(OSError, match="disk full"):
        hio.write(p, np.zeros((4, 9, 3), np.float32))
    assert p.read_bytes() == before
    assert os.listdir(tmp_path) == ["keep.hdr"]


def test_failed_exr_write_leaves_no_temporary(tmp_path, monkeypatch):
    p = tmp_path / "scene.exr"
    hio.write(p, np.ones((2, 2, 3), np.float32))
    before = p.read_bytes()
    from hdrjax.io import _exr

    def half_written(path, *a, **k):
        path.write_bytes(b"\x76\x2f\x31\x01partial")
        raise OSError("crash while writing")

    monkeypatch.setattr(_exr, "write_exr", half_written)
    with pytest.raises(OSError, match="crash while writing"):
        hio.write(p, np.zeros((2, 2, 3), np.float32))
    assert p.read_bytes() == before
    assert os.listdir(tmp_path) == ["scene.exr"]


# SOURCES.md table: (file, width, height, Y min, Y max, Y mean), Y in the file's own units
SOURCES_TABLE = [
    ("rooitou_park_1k.hdr", 1024, 512, 0.00526, 6.489e4, 0.5237),
    ("venice_sunset_1k.hdr", 1024, 512, 3.344e-5, 2091, 0.4251),
    ("empty_warehouse_01_1k.hdr", 1024, 512, 0.004586, 400.3, 0.6478),
    ("studio_small_03_1k.hdr", 1024, 512, 6.131e-5, 3352, 1.848),
    ("StageEnvLatLong.exr", 1000, 500, 0.0006271, 4096, 2.712),
    ("Desk.exr", 644, 874, -0.008582, 201.7, 5.821),
    ("MtTamWest.exr", 1214, 732, 0.0003367, 3.886, 0.3363),
    ("StillLife.exr", 1240, 846, 0, 229.1, 0.08883),
    ("Tree.exr", 928, 906, 0, 10.62, 0.918),
    ("CandleGlass.exr", 1000, 810, -0.0001963, 212.5, 0.07277),
    ("Carrots.exr", 600, 400, -0.04611, 0.9726, 0.1432),
    ("MtTamNorth.exr", 1198, 796, 0.0002975, 7.875, 0.791),
    ("Fog.exr", 1000, 672, 0.0001301, 50.69, 0.03042),
    ("multipart.0001.exr", 877, 876, 0, 0.5, 0.1973),
    ("singlepart.0001.exr", 911, 876, 0, 0.5, 0.19),
    ("composited.exr", 1022, 574, 0, 0.5343, 0.08616),
    ("XYZ.exr", 610, 406, 0.005844, 4.918, 0.2847),
    ("cornell_box.exr", 512, 512, 0, 12.1, 0.1324),
]


@pytest.mark.parametrize("name,w,h,lo,hi,mean", SOURCES_TABLE, ids=[r[0] for r in SOURCES_TABLE])
def test_every_real_file_matches_sources_md(name, w, h, lo, hi, mean):
    shipped = DATA / name
    img = hio.read(shipped if shipped.exists() else shared_file(name))
    assert (img.width, img.height) == (w, h)
    y = img.luminance()
    assert float(y.min()) == pytest.approx(lo, rel=RTOL_STATS, abs=1e-9)
    assert float(y.max()) == pytest.approx(hi, rel=RTOL_STATS)
    assert float(y.mean(dtype=np.float64)) == pytest.approx(mean, rel=RTOL_STATS)
    assert img.rgb().shape == (h, w, 3)


@pytest.mark.parametrize("shape", [(0, 8, 3), (8, 0), (0, 8, 4)])
@pytest.mark.parametrize("ext", ["exr", "hdr", "pfm", "png"])
def test_empty_image_is_not_written(tmp_path, ext, shape):
    """No format holds an empty image (Radiance and PFM wrote files no reader opens; OpenEXR
    failed with a multi-line library error): a one-line ValueError naming the argument and
    the shape, and no file (issue 16.4)."""
    write = hio.write_display if ext == "png" else hio.write
    name = "display image" if ext == "png" else "image"
    with pytest.raises(ValueError) as err:
        write(tmp_path / f"x.{ext}", np.zeros(shape, np.float32))
    msg = str(err.value)
    assert msg.startswith(f"{name}: expected a non-empty image (H, W)"), msg
    assert msg.endswith(f"with H, W >= 1, got shape {shape}") and "\n" not in msg, msg
    assert list(tmp_path.iterdir()) == []
