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
