"""``hdrjax falsecolor`` and ``hdrjax desaturate`` on the repository image and synthetic
layered files."""

import numpy as np
import pytest
from PIL import Image

from hdrjax import io as hio
from hdrjax.cli import main
from hdrjax.display import desaturate_highlights, false_color
from hdrjax.layers import LayeredImage

from ..conftest import DATA

CORNELL = str(DATA / "cornell_box.exr")


def _layered(tmp_path):
    """A small EXR with error and hits layers (written by hdrjax.io)."""
    rng = np.random.default_rng(0)
    rgb = rng.lognormal(0, 1, size=(32, 40, 3)).astype(np.float32)
    err = rng.random((32, 40)).astype(np.float32) * 0.2
    err[0, 0] = np.nan
    hits = rng.integers(0, 500, size=(32, 40)).astype(np.float32)
    img = LayeredImage(rgb, quantity="luminance", unit="cd/m²", layers={"error": err, "hits": hits})
    path = tmp_path / "sim.exr"
    hio.write(path, img)
    return path, err


def test_falsecolor_error_layer_with_log_range_and_legend(tmp_path, capsys):
    path, err = _layered(tmp_path)
    out = tmp_path / "err.png"
    code = main(
        ["falsecolor", str(path), "--layer", "error", "-o", str(out), "--range", "0.01:10", "--log"]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "calculation error [cd/m²]: log scale 0.01 .. 10" in text and "nan 1" in text
    png = np.asarray(Image.open(out).convert("RGB"))
    assert png.shape[0] == 300 and png.shape[1] > 40  # image + legend beside it
    ref = false_color(hio.read(path).layer("error"), vmin=0.01, vmax=10, log=True, legend=False)
    expect = np.rint(np.asarray(ref.image) * 255)
    np.testing.assert_array_equal(png[:32, :40], expect.astype(np.uint8))
    assert tuple(png[0, 0]) == (255, 0, 255)  # the NaN pixel


def test_falsecolor_default_luminance_bands_and_separate_legend(tmp_path):
    out, leg = tmp_path / "lum.png", tmp_path / "legend.svg"
    code = main(
        [
            "falsecolor",
            CORNELL,
            "-o",
            str(out),
            "--bands",
            "0.01,0.03,0.1,0.3",
            "--log",
            "--legend",
            str(leg),
            "--colors",
            "blue,yellow,red",
            "--isolines",
            "0.05",
        ]
    )
    assert code == 0
    assert np.asarray(Image.open(out)).shape[:2] == (512, 512)
    assert leg.read_text().lstrip().startswith("<?xml")


def test_falsecolor_errors(tmp_path, capsys):
    path, _ = _layered(tmp_path)
    assert (
        main(["falsecolor", str(path), "--layer", "position", "-o", str(tmp_path / "a.png")]) == 1
    )
    assert "no 'position' layer" in capsys.readouterr().err
    assert main(["falsecolor", str(path), "-o", str(tmp_path / "a.exr")]) == 2
    assert main(["falsecolor", str(path), "-o", str(tmp_path / "a.png"), "--cmap", "nope"]) == 2
    assert (
        main(["falsecolor", str(path), "-o", str(tmp_path / "a.png"), "--log", "--range", "0:1"])
        == 2
    )
    with pytest.raises(SystemExit) as e:
        main(["falsecolor", str(path), "-o", str(tmp_path / "a.png"), "--range", "3:1"])
    assert e.value.code == 2
    assert main(["falsecolor", str(tmp_path / "none.exr"), "-o", str(tmp_path / "a.png")]) == 1


def test_desaturate_command(tmp_path, capsys):
    out = tmp_path / "d.exr"
    assert main(["desaturate", CORNELL, "-o", str(out), "--threshold", "0.5"]) == 0
    img = hio.read(CORNELL)
    ref = np.asarray(desaturate_highlights(img.rgb(), 0.5, weights=img.luminance_weights))
    np.testing.assert_allclose(
        hio.read(out).rgb(), ref, rtol=1e-3
    )  # stored as half, like the input
    assert main(["desaturate", CORNELL, "-o", str(out)]) == 0
    assert "automatic, 2 x L90" in capsys.readouterr().out


def _xyz_crop(tmp_path):
    """A 12×16 crop of XYZ.exr (CIE XYZ primaries), written with its chromaticities."""
    img = hio.read(DATA / "XYZ.exr")
    crop = LayeredImage(img.image[200:212, 300:316], chromaticities=img.chromaticities)
    return hio.write(tmp_path / "xyz.exr", crop), crop


@pytest.mark.parametrize(
    "display, cicp, bits",
    [("P3", (12, 13, 0, 1), 8), ("PQ", (9, 16, 0, 1), 16), ("HLG", (9, 18, 0, 1), 16)],
)
def test_tonemap_display_encodes_and_tags_the_png(tmp_path, capsys, display, cicp, bits):
    """--display: the PNG's code values are encode(display=...) of the operator's output
    (sRGB working space) and its cICP chunk names that display (read by the test's own
    PNG parser); PQ and HLG are 16-bit by default."""
    from hdrjax import spaces
    from hdrjax.display import encode, quantize

    from .._png import decode_png

    path, crop = _xyz_crop(tmp_path)
    out = tmp_path / "o.png"
    args = ["tonemap", str(path), "-o", str(out), "--method", "linear", "--set", "L_max=2"]
    assert main([*args, "--display", display]) == 0
    pixels, chunks = decode_png(out.read_bytes())
    assert tuple(chunks[b"cICP"]) == cicp
    assert pixels.dtype.itemsize * 8 == bits
    srgb = spaces.convert_to(crop.image, crop.chromaticities)
    want = quantize(encode(np.asarray(srgb) / 2.0, display=display), bits)
    # the command line converts inside the operator's program: float32 rounding, 1 code
    np.testing.assert_allclose(pixels.astype(np.int64), want.astype(np.int64), rtol=0, atol=1)


def test_tonemap_exr_keeps_the_working_spaces_chromaticities(tmp_path, capsys):
    from hdrjax import spaces

    path, _ = _xyz_crop(tmp_path)
    out = tmp_path / "o.exr"
    args = ["tonemap", str(path), "-o", str(out), "--method", "linear", "--set", "L_max=2"]
    assert main([*args, "--working-space", "ACEScg"]) == 0
    got = hio.read(out).chromaticities
    np.testing.assert_allclose(got, spaces.space("ACEScg").chromaticities, atol=1e-7)
    assert main([*args]) == 0  # sRGB: no attribute (OpenEXR's default is Rec.709)
    assert hio.read(out).chromaticities is None


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--display", "PQ", "--bits", "8"], "--display ITU-R BT.2100 PQ needs 16 bits"),
        (["--peak", "500"], "--peak applies to --display PQ, not sRGB"),
        (["--display", "CRT"], "--display: unknown name 'CRT'; expected one of 'sRGB'"),
        (["--working-space", "Adobe99"], "--working-space: unknown name 'adobe99'"),
        (["--cat", "CAT99"], "--cat: unknown chromatic adaptation transform 'CAT99'"),
        (["--display", "P3", "--transfer", "gamma"], "--transfer does not apply with --display"),
    ],
)
def test_tonemap_colour_option_errors(tmp_path, capsys, extra, message):
    path, _ = _xyz_crop(tmp_path)
    assert main(["tonemap", str(path), "-o", str(tmp_path / "o.png"), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o.png").exists()
