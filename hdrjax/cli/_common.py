"""Shared pieces of the command line: error types and argument parsers."""

import argparse
import os

LDR_EXT = (".png", ".jpg", ".jpeg", ".tif", ".tiff")
"""Display-referred outputs (encoded, 8/16-bit)."""
HDR_EXT = (".exr", ".hdr", ".pfm")
"""Scene- or display-referred linear float files."""


class CLIError(Exception):
    """An error reported as one line on stderr; ``exit_code`` is the process status."""

    exit_code = 1


class UsageError(CLIError):
    """Bad arguments (exit code 2, like argparse)."""

    exit_code = 2


class DataError(CLIError):
    """Bad or unreadable data (exit code 1)."""

    exit_code = 1


def positive_float(text: str) -> float:
    """argparse type: a finite float > 0."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (v > 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return v


def value_range(text: str) -> tuple[float, float]:
    """argparse type: ``LO:HI`` with LO < HI."""
    try:
        lo, hi = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LO:HI, got {text!r}") from None
    if not lo < hi:
        raise argparse.ArgumentTypeError(f"expected LO < HI, got {text!r}")
    return lo, hi


def refuse_overwriting_inputs(outputs, inputs) -> None:
    """UsageError ``OUTPUT: output is the input file`` when a file a command would write
    (main output or an extra one) is one of the files it reads, through a symbolic or hard
    link too; called before anything is read. ``None`` entries are skipped, and ``-``
    (stdin/stdout) is never a file."""
    from ..io._atomic import file_identity

    read = {}
    for p in inputs:
        if p is not None and os.fspath(p) != "-":
            read.setdefault(file_identity(p), os.fspath(p))
    for p in outputs:
        if p is None or os.fspath(p) == "-":
            continue
        src = read.get(file_identity(p))
        if src is not None:
            same = os.path.normpath(src) == os.path.normpath(os.fspath(p))
            raise UsageError(f"{p}: output is the input file" + ("" if same else f" {src}"))


def read_image(path: str):
    """``hdrjax.io.read(path)``; a missing or unreadable file → DataError naming it."""
    from .. import io as hio

    if path != "-" and not os.path.exists(path):  # "-": standard input
        raise DataError(f"{path}: no such file")
    try:
        return hio.read(path)
    except (ValueError, OSError) as e:
        msg = str(e)
        raise DataError(msg if os.path.basename(path) in msg else f"{path}: {msg}") from None
