"""The ``hdrjax`` command line (also ``python -m hdrjax``).

Subcommands live in ``hdrjax/cli/_cmd_<name>.py``; each module defines
``register(subparsers)`` that adds its parser and sets ``func`` (a callable taking the parsed
namespace and returning an exit code). Errors are one line naming the file or argument and
the problem: exit code 2 for usage errors, 1 for bad data.
"""

import argparse
import importlib
import os
import pkgutil
import sys

from ._common import CLIError, DataError, UsageError

__all__ = ["CLIError", "DataError", "UsageError", "build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hdrjax",
        description="HDR tone mapping and analysis for lighting simulation and photography.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers.required = True
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_cmd_"):
            importlib.import_module(f"{__name__}.{info.name}").register(subparsers)
    return parser


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
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)
    except OSError:
        pass  # an unwritable cache folder only costs compile time


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    _enable_compilation_cache()
    try:
        return int(args.func(args) or 0)
    except CLIError as e:
        print(f"hdrjax {args.command}: error: {e}", file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:
        return 130
