"""User-facing text cites papers, not the project's internal documents (issue 24, point 5).

The development notes hdrjax was written from (the four "seed" documents, the formula notes
``formulas.md``, the data notes ``SOURCES.md``, all under ``../shared``) do not ship: a
docstring, a ``--help`` page, a notebook or a benchmark report that points at them points a
user at nothing. This scans every string of the package and of the benchmarks (docstrings,
help texts, messages, plot labels), the help of every command and every operator page, and
the notebooks' markdown, code strings and saved outputs."""

import ast
import contextlib
import io
import re

import nbformat
import pytest

from hdrjax.cli import _manifest, main

from ..conftest import REPO

INTERNAL = re.compile(
    r"seed[ _-]?00\d|\bthe seeds?(?:'s?)? (?:listings?|median|documents?|papers?)"
    r"|seeds?' listings?|formulas\.md|SOURCES\.md|\.\./shared"
    r"|shared/(?:seeds|reference|data)",
    re.I,
)
"""Names of documents a user does not have."""

ALLOWED: dict[tuple[str, str], str] = {
    (
        "benchmarks/bench_accuracy.py",
        "wide-range files of ``../shared/data/hdr`` when present",
    ): "the benchmark reads optional extra images from a development checkout's data folder",
    (
        "benchmarks/bench_lights.py",
        "the lat-long maps of ``../shared/data/hdr`` when present",
    ): "the benchmark reads optional extra maps from a development checkout's data folder",
    (
        "benchmarks/bench_operators.py",
        "(or the same file in ../shared/data/hdr)",
    ): "the benchmark falls back to a development checkout's data folder",
}
"""``(file, text)`` of strings that name the development checkout's optional data on
purpose, with the reason. Code that builds such a path (``REPO.parent / "shared" / …``)
holds no forbidden text and needs no entry."""


def _strings(path) -> list[str]:
    """Every string constant of a Python file (docstrings, f-string parts, help texts)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    return [
        n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)
    ]


def _hits(where: str, text: str) -> list[str]:
    out = []
    for m in INTERNAL.finditer(text):
        line = text[text.rfind("\n", 0, m.start()) + 1 : text.find("\n", m.end()) % (len(text) + 1)]
        if not any(f == where and snippet in line for f, snippet in ALLOWED):
            out.append(f"{where}: {line.strip()[:160]}")
    return out


def _sources() -> list:
    return sorted((REPO / "hdrjax").rglob("*.py")) + sorted((REPO / "benchmarks").glob("*.py"))


def test_package_and_benchmark_strings_cite_papers():
    hits = []
    for path in _sources():
        where = str(path.relative_to(REPO))
        for s in _strings(path):
            hits += _hits(where, s)
    assert not hits, "internal documents named in user-facing text:\n" + "\n".join(hits)


def _output(argv: list[str]) -> str:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main(argv)
        except SystemExit:
            pass
    return out.getvalue() + err.getvalue()


def test_command_line_help_cites_papers():
    commands = sorted(
        p.stem.removeprefix("_cmd_") for p in (REPO / "hdrjax" / "cli").glob("_cmd_*.py")
    )
    argvs = [["--help"], ["operators"]] + [[c, "--help"] for c in commands]
    argvs += [["operators", op["name"]] for op in _manifest.OPERATORS]
    hits = []
    for argv in argvs:
        text = _output(argv)
        assert text.strip(), f"hdrjax {' '.join(argv)}: no output"
        hits += _hits("hdrjax " + " ".join(argv), text)
    assert not hits, "internal documents named in the help:\n" + "\n".join(hits)


@pytest.mark.parametrize("path", sorted((REPO / "notebooks").glob("*.ipynb")), ids=lambda p: p.name)
def test_notebooks_cite_papers(path):
    nb = nbformat.read(path, as_version=4)
    hits = []
    for i, cell in enumerate(nb.cells):
        where = f"{path.name} cell {i}"
        if cell.cell_type == "markdown":
            hits += _hits(where, cell.source)
            continue
        if cell.cell_type != "code":
            continue
        with contextlib.suppress(SyntaxError):  # a cell with IPython magics: its outputs only
            tree = ast.parse(cell.source)
            for n in ast.walk(tree):
                if isinstance(n, ast.Constant) and isinstance(n.value, str):
                    hits += _hits(where, n.value)
        for out in cell.get("outputs", []):
            text = out.get("text", "") + str(out.get("data", {}).get("text/plain", ""))
            hits += _hits(where + " output", text)
    assert not hits, "internal documents named in a notebook:\n" + "\n".join(hits)


def test_every_allowance_is_still_needed():
    for (where, snippet), reason in ALLOWED.items():
        assert snippet in (REPO / where).read_text(), f"{where}: stale allowance ({reason})"
