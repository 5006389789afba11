"""``-o -``: every command that writes one image writes it to standard output when given
``--format`` (PNG, Radiance or PFM, the formats written front to back), byte for byte the
file it writes to a path, with its status text on standard error; without ``--format`` it
is a usage error that writes nothing."""

import io
import sys

import numpy as np
import pytest

from hdrjax import io as hio
from hdrjax.cli import build_parser, main

# command → (argv with {IN} and {OUT}, the formats its -o - takes)
CASES = {
    "tonemap": (["tonemap", "{IN}", "-o", "{OUT}"], ("png", "hdr", "pfm")),
    "fit": (["fit", "{IN}", "-o", "{OUT}", "--target", "mean=0.2"], ("png",)),
    "filter": (["filter", "{IN}", "-o", "{OUT}", "--mean", "3"], ("hdr", "pfm")),
    "desaturate": (["desaturate", "{IN}", "-o", "{OUT}"], ("pfm",)),
    "vision": (["vision", "{IN}", "-o", "{OUT}", "--scale", "100"], ("pfm",)),
    "falsecolor": (["falsecolor", "{IN}", "-o", "{OUT}"], ("png",)),
    "export": (["export", "{IN}", "-o", "{OUT}"], ("hdr", "pfm", "png")),
    "panorama": (
        ["panorama", "{IN}", "-o", "{OUT}", "--projection", "disc"]
        + ["--input-projection", "polar", "--size", "4"],
        ("hdr", "pfm"),
    ),
    "histogram": (["histogram", "{IN}", "-o", "{OUT}"], ("png",)),
}


def _stdout_commands() -> set[str]:
    """Subcommands with a --format option for -o - (as the parser declares them)."""
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    return {n for n, p in sub.choices.items() if any(a.dest == "format" for a in p._actions)}


def test_every_command_with_standard_output_is_covered():
    assert _stdout_commands() - {"batch"} == set(CASES)  # batch: --format of its folder


class _Stdout(io.TextIOWrapper):
    """A text stdout over a bytes buffer (what ``sys.stdout.buffer`` is in a process)."""

    def __init__(self):
        super().__init__(io.BytesIO(), encoding="utf-8")


def _run(argv, monkeypatch):
    out = _Stdout()
    monkeypatch.setattr(sys, "stdout", out)
    code = main(argv)
    out.flush()
    return code, out.buffer.getvalue()


@pytest.mark.parametrize("command", sorted(CASES))
def test_standard_output_equals_the_file(command, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rgb = np.random.default_rng(3).uniform(0.01, 4.0, (8, 8, 3)).astype(np.float32)
    hio.write("in.exr", rgb)
    argv, formats = CASES[command]
    for fmt in formats:
        fill = lambda out: [a.replace("{IN}", "in.exr").replace("{OUT}", out) for a in argv]  # noqa: E731
        code, data = _run(fill("-") + ["--format", fmt], monkeypatch)
        err = capsys.readouterr().err
        assert code == 0, err
        assert "wrote: -" in err  # status text on standard error
        code, nothing = _run(fill(f"ref.{fmt}"), monkeypatch)
        assert code == 0 and b"wrote: ref." in nothing
        ref = (tmp_path / f"ref.{fmt}").read_bytes()
        assert data == ref, f"{command} --format {fmt}: {len(data)} bytes, file {len(ref)}"
    # no --format: a one-line usage error, nothing on standard output
    code, data = _run(
        [a.replace("{IN}", "in.exr").replace("{OUT}", "-") for a in argv], monkeypatch
    )
    err = capsys.readouterr().err.strip()
    assert code == 2 and data == b"" and "-o -: give --format" in err and "\n" not in err


def test_format_without_standard_output_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    hio.write("in.exr", np.ones((4, 4, 3), np.float32))
    code, _ = _run(
        ["filter", "in.exr", "-o", "out.pfm", "--mean", "3", "--format", "pfm"], monkeypatch
    )
    assert code == 2 and "--format applies to -o -" in capsys.readouterr().err
    assert not (tmp_path / "out.pfm").exists()
    # a format the command does not write: argparse's usage error, nothing written
    with pytest.raises(SystemExit) as e:
        _run(["filter", "in.exr", "-o", "-", "--mean", "3", "--format", "png"], monkeypatch)
    assert e.value.code == 2 and "invalid choice: 'png'" in capsys.readouterr().err
