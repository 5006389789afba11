"""Shared pieces of the command line: error types and argument parsers."""

import argparse
import contextlib
import os
import sys
from collections.abc import Iterator

LDR_EXT = (".png", ".jpg", ".jpeg", ".tif", ".tiff")
"""Display-referred outputs (encoded, 8/16-bit)."""
HDR_EXT = (".exr", ".hdr", ".pfm")
"""Scene- or display-referred linear float files."""
STDOUT_FORMATS = ("png", "hdr", "pfm")
"""Formats ``-o -`` writes to standard output: those written front to back (EXR needs to
seek), as pfstools' ``pfsout*`` write to a pipe."""


class CLIError(Exception):
    """An error reported as one line on stderr; ``exit_code`` is the process status."""

    exit_code = 1


class UsageError(CLIError):
    """Bad arguments (exit code 2, like argparse)."""

    exit_code = 2


class DataError(CLIError):
    """Bad or unreadable data (exit code 1)."""

    exit_code = 1


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return v


def odd_size(text: str) -> int:
    """argparse type: an odd window size >= 1 (filters' K×K windows)."""
    try:
        k = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an odd integer, got {text!r}") from None
    if k < 1 or k % 2 == 0:
        raise argparse.ArgumentTypeError(f"expected an odd window size >= 1, got {k}")
    return k


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

    read: dict[tuple, str] = {}
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


WRITING_DESTS = ("output", "json_path", "region_out", "legend", "save_response", "sheet")
"""The parsed options that name a file a subcommand writes (``-o``, ``--json-out``,
``--region-out``, ``--legend FILE``, ``--save-response``, ``--sheet``)."""


def add_no_clobber_argument(p: argparse.ArgumentParser) -> None:
    """``--no-clobber``: refuse an existing output (the default replaces it, as pfstools,
    ImageMagick and OpenCV do; an input file is never replaced either way)."""
    p.add_argument(
        "--no-clobber",
        action="store_true",
        help="refuse to replace an existing output file (exit status 2); by default an "
        "existing output is replaced, atomically, and an input file never is",
    )


def refuse_clobbering(args: argparse.Namespace) -> None:
    """UsageError ``OUTPUT: already exists (--no-clobber)`` when ``--no-clobber`` was given
    and a file the command would write exists (standard output, ``None`` and the
    ``--legend side|none`` keywords are not files)."""
    if not getattr(args, "no_clobber", False):
        return
    for dest in WRITING_DESTS:
        path = getattr(args, dest, None)
        if not isinstance(path, str) or path == "-":
            continue
        if dest == "legend" and path in ("side", "none"):
            continue
        if os.path.lexists(path):
            raise UsageError(f"{path}: already exists (--no-clobber)")


class DeprecatedAlias(argparse.Action):
    """A renamed option's old spelling, kept hidden for one release: it stores into the new
    option's ``dest`` (``nargs=0``: stores nothing) and prints one note on stderr naming
    what to do instead (``replacement=``, e.g. ``"use --zlib-level"``)."""

    def __init__(self, option_strings, dest, replacement: str, nargs=None, **kwargs):
        kwargs["help"] = argparse.SUPPRESS
        super().__init__(option_strings, dest, nargs=nargs, **kwargs)
        self.replacement = replacement

    def __call__(self, parser, namespace, values, option_string=None):
        print(
            f"{parser.prog}: note: {option_string} is deprecated and will be removed; "
            f"{self.replacement}",
            file=sys.stderr,
        )
        if self.nargs != 0:
            setattr(namespace, self.dest, values)


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


def add_format_argument(p: argparse.ArgumentParser, formats: tuple[str, ...] = STDOUT_FORMATS):
    """``--format``: the format of ``-o -`` (standard output)."""
    p.add_argument(
        "--format",
        choices=formats,
        help="the format written to standard output with -o - (status text then goes to "
        "standard error)",
    )


def output_ext(args: argparse.Namespace, allowed: tuple[str, ...] | None = None) -> str:
    """The extension of ``args.output`` (lower case); for ``-`` (standard output) that of
    ``--format``, which ``-o -`` needs and a file output refuses (UsageError). ``allowed``:
    the extensions the command writes (UsageError naming them otherwise)."""
    fmt = getattr(args, "format", None)
    if args.output == "-":
        if not fmt:
            formats = [f for f in STDOUT_FORMATS if allowed is None or "." + f in allowed]
            raise UsageError(f"-o -: give --format ({', '.join(formats)}) for standard output")
        ext = "." + fmt
    else:
        if fmt:
            raise UsageError("--format applies to -o - (standard output) only")
        ext = os.path.splitext(args.output)[1].lower()
    if allowed is not None and ext not in allowed:
        raise UsageError(
            f"{args.output}: unsupported output type {ext or '(none)'}; "
            f"expected one of {', '.join(allowed)}"
        )
    return ext


@contextlib.contextmanager
def output_file(args: argparse.Namespace) -> Iterator[str]:
    """The path a command writes its output to: ``args.output``, or for ``-o -`` a
    temporary file of the ``--format``'s type whose bytes go to standard output once the
    block has finished without error (so an error leaves standard output empty, never half
    an image)."""
    if args.output != "-":
        yield args.output
        return
    import tempfile

    with tempfile.TemporaryDirectory(prefix="hdrjax-stdout-") as d:
        path = os.path.join(d, "stdout" + output_ext(args))
        yield path
        with open(path, "rb") as f:
            data = f.read()
    out = getattr(args, "stdout", None) or sys.stdout.buffer
    try:
        out.write(data)
        out.flush()
    except OSError as e:  # a closed pipe (e.g. `| head -c 10`)
        raise DataError(f"-o -: cannot write to standard output ({e.strerror or e})") from None
