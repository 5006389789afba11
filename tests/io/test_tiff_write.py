"""TIFF export through tifffile: the tags hdrjax.io.write_display promises (deflate at the
zlib level asked for, none at level 0; the display's ICC profile; Software; unassociated
alpha; grey as MinIsBlack; no tifffile JSON description), read back with tifffile, and the
atomic write (no temporary file left, an existing file kept when ``overwrite=False``)."""

import numpy as np
import pytest
import tifffile

import hdrjax.io as hio
from hdrjax.display import DEFAULT_PEAK, get_display
from hdrjax.io._icc import display_profile

COMPRESSION_DEFLATE, COMPRESSION_NONE = 8, 1  # TIFF 6.0 / Adobe tag 259 codes
PHOTOMETRIC_MINISBLACK, PHOTOMETRIC_RGB = 1, 2
EXTRASAMPLE_UNASSALPHA = 2


@pytest.mark.parametrize("channels", [1, 3, 4])
def test_tiff_tags_and_pixels(tmp_path, channels):
    rng = np.random.default_rng(channels)
    shape = (5, 7) if channels == 1 else (5, 7, channels)
    code = rng.integers(0, 65536, shape).astype(np.uint16)
    for level, compression in ((0, COMPRESSION_NONE), (1, COMPRESSION_DEFLATE)):
        p = hio.write_display(tmp_path / "o.tif", code, bits=16, compression=level)
        with tifffile.TiffFile(p) as tif:
            page = tif.pages[0]
            np.testing.assert_array_equal(page.asarray(), code)
            assert page.compression == compression
            assert page.planarconfig == 1  # chunky, as baseline readers expect
            assert page.photometric == (
                PHOTOMETRIC_MINISBLACK if channels == 1 else PHOTOMETRIC_RGB
            )
            assert tuple(page.extrasamples) == ((EXTRASAMPLE_UNASSALPHA,) if channels == 4 else ())
            want = display_profile(get_display("sRGB"), grey=channels == 1, peak=DEFAULT_PEAK)
            assert page.tags[34675].value == want
            assert page.tags["Software"].value == "hdrjax"
            assert "ImageDescription" not in page.tags
    assert [f.name for f in tmp_path.iterdir()] == ["o.tif"]  # no temporary left behind


def test_tiff_level_and_overwrite(tmp_path):
    """Level 9 is no larger than level 1; overwrite=False keeps the old file."""
    gx = np.linspace(0, 1, 64, dtype=np.float32)
    smooth = np.stack(np.broadcast_arrays(gx[None, :], gx[:, None], 0.5), axis=2)
    sizes = {
        lvl: hio.write_display(tmp_path / f"{lvl}.tif", smooth, compression=lvl).stat().st_size
        for lvl in (1, 9)
    }
    assert sizes[9] <= sizes[1]
    before = (tmp_path / "1.tif").read_bytes()
    with pytest.raises(FileExistsError):
        hio.write_display(tmp_path / "1.tif", np.zeros((2, 2, 3)), overwrite=False)
    assert (tmp_path / "1.tif").read_bytes() == before
