"""The command line: tonemap and info on the shipped image, exit codes and one-line errors,
``python -m hdrjax`` and the console script being the same command."""

import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from hdrjax.cli import main
from hdrjax.io import read

from ..conftest import DATA

CORNELL = str(DATA / "cornell_box.exr")


def test_tonemap_writes_png_and_reports_estimates(tmp_path, capsys):
    out = tmp_path / "cb.png"
    assert main(["tonemap", CORNELL, "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "operator: reinhard2002" in text and "(estimated from the image)" in text
    assert f"wrote: {out}" in text
    for name in ("key", "L_white", "log_average"):
        assert f"  {name}: " in text
    img = np.asarray(Image.open(out))
    assert img.shape == (512, 512, 3) and img.dtype == np.uint8
    assert 40 < img.mean() < 200 and img.max() == 255  # neither black nor blown out


@pytest.mark.parametrize(
    "argv,needle",
    [
        (
            ["--method", "linear", "--exposure-time", "0.01", "--f-number", "2", "--iso", "100"],
            "exposure_time: 0.01",
        ),
        (["--method", "tumblin_reinhard", "--L-wa", "0.05"], "L_wa: 0.05"),
        (["--method", "reinhard2002", "--key", "0.09", "--bits", "16"], "key: 0.09"),
    ],
)
def test_tonemap_options(tmp_path, capsys, argv, needle):
    out = tmp_path / "o.png"
    assert main(["tonemap", CORNELL, "-o", str(out), *argv]) == 0
    assert needle in capsys.readouterr().out
    assert out.read_bytes()[24] == (16 if "16" in argv else 8)  # PNG IHDR bit depth


def test_tonemap_table_and_exr_output(tmp_path, capsys):
    table = tmp_path / "t.csv"
    table.write_text("luminance,display\n0.001,0.01\n0.1,0.5\n10,1\n")
    exr = tmp_path / "o.exr"
    assert (
        main(["tonemap", CORNELL, "-o", str(exr), "--method", "tabulated", "--table", str(table)])
        == 0
    )
    from hdrjax import io

    back = io.read(exr)
    Y = back.luminance()
    assert back.image.shape == (512, 512, 3) and 0.5 < Y.max() <= 1.0 + 1e-6


@pytest.mark.parametrize(
    "argv,code,needle",
    [
        (["tonemap", "missing.exr", "-o", "x.png"], 1, "missing.exr: no such file"),
        (["tonemap", CORNELL, "-o", "x.bmp"], 2, "unsupported output type .bmp"),
        (["tonemap", CORNELL, "-o", "x.png", "--method", "nope"], 2, "valid: "),
        (
            ["tonemap", CORNELL, "-o", "x.png", "--method", "linear", "--key", "0.2"],
            2,
            "--key does not apply to --method linear",
        ),
        (["tonemap", CORNELL, "-o", "x.png", "--method", "tabulated"], 2, "needs --table"),
        (
            ["tonemap", CORNELL, "-o", "x.png", "--method", "linear", "--iso", "100"],
            2,
            "given together",
        ),
    ],
)
def test_errors_are_one_line_with_exit_codes(tmp_path, capsys, argv, code, needle):
    argv = [a if a != "x.png" and a != "x.bmp" else str(tmp_path / a) for a in argv]
    assert main(argv) == code
    err = capsys.readouterr().err.strip()
    assert needle in err and "\n" not in err and err.startswith("hdrjax tonemap: error:")


def test_corrupt_input_is_bad_data(tmp_path, capsys):
    bad = tmp_path / "bad.exr"
    bad.write_bytes(b"not an exr at all")
    assert main(["tonemap", str(bad), "-o", str(tmp_path / "o.png")]) == 1
    err = capsys.readouterr().err
    assert "bad.exr" in err and err.count("\n") == 1
    assert not (tmp_path / "o.png").exists()


def test_bad_table_is_bad_data(tmp_path, capsys):
    table = tmp_path / "t.csv"
    table.write_text("luminance,display\n1,0.9\n10,0.1\n")
    assert (
        main(
            [
                "tonemap",
                CORNELL,
                "-o",
                str(tmp_path / "o.png"),
                "--method",
                "tabulated",
                "--table",
                str(table),
            ]
        )
        == 1
    )
    assert "t.csv" in capsys.readouterr().err


def test_info_prints_statistics_and_estimates(capsys):
    assert main(["info", CORNELL]) == 0
    text = capsys.readouterr().out
    assert "size: 512 x 512" in text
    assert "max 12.09" in text  # SOURCES.md: Lum max 12.1
    assert "dynamic range 29.8" in text  # SOURCES.md: 29.8 stops
    # the percentiles come from the statistics' own histogram: those of hdrjax._stats.percentile
    assert "median 0.0508299" in text and "p99 0.2332   (histogram, rel. error <= 0.00098)" in text
    for name in ("reinhard2002:", "tumblin_reinhard:", "linear:", "reinhard2002_auto: local"):
        assert name in text


def test_module_and_script_are_the_same_command():
    a = subprocess.run(
        [sys.executable, "-m", "hdrjax", "tonemap", "--help"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    script = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; from hdrjax.cli import main; sys.argv[0] = 'hdrjax'; sys.exit(main())",
            "tonemap",
            "--help",
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert a == script and "--exposure-time" in a
    from importlib.metadata import entry_points

    (ep,) = [e for e in entry_points(group="console_scripts") if e.name == "hdrjax"]
    assert ep.value == "hdrjax.cli:main"


def test_luminance_uses_the_files_primaries(tmp_path, capsys):
    """Carrots.exr carries ACES AP0 chromaticities (D60 white): its luminance weights are
    (0.34397, 0.72817, -0.07213) (the Y row of AP0's matrix, SMPTE ST 2065-1). It is
    converted to the sRGB working space with CAT02, and its luminance stays its own: the
    log-average ``info`` prints is that of Y = 0.34397 R + 0.72817 G − 0.07213 B of the
    file's pixels."""
    import re

    carrots = str(DATA / "Carrots.exr")
    assert main(["info", carrots]) == 0
    out = capsys.readouterr().out
    assert "white (0.3217, 0.3377): converted to sRGB (CAT02)" in out
    rgb = read(carrots).image.astype(np.float64)
    y = rgb @ np.array([0.34397, 0.72817, -0.07213])
    y = y[np.isfinite(y) & (y > 0)]
    got = float(re.search(r"log-average ([0-9.e+-]+)", out).group(1))
    assert got == pytest.approx(np.exp(np.mean(np.log(y))), rel=2e-3)  # histogram bin
    in_ap0 = read(carrots).luminance_weights_in("ACES2065-1")  # no conversion: its own
    np.testing.assert_allclose(in_ap0, (0.34397, 0.72817, -0.07213), atol=5e-6)
    assert main(["tonemap", carrots, "-o", str(tmp_path / "c.png")]) == 0
    assert "converted to sRGB (CAT02)" in capsys.readouterr().out


def test_version_is_the_packages(capsys):
    import hdrjax

    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"hdrjax {hdrjax.__version__}"


@pytest.mark.parametrize(
    "argv",
    [["tonemap", CORNELL, "-o", "x.png", "--exposure-t", "2"], ["info", CORNELL, "--sca", "2"]],
)
def test_abbreviated_options_are_refused(tmp_path, capsys, argv):
    """``--exposure-t`` is not taken for ``--exposure-time`` (argparse's default would)."""
    argv = [str(tmp_path / a) if a == "x.png" else a for a in argv]
    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and "unrecognized arguments" in err and err.count("\n") == 1


def test_exposure_scales_the_input_in_stops(tmp_path, capsys):
    """``--exposure 1`` doubles the input: with a fixed white (linear, L_max) the display
    values double below white; ``--exposure 1 --scale 0.5`` is the identity."""
    outs = {}
    for name, extra in [
        ("a", []),
        ("b", ["--exposure", "1"]),
        ("c", ["--exposure", "1", "--scale", "0.5"]),
    ]:
        out = tmp_path / f"{name}.exr"
        argv = ["tonemap", CORNELL, "-o", str(out), "--method", "linear", "--L-max", "100"]
        assert main(argv + extra) == 0
        outs[name] = np.asarray(read(out).rgb())
    np.testing.assert_allclose(outs["b"], 2 * outs["a"], rtol=1e-6)
    np.testing.assert_array_equal(outs["c"], outs["a"])
    capsys.readouterr()
    for ev in ("nan", "200", "-200"):
        assert main(["tonemap", CORNELL, "-o", str(tmp_path / "d.png"), "--exposure", ev]) == 2
        err = capsys.readouterr().err
        assert err.startswith("hdrjax tonemap: error: --exposure:") and err.count("\n") == 1


def test_a_closed_pipe_ends_quietly():
    """``hdrjax info x.exr | head``: the reader has gone, so no traceback and no error line
    (the read end is closed before the command starts: every write fails)."""
    import os

    r, w = os.pipe()
    os.close(r)
    try:
        done = subprocess.run(
            [sys.executable, "-m", "hdrjax", "info", CORNELL],
            stdout=w,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, "HDRJAX_CACHE": "0"},
        )
    finally:
        os.close(w)
    assert done.returncode == 141 and done.stderr == ""
