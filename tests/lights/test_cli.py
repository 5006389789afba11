"""``hdrjax lights``: overlay, JSON, median cut and errors, on the shipped map."""

import json

import pytest

from hdrjax.cli import main

from ._synth import rooitou


def test_lights_overlay_and_json(tmp_path, capsys):
    png, js = tmp_path / "overlay.png", tmp_path / "lights.json"
    assert main(["lights", str(rooitou()), "-o", str(png), "--json-out", str(js)]) == 0
    out = capsys.readouterr().out
    assert "1 light(s)" in out and "az  +36.09" in out
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    doc = json.loads(js.read_text())
    assert doc["count"] == 1 and doc["convention"] == "hdrjax"
    (sun,) = doc["lights"]
    assert sun["azimuth_deg"] == pytest.approx(36.0, abs=0.36)
    assert sun["elevation_deg"] == pytest.approx(10.4, abs=0.36)
    assert sun["energy_share"] == pytest.approx(0.633, abs=0.04)


def test_lights_convention_and_median_cut(tmp_path):
    js = tmp_path / "l.json"
    assert main(["lights", str(rooitou()), "--json-out", str(js), "--convention", "blender"]) == 0
    d = json.loads(js.read_text())["lights"][0]["direction"]
    # Blender: centre +X, right -Y, up +Z; the sun is 36° right of centre, 10.5° up
    assert d[0] > 0.75 and d[1] < -0.55 and d[2] == pytest.approx(0.183, abs=0.01)
    assert (
        main(
            [
                "lights",
                str(rooitou()),
                "--method",
                "median-cut",
                "--n-lights",
                "8",
                "--json-out",
                str(js),
            ]
        )
        == 0
    )
    doc = json.loads(js.read_text())
    assert len(doc["lights"]) == 8
    assert sum(r["energy_share"] for r in doc["lights"]) == pytest.approx(1.0, abs=1e-5)


def test_lights_errors(tmp_path, capsys):
    assert main(["lights", str(tmp_path / "missing.hdr")]) == 1
    assert "no such file" in capsys.readouterr().err
    assert main(["lights", str(rooitou()), "-o", str(tmp_path / "x.bmp")]) == 2
    assert (
        main(["lights", str(rooitou()), "--method", "median-cut", "-o", str(tmp_path / "x.png")])
        == 2
    )
    assert main(["lights", str(rooitou()), "--method", "median-cut", "--n-lights", "6"]) == 2
    with pytest.raises(SystemExit) as e:
        main(["lights", str(rooitou()), "--width", "0"])
    assert e.value.code == 2
