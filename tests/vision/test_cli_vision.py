"""``hdrjax vision``: report, simulation output, and one-line errors."""

import json

import numpy as np
import pytest

from hdrjax import io as hio
from hdrjax.cli import main

from ..conftest import DATA


@pytest.fixture
def night_exr(tmp_path):
    rng = np.random.default_rng(0)
    rgb = (rng.uniform(0.02, 0.4, (48, 96, 1)) * np.array([1.0, 0.8, 0.6])).astype(np.float32)
    rgb[20:22, 40:42] = 3e3  # a lamp
    path = tmp_path / "night.exr"
    hio.write(path, rgb)
    return path, rgb


def test_report_as_json(night_exr, capsys):
    path, rgb = night_exr
    assert main(["vision", str(path), "--fov", "30", "--scale", "1", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert set(rep["selected"]) >= {"glare", "colour_loss"}
    assert rep["view"]["hfov"] == 30.0
    assert rep["luminance_max"] == pytest.approx(3e3, rel=1e-4)
    assert rep["decisions"]["glare"]["threshold"] == 4.5


def test_simulate_to_exr_and_png(night_exr, tmp_path, capsys):
    path, rgb = night_exr
    out = tmp_path / "sim.exr"
    code = main(["vision", str(path), "--scale", "1", "-o", str(out), "--without", "contrast"])
    assert code == 0
    text = capsys.readouterr().out
    assert "applied: glare, colour_loss, blue_shift" in text
    # the report printed says so too (its decisions are the rules', which add contrast)
    assert "effects simulated: glare, colour_loss, blue_shift (" in text
    sim = hio.read(out).rgb()
    assert sim.shape == rgb.shape and np.isfinite(sim).all()
    assert sim[0, 0].std() < rgb[0, 0].std()  # night colours lost
    png = tmp_path / "sim.png"  # after contrast: linear display mapping at --display-max
    args = ["--effects", "colour_loss,contrast", "-o", str(png)]
    assert main(["vision", str(path), "--scale", "1", *args]) == 0
    assert png.stat().st_size > 0
    pp = tmp_path / "perc.png"  # Budak2005 re-adapts itself: contrast is dropped
    args = ["--effects", "colour_loss,contrast", "-o", str(pp), "--perceptual"]
    assert main(["vision", str(path), "--scale", "1", *args]) == 0
    applied = capsys.readouterr().out.split("applied:")
    assert "contrast" in applied[-2] and "contrast" not in applied[-1]


def test_errors_are_one_line(night_exr, tmp_path, capsys):
    path, _ = night_exr
    assert main(["vision", str(path)]) == 2  # relative file, no --scale
    err = capsys.readouterr().err
    assert "scale" in err and err.count("\n") == 1
    assert main(["vision", str(tmp_path / "missing.exr"), "--scale", "1"]) == 1
    assert main(["vision", str(path), "--scale", "1", "--with", "bloom"]) == 2
    assert main(["vision", str(path), "--scale", "1", "-o", str(tmp_path / "x.gif")]) == 2
    assert "unknown effect" not in capsys.readouterr().out


def test_real_file_cornell_box(capsys):
    assert main(["vision", str(DATA / "cornell_box.exr"), "--scale", "0.01"]) == 0
    out = capsys.readouterr().out
    assert "colour_loss  yes" in out and "acuity       yes" in out
