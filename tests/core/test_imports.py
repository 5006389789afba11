"""The package's import structure, read from the source with ``ast`` (nothing is imported):
no import cycle between modules or subpackages, no private name used across modules, no
private JAX (issue 17, point 5).

Every ``import`` statement counts: module level, inside functions, under ``TYPE_CHECKING``,
relative and absolute. ``importlib.import_module`` calls with computed names (the package's
lazy attributes, the command line's subcommand discovery) are not statements and only go
downwards.
"""

import ast
import collections
import functools
from pathlib import Path

PACKAGE = "hdrjax"
ROOT = Path(__file__).resolve().parents[2] / PACKAGE

# Private statistics internals still imported across modules: issue 17 point 1 replaces them
# with the one mergeable statistics implementation. An entry that no longer occurs fails
# (remove it).
KNOWN_PRIVATE: set[tuple[str, str]] = set()


def _modules(root: Path | None = None) -> dict[str, tuple[Path, bool]]:
    """Dotted module name → (file, whether it is a package's ``__init__``)."""
    root = ROOT if root is None else root
    package = root.name
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = [package, *path.relative_to(root).with_suffix("").parts]
        is_pkg = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_pkg else parts)] = (path, is_pkg)
    return out


def _resolve(module: str, is_pkg: bool, node: ast.ImportFrom) -> str:
    """The absolute name ``from <node.module>`` refers to, inside ``module``."""
    if node.level == 0:
        return node.module or ""
    base = module.split(".")
    if not is_pkg:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _scan(modules: dict[str, tuple[Path, bool]]):
    """Per module: the package modules it imports ``(target, line)``, the names it takes
    from them ``(owner module, name, line)`` (``module.name`` attributes included), and its
    uses of private JAX (``file:line: name``)."""
    edges: dict[str, set[tuple[str, int]]] = collections.defaultdict(set)
    names: dict[str, set[tuple[str, str, int]]] = collections.defaultdict(set)
    private_jax: list[str] = []

    def owner(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    for module, (path, is_pkg) in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        where = f"{path.relative_to(ROOT.parent)}"
        aliases: dict[str, str] = {}  # local name → package module it is bound to
        attributes = []
        for node in ast.walk(tree):
            imported = []
            if isinstance(node, ast.Import):
                imported = [a.name for a in node.names]
                for a in node.names:
                    target = owner(a.name)
                    if target is not None:
                        edges[module].add((target, node.lineno))
                        bound = a.name if a.asname else a.name.partition(".")[0]
                        aliases[a.asname or bound] = bound
            elif isinstance(node, ast.ImportFrom):
                source = _resolve(module, is_pkg, node)
                imported = [source] + [f"{source}.{a.name}" for a in node.names]
                for a in node.names:
                    full = f"{source}.{a.name}"
                    if full in modules:  # a submodule: ``from . import _exr``
                        edges[module].add((full, node.lineno))
                        aliases[a.asname or a.name] = full
                        continue
                    target = owner(source)
                    if target is not None:
                        edges[module].add((target, node.lineno))
                        names[module].add((target, a.name, node.lineno))
            elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
                attributes.append(node)
                imported = [f"{node.value.id}.{node.attr}"]
            for name in imported:
                if name.split(".")[:2] == ["jax", "_src"] or name.startswith("jaxlib."):
                    private_jax.append(f"{where}:{node.lineno}: {name}")
        for node in attributes:
            target = aliases.get(node.value.id)
            if target is not None and f"{target}.{node.attr}" not in modules:
                names[module].add((target, node.attr, node.lineno))
    return edges, names, private_jax


@functools.cache
def _scan_package():
    return _scan(_modules())


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """One cycle (a list of nodes, first repeated last) per strongly connected component."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def visit(v: str) -> None:  # Tarjan; the graph is a few hundred nodes deep at most
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph.get(v, ()):
                components.append(comp)

    for v in sorted(graph):
        if v not in index:
            visit(v)
    cycles = []
    for comp in components:
        start, members = min(comp), set(comp)
        # shortest path from start's successors back to start, inside the component
        prev: dict[str, str] = {}
        queue = collections.deque([start])
        seen = {start}
        found = None
        while queue and found is None:
            v = queue.popleft()
            for w in sorted(graph.get(v, ())):
                if w == start:
                    found = v
                    break
                if w in members and w not in seen:
                    seen.add(w)
                    prev[w] = v
                    queue.append(w)
        path = [start]
        v = found
        while v is not None and v != start:
            path.append(v)
            v = prev.get(v)
        cycles.append([start, *reversed(path[1:]), start])
    return cycles


def _describe(cycle: list[str], where: dict[tuple[str, str], list[str]]) -> str:
    pairs = zip(cycle[:-1], cycle[1:], strict=True)
    steps = [f"{a} -> {b} ({', '.join(where[a, b])})" for a, b in pairs]
    return "\n  ".join(steps)


def _subpackage(module: str) -> str:
    """``hdrjax.batch._pipeline`` → ``hdrjax.batch``; top-level modules stay themselves."""
    return ".".join(module.split(".")[:2])


def _import_cycles(modules: dict[str, tuple[Path, bool]], edges) -> list[str]:
    found = []
    for level in (lambda m: m, _subpackage):
        graph: dict[str, set[str]] = collections.defaultdict(set)
        where: dict[tuple[str, str], list[str]] = collections.defaultdict(list)
        for a, targets in edges.items():
            for b, line in sorted(targets):
                la, lb = level(a), level(b)
                # a package's own modules import each other; a module's parent package is
                # imported before it in any case
                if la == lb or a.startswith(b + "."):
                    continue
                graph[la].add(lb)
                where[la, lb].append(f"{modules[a][0].relative_to(ROOT.parent)}:{line}")
        found += [_describe(c, where) for c in _cycles(graph)]
    return found


def _write(tmp_path: Path, files: dict[str, str]) -> dict[str, tuple[Path, bool]]:
    for name, text in files.items():
        p = tmp_path / PACKAGE / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    return _modules(tmp_path / PACKAGE)


def test_the_import_check_finds_cycles_through_function_level_imports(tmp_path, monkeypatch):
    # the checker itself: a cycle closed by an import inside a function, between two
    # subpackages, is found and reported with its path
    monkeypatch.setattr(f"{__name__}.ROOT", tmp_path / PACKAGE)
    modules = _write(
        tmp_path,
        {
            "__init__.py": "",
            "a/__init__.py": "from ._x import f as f\n",
            "a/_x.py": "from ..b._y import g\n\ndef f():\n    return g()\n",
            "b/__init__.py": "",
            "b/_y.py": "def g():\n    from ..a import _x\n    return _x\n",
            "c.py": "import hdrjax.a._x\n",
        },
    )
    found = _import_cycles(modules, _scan(modules)[0])
    assert found == [
        "hdrjax.a._x -> hdrjax.b._y (hdrjax/a/_x.py:1)\n"
        "  hdrjax.b._y -> hdrjax.a._x (hdrjax/b/_y.py:2)",
        "hdrjax.a -> hdrjax.b (hdrjax/a/_x.py:1)\n  hdrjax.b -> hdrjax.a (hdrjax/b/_y.py:2)",
    ], found


def test_no_import_cycle():
    found = _import_cycles(_modules(), _scan_package()[0])
    assert not found, "import cycles:\n  " + "\n\n  ".join(found)


def test_no_private_names_across_modules():
    # a helper two modules share lives in a named internal module and has a public name;
    # private modules themselves (``from . import _exr``) are the package's layout
    _, names, _ = _scan_package()
    used = set()
    for module, taken in names.items():
        for owner, name, line in taken:
            if name.startswith("_") and not name.startswith("__") and owner != module:
                used.add((module, f"{owner}.{name}", line))
    bad = sorted(u for u in used if u[:2] not in KNOWN_PRIVATE)
    assert not bad, "private names used across modules:\n" + "\n".join(
        f"  {m}:{line} uses {n}" for m, n, line in bad
    )
    stale = KNOWN_PRIVATE - {u[:2] for u in used}
    assert not stale, f"KNOWN_PRIVATE entries no longer used (remove them): {sorted(stale)}"


def test_no_private_jax():
    # jax._src (and jaxlib's internals) change without notice between releases
    bad = sorted(set(_scan_package()[2]))
    assert not bad, "private JAX used:\n  " + "\n  ".join(bad)
