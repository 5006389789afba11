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
