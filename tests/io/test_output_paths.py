"""Where outputs go: a command never writes over a file it reads (same path, symbolic link
or hard link), and sibling quantities recorded in a written file still point at them."""

import os

import numpy as np
import pytest

from hdrjax import io as hio
from hdrjax.cli import build_parser, main
from hdrjax.cli._common import UsageError, refuse_overwriting_inputs
from hdrjax.layers import LayeredImage

# subcommand call → the file it must not overwrite ({P}); {OUT} is the output (the
# protected file itself, or a link to it). Files named scene.exr and frames/a.exr exist.
CASES = {
    "tonemap": (["tonemap", "{P}", "-o", "{OUT}"], "x.hdr"),
    "filter": (["filter", "{P}", "-o", "{OUT}", "--mean", "3"], "x.exr"),
    "desaturate": (["desaturate", "{P}", "-o", "{OUT}"], "x.exr"),
    "fit": (["fit", "{P}", "-o", "{OUT}", "--target", "mean=0.2"], "x.exr"),
    "fit reference": (["fit", "scene.exr", "-o", "{OUT}", "--target", "reference={P}"], "x.png"),
    "vision": (["vision", "{P}", "-o", "{OUT}", "--scale", "100"], "x.exr"),
    "export": (["export", "{P}", "-o", "{OUT}"], "x.exr"),
    "falsecolor": (["falsecolor", "{P}", "-o", "{OUT}"], "x.png"),
    "falsecolor legend": (["falsecolor", "{P}", "-o", "fc.png", "--legend", "{OUT}"], "x.png"),
    "lights": (["lights", "{P}", "-o", "{OUT}"], "x.png"),
    "lights json": (["lights", "{P}", "--json-out", "{OUT}"], "x.json"),
    "measure": (["measure", "{P}", "--rect", "0,0,2,2", "--region-out", "{OUT}"], "x.json"),
    "compare": (["compare", "{P}", "-o", "{OUT}", "--methods", "linear"], "x.hdr"),
    "compare json": (["compare", "{P}", "-o", "r.html", "--json-out", "{OUT}"], "x.exr"),
    "compare reference": (["compare", "scene.exr", "--reference", "{P}", "-o", "{OUT}"], "x.png"),
    "merge": (["merge", "{P}", "b.png", "-o", "{OUT}"], "x.png"),
    "merge response": (
        ["merge", "a.png", "b.png", "-o", "m.exr", "--response", "{P}", "--save-response", "{OUT}"],
        "x.json",
    ),
    "fuse": (["fuse", "a.png", "{P}", "-o", "{OUT}"], "x.png"),
    "panorama": (["panorama", "{P}", "-o", "{OUT}", "--projection", "cube"], "x.exr"),
    "histogram": (["histogram", "{P}", "-o", "{OUT}"], "x.png"),
    # batch: the output folder holds the input frame under its output name
    "batch": (["batch", "{P}", "-o", "{OUT}", "--format", "exr", "--no-resume"], "frames/a.exr"),
    "batch folder": (["batch", "{P}", "-o", "{OUT}"], "x.exr"),  # -o names an input file
}
# options whose value is a file or folder a subcommand writes
WRITING_DESTS = {"output", "json_path", "region_out", "legend", "save_response"}


def _writers() -> set[str]:
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    return {n for n, p in sub.choices.items() if any(a.dest in WRITING_DESTS for a in p._actions)}


def test_every_writing_command_is_covered():
    assert {argv[0] for argv, _ in CASES.values()} == _writers()


def _image(path, seed=0):
    rgb = np.random.default_rng(seed).uniform(0.01, 4.0, (8, 8, 3)).astype(np.float32)
    hio.write(path, rgb)


@pytest.mark.parametrize("link", ["same path", "symlink", "hard link"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_output_that_is_an_input_is_refused(case, link, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    argv, protected = CASES[case]
    os.mkdir("frames")
    _image("scene.exr")
    if protected.endswith((".exr", ".hdr")):
        _image(protected, seed=1)
    else:  # never read: the refusal comes first
        with open(protected, "wb") as f:
            f.write(b"not to be replaced\n")
    with open(protected, "rb") as f:
        before = f.read()
    if case == "batch":  # the output is a folder; the frame's output name is the frame's
        out = {"same path": "frames", "symlink": "linked", "hard link": "hard"}[link]
        target = os.path.join(out, "a.exr")
        if link == "symlink":
            os.symlink("frames", "linked")
        elif link == "hard link":
            os.mkdir("hard")
            os.link(protected, target)
    else:
        out = target = {"same path": protected, "symlink": "l_", "hard link": "h_"}[link]
        if link != "same path":
            out = target = out + os.path.basename(protected)
            (os.symlink if link == "symlink" else os.link)(protected, out)
    args = [a.replace("{P}", protected).replace("{OUT}", out) for a in argv]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert err.startswith(f"hdrjax {argv[0]}: error: {target}: output is the input file"), err
    with open(protected, "rb") as f:
        assert f.read() == before


def test_standard_streams_are_never_a_file(tmp_path):
    p = tmp_path / "x.exr"
    p.write_bytes(b"x")
    refuse_overwriting_inputs(["-", None, tmp_path / "y.exr"], ["-", p])  # nothing shared
    with pytest.raises(UsageError, match="x.exr: output is the input file$"):
        refuse_overwriting_inputs(["-", str(p)], ["-", str(p)])


def _simulation(folder):
    """``scene.exr`` (luminance) and its sibling ``scene.illuminance.exr`` in ``folder``."""
    folder.mkdir(parents=True)
    rng = np.random.default_rng(3)
    lum = LayeredImage(image=rng.uniform(0.1, 9.0, (8, 8, 3)).astype(np.float32))
    ill = LayeredImage(image=rng.uniform(1.0, 500.0, (8, 8, 1)).astype(np.float32))
    hio.write(folder / "scene.exr", lum.replace(quantity="luminance"))
    hio.write(folder / "scene.illuminance.exr", ill.replace(quantity="illuminance"))
    return ill.image


def _recorded(path) -> list[str]:
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        return list(f.header()["hdrjax.siblings"])


def test_siblings_stay_linked_from_another_folder(tmp_path):
    ill = _simulation(tmp_path / "sim" / "in")
    src = tmp_path / "sim" / "in" / "scene.exr"
    img = hio.read(src)
    assert set(img.siblings) == {"illuminance"}
    med = tmp_path / "sim" / "out" / "scene_med.exr"
    med.parent.mkdir()
    hio.write(med, img)  # what `hdrjax filter` does with the filtered image
    assert main(["export", str(src), "-o", str(tmp_path / "copy.exr")]) == 0
    # recorded relative to the output's folder
    assert _recorded(med) == ["illuminance=../in/scene.illuminance.exr"]
    assert _recorded(tmp_path / "copy.exr") == ["illuminance=sim/in/scene.illuminance.exr"]
    for out in (med, tmp_path / "copy.exr"):
        sib = hio.read(out).siblings["illuminance"]
        assert sib.samefile(tmp_path / "sim" / "in" / "scene.illuminance.exr")
    # a relative link survives moving the output together with its sibling
    os.rename(tmp_path / "sim", tmp_path / "moved")
    other = hio.read(hio.read(tmp_path / "moved" / "out" / "scene_med.exr").siblings["illuminance"])
    assert other.quantity == "illuminance"
    np.testing.assert_array_equal(other.image, ill)


def test_a_sibling_that_does_not_exist_is_dropped_with_a_note(tmp_path):
    _simulation(tmp_path / "in")
    img = hio.read(tmp_path / "in" / "scene.exr")
    os.remove(tmp_path / "in" / "scene.illuminance.exr")
    with pytest.warns(UserWarning, match=r"out\.exr: sibling illuminance .* does not exist; not"):
        hio.write(tmp_path / "out.exr", img)
    assert hio.read(tmp_path / "out.exr").siblings == {}
