"""Griffe extensions for the API reference (mkdocstrings reads the sources statically).

``RedundantAliasesArePublic``: hdrjax exports a name from a subpackage's ``__init__`` in
the redundant alias form (``from ._reinhard2002 import Reinhard2002 as Reinhard2002``, PEP
484's re-export
convention) rather than through ``__all__``; griffe, reading the sources statically, counts
an imported name as private unless ``__all__`` lists it. This marks those aliases public
(a subpackage imported by name stays a page of its own, not a member of its parent).

``DoctestsAreCode``: doctests fenced and Sphinx roles shown as code, so docstrings written
for ``help()`` read well as Markdown.
"""

import ast
import re
from typing import Any

import griffe


class RedundantAliasesArePublic(griffe.Extension):
    def __init__(self) -> None:
        self._aliases: list[griffe.Alias] = []

    def on_alias_instance(self, *, node: Any, alias: griffe.Alias, **kwargs: Any) -> None:
        if isinstance(node, ast.ImportFrom) and any(
            n.asname == n.name == alias.name for n in node.names
        ):
            self._aliases.append(alias)

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        for alias in self._aliases:
            try:
                is_module = alias.final_target.is_module
            except (griffe.AliasResolutionError, griffe.CyclicAliasError):
                continue
            if not is_module:
                alias.public = True


def fence_doctests(text: str) -> str:
    """Doctest runs (``>>>`` lines and their output, up to a blank line) as fenced ``pycon``
    code: outside a fence Markdown reads ``>>>`` as quotes and ``[a]`` in an output as a
    link."""
    out: list[str] = []
    lines = text.split("\n")
    i, fenced = 0, False
    while i < len(lines):
        line = lines[i]
        stripped = line.lstrip()
        if stripped.startswith("```"):
            fenced = not fenced
        if not fenced and stripped.startswith(">>>"):
            indent = line[: len(line) - len(stripped)]
            block = []
            while i < len(lines) and lines[i].strip():
                block.append(lines[i])
                i += 1
            out += [f"{indent}```pycon", *block, f"{indent}```"]
            continue
        out.append(line)
        i += 1
    return "\n".join(out)


_ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|attr|data|obj|exc):`~?([^`]+)`")


def roles_as_code(text: str) -> str:
    """Sphinx roles (``:func:`name```) as inline code: Markdown shows them literally."""
    return _ROLE.sub(r"`\1`", text)


class DoctestsAreCode(griffe.Extension):
    """Docstrings written for reading in an editor, made Markdown: doctests fenced, Sphinx
    roles as code."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        stack: list[griffe.Object] = [pkg]
        while stack:
            obj = stack.pop()
            if obj.docstring is not None:
                text = obj.docstring.value
                if ">>>" in text:
                    text = fence_doctests(text)
                obj.docstring.value = roles_as_code(text)
            stack += [m for m in obj.members.values() if not m.is_alias]
