"""Reading brackets from files (hdrjax.merge.read_bracket): real PNG, TIFF, JPEG and DNG
files written from synthetic brackets, read back exactly (JPEG approximately), with their
EXIF exposure settings, sorted, and one-line errors naming the file."""

import struct
import zlib
from fractions import Fraction

import numpy as np
import pytest
import tifffile
from PIL import Image, TiffImagePlugin

import hdrjax.merge as hm
from hdrjax.io import read, write_display

from ..conftest import DATA

JPEG_MEAN_ABS_CODES = 3.0
"""JPEG (quality 95, 4:4:4) changes codes; mean absolute error measured 2.3 codes."""
RAW_MAX_ABS_CODES = 8
"""LibRaw's linear decoding of a DNG written with the sRGB matrix: measured ≤ 6 of 65535
(its colour-matrix arithmetic, mean 0.2), away from the 2-pixel border demosaicing
changes."""

SCENE = np.asarray(read(DATA / "Carrots.exr").rgb())[::6, ::6][:64, :96]
TIMES = np.array([1 / 64, 1 / 16, 1 / 4, 1.0, 4.0])
B8 = hm.simulate_bracket(SCENE, TIMES, curve="srgb", bits=8)
B16 = hm.simulate_bracket(SCENE, TIMES, curve="per_channel", bits=16)
SHUFFLE = [3, 0, 4, 2, 1]


def exif_for(t, f_number=None, iso=None, orientation=None):
    """A Pillow ``Exif`` with the settings in the EXIF IFD, as cameras write them."""
    exif = Image.Exif()
    sub = exif.get_ifd(0x8769)
    sub[0x829A] = TiffImagePlugin.IFDRational(Fraction(t).limit_denominator(1_000_000))
    if f_number is not None:
        sub[0x829D] = TiffImagePlugin.IFDRational(Fraction(f_number).limit_denominator(100))
    if iso is not None:
        sub[0x8827] = iso
    if orientation is not None:
        exif[0x0112] = orientation
    return exif


def png_with_exif(png: bytes, exif: Image.Exif) -> bytes:
    """Insert an ``eXIf`` chunk (PNG third edition) after IHDR."""
    data = exif.tobytes()[6:]  # without the "Exif\0\0" JPEG prefix
    chunk = struct.pack(">I", len(data)) + b"eXIf" + data
    chunk += struct.pack(">I", zlib.crc32(b"eXIf" + data) & 0xFFFFFFFF)
    end = 8 + 25  # signature + IHDR chunk
    return png[:end] + chunk + png[end:]


def png_grey_alpha_16(a):
    """A 16-bit grey + alpha PNG (colour type 4), unfiltered rows (PNG spec, section 11)."""

    def chunk(kind, data):
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    h, w = a.shape[:2]
    rows = b"".join(b"\0" + row.astype(">u2").tobytes() for row in a)
    ihdr = struct.pack(">IIBBBBB", w, h, 16, 4, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", ihdr)
        + chunk(b"IDAT", zlib.compress(rows))
        + chunk(b"IEND", b"")
    )


def save_png(path, codes, exif):
    """An 8-bit PNG with EXIF (Pillow's PNG writer leaves an ``Exif`` object out)."""
    Image.fromarray(codes).save(path)
    path.write_bytes(png_with_exif(path.read_bytes(), exif))


def test_png_8bit_with_exif_sorted_and_exact(tmp_path):
    paths = []
    for j in SHUFFLE:
        p = tmp_path / f"m{j}.png"
        save_png(p, B8.codes[j], exif_for(TIMES[j], 5.6, 100 * (j + 1)))
        paths.append(p)
    b = hm.read_bracket(paths)
    np.testing.assert_array_equal(b.images, B8.codes)
    assert b.images.dtype == np.uint8
    np.testing.assert_array_equal(b.exposure_times, TIMES)
    np.testing.assert_allclose(b.f_numbers, 5.6)
    np.testing.assert_array_equal(b.isos, [100, 200, 300, 400, 500])
    assert b.paths == tuple(str(tmp_path / f"m{j}.png") for j in range(5))
    # the library's functions take the paths as they are (as_codes → read_bracket)
    codes = hm.as_codes([str(p) for p in paths])
    np.testing.assert_array_equal(codes.codes, B8.codes)
    np.testing.assert_array_equal(codes.exposure_times, TIMES)


def test_png_16bit_is_read_with_all_16_bits(tmp_path):
    """Pillow alone keeps only the high byte of 48-bit PNG samples; the reader keeps both,
    for hdrjax's own writer (Sub filter) and libpng's (OpenCV: adaptive filters, Paeth)."""
    cv2 = pytest.importorskip("cv2")
    paths = []
    for j in range(5):
        p = tmp_path / f"h{j}.png"
        write_display(p, B16.codes[j], bits=16)
        p.write_bytes(png_with_exif(p.read_bytes(), exif_for(TIMES[j], 8.0, 400)))
        paths.append(p)
    with Image.open(paths[2]) as im:  # what Pillow gives by itself: 8 bits
        assert np.asarray(im).dtype == np.uint8
    b = hm.read_bracket(paths)
    assert b.images.dtype == np.uint16
    np.testing.assert_array_equal(b.images, B16.codes)
    assert np.any(B16.codes & 0xFF)  # the low bytes carry information
    np.testing.assert_array_equal(b.exposure_times, TIMES)
    np.testing.assert_array_equal(b.f_numbers, 8.0)
    noise = np.random.default_rng(3).integers(0, 65536, (64, 96, 4), dtype=np.uint16)
    cv2.imwrite(str(tmp_path / "cv.png"), noise[..., [2, 1, 0, 3]])  # RGBA, BGR order
    cv2.imwrite(str(tmp_path / "cv3.png"), B16.codes[3][..., ::-1])
    b = hm.read_bracket([tmp_path / "cv.png", tmp_path / "cv3.png"], [1.0, 2.0])
    np.testing.assert_array_equal(b.images[0], noise[..., :3])  # alpha dropped
    np.testing.assert_array_equal(b.images[1], B16.codes[3])


def test_png_grey_16bit_and_grey_alpha_become_three_channels(tmp_path):
    grey = B16.codes[2][..., 1]
    write_display(tmp_path / "g.png", grey[..., None], bits=16)
    ga = np.stack([grey, 65535 - grey], axis=-1)
    (tmp_path / "ga.png").write_bytes(png_grey_alpha_16(ga))
    Image.fromarray(B8.codes[2][..., 0]).save(tmp_path / "g8.png")
    Image.fromarray(B8.codes[3][..., 0]).save(tmp_path / "g8b.png")
    b = hm.read_bracket([tmp_path / "g.png", tmp_path / "ga.png"], [1.0, 2.0])
    np.testing.assert_array_equal(b.images, np.repeat(grey[None, ..., None], 3, -1)[[0, 0]])
    b = hm.read_bracket([tmp_path / "g8.png", tmp_path / "g8b.png"], [1.0, 2.0])
    np.testing.assert_array_equal(b.images[1], np.repeat(B8.codes[3][..., :1], 3, -1))


def test_tiff_16bit_with_exif_chunky_planar_and_lzw(tmp_path):
    paths = []
    for j in SHUFFLE:
        p = tmp_path / f"t{j}.tif"
        tags = [
            (33434, "2I", 1, (int(TIMES[j] * 4096), 4096), True),  # ExposureTime
            (33437, "2I", 1, (28, 10), True),  # FNumber
            (34855, "H", 1, 800, True),  # ISOSpeedRatings
        ]
        if j % 2:  # planar: the samples first
            data, planar = np.moveaxis(B16.codes[j], -1, 0), "separate"
        else:
            data, planar = B16.codes[j], "contig"
        tifffile.imwrite(p, data, photometric="rgb", planarconfig=planar, extratags=tags)
        paths.append(p)
    b = hm.read_bracket(paths)
    np.testing.assert_array_equal(b.images, B16.codes)
    np.testing.assert_array_equal(b.exposure_times, TIMES)
    np.testing.assert_allclose(b.f_numbers, 2.8)
    np.testing.assert_array_equal(b.isos, 800)
    # EXIF in its own IFD (as cameras and raw converters write it; Pillow's TIFF writer)
    info = TiffImagePlugin.ImageFileDirectory_v2()
    info[0x8769] = {0x829A: TiffImagePlugin.IFDRational(1, 250), 0x8827: 640}
    Image.fromarray(B8.codes[0]).save(tmp_path / "sub.tif", tiffinfo=info)
    b = hm.read_bracket([tmp_path / "sub.tif"])
    np.testing.assert_array_equal(b.images[0], B8.codes[0])
    assert b.exposure_times[0] == 1 / 250 and b.isos[0] == 640 and b.f_numbers is None
    # hdrjax's own TIFF writer, and LZW (OpenCV's default; tifffile needs imagecodecs for
    # it, so Pillow decodes it, in two passes for 16 bits)
    write_display(tmp_path / "own.tif", B16.codes[1], bits=16)
    cv2 = pytest.importorskip("cv2")
    cv2.imwrite(str(tmp_path / "lzw.tif"), B16.codes[4][..., ::-1])
    cv2.imwrite(str(tmp_path / "lzw8.tif"), B8.codes[4][..., ::-1])
    b = hm.read_bracket([tmp_path / "own.tif", tmp_path / "lzw.tif"], [1.0, 2.0])
    np.testing.assert_array_equal(b.images, B16.codes[[1, 4]])
    cv2.imwrite(str(tmp_path / "lzw8b.tif"), B8.codes[0][..., ::-1])
    b = hm.read_bracket([tmp_path / "lzw8.tif", tmp_path / "lzw8b.tif"], [2.0, 1.0], progress=True)
    np.testing.assert_array_equal(b.images, B8.codes[[0, 4]])


def test_jpeg_with_exif_approximately(tmp_path):
    paths = []
    for j in SHUFFLE:
        p = tmp_path / f"j{j}.jpg"
        exif = exif_for(TIMES[j], 4.0, 200)
        Image.fromarray(B8.codes[j]).save(p, quality=95, subsampling=0, exif=exif)
        paths.append(p)
    b = hm.read_bracket(paths)
    np.testing.assert_array_equal(b.exposure_times, TIMES)
    np.testing.assert_array_equal(b.f_numbers, 4.0)
    np.testing.assert_array_equal(b.isos, 200)
    err = np.abs(b.images.astype(float) - B8.codes)
    assert err.mean() < JPEG_MEAN_ABS_CODES


def test_user_times_override_exif_and_orientation_is_applied(tmp_path):
    a, c = tmp_path / "a.jpg", tmp_path / "c.png"
    Image.fromarray(B8.codes[1]).save(a, quality=100, subsampling=0, exif=exif_for(0.5))
    save_png(c, B8.codes[2], exif_for(0.25))
    b = hm.read_bracket([a, c], exposure_times=[2.0, 0.1])
    assert b.paths == (str(c), str(a))
    np.testing.assert_array_equal(b.exposure_times, [0.1, 2.0])
    assert b.f_numbers is None and b.isos is None
    # orientation 6 (TIFF 6.0): the stored pixels are shown rotated 90° clockwise
    d = tmp_path / "d.png"
    save_png(d, B8.codes[3], exif_for(1.0, orientation=6))
    with pytest.raises(ValueError, match=r"d\.png: 64x96 pixels, but .*c\.png has 96x64"):
        hm.read_bracket([c, d])
    e = tmp_path / "e.png"
    save_png(e, B8.codes[2], exif_for(0.25, orientation=6))
    b = hm.read_bracket([e, d])
    np.testing.assert_array_equal(b.images, np.rot90(B8.codes[[2, 3]], -1, axes=(1, 2)))


def test_errors_name_the_file(tmp_path):
    good = []
    for j in range(2):
        p = tmp_path / f"ok{j}.png"
        save_png(p, B8.codes[j], exif_for(TIMES[j]))
        good.append(p)
    with pytest.raises(FileNotFoundError, match="nope.png"):
        hm.read_bracket([good[0], tmp_path / "nope.png"])
    (tmp_path / "bad.png").write_bytes(b"not a png at all")
    with pytest.raises(ValueError, match=r"bad\.png: cannot read the image"):
        hm.read_bracket([good[0], tmp_path / "bad.png"])
    for i, junk in enumerate((b"II*\0garbage", b"not a tiff at all")):
        (tmp_path / f"bad{i}.tif").write_bytes(junk)
        with pytest.raises(ValueError, match=rf"bad{i}\.tif: not a readable TIFF file"):
            hm.read_bracket([good[0], tmp_path / f"bad{i}.tif"])
    cmyk = np.zeros((8, 8, 4), np.uint8)
    tifffile.imwrite(tmp_path / "cmyk.tif", cmyk, photometric="separated")
    with pytest.raises(ValueError, match=r"cmyk\.tif: unsupported TIFF photometric SEPARATED"):
        hm.read_bracket([tmp_path / "cmyk.tif"], [1.0])
    (tmp_path / "x.bmp").write_bytes(b"BM")
    with pytest.raises(ValueError, match=r"x\.bmp: unsupported file type \.bmp"):
        hm.read_bracket([tmp_path / "x.bmp"])
    Image.fromarray(B8.codes[2]).save(tmp_path / "noexif.png")
    with pytest.raises(ValueError, match=r"noexif\.png: no exposure time in EXIF and none given"):
        hm.read_bracket([good[0], tmp_path / "noexif.png"])
    save_png(tmp_path / "small.png", B8.codes[2][:32], exif_for(1.0))
    with pytest.raises(ValueError, match=r"small\.png: 96x32 pixels, but .*ok0\.png has 96x64"):
        hm.read_bracket([*good, tmp_path / "small.png"])
    write_display(tmp_path / "deep.png", B16.codes[2], bits=16)
    with pytest.raises(ValueError, match=r"deep\.png: 16-bit, but .*ok0\.png is 8-bit"):
        hm.read_bracket([good[0], tmp_path / "deep.png"], [1.0, 2.0])
    save_png(tmp_path / "same.png", B8.codes[3], exif_for(TIMES[1]))
    with pytest.raises(ValueError, match=r"same\.png: same exposure time .* as .*ok1\.png"):
        hm.read_bracket([*good, tmp_path / "same.png"])
    with pytest.raises(ValueError, match=r"exposure_times: expected one time per file \(2\)"):
        hm.read_bracket(good, [1.0])
    with pytest.raises(ValueError, match="exposure_times: expected positive"):
        hm.read_bracket(good, [1.0, -1.0])
    tifffile.imwrite(tmp_path / "float.tif", SCENE.astype(np.float32), photometric="rgb")
    with pytest.raises(ValueError, match=r"float\.tif: expected 8- or 16-bit"):
        hm.read_bracket([tmp_path / "float.tif"], [1.0])
    with pytest.raises(ValueError, match="paths: expected at least one"):
        hm.read_bracket([])


# -- camera RAW: tiny DNG files LibRaw reads -------------------------------------------------

# XYZ → linear sRGB (IEC 61966-2-1): as the DNG ColorMatrix1 it makes the camera's RGB
# linear sRGB, so LibRaw's camera → sRGB conversion is the identity
XYZ_TO_SRGB = np.array(
    [
        [3.2404542, -1.5371385, -0.4985314],
        [-0.969266, 1.8760108, 0.041556],
        [0.0556434, -0.2040259, 1.0572252],
    ]
)


def write_dng(path, data, *, t, f_number, iso, cfa):
    """A minimal DNG 1.4 (Adobe DNG specification): ``data`` (H, W, 3) uint16 as LinearRaw,
    or (H, W) as an RGGB colour filter array; white level 65535, black 0, neutral white
    balance, EXIF exposure tags in IFD 0 (TIFF/EP allows them there)."""
    rationals = tuple(v for x in XYZ_TO_SRGB.ravel() for v in (round(x * 10000), 10000))
    tags = [
        (50706, "B", 4, (1, 4, 0, 0), True),  # DNGVersion
        (50707, "B", 4, (1, 1, 0, 0), True),  # DNGBackwardVersion
        (50708, "s", 0, "hdrjax test camera", True),  # UniqueCameraModel
        (50721, "2i", 9, rationals, True),  # ColorMatrix1
        (50778, "H", 1, 21, True),  # CalibrationIlluminant1: D65
        (50728, "2I", 3, (1, 1, 1, 1, 1, 1), True),  # AsShotNeutral
        (50714, "I", 1, 0, True),  # BlackLevel
        (50717, "I", 1, 65535, True),  # WhiteLevel
        (33434, "2I", 1, (round(t * 1_000_000), 1_000_000), True),  # ExposureTime
        (33437, "2I", 1, (round(f_number * 10), 10), True),  # FNumber
        (34855, "H", 1, iso, True),  # ISOSpeedRatings
    ]
    if cfa:
        tags += [(33421, "H", 2, (2, 2), True), (33422, "B", 4, (0, 1, 1, 2), True)]
    tifffile.imwrite(path, data, photometric=32803 if cfa else 34892, extratags=tags, subfiletype=0)


def test_dng_is_decoded_linear_with_its_exif(tmp_path):
    pytest.importorskip("rawpy")
    linear = hm.simulate_bracket(SCENE, TIMES[1:4], curve="linear", bits=16, fill=0.6)
    paths = []
    for j in (2, 0, 1):
        p = tmp_path / f"r{j}.dng"
        write_dng(p, linear.codes[j], t=TIMES[1 + j], f_number=5.6, iso=100, cfa=False)
        paths.append(p)
    b = hm.read_bracket(paths)
    assert b.images.dtype == np.uint16 and b.images.shape == (3, 64, 96, 3)
    np.testing.assert_allclose(b.exposure_times, TIMES[1:4])
    np.testing.assert_allclose(b.f_numbers, 5.6)
    np.testing.assert_array_equal(b.isos, 100)
    # linear, same scale in every member (no auto-brightening, no white-level rescaling)
    err = np.abs(b.images.astype(np.int64) - linear.codes)
    assert err[:, 2:-2, 2:-2].max() <= RAW_MAX_ABS_CODES
    # a colour filter array is demosaiced: a flat grey patch keeps its value in each channel
    flat = np.full((64, 96), 30000, np.uint16)
    write_dng(tmp_path / "cfa.dng", flat, t=0.01, f_number=2.0, iso=3200, cfa=True)
    write_dng(tmp_path / "cfa2.dng", flat // 2, t=0.005, f_number=2.0, iso=3200, cfa=True)
    b = hm.read_bracket([tmp_path / "cfa.dng", tmp_path / "cfa2.dng"])
    assert np.abs(b.images[1, 2:-2, 2:-2].astype(int) - 30000).max() <= RAW_MAX_ABS_CODES
    assert np.abs(b.images[0, 2:-2, 2:-2].astype(int) - 15000).max() <= RAW_MAX_ABS_CODES
    np.testing.assert_array_equal(b.isos, 3200)


def test_raw_errors_name_the_file(tmp_path):
    pytest.importorskip("rawpy")
    (tmp_path / "broken.nef").write_bytes(b"\0" * 64)
    with pytest.raises(ValueError, match=r"broken\.nef: LibRaw cannot read it"):
        hm.read_bracket([tmp_path / "broken.nef"], [1.0])
