"""``hdrjax merge`` and ``hdrjax fuse``: the commands write what the library computes from the
same files, calibrated files read as cd/m² downstream, and bad brackets are one-line errors
naming the file."""

import errno
import os
from pathlib import Path

import numpy as np
import pytest
import tifffile
from PIL import Image

import hdrjax.merge as hm
from hdrjax import io as hio
from hdrjax.cli import build_parser, main

from .test_read import B8, SCENE, TIMES, exif_for, save_png, write_dng


def _bracket(folder: Path, *, f_number=8.0, iso=100, codes=B8.codes, times=TIMES, stem="m"):
    paths = []
    for j in range(len(times)):
        p = folder / f"{stem}{j}.png"
        save_png(p, codes[j], exif_for(times[j], f_number, iso))
        paths.append(str(p))
    return paths


def _run(argv):
    try:
        return main(argv)
    except SystemExit as e:  # argparse's usage errors
        return e.code


def _error(capsys, command):
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"hdrjax {command}: error: "), err
    return err


def test_help_lists_both_commands(capsys):
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    assert {"merge", "fuse"} <= set(sub.choices)
    # the parser lists the weights without importing JAX: the same as the library's
    (weights,) = [a for a in sub.choices["merge"]._actions if a.dest == "weights"]
    assert tuple(weights.choices) == hm.WEIGHTS
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert "merge an exposure bracket" in out and "fuse an exposure bracket" in out


def test_merge_writes_the_librarys_radiance_and_calibrates(tmp_path, capsys):
    paths = _bracket(tmp_path)
    out, resp = tmp_path / "out.exr", tmp_path / "r.json"
    shuffled = [paths[j] for j in (2, 4, 0, 3, 1)]
    assert main(["merge", *shuffled, "-o", str(out), "--save-response", str(resp)]) == 0
    text = capsys.readouterr().out
    assert "bracket: 5 exposures, 96x64, 8-bit" in text and "1/64 s  f/8  ISO 100" in text
    g = hm.recover_response(B8.codes, TIMES)
    expected = np.asarray(hm.merge(B8.codes, TIMES, g))
    img = hio.read(out)
    assert img.quantity == "relative"
    np.testing.assert_array_equal(img.image, expected)
    np.testing.assert_array_equal(np.asarray(hm.load_response(resp)), np.asarray(g))
    # the saved response, loaded back, merges to the same image; calibrated to cd/m²
    cal = tmp_path / "cal.hdr"
    argv = ["merge", *paths, "-o", str(cal), "--response", str(resp), "--calibrate"]
    assert main(argv) == 0
    assert "f/8, ISO 100: 76.6144 cd/m² per unit" in capsys.readouterr().out
    img = hio.read(cal)
    assert img.quantity == "luminance" and img.unit == "cd/m²"
    scale = float(hm.absolute_scale(8.0, 100))
    # Radiance RGBE: 8-bit mantissas under the pixel's largest channel's exponent
    top = expected.max(axis=-1, keepdims=True) * scale
    assert np.all(np.abs(img.image - expected * scale) <= top / 128)
    # downstream commands read cd/m² without --scale
    exr = tmp_path / "cal.exr"
    assert main(["merge", *paths, "-o", str(exr), "--response", str(resp), "--calibrate"]) == 0
    back = hio.read(exr)
    np.testing.assert_array_equal(back.image, (expected * np.float32(scale)))
    # OpenEXR's own attribute too: RGB (1, 1, 1) is 1 cd/m²
    assert back.white_luminance == 1.0 and back.quantity == "luminance"
    capsys.readouterr()
    assert main(["falsecolor", str(exr), "-o", str(tmp_path / "fc.png")]) == 0
    assert "cd/m²" in capsys.readouterr().out
    assert main(["vision", str(exr), "-o", str(tmp_path / "v.exr"), "--effects", "none"]) == 0


def test_merge_options_align_deghost_weights(tmp_path, capsys):
    shifted = hm.simulate_bracket(SCENE, TIMES, shifts=[[3, -2], [1, 0], [0, 0], [-2, 1], [4, 4]])
    paths = _bracket(tmp_path, codes=shifted.codes)
    out = tmp_path / "a.exr"
    argv = ["merge", *paths, "-o", str(out), "--align", "--deghost", "--weights", "triangle"]
    assert main([*argv, "--response", "robertson", "--samples", "2000"]) == 0
    text = capsys.readouterr().out
    shifts = hm.align_mtb(shifted.codes)
    listed = ", ".join(f"({dx:+d}, {dy:+d})" for dx, dy in shifts.tolist())
    assert f"shifts (dx, dy) {listed}" in text and "deghosted (Grosch 2006)" in text
    codes = hm.apply_shifts(shifted.codes, shifts)
    # the response comes from inside the border the shifts uncovered (edge pixels repeated)
    b = int(np.abs(shifts).max())
    g = hm.recover_response(codes[:, b:-b, b:-b], TIMES, method="robertson", samples=2000)
    mask = hm.ghost_mask(codes, TIMES, g)
    expected = hm.merge(codes, TIMES, g, weights="triangle", mask=mask)
    np.testing.assert_array_equal(hio.read(out).image, np.asarray(expected))


def test_merge_16bit_tiff_linear_and_raw(tmp_path, capsys):
    lin = hm.simulate_bracket(SCENE, TIMES[1:4], curve="linear", bits=16, fill=0.6)
    tifs = []
    for j in range(3):
        p = tmp_path / f"t{j}.tif"
        tifffile.imwrite(p, lin.codes[j], photometric="rgb")
        tifs.append(str(p))
    times = [str(t) for t in TIMES[1:4]]
    out = tmp_path / "t.exr"
    argv = ["merge", *tifs, "-o", str(out), "--exposure-times", *times, "--response", "linear"]
    assert main(argv) == 0
    with np.errstate(divide="ignore"):  # g(0) = −inf: no exposure gives code 0
        g = np.log(np.arange(65536) / 65535.0)[:, None].repeat(3, 1)
    expected = np.asarray(hm.merge(lin.codes, TIMES[1:4], g))
    np.testing.assert_array_equal(hio.read(out).image, expected)
    # linear merge of a well-exposed pixel is the truth X / t
    ok = (lin.codes > 1000).all(0) & (lin.codes < 60000).all(0)
    np.testing.assert_allclose(expected[ok], lin.radiance[ok], rtol=1e-3)
    pytest.importorskip("rawpy")
    dngs = []
    for j in range(3):
        p = tmp_path / f"r{j}.dng"
        write_dng(p, lin.codes[j], t=TIMES[1 + j], f_number=4.0, iso=400, cfa=False)
        dngs.append(str(p))
    capsys.readouterr()
    assert main(["merge", *dngs, "-o", str(tmp_path / "r.exr"), "--calibrate"]) == 0
    assert "response: linear" in capsys.readouterr().out  # the default for RAW
    got = hio.read(tmp_path / "r.exr").image / float(hm.absolute_scale(4.0, 400))
    assert np.median(np.abs(got[ok] / lin.radiance[ok] - 1)) < 1e-3
    # fusion sRGB-encodes the linear RAW members first
    assert main(["fuse", *dngs, "-o", str(tmp_path / "r.png")]) == 0
    from hdrjax.display import encode

    codes = hm.read_bracket(dngs).images
    shown = np.stack([np.asarray(encode(m.astype(np.float32) / 65535, "srgb")) for m in codes])
    expected = np.rint(np.clip(np.asarray(hm.fuse(shown)), 0, 1) * 255).astype(np.uint8)
    diff = np.abs(np.asarray(Image.open(tmp_path / "r.png")).astype(int) - expected)
    assert diff.max() <= 1 and np.mean(diff > 0) < 1e-3  # float32 rounding at a code edge


def test_fuse_writes_the_librarys_fusion(tmp_path, capsys):
    paths = _bracket(tmp_path)
    for j in range(5):  # fusion needs no exposure times: files without EXIF are fine
        Image.fromarray(B8.codes[j]).save(tmp_path / f"plain{j}.png")
    plain = [str(tmp_path / f"plain{j}.png") for j in range(5)]
    assert main(["fuse", *plain, "-o", str(tmp_path / "f.png")]) == 0
    expected = np.rint(np.clip(np.asarray(hm.fuse(B8.codes)), 0, 1) * 255).astype(np.uint8)
    got = np.asarray(Image.open(tmp_path / "f.png"))
    np.testing.assert_array_equal(got, expected)
    argv = ["fuse", *paths, "-o", str(tmp_path / "f16.tif"), "--bits", "16", "--align"]
    assert main([*argv, "--contrast", "0.5", "--exposedness", "2", "--sigma", "0.3"]) == 0
    fused = hm.fuse(B8.codes, contrast=0.5, exposedness=2.0, sigma=0.3)
    expected = np.rint(np.clip(np.asarray(fused, np.float64), 0, 1) * 65535).astype(np.uint16)
    np.testing.assert_array_equal(tifffile.imread(tmp_path / "f16.tif"), expected)
    assert "fused (Mertens et al. 2007): contrast 0.5" in capsys.readouterr().out


def test_errors_are_one_line(tmp_path, capsys):
    paths = _bracket(tmp_path)
    out = str(tmp_path / "o.exr")
    Image.fromarray(B8.codes[1]).save(tmp_path / "noexif.png")
    noexif = str(tmp_path / "noexif.png")
    cases = [
        (["merge", paths[0], noexif, "-o", out], 1, "noexif.png: no exposure time in EXIF"),
        (["merge", paths[0], noexif, "-o", out], 1, "(--exposure-times)"),
        (["merge", *paths[:2], "-o", out, "--exposure-times", "1"], 2, "one time per image (2)"),
        (["merge", paths[0], "-o", out], 2, "at least 2 images"),
        (["merge", *paths, "-o", str(tmp_path / "o.png")], 2, "unsupported output type .png"),
        (["merge", *paths, "-o", out, "--response", "nope"], 2, "--response nope: neither"),
        (["merge", *paths, "-o", out, "--response", "linear", "--samples", "9"], 2, "--samples"),
        (["merge", *paths, "-o", out, "--iso", "100"], 2, "apply with --calibrate"),
        (["merge", *paths, "-o", "-"], 2, "-o -: merge writes a file"),
        (["merge", *paths, "-o", out, "--weights", "nope"], 2, "nope"),
        (["fuse", *paths, "-o", str(tmp_path / "f.jpg"), "--bits", "16"], 2, "JPEG is 8-bit"),
        (["fuse", *paths, "-o", str(tmp_path / "f.png"), "--contrast", "-1"], 2, "--contrast"),
        (["fuse", *paths, "-o", out], 2, "unsupported output type .exr"),
        (["merge", str(tmp_path / "gone.png"), *paths, "-o", out], 1, "gone.png: no such file"),
    ]
    for argv, code, needle in cases:
        assert _run(argv) == code, argv
        err = _error(capsys, argv[0])
        assert needle in err, (needle, err)
    plain = _bracket(tmp_path, f_number=None, iso=None, stem="plain")
    assert main(["merge", *plain, "-o", out, "--calibrate"]) == 1
    assert "plain0.png: no f-number in EXIF; --calibrate needs it" in _error(capsys, "merge")
    mixed = _bracket(tmp_path, stem="iso")
    save_png(Path(mixed[3]), B8.codes[3], exif_for(TIMES[3], 8.0, 200))
    assert main(["merge", *mixed, "-o", out, "--calibrate"]) == 1
    assert "iso3.png: ISO 200, but" in _error(capsys, "merge")
    save_png(tmp_path / "small.png", B8.codes[2][:32], exif_for(0.3))
    assert main(["merge", *paths, str(tmp_path / "small.png"), "-o", out]) == 1
    assert "small.png: 96x32 pixels" in _error(capsys, "merge")
    g16 = tmp_path / "g16.json"
    hm.save_response(g16, np.log(np.arange(1, 65537) / 65536.0)[:, None].repeat(3, 1))
    assert main(["merge", *paths, "-o", out, "--response", str(g16)]) == 1
    assert "g16.json: a response for 65536 code values" in _error(capsys, "merge")
    assert not os.path.exists(out)


@pytest.mark.parametrize("command,name", [("merge", "o.exr"), ("fuse", "o.png")])
def test_output_folder_not_writable_and_disk_full(command, name, tmp_path, capsys, monkeypatch):
    paths = _bracket(tmp_path)
    blocker = tmp_path / "plainfile"
    blocker.write_text("not a folder")
    assert main([command, *paths, "-o", str(blocker / name)]) == 1
    assert "plainfile" in _error(capsys, command)
    target = tmp_path / name
    target.write_bytes(b"previous output, must survive")
    import hdrjax.io._atomic as atomic

    def enospc(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(atomic.os, "replace", enospc)
    assert main([command, *paths, "-o", str(target)]) == 1
    monkeypatch.undo()
    assert "No space left on device" in _error(capsys, command)
    assert target.read_bytes() == b"previous output, must survive"
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
