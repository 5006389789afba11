"""``hdrjax layers``, ``hdrjax measure`` and ``hdrjax export`` (run in-process)."""

import json

import numpy as np
import pytest

import hdrjax.io as hio
from hdrjax.cli import main
from hdrjax.layers import LayeredImage

from ..conftest import DATA


@pytest.fixture
def scene(tmp_path):
    h, w = 4, 6
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    img = LayeredImage(
        image=np.stack([xx, yy, xx * 0 + 1], axis=2),
        quantity="luminance",
        layers={
            "position": np.stack([xx, yy, xx * 0], axis=2),
            "hits": np.full((h, w), 2, np.uint32),
            "view": {"fov_deg": 90.0},
        },
    )
    return hio.write(tmp_path / "scene.exr", img, sidecars=["position"])


def test_layers_lists_parts_channels_and_layers(scene, capsys):
    assert main(["layers", str(scene)]) == 0
    out = capsys.readouterr().out
    assert "part 0: (unnamed), scanlineimage" in out
    assert "data window [0, 0, 5, 3], display window [0, 0, 5, 3]" in out
    assert "channel hits: uint" in out and "channel R: float" in out
    assert "attribute quantity: luminance" in out
    assert "layer position: grid float32 (4, 6, 3) [X, Y, Z]" in out
    assert "layer view: non-grid dict (fov_deg)" in out
    assert "sidecar position: " in out and "scene.position.exr" in out
    assert main(["layers", str(DATA / "MtTamNorth.exr"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    ry = [c for c in doc["parts"][0]["channels"] if c["name"] == "RY"][0]
    assert ry == {"name": "RY", "type": "half", "sampling": [2, 2]}
    assert doc["image"]["channels"] == ["Y", "RY", "BY"]


def test_measure_distance_readout_and_region(scene, tmp_path, capsys):
    assert main(["measure", str(scene), "--from", "0,0", "--to", "3,4", "--2d"]) == 1
    assert "outside the 6 x 4 image" in capsys.readouterr().err
    assert main(["measure", str(scene), "--from", "0,0", "--to", "3,3", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)["distance"]
    assert d["mode"] == "3d" and d["value"] == pytest.approx(np.hypot(3, 3))
    out_json = tmp_path / "region.json"
    argv = [
        "measure",
        str(scene),
        "--at",
        "2,1",
        "--rect",
        "0,0,2,2",
        "--region-out",
        str(out_json),
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "pixel (2, 1): luminance" in out and "hits: 2" in out and "total hits: 8" in out
    assert json.loads(out_json.read_text())["stats"]["pixels"] == 4
    assert main(argv) == 0  # an existing region file is replaced
    assert main([*argv, "--no-clobber"]) == 2  # unless refused
    assert "already exists (--no-clobber)" in capsys.readouterr().err
    assert main(["measure", str(scene)]) == 2
    assert main(["measure", str(scene), "--from", "1,1"]) == 2


def test_export_conversions_and_overwrite(scene, tmp_path, capsys):
    hdr = tmp_path / "out.hdr"
    assert main(["export", str(scene), "-o", str(hdr), "--sidecars"]) == 0
    assert (tmp_path / "out.position.exr").exists()
    got = hio.read(hdr)
    np.testing.assert_array_equal(got.layers["position"], hio.read(scene).layers["position"])
    assert main(["export", str(scene), "-o", str(hdr)]) == 0  # replaced
    hdr.unlink()  # the sidecar is still there: written by the library, refused by it too
    assert main(["export", str(scene), "-o", str(hdr), "--sidecars", "--no-clobber"]) == 2
    assert ".exr: already exists (--no-clobber)" in capsys.readouterr().err  # a sidecar
    half = tmp_path / "half.exr"
    assert (
        main(["export", str(DATA / "cornell_box.exr"), "-o", str(half), "--pixel-type", "half"])
        == 0
    )
    np.testing.assert_array_equal(hio.read(half).image, hio.read(DATA / "cornell_box.exr").image)
    png = tmp_path / "view.png"
    assert main(["export", str(scene), "-o", str(png), "--exposure", "-3"]) == 0
    from PIL import Image

    with Image.open(png) as im:
        assert im.size == (6, 4) and im.mode == "RGB"
    assert main(["export", str(scene), "-o", str(tmp_path / "x.bmp")]) == 2
    bad = tmp_path / "bad.exr"
    bad.write_bytes(b"\x76\x2f\x31\x01garbage")
    assert main(["export", str(bad), "-o", str(tmp_path / "y.exr")]) == 1
    assert "bad.exr: corrupt" in capsys.readouterr().err
