"""Bad input raises hdrjax's ReadError (a ValueError) naming the file, and nothing else:
hand-made corruptions plus fuzz-style random truncations and byte flips of real files.
"""

import struct

import numpy as np
import pytest

import hdrjax.io as hio
from hdrjax.io import ReadError
from hdrjax.layers import LayeredImage, LayerShapeError

from ..conftest import DATA


def _small_exr(tmp_path, **kw):
    img = LayeredImage(
        image=np.random.default_rng(0).random((8, 12, 3)).astype(np.float32),
        layers={
            "object_id": np.arange(96, dtype=np.uint32).reshape(8, 12),
            "view": {"fov_deg": 45.0},
        },
        **kw,
    )
    return hio.write(tmp_path / "small.exr", img, pixel_type="half")


def _expect_read_error(p, *fragments):
    with pytest.raises(ReadError) as e:
        hio.read(p)
    msg = str(e.value)
    assert msg.startswith(p.name + ":") and "\n" not in msg, msg
    for f in fragments:
        assert f in msg, msg
    return msg


def test_exr_bad_magic_and_truncation(tmp_path):
    p = tmp_path / "notexr.exr"
    p.write_bytes(b"\x76\x2f\x31\x02" + b"\0" * 100)
    _expect_read_error(p, "not an OpenEXR file (bad magic number)")
    src = _small_exr(tmp_path).read_bytes()
    t = tmp_path / "trunc.exr"
    t.write_bytes(src[: len(src) // 2])
    _expect_read_error(t, "corrupt")


def test_exr_absurd_data_window(tmp_path):
    raw = bytearray(_small_exr(tmp_path).read_bytes())
    key = b"dataWindow\x00box2i\x00"
    at = raw.index(key) + len(key) + 4  # after the attribute size
    raw[at + 8 : at + 16] = struct.pack("<ii", 2**30, 2**30)
    p = tmp_path / "huge.exr"
    p.write_bytes(bytes(raw))
    _expect_read_error(p)


def test_exr_unknown_pixel_type(tmp_path):
    raw = bytearray(_small_exr(tmp_path).read_bytes())
    at = raw.index(b"chlist\x00") + len(b"chlist\x00") + 4
    at = raw.index(b"B\x00", at) + 2
    raw[at : at + 4] = struct.pack("<i", 9)
    p = tmp_path / "ptype.exr"
    p.write_bytes(bytes(raw))
    _expect_read_error(p)


def test_exr_corrupt_non_grid_layer_attribute(tmp_path):
    import OpenEXR

    p = tmp_path / "attr.exr"
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    header["hdrjax.layer.view"] = "{not json"
    OpenEXR.File(header, {"Y": np.ones((2, 2), np.float32)}).write(str(p))
    _expect_read_error(p, "corrupt non-grid layer attribute 'hdrjax.layer.view'")


def test_layer_shape_disagreeing_with_image():
    with pytest.raises(LayerShapeError, match="layer 'position' has shape"):
        LayeredImage(image=np.zeros((4, 5, 3)), layers={"position": np.zeros((4, 5, 2))})
    with pytest.raises(LayerShapeError, match="layer 'error' has shape"):
        LayeredImage(image=np.zeros((4, 5, 3)), layers={"error": np.zeros((5, 4))})
    with pytest.raises(LayerShapeError, match="'wavelengths' layer has 3 entries"):
        LayeredImage(image=np.zeros((4, 5, 4)), layers={"wavelengths": np.arange(3.0)})
    with pytest.raises(ReadError, match="'object_id' must hold integers"):
        LayeredImage(image=np.zeros((1, 2, 3)), layers={"object_id": np.array([[0.5, 1]])})


def test_sidecar_with_wrong_size(tmp_path):
    hio.write(tmp_path / "scene.exr", np.ones((4, 6, 3), np.float32))
    hio.write(tmp_path / "scene.position.exr", np.ones((5, 6, 3), np.float32))
    with pytest.raises(ReadError, match="scene.position.exr: sidecar layer 'position' is 6 x 5"):
        hio.read(tmp_path / "scene.exr")


def test_unknown_extension_and_missing_file(tmp_path):
    p = tmp_path / "x.bmp"
    p.write_bytes(b"BM" + b"\0" * 50)
    _expect_read_error(p, "unknown image format '.bmp'")
    with pytest.raises(FileNotFoundError, match="no such file"):
        hio.read(tmp_path / "missing.exr")
    with pytest.raises(ValueError, match="unknown HDR format '.bmp'"):
        hio.write(tmp_path / "y.bmp", np.ones((2, 2, 3)))


def _fuzz(src, tmp_path, n, seed):
    """Random truncations, single and multiple byte flips of ``src``; only ReadError allowed."""
    data = src.read_bytes()
    rng = np.random.default_rng(seed)
    outcomes = {"ok": 0, "error": 0}
    for i in range(n):
        d = bytearray(data)
        kind = i % 3
        if kind == 0:
            d = d[: int(rng.integers(0, len(d)))]
        elif kind == 1:
            for _ in range(int(rng.integers(1, 16))):
                d[int(rng.integers(0, len(d)))] = int(rng.integers(0, 256))
        else:  # headers are where parsers break: flip inside the first 600 bytes
            d[int(rng.integers(0, min(len(d), 600)))] = int(rng.integers(0, 256))
        p = tmp_path / f"fuzz{src.suffix}"
        p.write_bytes(bytes(d))
        try:
            img = hio.read(p, sidecars=False)
        except ReadError as e:
            assert str(e).startswith("fuzz") and "\n" not in str(e), str(e)
            outcomes["error"] += 1
        else:
            assert img.image.dtype == np.float32 and img.image.ndim == 3
            outcomes["ok"] += 1
    assert outcomes["error"] > 0  # truncations must be caught, not read as garbage
    return outcomes


def test_fuzz_exr_written(tmp_path):
    _fuzz(_small_exr(tmp_path), tmp_path, 90, seed=1)


def test_fuzz_exr_real(tmp_path):
    _fuzz(DATA / "Carrots.exr", tmp_path, 45, seed=2)
    _fuzz(DATA / "MtTamNorth.exr", tmp_path, 30, seed=3)


def test_fuzz_radiance(tmp_path):
    small = hio.write(tmp_path / "small.hdr", np.random.default_rng(5).random((16, 40, 3)) * 10)
    _fuzz(small, tmp_path, 90, seed=4)
    _fuzz(DATA / "venice_sunset_1k.hdr", tmp_path, 30, seed=5)


def test_fuzz_pfm(tmp_path):
    small = hio.write(tmp_path / "small.pfm", np.random.default_rng(6).random((8, 9, 3)))
    _fuzz(small, tmp_path, 60, seed=6)


def _read_ok_or_read_error(p, **kw):
    """hdrjax's one-line ReadError naming the file, or an image of the documented form."""
    try:
        img = hio.read(p, **kw)
    except ReadError as e:
        msg = str(e)
        assert "\n" not in msg and msg.split(":")[0].endswith(p.suffix), msg
        return None
    assert img.image.dtype == np.float32 and img.image.ndim == 3
    return img


# header edits: each replaces one header field of a valid small file with a hostile value
RADIANCE_EDITS = [
    (b"-Y 16 +X 40", b"-Y 0 +X 40"),
    (b"-Y 16 +X 40", b"-Y 99999999 +X 99999999"),
    (b"-Y 16 +X 40", b"-Y 16 +X -5"),
    (b"-Y 16 +X 40", b"-Y 16"),
    (b"-Y 16 +X 40", b"+Y 16 -Y 40"),
    (b"-Y 16 +X 40", b"-Y 1.5e3 +X 40"),
    (b"-Y 16 +X 40", b"+X 40 -Y 16"),  # valid: a transposed orientation
    (b"FORMAT=32-bit_rle_rgbe", b"FORMAT=bogus"),
    (b"FORMAT=32-bit_rle_rgbe", b"FORMAT=32-bit_rle_xyze"),  # valid: XYZ
    (b"FORMAT=32-bit_rle_rgbe\n", b"FORMAT=32-bit_rle_rgbe\nEXPOSURE=0\n"),
    (b"FORMAT=32-bit_rle_rgbe\n", b"FORMAT=32-bit_rle_rgbe\nEXPOSURE=nan\n"),
    (b"FORMAT=32-bit_rle_rgbe\n", b"FORMAT=32-bit_rle_rgbe\nPRIMARIES=0 0 0 0 0 0 0 0\n"),
    (b"\n\n-Y", b"\n-Y"),  # no blank line ending the header
    (b"#?RADIANCE", b"#?RGBE"),
]
PFM_EDITS = [
    (b"9 8\n", b"0 8\n"),
    (b"9 8\n", b"-9 8\n"),
    (b"9 8\n", b"99999999 99999999\n"),
    (b"9 8\n", b"9\n"),
    (b"9 8\n", b"9 8 7\n"),
    (b"-1.0\n", b"0\n"),
    (b"-1.0\n", b"nan\n"),
    (b"-1.0\n", b"abc\n"),
    (b"-1.0\n", b"1.0\n"),  # valid: big-endian scale, values byte-swapped
    (b"PF\n", b"Pf\n"),  # greyscale header on 3-channel data
    (b"PF\n", b"PX\n"),
]
EXR_EDITS = [
    (
        b"compression\x00compression\x00\x01\x00\x00\x00\x03",
        b"compression\x00compression\x00\x01\x00\x00\x00\x63",
    ),
    (
        b"lineOrder\x00lineOrder\x00\x01\x00\x00\x00\x00",
        b"lineOrder\x00lineOrder\x00\x01\x00\x00\x00\x07",
    ),
    (b"\x76\x2f\x31\x01\x02\x00\x00\x00", b"\x76\x2f\x31\x01\x02\x02\x00\x00"),  # tiled flag
    (b"\x76\x2f\x31\x01\x02\x00\x00\x00", b"\x76\x2f\x31\x01\x09\x00\x00\x00"),  # version 9
    (b"B\x00", b"\xff\x00"),  # a channel name byte
]


def _edits(src, edits):
    for old, new in edits:
        if old in src:
            yield src.replace(old, new, 1)


def test_header_edits(tmp_path):
    rng = np.random.default_rng(8)
    hdr = hio.write(tmp_path / "e.hdr", rng.random((16, 40, 3)) * 10).read_bytes()
    pfm = hio.write(tmp_path / "e.pfm", rng.random((8, 9, 3))).read_bytes()
    exr = _small_exr(tmp_path).read_bytes()
    outcomes = []
    for src, edits, suffix in (
        (hdr, RADIANCE_EDITS, ".hdr"),
        (pfm, PFM_EDITS, ".pfm"),
        (exr, EXR_EDITS, ".exr"),
    ):
        n = 0
        for data in _edits(src, edits):
            p = tmp_path / f"edit{suffix}"
            p.write_bytes(data)
            outcomes.append(_read_ok_or_read_error(p, sidecars=False) is None)
            n += 1
        assert n == len(edits), f"{suffix}: some edits no longer match the written header"
    assert sum(outcomes) >= len(outcomes) // 2  # most edits are errors, not garbage images


def test_fuzz_sidecars(tmp_path):
    """A corrupt sidecar layer (truncated, flipped bytes) fails the read of the main image
    with ReadError naming the sidecar, or the image reads correctly."""
    main = np.random.default_rng(9).random((6, 8, 3)).astype(np.float32)
    hio.write(tmp_path / "scene.exr", main)
    good = hio.write(tmp_path / "scene.position.exr", np.ones((6, 8, 3), np.float32))
    data = good.read_bytes()
    rng = np.random.default_rng(10)
    errors = 0
    for i in range(30):
        d = bytearray(data)
        if i % 2:
            d = d[: int(rng.integers(0, len(d)))]
        else:
            for _ in range(int(rng.integers(1, 8))):
                d[int(rng.integers(0, min(len(d), 400)))] = int(rng.integers(0, 256))
        good.write_bytes(bytes(d))
        try:
            img = hio.read(tmp_path / "scene.exr")
        except ReadError as e:
            assert "scene.position.exr" in str(e) and "\n" not in str(e), str(e)
            errors += 1
        else:
            np.testing.assert_array_equal(img.image, main)
    assert errors > 0
