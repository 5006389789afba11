"""Display exports are tagged for the display their pixels were encoded for.

Every tag is read back by a reader independent of the writer: the PNG chunks by
tests/_png.py and a chunk lister below (PNG Specification, third edition, W3C 2025), ICC
profiles by LittleCMS (Pillow's ImageCms) and by a tag-table reader below (ICC.1:2001-04),
16-bit pixels by OpenCV (libpng, libtiff), EXR attributes by the OpenEXR library. Expected
values come from colour-science: primaries and matrices (``colour.RGB_COLOURSPACES``), the
Bradford adaptation to D50 (``matrix_chromatic_adaptation_VonKries``) and the transfer
functions (``eotf_sRGB``, ``eotf_ST2084``, ``oetf_inverse_BT2100_HLG``, ``eotf_BT1886``).
"""

import io
import struct

import colour
import numpy as np
import pytest
from PIL import Image, ImageCms

import hdrjax.io as hio
from hdrjax.display import get_display as find_display
from hdrjax.io._icc import BRADFORD, display_profile
from hdrjax.layers import LayeredImage
from tests._png import decode_png

PCS_D50 = np.array([0.9642, 1.0, 0.8249])  # the ICC header's PCS illuminant
S15F16 = 1e-4  # colorant tolerance: s15Fixed16 steps are 1.5e-5
U16 = 1.0 / 65535  # one step of a sampled curv entry
PEAK = 1000.0  # cd/m² at linear 1.0 in the encoder's PQ (DEFAULT_PEAK)
SRGB = ImageCms.createProfile("sRGB")  # LittleCMS's own sRGB
EXACT = ImageCms.Flags.NOOPTIMIZE

# name → (colour-science colourspace, expected cICP or None, expected gAMA or None)
CASES = {
    "sRGB": ("sRGB", (1, 13, 0, 1), 45455),
    "Display P3": ("Display P3", (12, 13, 0, 1), 45455),
    "ITU-R BT.2020": ("ITU-R BT.2020", (9, 1, 0, 1), 41667),
    "ITU-R BT.2100 PQ": ("ITU-R BT.2020", (9, 16, 0, 1), None),
    "ITU-R BT.2100 HLG": ("ITU-R BT.2020", (9, 18, 0, 1), None),
    "linear": ("sRGB", (1, 8, 0, 1), 100000),
    "gamma": ("sRGB", (1, 4, 0, 1), 45455),
    "gamma 1.8": ("sRGB", None, 55556),
}
HDR = ("ITU-R BT.2100 PQ", "ITU-R BT.2100 HLG")


def _display(name):
    return find_display("gamma", 1.8) if name == "gamma 1.8" else find_display(name)


def _decode(name, v):
    """Linear display value of code values ``v`` for a display, by colour-science."""
    v = np.asarray(v, np.float64)
    if name in ("sRGB", "Display P3"):
        return colour.models.eotf_sRGB(v)
    if name == "ITU-R BT.2020":
        return colour.models.eotf_BT1886(v, L_B=0, L_W=1)
    if name == "ITU-R BT.2100 PQ":
        return np.minimum(colour.models.eotf_ST2084(v) / PEAK, 1.0)
    if name == "ITU-R BT.2100 HLG":
        return colour.models.oetf_inverse_BT2100_HLG(v)
    if name == "linear":
        return v
    return v ** (1.8 if name == "gamma 1.8" else 2.2)


def _as_stored(name, v):
    """What the profile can hold of the display's decoding: a power law's exponent is a
    u8Fixed8Number (ICC.1:2001-04 curveType), 2.4 becomes 614/256 = 2.3984."""
    g = {"ITU-R BT.2020": 2.4, "gamma": 2.2, "gamma 1.8": 1.8}.get(name)
    return _decode(name, v) if g is None else np.asarray(v, np.float64) ** (round(g * 256) / 256)


def _image(bits, seed=0, shape=(6, 9, 3)):
    return (
        np.random.default_rng(seed)
        .integers(0, 1 << bits, shape)
        .astype(np.uint8 if bits == 8 else np.uint16)
    )


def _bits(name):
    return 16 if name in HDR else 8


def _chunk_order(data: bytes) -> list[bytes]:
    pos, out = 8, []
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos : pos + 4])
        out.append(data[pos + 4 : pos + 8])
        pos += 12 + n
    return out


def _icc_tags(icc: bytes) -> tuple[bytes, dict[bytes, bytes]]:
    """``(colour space, {tag signature: element bytes})`` of an ICC profile."""
    assert struct.unpack(">I", icc[:4])[0] == len(icc) and icc[36:40] == b"acsp"
    assert icc[8:12] == b"\x02\x40\x00\x00" and icc[12:16] == b"mntr" and icc[20:24] == b"XYZ "
    (count,) = struct.unpack(">I", icc[128:132])
    tags = {}
    for i in range(count):
        sig, off, size = struct.unpack(">4sII", icc[132 + 12 * i : 144 + 12 * i])
        assert off % 4 == 0 and off + size <= len(icc)
        tags[sig] = icc[off : off + size]
    return icc[16:20], tags


def _curve(body: bytes):
    """A curveType: the exponent (one entry, u8Fixed8Number) or the table in [0, 1]."""
    assert body[:4] == b"curv"
    (n,) = struct.unpack(">I", body[8:12])
    if n == 1:
        return struct.unpack(">H", body[12:14])[0] / 256.0
    return np.frombuffer(body[12 : 12 + 2 * n], ">u2") / 65535.0


def _adapted_colorants(cs_name):
    cs = colour.RGB_COLOURSPACES[cs_name]
    white = cs.matrix_RGB_to_XYZ @ np.ones(3)
    cat = colour.adaptation.matrix_chromatic_adaptation_VonKries(white, PCS_D50, "Bradford")
    return cat @ cs.matrix_RGB_to_XYZ, white


def _png_icc(data: bytes) -> bytes:
    with Image.open(io.BytesIO(data)) as im:
        return im.info["icc_profile"]


# -- PNG chunks --------------------------------------------------------------------------


@pytest.mark.parametrize("name", CASES)
def test_png_chunks_for_each_display(tmp_path, name):
    """cICP bytes, cHRM = the space's chromaticities, gAMA for power laws (1/2.2 with the
    sRGB curve), sRGB only for sRGB and iCCP for the other curves, never both; the colour
    chunks come before IDAT (cICP must); the pixels are unchanged."""
    cs_name, cicp, gama = CASES[name]
    code = _image(_bits(name))
    data = hio.write_display(tmp_path / "o.png", code, bits=_bits(name), display=_display(name))
    data = data.read_bytes()
    px, chunks = decode_png(data)
    np.testing.assert_array_equal(px, code)
    order = _chunk_order(data)
    colour_chunks = [k for k in order if k in (b"cICP", b"cHRM", b"gAMA", b"iCCP", b"sRGB")]
    assert order.index(b"IDAT") > max(order.index(k) for k in colour_chunks)
    if cicp is None:
        assert b"cICP" not in chunks
    else:
        assert tuple(chunks[b"cICP"]) == cicp
    cs = colour.RGB_COLOURSPACES[cs_name]
    want = np.rint(np.r_[cs.whitepoint, np.ravel(cs.primaries)] * 100000)
    np.testing.assert_array_equal(struct.unpack(">8I", chunks[b"cHRM"]), want)
    if gama is None:
        assert b"gAMA" not in chunks
    else:
        assert struct.unpack(">I", chunks[b"gAMA"])[0] == gama
    assert (b"sRGB" in chunks) == (name == "sRGB")
    assert (b"iCCP" in chunks) == (name in ("Display P3", *HDR))
    assert not (b"sRGB" in chunks and b"iCCP" in chunks)
    if b"iCCP" in chunks:  # profile name, NUL, compression method 0, zlib stream
        assert chunks[b"iCCP"].startswith(name.encode("latin-1") + b"\x00\x00\x78")


def test_srgb_png_holds_the_specifications_values(tmp_path):
    """The default is sRGB: the sRGB chunk (perceptual) with the cHRM and gAMA values the
    PNG specification lists for it, no profile; the name and a Display give the same file."""
    d = np.linspace(0, 1, 30).reshape(2, 5, 3)
    raw = hio.write_display(tmp_path / "a.png", d).read_bytes()
    _, chunks = decode_png(raw)
    assert chunks[b"sRGB"] == b"\x00" and b"iCCP" not in chunks
    assert struct.unpack(">8I", chunks[b"cHRM"]) == (
        31270, 32900, 64000, 33000, 30000, 60000, 15000, 6000
    )  # fmt: skip
    assert struct.unpack(">I", chunks[b"gAMA"])[0] == 45455
    same = hio.write_display(tmp_path / "b.png", d, display=find_display("srgb"))
    assert same.read_bytes() == raw
    p3 = hio.write_display(tmp_path / "c.png", d, display="P3").read_bytes()
    assert p3 == hio.write_display(tmp_path / "d.png", d, display="display-p3").read_bytes()
    with pytest.raises(ValueError, match="unknown name 'Rec.3000'"):
        hio.write_display(tmp_path / "e.png", d, display="Rec.3000")


# -- ICC profiles ------------------------------------------------------------------------


def _files(tmp_path, name, channels=3):
    """ICC profiles of the PNG (where it has one), TIFF and JPEG written for a display."""
    disp, bits = _display(name), _bits(name)
    code = _image(bits, shape=(4, 6, channels) if channels > 1 else (4, 6))
    out = {}
    png = hio.write_display(tmp_path / "o.png", code, bits=bits, display=disp)
    if name in ("Display P3", *HDR):
        out["png"] = _png_icc(png.read_bytes())
    for ext in ("tif", "jpg") if bits == 8 else ("tif",):
        written = hio.write_display(tmp_path / f"o.{ext}", code, bits=bits, display=disp)
        with Image.open(written) as im:
            out[ext] = im.info["icc_profile"]
    return out


@pytest.mark.parametrize("name", CASES)
def test_icc_colorants_white_and_curve(tmp_path, name):
    """Colorants are colour-science's RGB→XYZ columns Bradford-adapted to D50 (to s15Fixed16
    precision) and sum to D50, read by LittleCMS; wtpt is the display's white; the curve is
    the display's EOTF (a table: to its 16-bit step; a power law: the exponent to u8Fixed8)."""
    cs_name = CASES[name][0]
    colorants, white = _adapted_colorants(cs_name)
    for fmt, icc in _files(tmp_path, name).items():
        prof = ImageCms.ImageCmsProfile(io.BytesIO(icc)).profile
        assert prof.version == pytest.approx(2.4) and prof.profile_description == (
            _display(name).name
        ), fmt
        got = np.array([prof.red_colorant[0], prof.green_colorant[0], prof.blue_colorant[0]]).T
        np.testing.assert_allclose(got, colorants, atol=S15F16, err_msg=fmt)
        np.testing.assert_allclose(got.sum(axis=1), PCS_D50, atol=S15F16)
        np.testing.assert_allclose(prof.media_white_point[0], white, atol=S15F16)
        space, tags = _icc_tags(icc)
        assert space == b"RGB " and tags[b"rTRC"] == tags[b"gTRC"] == tags[b"bTRC"]
        curve = _curve(tags[b"rTRC"])
        if isinstance(curve, float):
            # a u8Fixed8 exponent is off by at most 1/512, which moves x^γ by at most
            # max_x x^γ |ln x| / 512 = 1 / (512 e γ) < 3e-4 for γ ≥ 1
            v = np.linspace(0, 1, 1001)
            assert np.abs(v**curve - _decode(name, v)).max() < 3e-4, (fmt, curve)
        else:
            v = np.linspace(0, 1, curve.size)
            np.testing.assert_allclose(curve, _decode(name, v), atol=0.5 * U16 + 1e-12)


def _srgb_from(name, code):
    """8-bit sRGB that code values for a display decode to (relative colorimetric, both
    whites D65: no adaptation), by colour-science; NaN where out of the sRGB gamut."""
    lin = _as_stored(name, code / 255.0)
    cs = colour.RGB_COLOURSPACES[CASES[name][0]]
    srgb = colour.RGB_to_RGB(lin, cs, colour.RGB_COLOURSPACES["sRGB"], None)
    srgb[np.any((srgb < -1e-4) | (srgb > 1 + 1e-4), axis=-1)] = np.nan
    return colour.models.eotf_inverse_sRGB(np.clip(srgb, 0, 1)) * 255.0


@pytest.mark.parametrize("name", CASES)
def test_littlecms_decodes_like_the_display(name):
    """A LittleCMS transform from each profile to its own sRGB profile maps a grid of code
    values where colour-science's decoding, conversion and sRGB encoding do (in-gamut
    colours; 8-bit output, so within 1 code value). LittleCMS's optimisation, which
    resamples the joined curves, is off: it is LittleCMS's error, not the profile's."""
    v = np.arange(0, 256, 15)
    code = np.stack(np.meshgrid(v, v, v, indexing="ij"), axis=-1).reshape(1, -1, 3)
    want = _srgb_from(name, code.astype(np.float64))
    src = ImageCms.ImageCmsProfile(io.BytesIO(display_profile(_display(name), peak=PEAK)))
    xf = ImageCms.buildTransform(
        src, SRGB, "RGB", "RGB", ImageCms.Intent.RELATIVE_COLORIMETRIC, EXACT
    )
    got = np.asarray(ImageCms.applyTransform(Image.fromarray(code.astype(np.uint8)), xf))
    ok = ~np.isnan(want).any(axis=-1)
    assert ok.sum() > 200  # enough in-gamut colours to mean something
    assert np.abs(got[ok] - want[ok]).max() <= 1


@pytest.mark.parametrize("name", ["Display P3", "ITU-R BT.2100 PQ", "gamma 1.8"])
def test_grey_images_get_grey_profiles(tmp_path, name):
    """One-channel images carry a GRAY profile (kTRC; PNG forbids an RGB one on grey, and
    libpng drops it with a warning): LittleCMS decodes it as the display's curve."""
    for fmt, icc in _files(tmp_path, name, channels=1).items():
        space, tags = _icc_tags(icc)
        assert space == b"GRAY" and b"rXYZ" not in tags, fmt
        wtpt = np.array(struct.unpack(">3i", tags[b"wtpt"][8:20])) / 65536.0
        np.testing.assert_allclose(wtpt, _adapted_colorants(CASES[name][0])[1], atol=S15F16)
        src = ImageCms.ImageCmsProfile(io.BytesIO(icc))
        xf = ImageCms.buildTransform(src, SRGB, "L", "RGB", 1, EXACT)
        code = np.arange(0, 256, 5, dtype=np.uint8).reshape(1, -1)
        got = np.asarray(ImageCms.applyTransform(Image.fromarray(code), xf))
        want = colour.models.eotf_inverse_sRGB(_as_stored(name, code / 255.0)) * 255.0
        assert np.abs(got - want[..., None]).max() <= 1, fmt


# -- 16-bit HDR files --------------------------------------------------------------------


@pytest.mark.parametrize("name", [*HDR, "Display P3"])
def test_opencv_reads_16_bit_pixels_without_warnings(tmp_path, capfd, name):
    """libpng (through OpenCV) checks the iCCP profile's header and tag table and warns
    on stderr when it rejects one; libtiff reads the TIFF. Pixels come back exactly."""
    cv2 = pytest.importorskip("cv2")
    code = _image(16, seed=3, shape=(5, 7, 3))
    grey = code[:, :, 0]
    for ext in ("png", "tif"):
        for img in (code, grey):
            p = hio.write_display(tmp_path / f"o.{ext}", img, bits=16, display=name)
            got = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
            assert got.dtype == np.uint16
            np.testing.assert_array_equal(got[..., ::-1] if img.ndim == 3 else got, img)
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize("name", HDR)
def test_hdr_needs_16_bits(tmp_path, name):
    """PQ and HLG are refused in 8 bits and in JPEG, with the file's name; nothing written."""
    d = np.full((2, 2, 3), 0.5)
    for f in ("o.png", "o.tif"):
        with pytest.raises(ValueError, match=rf"^{f}: .*needs 16-bit.*use bits=16$"):
            hio.write_display(tmp_path / f, d, display=name)
    with pytest.raises(ValueError, match=r"^o\.jpg: JPEG holds 8 bits.*bits=16$"):
        hio.write_display(tmp_path / "o.jpg", d, display=name)
    assert not list(tmp_path.iterdir())


# -- EXR ---------------------------------------------------------------------------------


def test_exr_keeps_acescg_chromaticities(tmp_path):
    """hdrjax.io.write stores the image's chromaticities attribute: OpenEXR reads ACEScg's
    primaries and white back (as the attribute's float32)."""
    OpenEXR = pytest.importorskip("OpenEXR")
    from hdrjax import spaces

    cs = colour.RGB_COLOURSPACES["ACEScg"]
    want = np.float32(np.r_[np.ravel(cs.primaries), cs.whitepoint])
    img = LayeredImage(
        image=np.ones((2, 3, 3), np.float32), chromaticities=spaces.space("ACEScg").chromaticities
    )
    p = tmp_path / "a.exr"
    hio.write(p, img)
    with OpenEXR.File(str(p)) as f:
        np.testing.assert_array_equal(np.float32(f.header()["chromaticities"]), want)
    np.testing.assert_array_equal(np.float32(hio.read(p).chromaticities), want)


def test_bradford_matrix_is_colour_sciences():
    """The writer's own Bradford matrix (it avoids importing colour) is colour-science's."""
    np.testing.assert_array_equal(BRADFORD, colour.adaptation.CAT_BRADFORD)
