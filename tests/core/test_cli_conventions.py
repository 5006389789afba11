"""Command-line conventions shared by every subcommand: one meaning per option name, and
one overwrite policy (an existing output is replaced, never an input; ``--no-clobber``
refuses an existing output).

The parsers are those of the real ``hdrjax`` command (:func:`hdrjax.cli.build_parser`),
walked at run time, so a subcommand added later is held to the same rules."""

import argparse
import os

import numpy as np
import pytest

from hdrjax import io as hio
from hdrjax.cli import build_parser, main


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    (sub,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(sub.choices)


def _meaning(action: argparse.Action) -> tuple:
    """What an option is, as far as a user typing it can tell: a flag or a value (and how
    many), and the type of the value."""
    kind = type(action).__name__.strip("_").removesuffix("Action")
    return kind, action.nargs, getattr(action.type, "__qualname__", action.type)


def test_one_meaning_per_option_name():
    seen: dict[str, dict[tuple, list[str]]] = {}
    for name, parser in _subparsers().items():
        for action in parser._actions:
            if action.help == argparse.SUPPRESS:  # a renamed option's old spelling
                continue
            for option in action.option_strings:
                seen.setdefault(option, {}).setdefault(_meaning(action), []).append(name)
    clashes = {o: m for o, m in seen.items() if len(m) > 1}
    assert not clashes, "\n".join(f"{o}: {m}" for o, m in sorted(clashes.items()))


@pytest.mark.parametrize(
    ("argv", "dest", "value", "note"),
    [
        (["measure", "x.exr", "--scale", "50"], "scale", 50.0, "--view-scale"),
        (["batch", "x.exr", "-o", "d", "--compression", "6"], "zlib_level", 6, "--zlib-level"),
        (["lights", "x.exr", "--json", "l.json"], "json_path", "l.json", "--json-out"),
        (
            ["compare", "x.exr", "-o", "r.html", "--json", "t.json"],
            "json_path",
            "t.json",
            "--json-out",
        ),
        (["export", "x.exr", "-o", "y.exr", "--overwrite"], "no_clobber", False, "--no-clobber"),
    ],
)
def test_renamed_options_still_work_for_one_release(argv, dest, value, note, capsys):
    args = build_parser().parse_args(argv)
    assert getattr(args, dest) == value
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is deprecated" in err and note in err, err


# every command that writes files: its call on scene.exr (a.png, b.png: a bracket), with
# {OUT} the output that exists beforehand; batch's output is a folder of frames, whose
# existing frames are skipped (resume) or replaced (--no-resume): tests/batch
POLICY = {
    "tonemap": ["tonemap", "scene.exr", "-o", "{OUT}.png", "--method", "linear"],
    "filter": ["filter", "scene.exr", "-o", "{OUT}.exr", "--mean", "3"],
    "desaturate": ["desaturate", "scene.exr", "-o", "{OUT}.exr", "--threshold", "2"],
    "falsecolor": ["falsecolor", "scene.exr", "-o", "{OUT}.png", "--legend", "none"],
    "vision": ["vision", "scene.exr", "-o", "{OUT}.exr", "--scale", "100", "--effects", "none"],
    "fit": ["fit", "scene.exr", "-o", "{OUT}.exr", "--method", "linear", "--target",
            "mean=0.2", "--max-steps", "2", "--force"],
    "export": ["export", "scene.exr", "-o", "{OUT}.hdr"],
    "measure": ["measure", "scene.exr", "--rect", "0,0,2,2", "--region-out", "{OUT}.json"],
    "lights": ["lights", "scene.exr", "--json-out", "{OUT}.json", "--width", "16"],
    "compare": ["compare", "scene.exr", "-o", "{OUT}.html", "--methods", "linear",
                "--max-size", "8", "--repeats", "1"],
    "merge": ["merge", "a.png", "b.png", "-o", "{OUT}.exr", "--exposure-times", "0.01",
              "0.04", "--response", "linear"],
    "fuse": ["fuse", "a.png", "b.png", "-o", "{OUT}.png", "--exposure-times", "0.01", "0.04"],
    "panorama": ["panorama", "scene.exr", "-o", "{OUT}.exr", "--projection", "perspective",
                 "--input-projection", "fisheye", "--size", "4"],
    "histogram": ["histogram", "scene.exr", "-o", "{OUT}.png"],
}  # fmt: skip


def _writers() -> set[str]:
    return {n for n, p in _subparsers().items() if "--no-clobber" in p._option_string_actions}


def test_every_writing_command_has_one_policy():
    from hdrjax.cli._common import WRITING_DESTS

    subs = _subparsers()
    writing = {n for n, p in subs.items() if any(a.dest in WRITING_DESTS for a in p._actions)}
    assert writing - _writers() == {"batch"}  # its own: resume, or --no-resume
    assert set(POLICY) == _writers(), "add the new writing command to POLICY"


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("policy")
    rng = np.random.default_rng(0)
    hio.write(d / "scene.exr", rng.uniform(0.05, 4.0, (8, 8, 3)).astype(np.float32))
    base = rng.uniform(0.02, 0.2, (8, 8, 3))
    for name, gain in (("a.png", 1.0), ("b.png", 4.0)):
        hio.write_display(d / name, np.round(np.clip(base * gain, 0, 1) * 255).astype(np.uint8))
    return d


# the commands run to the end here (the others compute for seconds; that they reach the
# atomic replacement of an existing output is tested for each of them by
# tests/conformance/test_cli_errors.py::test_disk_full_keeps_the_previous_output)
RUN = ("desaturate", "export", "filter", "measure", "merge")


@pytest.mark.parametrize("cmd", sorted(POLICY))
def test_existing_output_is_replaced_unless_no_clobber(cmd, folder, monkeypatch, capsys):
    monkeypatch.chdir(folder)
    argv = [a.replace("{OUT}", f"out_{cmd}") for a in POLICY[cmd]]
    (out,) = [a for a in argv if a.startswith("out_")]
    old = b"an older output\n"
    with open(out, "wb") as f:
        f.write(old)
    assert main([*argv, "--no-clobber"]) == 2
    err = capsys.readouterr().err
    assert err == f"hdrjax {cmd}: error: {out}: already exists (--no-clobber)\n"
    with open(out, "rb") as f:
        assert f.read() == old
    # an input is never replaced, --no-clobber or not (every way of naming it:
    # tests/io/test_output_paths.py)
    src = argv[1]
    with open(src, "rb") as f:
        before = f.read()
    assert main([a.replace(out, src) for a in argv]) == 2
    with open(src, "rb") as f:
        assert f.read() == before
    if cmd in RUN:
        assert main(argv) == 0, capsys.readouterr().err
        with open(out, "rb") as f:
            assert f.read() != old
        assert not [p for p in os.listdir() if p.endswith(".tmp")]
