"""Sidecar layer files and sibling quantity files (seed 000, section 3)."""

import warnings

import numpy as np
import pytest

import hdrjax.io as hio
from hdrjax.layers import LayeredImage


def _scene(h=5, w=7, seed=0, quantity="luminance"):
    rng = np.random.default_rng(seed)
    return LayeredImage(
        image=rng.random((h, w, 3)).astype(np.float32) * 100,
        quantity=quantity,
        layers={
            "position": rng.normal(size=(h, w, 3)).astype(np.float32),
            "object_id": rng.integers(0, 9, (h, w)).astype(np.uint32),
            "error": rng.random((h, w)).astype(np.float32),
            "mask": rng.random((h, w)).astype(np.float32),
        },
    )


def test_exr_sidecars_round_trip(tmp_path):
    src = _scene()
    hio.write(tmp_path / "scene.exr", src, sidecars=["position", "object_id", "mask"])
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["scene.exr", "scene.mask.exr", "scene.object_id.exr", "scene.position.exr"]
    got = hio.read(tmp_path / "scene.exr")
    for key in ("position", "object_id", "error", "mask"):
        np.testing.assert_array_equal(got.layers[key], src.layers[key])
    assert got.layers["object_id"].dtype == np.uint32
    assert set(got.attributes["sidecar_files"]) == {"position", "object_id", "mask"}
    # without sidecar lookup the main file holds only what was kept inside
    alone = hio.read(tmp_path / "scene.exr", sidecars=False)
    assert sorted(alone.layers) == ["error"]
    # a sidecar layer can be selected as the main image
    pos = hio.read(tmp_path / "scene.exr", layer="position")
    assert pos.channels == ("X", "Y", "Z")
    np.testing.assert_array_equal(pos.image, src.layers["position"])


def test_radiance_and_pfm_main_files_with_sidecars(tmp_path):
    src = _scene(seed=1)
    hio.write(tmp_path / "cam.hdr", src, sidecars=True)
    assert b"SIDECARS=mask" in (tmp_path / "cam.hdr").read_bytes()[:200]
    known = src.replace(layers={k: v for k, v in src.layers.items() if k != "mask"})
    with pytest.raises(ValueError, match="PFM has no room for metadata"):
        hio.write(tmp_path / "cam.pfm", src, sidecars=True)
    hio.write(tmp_path / "cam.pfm", known, sidecars=True)
    for ext in (".hdr", ".pfm"):
        got = hio.read(tmp_path / f"cam{ext}")
        assert sorted(got.layers) == (
            ["error", "mask", "object_id", "position"]
            if ext == ".hdr"
            else ["error", "object_id", "position"]
        )
        for key in got.layers:
            np.testing.assert_array_equal(got.layers[key], src.layers[key])
        assert got.layers["object_id"].dtype == np.uint32
    with pytest.warns(UserWarning, match="cannot hold layers; dropped error, mask"):
        hio.write(
            tmp_path / "plain.hdr",
            src.replace(layers={k: src.layers[k] for k in ("error", "mask")}),
        )


def test_sibling_quantities_share_layers(tmp_path):
    lum = _scene(seed=2, quantity="luminance")
    ill = LayeredImage(image=lum.image[:, :, :1] * 3, quantity="illuminance")
    hio.write(tmp_path / "room.luminance.exr", lum.replace(layers={}))
    hio.write(tmp_path / "room.illuminance.exr", ill)
    hio.write(tmp_path / "room.position.exr", lum.layers["position"])
    got = hio.read(tmp_path / "room.luminance.exr")
    assert got.quantity == "luminance" and got.unit == "cd/m²"
    assert got.siblings == {"illuminance": tmp_path / "room.illuminance.exr"}
    np.testing.assert_array_equal(got.layers["position"], lum.layers["position"])
    other = hio.read(got.siblings["illuminance"])
    assert other.quantity == "illuminance" and other.unit == "lx"
    assert other.siblings == {"luminance": tmp_path / "room.luminance.exr"}
    found, sib = hio.find_sidecars(tmp_path / "room.illuminance.exr")
    assert found == {"position": tmp_path / "room.position.exr"}


def test_overwrite_refusal_covers_sidecars(tmp_path):
    src = _scene(seed=3)
    hio.write(tmp_path / "s.exr", src, sidecars=["position"])
    (tmp_path / "s.exr").unlink()
    with pytest.raises(FileExistsError, match="s.position.exr"):
        hio.write(tmp_path / "s.exr", src, sidecars=["position"], overwrite=False)
    assert not (tmp_path / "s.exr").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hio.write(tmp_path / "s.exr", src, sidecars=["position"])  # overwrite=True replaces
