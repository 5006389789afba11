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
