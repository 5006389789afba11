"""The ``hdrjax`` command line (also ``python -m hdrjax``).

Subcommands live in ``hdrjax/cli/_cmd_<name>.py``; each module defines
``register(subparsers)`` that adds its parser and sets ``func`` (a callable taking the parsed
namespace and returning an exit code). A module imports what ``func`` needs inside it, so
building the parsers imports no JAX (what they show of the operators comes from
:mod:`._registry`). Errors are one line naming the file or argument and the problem: exit
code 2 for usage errors, 1 for bad data; Ctrl-C ends a command at once with exit code 130
and one line. A command replaces an existing output file (atomically: a finished temporary
file is renamed onto it) but never a file it reads; ``--no-clobber`` refuses an existing
output (exit code 2).

Before parsing, the modules listed in the environment variable ``HDRJAX_PLUGINS``
(comma-separated module names or ``.py`` file paths) are imported, so the operators they
register with :func:`hdrjax.operators.register` work in every subcommand.
"""

import argparse
import contextlib
import importlib
import os
import sys

from ._common import (
    WRITING_DESTS,
    CLIError,
    DataError,
    UsageError,
    add_no_clobber_argument,
    refuse_clobbering,
)
from ._interrupt import claim_report, interrupted_line, prompt_interrupt

__all__ = ["CLIError", "DataError", "UsageError", "build_parser", "load_plugins", "main"]


class _Parser(argparse.ArgumentParser):
    """argparse with the command line's error form: one line on stderr, exit status 2
    (argparse's default prints the whole usage block first), and no abbreviated options
    (``--exposure`` must not silently stand for ``--exposure-time``). Subcommands' parsers
    are made by this class too."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message: str):  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="hdrjax",
        description="HDR tone mapping and analysis for lighting simulation and photography.",
    )
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"hdrjax {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers.required = True
    for name in _command_modules():
        importlib.import_module(f"{__name__}.{name}").register(subparsers)
    for sub in subparsers.choices.values():
        _add_overwrite_policy(sub)
    return parser


def _add_overwrite_policy(sub: argparse.ArgumentParser) -> None:
    """One overwrite policy for every command that writes files: an existing output is
    replaced (atomically: :func:`hdrjax.io.atomic_path`), never an input, and
    ``--no-clobber`` refuses an existing output (checked by :func:`_run` before the command
    starts). ``batch``, whose output is a folder of frames, keeps its own (existing frames
    are skipped, ``--no-resume`` replaces them): a command states that with
    ``set_defaults(overwrite_policy="resume")``."""
    options = {o for a in sub._actions for o in a.option_strings}
    if sub.get_default("overwrite_policy") == "resume" or "--no-clobber" in options:
        return
    if any(a.dest in WRITING_DESTS for a in sub._actions):
        add_no_clobber_argument(sub)


def _command_modules() -> list[str]:
    """The ``_cmd_*`` modules of this package, sorted: a directory listing (pkgutil's module
    scan imports inspect, which start-up does not otherwise need)."""
    names = set()
    for folder in __path__:
        for entry in os.listdir(folder):
            stem, ext = os.path.splitext(entry)
            if stem.startswith("_cmd_") and ext == ".py":
                names.add(stem)
    return sorted(names)


def _enable_compilation_cache() -> None:
    """Persistent XLA compilation cache in the user's cache folder (HDRJAX_CACHE=0 disables)."""
    if os.environ.get("HDRJAX_CACHE", "1") == "0":
        return
    import jax

    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    path = os.path.join(base, "hdrjax", "jax")
    try:
        os.makedirs(path, exist_ok=True)
        jax.config.update("jax_compilation_cache_dir", path)
        # every executable, however quick to compile: a warm start then compiles nothing
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
        jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    except OSError:
        pass  # an unwritable cache folder only costs compile time


def load_plugins(spec: str) -> None:
    """Import the plug-in modules ``spec`` lists (``HDRJAX_PLUGINS``): comma-separated
    module names (``mypkg.operators``) or paths of ``.py`` files. A file is imported once
    per process while it is unchanged. Raises :class:`UsageError` naming the first entry
    that cannot be imported."""
    for entry in (e.strip() for e in spec.split(",")):
        if not entry:
            continue
        try:
            if entry.endswith(".py") or os.sep in entry or "/" in entry:
                _import_file(entry)
            else:
                importlib.import_module(entry)
        except Exception as e:  # any failure of a plug-in's code is the user's to fix
            raise UsageError(
                f"HDRJAX_PLUGINS: cannot import {entry!r}: {type(e).__name__}: {_one_line(e)}"
            ) from None


def _import_file(path: str) -> None:
    import hashlib
    import importlib.util

    full = os.path.realpath(path)
    stamp = os.stat(full).st_mtime_ns  # FileNotFoundError names the path
    stem = os.path.splitext(os.path.basename(full))[0]
    digest = hashlib.sha1(full.encode()).hexdigest()[:8]
    name = f"hdrjax_plugin_{''.join(c if c.isalnum() else '_' for c in stem)}_{digest}"
    loaded = sys.modules.get(name)
    if loaded is not None and getattr(loaded, "__hdrjax_plugin_stamp__", None) == stamp:
        return
    spec = importlib.util.spec_from_file_location(name, full)
    if spec is None or spec.loader is None:
        raise ImportError(f"not a Python file: {path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and pickling look classes up by module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    module.__hdrjax_plugin_stamp__ = stamp  # type: ignore[attr-defined]


def main(argv: list[str] | None = None) -> int:
    try:
        load_plugins(os.environ.get("HDRJAX_PLUGINS", ""))
    except UsageError as e:
        print(f"hdrjax: error: {e}", file=sys.stderr)
        return e.exit_code
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "uses_jax", True):  # not for `operators`, which compiles nothing
        _enable_compilation_cache()
        if argv is None:  # the command line's own process (not main([...]) in a program)
            from .._memory import tune_memory

            tune_memory()
    cluster = getattr(args, "workers", None) or getattr(args, "scheduler", None)
    # the command line itself (not ``main([...])`` in a program, nor a Dask cluster's
    # client, whose workers the normal exit shuts down): Ctrl-C ends it within a second
    prompt = argv is None and not cluster
    with prompt_interrupt(args.command) if prompt else contextlib.nullcontext():
        if getattr(args, "output", None) == "-":
            # the image goes to standard output: everything printed goes to standard error
            args.stdout = sys.stdout.buffer
            with contextlib.redirect_stdout(sys.stderr):
                code = _run(args)
        else:
            code = _run(args)
    if code == 130 and prompt:
        _leave_now(code)
    return code


def _leave_now(code: int) -> None:
    """Ctrl-C on the command line: leave at once. The interpreter's normal exit waits for
    the compiled computations still running (a tile, a whole image: seconds), so the
    process ends here, standard streams flushed; the interrupted command has already
    removed its temporary files (:func:`hdrjax.io.atomic_path` on the way out). Not for a
    Dask cluster, whose workers are shut down by the normal exit, nor in-process calls
    (``main([...])``)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):
            stream.flush()
    os._exit(code)


def _run(args: argparse.Namespace) -> int:
    try:
        refuse_clobbering(args)
        return int(args.func(args) or 0)
    except CLIError as e:
        print(f"hdrjax {args.command}: error: {e}", file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:
        # Ctrl-C: one line (on a new one where a progress bar was drawn), status 128 + SIGINT;
        # outputs are written by renaming a finished temporary file, so none is left half
        if claim_report():
            with contextlib.suppress(OSError, ValueError):
                print(interrupted_line(args.command), file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader went away (``hdrjax info x.exr | head``): stop quietly, and point
        # standard output at /dev/null so that the interpreter's final flush does not fail
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except (OSError, ValueError) as e:
        # what a subcommand did not translate: file-system failures (permissions, a full
        # disk) and validation errors from the library; still one line, never a traceback
        print(f"hdrjax {args.command}: error: {_one_line(e)}", file=sys.stderr)
        return 1


def _one_line(e: BaseException) -> str:
    text = " ".join(str(e).split()) or type(e).__name__
    if isinstance(e, OSError) and e.filename and str(e.filename) not in text:
        text = f"{e.filename}: {text}"
    return text
