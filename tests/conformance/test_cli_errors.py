"""Bad input on the command line: one line on stderr naming the file or argument, a non-zero
exit status, never a traceback — for every subcommand that reads an image (found from the
parser, so a new subcommand must say here how it is called).

Cases: missing file, unreadable file (a directory under an image name — chmod 000 does not
stop root, which CI may be — and chmod 000 when not root), wrong format (bytes of another
format under an image extension), unknown method, invalid parameter, output folder not
writable (a path under a regular *file*: fails for root too), disk full (the writer raises
``OSError(ENOSPC)``; the previous output file must survive intact).
"""

import errno
import os

import pytest

from hdrjax.cli import build_parser, main

from ..conftest import DATA

# how each subcommand is called: input first, then the arguments it needs; OUT marks the
# output path (None: the command writes nothing by default)
ARGV = {
    "batch": (["-o", "OUTDIR", "--format", "png"], "OUTDIR"),
    "compare": (["-o", "OUT.html", "--methods", "drago2003", "--max-size", "32"], "OUT.html"),
    "desaturate": (["-o", "OUT.exr"], "OUT.exr"),
    "export": (["-o", "OUT.png"], "OUT.png"),
    "falsecolor": (["-o", "OUT.png", "--legend", "none"], "OUT.png"),
    "filter": (["-o", "OUT.exr", "--mean", "3"], "OUT.exr"),
    "fit": (["-o", "OUT.png", "--target", "mean=0.2", "--max-steps", "3", "--force"], "OUT.png"),
    "histogram": (["-o", "OUT.png"], "OUT.png"),
    "info": ([], None),
    "layers": ([], None),
    "lights": (["--json-out", "OUT.json", "--width", "64"], "OUT.json"),
    "measure": (["--at", "2,2"], None),
    # merge/fuse read a bracket of images, not one EXR: their unwritable-folder and full-disk
    # cases are in tests/merge/test_cli_merge.py
    "merge": (["-o", "OUT.exr"], None),
    "fuse": (["-o", "OUT.png"], None),
    "panorama": (
        [
            "-o",
            "OUT.exr",
            "--projection",
            "perspective",
            "--input-projection",
            "fisheye",
            "--size",
            "8",
        ],
        "OUT.exr",
    ),
    "tonemap": (["-o", "OUT.png"], "OUT.png"),
    "vision": (["-o", "OUT.exr", "--scale", "100", "--effects", "none"], "OUT.exr"),
}


# subcommands that read no image, so none of these cases applies; each tested where it says
NO_IMAGE = {"operators": "lists the registry (tests/core/test_cli_operators.py)"}


def _commands():
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    return sorted(set(sub.choices) - set(NO_IMAGE))


COMMANDS = _commands()
WRITERS = [c for c in COMMANDS if ARGV[c][1] is not None]


def test_every_subcommand_has_a_call():
    assert set(COMMANDS) == set(ARGV), "add the new subcommand's arguments to ARGV"


def _argv(cmd, src, out_dir):
    return [cmd, str(src), *_fill(ARGV[cmd][0], out_dir)]


# commands whose bad input may take more than one line (none: `hdrjax batch` reports each
# failed frame on its own line, and lists them again only when several failed)
MANY_LINES: set[str] = set()


def _one_line_error(capsys, cmd, code, *needles):
    err = capsys.readouterr().err
    assert code != 0, f"{cmd}: exit status 0 for bad input"
    assert "Traceback" not in err, f"{cmd}: traceback\n{err}"
    if cmd not in MANY_LINES:
        assert err.count("\n") == 1 and err.endswith("\n"), f"{cmd}: not one line:\n{err}"
        assert err.startswith(f"hdrjax {cmd}: error:"), err
    for n in needles:
        assert n in err, f"{cmd}: {n!r} not in {err!r}"
    return err


def _run(argv):
    try:
        return main(argv)
    except SystemExit as e:  # argparse's usage errors exit 2 by raising
        return e.code


@pytest.mark.parametrize("cmd", COMMANDS)
def test_missing_file(cmd, tmp_path, capsys):
    code = _run(_argv(cmd, tmp_path / "missing.exr", tmp_path))
    _one_line_error(capsys, cmd, code, "missing.exr")


@pytest.mark.parametrize("cmd", COMMANDS)
def test_unreadable_file(cmd, tmp_path, capsys):
    d = tmp_path / "folder.exr"  # a directory under an image name: unreadable as a file
    d.mkdir()
    code = _run(_argv(cmd, d, tmp_path))
    _one_line_error(capsys, cmd, code, "folder.exr")
    if os.geteuid() != 0:  # chmod 000 stops everyone but root
        f = tmp_path / "locked.exr"
        f.write_bytes((DATA / "cornell_box.exr").read_bytes()[:4096])
        f.chmod(0)
        code = _run(_argv(cmd, f, tmp_path))
        _one_line_error(capsys, cmd, code, "locked.exr")


@pytest.mark.parametrize("cmd", COMMANDS)
def test_wrong_format(cmd, tmp_path, capsys):
    png = tmp_path / "photo.exr"  # PNG bytes under an EXR name
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))
    code = _run(_argv(cmd, png, tmp_path))
    _one_line_error(capsys, cmd, code, "photo.exr")
    bmp = tmp_path / "picture.bmp"
    bmp.write_bytes(b"BM" + bytes(100))
    code = _run(_argv(cmd, bmp, tmp_path))
    _one_line_error(capsys, cmd, code, "picture.bmp")


CORNELL = DATA / "cornell_box.exr"

# (argv after the input, expected fragment): an unknown name for a method-like option
UNKNOWN_METHOD = {
    "tonemap": (["-o", "OUT.png", "--method", "nope"], "nope"),
    "batch": (["-o", "OUTDIR", "--method", "nope"], "nope"),
    "compare": (["-o", "OUT.html", "--methods", "drago2003,nope"], "nope"),
    "fit": (["-o", "OUT.png", "--method", "nope", "--target", "mean=0.2"], "nope"),
    "filter": (["-o", "OUT.exr", "--median", "3", "--criterion", "nope"], "nope"),
    "lights": (["--method", "nope"], "nope"),
    "vision": (["-o", "OUT.exr", "--scale", "100", "--effects", "nope"], "nope"),
    "falsecolor": (["-o", "OUT.png", "--cmap", "nope"], "nope"),
    "histogram": (["-o", "OUT.png", "--method", "nope"], "nope"),
    "merge": (["-o", "OUT.exr", "--weights", "nope"], "nope"),
}

# invalid parameter values (out of range or malformed)
INVALID_PARAMETER = {
    "tonemap": (["-o", "OUT.png", "--key", "-1"], "--key"),
    "desaturate": (["-o", "OUT.exr", "--threshold", "-1"], "threshold"),
    "filter": (["-o", "OUT.exr", "--mean", "4"], "--mean"),
    "lights": (["--width", "0"], "--width"),
    "vision": (["-o", "OUT.exr", "--scale", "100", "--fov", "0"], "fov"),
    "falsecolor": (["-o", "OUT.png", "--range", "3:1"], "--range"),
    "measure": (["--at", "not,a,point"], "--at"),
    "export": (["-o", "OUT.png", "--bits", "12"], "--bits"),
    "fit": (["-o", "OUT.png", "--target", "mean=abc"], "mean"),
    "batch": (["-o", "OUTDIR", "--key", "-1"], "--key"),
    "compare": (["-o", "OUT.html", "--max-size", "0"], "--max-size"),
    "merge": (["-o", "OUT.exr", "--samples", "0"], "--samples"),
    "fuse": (["-o", "OUT.png", "--contrast", "-1"], "--contrast"),
    "histogram": (["-o", "OUT.png", "--bins", "1"], "--bins"),
    "panorama": (
        [
            "-o",
            "OUT.exr",
            "--projection",
            "perspective",
            "--input-projection",
            "fisheye",
            "--fov",
            "200",
        ],
        "--fov",
    ),
}


def _fill(args, tmp_path):
    return [
        a.replace("OUTDIR", str(tmp_path / "outdir")).replace("OUT.", str(tmp_path / "out."))
        for a in args
    ]


@pytest.mark.parametrize("cmd", sorted(UNKNOWN_METHOD))
def test_unknown_method(cmd, tmp_path, capsys):
    args, needle = UNKNOWN_METHOD[cmd]
    code = _run([cmd, str(CORNELL), *_fill(args, tmp_path)])
    _one_line_error(capsys, cmd, code, needle)
    assert code == 2


@pytest.mark.parametrize("cmd", sorted(INVALID_PARAMETER))
def test_invalid_parameter(cmd, tmp_path, capsys):
    args, needle = INVALID_PARAMETER[cmd]
    code = _run([cmd, str(CORNELL), *_fill(args, tmp_path)])
    _one_line_error(capsys, cmd, code, needle)
    assert code == 2


@pytest.mark.parametrize("cmd", WRITERS)
def test_output_folder_not_writable(cmd, tmp_path, capsys):
    blocker = tmp_path / "plainfile"  # a regular file used as a folder: ENOTDIR, even as root
    blocker.write_text("not a folder")
    extra, _ = ARGV[cmd]
    args = [
        a.replace("OUTDIR", str(blocker / "outdir")).replace("OUT.", str(blocker / "out."))
        for a in extra
    ]
    code = _run([cmd, str(CORNELL), *args])
    _one_line_error(capsys, cmd, code, "plainfile")
    assert blocker.read_text() == "not a folder"


def _enospc(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


@pytest.mark.parametrize("cmd", [c for c in WRITERS if c != "batch"])
def test_disk_full_keeps_the_previous_output(cmd, tmp_path, capsys, monkeypatch):
    """Every writer goes through hdrjax.io's atomic replacement; a full disk while the
    temporary file is written must leave the old output byte for byte."""
    extra, out = ARGV[cmd]
    target = tmp_path / ("out." + out.split(".", 1)[1])
    old = b"previous output, must survive"
    target.write_bytes(old)
    import hdrjax.io._atomic as atomic

    real = atomic.os.replace
    monkeypatch.setattr(atomic.os, "replace", _enospc)
    code = _run([cmd, str(CORNELL), *_fill(extra, tmp_path)])
    monkeypatch.setattr(atomic.os, "replace", real)
    err = _one_line_error(capsys, cmd, code)
    assert "No space left on device" in err, err
    assert target.read_bytes() == old
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")], "temporary left"
