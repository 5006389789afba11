"""The installed distribution's metadata: one source for the version, the licence as an SPDX
expression with its text shipped, the extras the README names."""

import importlib.metadata as md
import tomllib

import hdrjax

from ..conftest import REPO


def test_one_version():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert "version" not in project and "version" in project["dynamic"]
    assert md.version("hdrjax") == hdrjax.__version__


def test_licence_and_extras():
    meta = md.metadata("hdrjax")
    assert meta["License-Expression"] == "MIT"
    assert (REPO / "LICENSE").read_text().startswith("MIT License")
    extras = set(meta.get_all("Provides-Extra"))
    assert {"dask", "raw", "notebooks", "test", "bench", "dev"} <= extras
    assert "Typing :: Typed" in meta.get_all("Classifier")


def test_project_urls_and_docs_extra():
    """The URLs PyPI shows, and the ``[docs]`` extra `make docs` installs (each with a lower
    bound)."""
    meta = md.metadata("hdrjax")
    urls = dict(u.split(", ", 1) for u in meta.get_all("Project-URL"))
    assert {"Homepage", "Documentation", "Source", "Issues"} <= set(urls)
    assert all(u.startswith("https://") for u in urls.values())
    assert urls["Issues"] == urls["Source"] + "/issues"
    docs = [r for r in meta.get_all("Requires-Dist") if r.endswith('extra == "docs"')]
    names = {r.split(">=")[0] for r in docs}
    assert names == {"mkdocs", "mkdocs-material", "mkdocstrings", "mkdocstrings-python"}
    assert all(">=" in r for r in docs)


def _recipe(makefile: str, target: str) -> list[str]:
    """The command lines of ``target`` in a Makefile's text."""
    lines = makefile.splitlines()
    start = next(i for i, s in enumerate(lines) if s.startswith(f"{target}:"))
    out = []
    for s in lines[start + 1 :]:
        if not s.startswith("\t"):
            break
        out.append(s.strip())
    return out


def test_lint_type_checks_the_package_and_ci_runs_it():
    """`make lint` runs ruff and then mypy on the package (py.typed is a promise), the
    virtual environment `make lint` builds has mypy, the checker's configuration silences
    no whole module, and CI runs `make lint` before `make test`."""
    makefile = (REPO / "Makefile").read_text()
    lint = _recipe(makefile, "lint")
    assert any("ruff check" in s for s in lint)
    assert any(s.split()[0].endswith("/mypy") for s in lint)
    assert "lint" in makefile.split("-m pip install --quiet -e '.[")[1].split("]")[0].split(",")
    pyproject = tomllib.loads((REPO / "pyproject.toml").read_text())
    extras = pyproject["project"]["optional-dependencies"]
    assert any(r.startswith("mypy") for r in extras["lint"])
    assert "hdrjax[test,bench,notebooks,lint]" in extras["dev"]
    mypy = pyproject["tool"]["mypy"]
    assert mypy["files"] == ["hdrjax"] and not mypy.get("ignore_errors")
    assert not any(o.get("ignore_errors") for o in mypy.get("overrides", []))
    assert (REPO / "hdrjax" / "py.typed").exists()
    ci = [s.strip() for s in (REPO / ".ci" / "run").read_text().splitlines()]
    assert ci.index("make lint") < ci.index("make test")
