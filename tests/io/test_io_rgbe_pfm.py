"""Radiance RGBE and PFM details: header quirks, orientations, RLE flavours, errors."""

import numpy as np
import pytest

import hdrjax.io as hio
from hdrjax.io import ReadError, _rgbe

from ..conftest import DATA


def _pixels(h, w, seed=0):
    rng = np.random.default_rng(seed)
    return np.exp(rng.normal(0, 2, (h, w, 3))).astype(np.float32)


def _quant(rgb):
    """What RGBE can hold of ``rgb``: encode, then decode."""
    m = _rgbe.float_to_rgbe(rgb)
    return _rgbe.rgbe_to_float(m[..., :3], m[..., 3])


def _flat(head: str, px: np.ndarray) -> bytes:
    return head.encode() + _rgbe.float_to_rgbe(px).tobytes()


def test_rle_matches_flat_and_opencv_convention(tmp_path):
    rgb = _pixels(20, 33)
    quant = _quant(rgb)
    # exponent table: value = m * 2^(E - 136), exactly what OpenCV / rgbe.c decode
    m = _rgbe.float_to_rgbe(rgb)
    np.testing.assert_array_equal(
        quant, m[..., :3].astype(np.float32) * np.ldexp(1.0, m[..., 3:4].astype(int) - 136)
    )
    rle = hio.read(hio.write(tmp_path / "rle.hdr", rgb)).image
    flat = hio.read(hio.write(tmp_path / "flat.hdr", rgb, rle=False)).image
    np.testing.assert_array_equal(rle, quant)
    np.testing.assert_array_equal(flat, quant)
    assert (tmp_path / "rle.hdr").read_bytes().split(b"+X 33\n")[1][:4] == b"\x02\x02\x00\x21"


def test_rle_with_false_scanline_headers(tmp_path):
    """Pixel data that contains the scanline-header byte pattern must not confuse the reader."""
    w = 16
    rgb = _pixels(6, w, seed=1)
    m = _rgbe.float_to_rgbe(rgb)
    m[:, 3:7, 0] = [2, 2, 0, w]  # R mantissas spell '2 2 0 16' inside a literal run
    m[:, 3:7, 3] = 130
    rgb = _rgbe.rgbe_to_float(m[..., :3], m[..., 3])
    data = _rgbe.encode_rgbe(rgb)
    assert data.count(bytes([2, 2, 0, w])) > 6  # more candidates than scanlines
    got, _ = _rgbe.decode_rgbe_float(data)
    np.testing.assert_array_equal(got, rgb)


def test_long_runs_and_constant_image(tmp_path):
    rgb = np.zeros((5, 600, 3), np.float32)
    rgb[:, 100:400] = 7.0
    rgb[2, 500] = 1e-40  # below the RGBE range (1e-32): stored as zero
    got = hio.read(hio.write(tmp_path / "c.hdr", rgb)).image
    expect = rgb.copy()
    expect[2, 500] = 0
    np.testing.assert_array_equal(got, expect)
    assert (tmp_path / "c.hdr").stat().st_size < 5 * 600  # runs compress


def test_header_quirks_view_first_exposure_colorcorr_primaries(tmp_path):
    rgb = _pixels(4, 5)
    quant = _quant(rgb)
    head = (
        "VIEW= -vtv -vp 0 0 0 -vd 0 1 0\n#?RADIANCE\n# comment\nEXPOSURE=2\nEXPOSURE=0.5e1\n"
        "COLORCORR=1 2 4\nPRIMARIES=0 0 0 0 0 0 0 0\nGAMMA=1\nFORMAT=32-bit_rle_rgbe\n\n"
        "-Y 4 +X 5\n"
    )
    p = tmp_path / "quirks.hdr"
    p.write_bytes(_flat(head, rgb))
    img = hio.read(p)
    # original radiance = pixel / (EXPOSURE product * COLORCORR)
    np.testing.assert_allclose(
        img.image, quant / (10.0 * np.array([1, 2, 4], np.float32)), rtol=1e-6
    )
    assert img.chromaticities is None and img.attributes["exposure"] == 10.0
    valid = head.replace(
        "PRIMARIES=0 0 0 0 0 0 0 0", "PRIMARIES=0.64 0.33 0.3 0.6 0.15 0.06 0.3333 0.3333"
    )
    p.write_bytes(_flat(valid, rgb))
    assert hio.read(p).chromaticities == (0.64, 0.33, 0.3, 0.6, 0.15, 0.06, 0.3333, 0.3333)


def test_real_file_photoshop_header_and_round_trip(tmp_path):
    p = DATA / "venice_sunset_1k.hdr"
    raw = p.read_bytes()
    assert b"PRIMARIES=0 0 0 0 0 0 0 0" in raw[:200]
    mant, exp, info = _rgbe.decode_rgbe(raw, p.name)
    assert (info["width"], info["height"], info["orientation"]) == (1024, 512, "-Y +X")
    # decode -> encode -> decode is bit-exact on real data
    img = hio.read(p)
    again, _ = _rgbe.decode_rgbe_float(_rgbe.encode_rgbe(img.image))
    np.testing.assert_array_equal(again, img.image)
    np.testing.assert_array_equal(img.image, _rgbe.rgbe_to_float(mant, exp))


@pytest.mark.parametrize(
    "res,transform",
    [
        ("-Y 4 +X 6", lambda a: a),
        ("+Y 4 +X 6", lambda a: a[::-1]),
        ("-Y 4 -X 6", lambda a: a[:, ::-1]),
        ("+Y 4 -X 6", lambda a: a[::-1, ::-1]),
        ("+X 6 -Y 4", lambda a: a.transpose(1, 0, 2)),
        ("+X 6 +Y 4", lambda a: a[::-1].transpose(1, 0, 2)),
        ("-X 6 -Y 4", lambda a: a[:, ::-1].transpose(1, 0, 2)),
        ("-X 6 +Y 4", lambda a: a[::-1, ::-1].transpose(1, 0, 2)),
    ],
)
def test_all_eight_orientations(tmp_path, res, transform):
    """The file stores `transform(image)` scanline by scanline; the reader undoes it."""
    rgb = _pixels(4, 6, seed=3)
    quant = _quant(rgb)
    stored = np.ascontiguousarray(transform(rgb))
    p = tmp_path / "o.hdr"
    p.write_bytes(_flat(f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n{res}\n", stored))
    np.testing.assert_array_equal(hio.read(p).image, quant)


def test_old_style_rle(tmp_path):
    px = _rgbe.float_to_rgbe(_pixels(2, 10, seed=4))
    # first scanline: pixel 0, then "repeat 3 times", then pixels 4..9
    line0 = [px[0, 0], np.array([1, 1, 1, 3], np.uint8), *px[0, 4:]]
    data = b"#?RADIANCE\n\n-Y 2 +X 10\n" + b"".join(p.tobytes() for p in line0) + px[1].tobytes()
    p = tmp_path / "old.hdr"
    p.write_bytes(data)
    got = _rgbe.decode_rgbe(data)[0]
    expect = px[..., :3].copy()
    expect[0, 1:4] = px[0, 0, :3]
    np.testing.assert_array_equal(got, expect)


def test_xyze_format_is_xyz():
    data = _flat("#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 2 +X 3\n", _pixels(2, 3))
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "xyz.hdr"
        p.write_bytes(data)
        img = hio.read(p)
    np.testing.assert_allclose(img.luminance_weights, (0, 1, 0), atol=1e-6)


@pytest.mark.parametrize(
    "data,message",
    [
        (
            b"P6\n1 1\n255\n\x00\x00\x00",
            "not a Radiance file (missing '#?RADIANCE' or '#?RGBE' header)",
        ),
        (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n", "truncated Radiance header"),
        (b"#?RADIANCE\n\n-Y 10 *X 10\n", "bad Radiance resolution line"),
        (b"#?RADIANCE\n\n-Y 99999999 +X 99999999\n", "absurd Radiance image size"),
        # a file that would decode to no rows or no columns (issue 16.4)
        (b"#?RADIANCE\n\n-Y 0 +X 8\n", "empty Radiance image 0 x 8; expected at least 1 x 1"),
        (b"#?RADIANCE\n\n-Y 8 +X 0\n", "empty Radiance image 8 x 0; expected at least 1 x 1"),
        (b"#?RADIANCE\n\n-Y 60000 +X 60000\n\x02\x02\xea\x60", "truncated Radiance file"),
        (
            b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 8\n"
            + bytes([2, 2, 0, 8, 200, 1])
            + b"\0" * 60,
            "corrupt",
        ),
        (b"#?RADIANCE\nFORMAT=16-bit_float\n\n-Y 1 +X 1\n\0\0\0\0", "unsupported Radiance FORMAT"),
        (b"#?RADIANCE\nEXPOSURE=-1\n\n-Y 1 +X 1\n\0\0\0\0", "bad Radiance EXPOSURE"),
    ],
)
def test_radiance_errors(tmp_path, data, message):
    p = tmp_path / "x.hdr"
    p.write_bytes(data)
    with pytest.raises(ReadError) as e:
        hio.read(p)
    assert str(e.value).startswith("x.hdr: ")
    assert message in str(e.value)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize(
    "data,message",
    [
        (b"P7\n", "not a PFM file (expected 'PF' or 'Pf' magic)"),
        (b"PF\n2 x\n-1\n", "malformed PFM header"),
        (b"PF\n2 2\n0\n" + b"\0" * 48, "bad PFM scale"),
        (b"Pf\n2 2\n-1\n" + b"\0" * 15, "truncated PFM file"),
        (b"PF\n100000 100000\n-1\n" + b"\0" * 12, "truncated PFM file"),
        (b"PF\n9999999 9999999\n-1\n", "absurd PFM image size"),
        (b"PF\n0 8\n-1\n", "empty PFM image 0 x 8; expected at least 1 x 1"),
        (b"Pf\n8 0\n-1\n", "empty PFM image 8 x 0; expected at least 1 x 1"),
    ],
)
def test_pfm_errors(tmp_path, data, message):
    p = tmp_path / "x.pfm"
    p.write_bytes(data)
    with pytest.raises(ReadError, match="^x.pfm: ") as e:
        hio.read(p)
    assert message in str(e.value)


def test_rle_with_bottom_up_orientation():
    rgb = _pixels(5, 12, seed=7)
    data = _rgbe.encode_rgbe(rgb).replace(b"-Y 5 +X 12\n", b"+Y 5 +X 12\n")
    got, info = _rgbe.decode_rgbe_float(data)
    assert info["orientation"] == "+Y +X"
    np.testing.assert_array_equal(got, _quant(rgb)[::-1])
