"""The code blocks of the README and of the user guide (``docs/``): extraction, running,
and the command lines they show."""

import re
import shlex
from pathlib import Path

from ..conftest import REPO

DOCS = REPO / "docs"
README = REPO / "README.md"

# names of the project's internal notes, which a user of the package does not have: user
# text cites the papers instead
INTERNAL = re.compile(
    r"seed[ _-]?\d{3}|\bthe seeds?(?:'s?)? (?:listings?|median|documents?|papers?)"
    r"|seeds?' listings?|formulas\.md|SOURCES\.md|\.\./shared|shared/(?:seeds|reference|data)",
    re.I,
)

# Pages of the site whose blocks are tested elsewhere, with where: the plug-in example of
# docs/operators.md is imported as a module by those tests (a plug-in must be a file), and
# its shell lines name that plug-in's operator, which the parser knows only once loaded.
TESTED_ELSEWHERE = {
    "operators.md": "tests/operators/test_plugins.py and tests/core/test_startup.py",
}


def guide_pages() -> list[Path]:
    """The site's hand-written pages (the API pages are generated from docstrings)."""
    return sorted(
        p
        for p in DOCS.rglob("*.md")
        if "api" not in p.relative_to(DOCS).parts and p.name not in TESTED_ELSEWHERE
    )


def python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(), re.S)


def shell_blocks(path: Path) -> list[str]:
    return re.findall(r"```(?:bash|sh)\n(.*?)```", path.read_text(), re.S)


def page_name(path: Path) -> str:
    return path.relative_to(REPO).as_posix()


def run_block(code: str, name: str, monkeypatch, capsys) -> None:
    """Run one example as a user would, from the repository root (examples use ``data/``
    and ``out/``), and require that it prints what it computed."""
    monkeypatch.chdir(REPO)
    (REPO / "out").mkdir(exist_ok=True)  # as `make demo` creates it; a fresh clone has none
    exec(compile(code, name, "exec"), {"__name__": "__example__"})
    assert capsys.readouterr().out.strip(), f"{name} prints nothing"


_SEPARATORS = {"&&", "||", "|", ";", "&"}
_REDIRECTS = {">", ">>", "<", "2>", "&>"}


def hdrjax_commands(block: str) -> list[list[str]]:
    """The ``hdrjax`` command lines of a shell block, as argument lists (without the
    program name): continuation lines joined, comments, redirections and the other
    commands of a pipeline or ``&&`` chain left out."""
    text = block.replace("\\\n", " ")
    commands = []
    for line in text.splitlines():
        line = re.sub(r"(?<=\s)\d(?=>)", "", line)  # 2>file: a redirection, not an argument
        lexer = shlex.shlex(line, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        lexer.commenters = "#"
        current: list[str] = []
        tokens = list(lexer)
        i = 0
        while i < len(tokens) + 1:
            tok = tokens[i] if i < len(tokens) else ";"
            if tok in _SEPARATORS:
                while current and re.fullmatch(r"[A-Z_]+=\S*", current[0]):  # VAR=value cmd
                    current.pop(0)
                if current and current[0] == "hdrjax":
                    commands.append(current[1:])
                current = []
            elif tok in _REDIRECTS:
                i += 1  # and its target
            else:
                current.append(tok)
            i += 1
    return commands


def flat(text: str) -> str:
    """Text with its line breaks (and list indentation) as single spaces."""
    return re.sub(r"\s+", " ", text)
