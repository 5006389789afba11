"""MkDocs build hook: the command line's help, generated at build time.

A page line ``<!-- cli-help -->`` becomes the ``--help`` text of ``hdrjax`` and of every
subcommand, read from the parser the command line builds (``hdrjax.cli.build_parser``,
which imports no JAX), so the reference cannot fall behind the code.
"""

import argparse
import os

MARKER = "<!-- cli-help -->"


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:  # argparse has no public accessor for subparsers
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def cli_help_markdown() -> str:
    """``hdrjax --help`` and each subcommand's, as Markdown sections."""
    from hdrjax.cli import build_parser

    columns = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal: a fixed width here
    try:
        parser = build_parser()
        parts = ["### `hdrjax`", "", "```text", parser.format_help().rstrip(), "```", ""]
        for name, sub in sorted(_subcommands(parser).items()):
            parts += [f"### `hdrjax {name}`", "", "```text", sub.format_help().rstrip()]
            parts += ["```", ""]
    finally:
        if columns is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = columns
    return "\n".join(parts)


def on_page_markdown(markdown: str, page, config, files) -> str:
    if MARKER in markdown:
        markdown = markdown.replace(MARKER, cli_help_markdown())
    return markdown
