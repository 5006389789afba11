"""Start-up (issue 19, point 2): ``hdrjax --help``, ``hdrjax <command> --help`` and
``hdrjax operators`` import neither JAX nor the other heavy dependencies; they read the
operators from the recorded manifest (``hdrjax/cli/_manifest.py``), which must equal the
live registry, and fall back to the live registry when plug-ins are present
(``HDRJAX_PLUGINS``, an installed ``hdrjax.operators`` entry point)."""

import contextlib
import importlib
import importlib.metadata
import io
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from hdrjax.cli import _manifest, _registry, main

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs" / "operators.md"
EXAMPLE = re.search(r"<!-- plugin-example -->\n```python\n(.*?)```", DOCS.read_text(), re.S)
PLUGIN = "simple_photographic"
HEAVY = ("jax", "jaxlib", "equinox", "colour", "matplotlib", "scipy", "dask", "optimistix")
REGENERATE = "regenerate it: python -m hdrjax.cli._registry"


def _commands() -> list[str]:
    return sorted(p.stem.removeprefix("_cmd_") for p in (REPO / "hdrjax" / "cli").glob("_cmd_*.py"))


def _argvs() -> list[list[str]]:
    """Every command's help, the listing, one page, an unknown name, a parser error."""
    return [
        ["--help"],
        *([cmd, "--help"] for cmd in _commands()),
        ["operators"],
        ["operators", "Reinhard-2002"],
        ["operators", "no_such_operator"],
        ["tonemap", "in.hdr", "-o", "out.png", "--key", "-1"],
    ]


def _run(code: str, *args: str, **env: str) -> subprocess.CompletedProcess:
    """``python -c code args`` in the repository, without the caller's HDRJAX_PLUGINS."""
    environ = {k: v for k, v in os.environ.items() if k != "HDRJAX_PLUGINS"}
    return subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        check=True,
        env={**environ, **env},
        cwd=REPO,
    )


def _outputs(argvs: list[list[str]]) -> dict[str, str]:
    """stdout, stderr and exit status of in-process ``main`` calls, by command line."""
    out = {}
    for argv in argvs:
        o, e = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
            try:
                rc = main(list(argv))
            except SystemExit as x:
                rc = x.code
        out[" ".join(argv)] = f"{rc}\n{o.getvalue()}\n{e.getvalue()}"
    return out


_NO_JAX = """
import contextlib, io, json, sys

heavy, argvs = json.loads(sys.argv[1])
loaded = lambda: sorted(m for m in sys.modules if m.split(".")[0] in heavy)
import hdrjax

lazy = loaded()
from hdrjax.cli import main

codes = []
for argv in argvs:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        try:
            codes.append(main(argv))
        except SystemExit as e:
            codes.append(e.code)
print(json.dumps({"lazy": lazy, "loaded": loaded(), "codes": codes}))
"""


def test_help_and_operators_import_no_jax():
    """Each command line in one fresh interpreter; then no heavy module is loaded (nor
    after ``import hdrjax`` alone)."""
    if _registry.entry_points_declared("hdrjax.operators"):
        pytest.skip("an installed package declares hdrjax.operators entry points")
    got = json.loads(_run(_NO_JAX, json.dumps([HEAVY, _argvs()])).stdout)
    assert got["lazy"] == [], f"import hdrjax loads {got['lazy']}"
    assert got["loaded"] == [], f"loaded: {got['loaded'][:10]}"
    # the commands ran: the help texts, the listing and a page exit 0, the unknown name
    # and the bad --key 2 (usage errors)
    assert got["codes"] == [0] * (len(_commands()) + 3) + [2, 2], got["codes"]


def test_manifest_equals_the_live_registry():
    """The recorded operators and constants are the live registry's built-in operators
    and the modules' constants (else: regenerate the manifest)."""
    recorded = {op.name: op for op in _registry.manifest_operators()}
    live = {op.name: op for op in _registry.live_operators(builtin=True)}
    assert sorted(recorded) == sorted(live), f"operators differ; {REGENERATE}"
    for name, op in live.items():
        assert recorded[name] == op, f"{name} differs from the manifest; {REGENERATE}"
    assert list(recorded) == sorted(recorded)  # operator_names() order
    assert _manifest.CONSTANTS == _registry.live_constants(), REGENERATE
    # nothing but built-in operators in the registry here: every test sees the same list
    assert _registry.live_operators() == _registry.live_operators(builtin=True)


def test_manifest_and_live_registry_print_the_same(monkeypatch):
    """Every command's help, the listing, every operator's page and the lookup's errors
    are the same from the manifest and from the live registry."""
    names = [op.name for op in _registry.manifest_operators()]
    argvs = [*_argvs(), *(["operators", n] for n in names), ["operators", "TUMBLIN reinhard"]]
    assert _registry.live_registry_needed()  # the registry is imported in this process
    live = _outputs(argvs)
    monkeypatch.setattr(_registry, "live_registry_needed", lambda: False)
    assert _outputs(argvs) == live
    assert (
        "2\n\nhdrjax operators: error: method: unknown operator 'no_such_operator'"
        in (live["operators no_such_operator"])
    )


@pytest.fixture
def plugin(tmp_path) -> Path:
    """The plug-in example of docs/operators.md as a file outside the package."""
    assert EXAMPLE is not None, "docs/operators.md: the plug-in example block is missing"
    path = tmp_path / f"{PLUGIN}.py"
    path.write_text(EXAMPLE[1])
    return path


_LIST = (
    "import sys\n"
    "from hdrjax.cli import main\n"
    "main(['operators'])\n"
    "print('=====')\n"
    "main(['operators', 'simple-photographic'])\n"
    "print('=====')\n"
    "try:\n"
    "    main(['tonemap', '--help'])\n"
    "except SystemExit:\n"
    "    pass\n"
)


def _check_listed(out: str, name: str) -> None:
    listing, page, helptext = out.split("=====\n")
    assert any(ln.startswith(name + " ") for ln in listing.splitlines()), listing
    assert "reinhard2002" in listing
    assert page.startswith(f"{name}: ") and "default: 0.18; range: (0, inf)" in page
    # --key's help names the operators that have a key, the plug-in among them
    key = helptext[helptext.index("\n  --key KEY") : helptext.index("\n  --white")]
    assert name in " ".join(key.split()), key


def test_hdrjax_plugins_are_listed(plugin):
    """``HDRJAX_PLUGINS``: the live registry, with the plug-in, in the listing, its page
    and the parsers' help."""
    _check_listed(_run(_LIST, HDRJAX_PLUGINS=str(plugin), COLUMNS="80").stdout, PLUGIN)


def test_entry_point_plugins_are_listed(tmp_path):
    """An installed package declaring an ``hdrjax.operators`` entry point: the live
    registry, with its operator."""
    name = "plugin_pkg_op"
    (tmp_path / "plugin_pkg_mod.py").write_text(EXAMPLE[1].replace(PLUGIN, name))
    info = tmp_path / "plugin_pkg-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: plugin_pkg\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[hdrjax.operators]\n{name} = plugin_pkg_mod\n")
    code = _LIST.replace("simple-photographic", name)
    _check_listed(_run(code, PYTHONPATH=str(tmp_path), COLUMNS="80").stdout, name)


def test_entry_point_scan_agrees_with_importlib_metadata(tmp_path, monkeypatch):
    """The start-up's own scan of the installed distributions' entry points answers as
    importlib.metadata does: here, with a package declaring another group, with one
    declaring the registry's group, and for a zip file on the path."""
    group = "hdrjax.operators"

    def both() -> tuple[bool, bool]:
        importlib.invalidate_caches()
        expected = bool(importlib.metadata.entry_points(group=group))
        return _registry.entry_points_declared(group), expected

    got, expected = both()
    assert got == expected
    info = tmp_path / "other_pkg-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: other_pkg\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[console_scripts]\nother = other_pkg:main\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert both() == (expected, expected)
    egg = tmp_path / "op_pkg-1.0.egg-info"
    egg.mkdir()
    (egg / "PKG-INFO").write_text("Metadata-Version: 2.1\nName: op_pkg\nVersion: 1.0\n")
    (egg / "entry_points.txt").write_text(f"\n  [{group}]  \nop = op_pkg\n")
    assert both() == (True, True)
    # a zip on the path: importlib.metadata decides (here: the same answer)
    (egg / "entry_points.txt").unlink()
    monkeypatch.syspath_prepend(str(REPO / "no_such.zip"))
    zipped = tmp_path / "lib.zip"
    zipped.write_bytes(b"")
    monkeypatch.syspath_prepend(str(zipped))
    assert both() == (expected, expected)
