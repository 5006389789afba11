"""What the command line's parsers and ``hdrjax operators`` read from the operator registry
and from modules that import JAX, without importing JAX.

The parsers need the operators' names and parameter metadata (``--key``'s help and type,
``hdrjax operators``' listing and pages) and a few defaults (``lights --width``, ``batch
--zlib-level``). Importing the registry imports JAX and equinox, which takes far longer
than everything else ``hdrjax --help`` does, so ``hdrjax --help``, ``hdrjax <command>
--help`` and ``hdrjax operators`` read them from ``_manifest.py``, which
:func:`write_manifest` generates from the live registry (``python -m
hdrjax.cli._registry``) and which tests/core/test_startup.py checks against it.

Where other operators may exist, the live registry is read instead: when
``HDRJAX_PLUGINS`` names a plug-in, an installed package declares an entry point in the
``hdrjax.operators`` group, or the registry is imported already (its operators then are
the truth, and reading them costs nothing).
"""

import functools
import importlib
import os
import re
import sys
from typing import Any, NamedTuple

CONSTANT_NAMES = (
    "hdrjax.io.DEFAULT_COMPRESSION",
    "hdrjax.lights.CONVENTIONS",
    "hdrjax.lights.DEFAULT_BLUR",
    "hdrjax.lights.DEFAULT_MAX_LIGHTS",
    "hdrjax.lights.DEFAULT_MAX_RADIUS",
    "hdrjax.lights.DEFAULT_WIDTH",
    "hdrjax.operators.ENTRY_POINT_GROUP",
)
"""The module attributes the parsers use, recorded in the manifest's ``CONSTANTS``."""

MANIFEST_PATH = os.path.join(os.path.dirname(__file__), "_manifest.py")


class ParameterEntry(NamedTuple):
    """One parameter of an operator as the command line shows it (from
    :class:`hdrjax.operators.ParameterInfo`)."""

    name: str
    help: str
    unit: str
    default: str
    """As ``hdrjax operators NAME`` prints it: a number, ``required``, ``estimated``,
    ``none``, a name or a vector."""
    range: tuple[float, float] | None
    range_text: str
    """The range in interval notation, the choices ``a | b``, or empty."""
    choices: tuple[str, ...] | None
    estimated: bool
    pooling: str | None
    static: bool


class OperatorEntry(NamedTuple):
    """One registered operator as the command line shows it."""

    name: str
    summary: str
    """The first paragraph of the class docstring, on one line, without markup."""
    reference: str
    per_channel: bool
    scale_invariant: bool
    default_fit_params: tuple[str, ...]
    parameters: tuple[ParameterEntry, ...]


def operators() -> tuple[OperatorEntry, ...]:
    """Every registered operator, sorted by name: from the manifest, or from the live
    registry where plug-ins may add operators (see the module docstring)."""
    if live_registry_needed():
        return live_operators()
    return manifest_operators()


def find(name: str) -> OperatorEntry:
    """The operator registered under ``name`` (case and ``_``/``-`` insensitive); the
    ``ValueError`` of :func:`hdrjax.operators.get_operator` otherwise."""
    if live_registry_needed():
        from ..operators import get_operator

        return operator_entry(get_operator(name))
    entries = manifest_operators()
    wanted = _key(name)
    for entry in entries:
        if _key(entry.name) == wanted:
            return entry
    valid = ", ".join(e.name for e in entries)
    raise ValueError(f"method: unknown operator {name!r}; valid: {valid}")


def constant(name: str) -> Any:
    """A module attribute of :data:`CONSTANT_NAMES` (``"hdrjax.lights.DEFAULT_WIDTH"``),
    from the manifest."""
    from . import _manifest

    return _manifest.CONSTANTS[name]


def _key(name: str) -> str:
    # the registry's own normalisation (hdrjax.operators.get_operator)
    return re.sub(r"[\s_\-]", "", name.lower())


def live_registry_needed() -> bool:
    """Whether operators other than the manifest's may be registered: the registry is
    imported already (in-process registrations), ``HDRJAX_PLUGINS`` names a module, or an
    installed package declares an ``hdrjax.operators`` entry point."""
    if "hdrjax.operators" in sys.modules:
        return True
    if any(e.strip() for e in os.environ.get("HDRJAX_PLUGINS", "").split(",")):
        return True
    return _entry_points_declared()


@functools.cache
def _entry_points_declared() -> bool:
    # once per process, as the registry loads its entry points once
    return entry_points_declared(constant("hdrjax.operators.ENTRY_POINT_GROUP"))


def entry_points_declared(group: str) -> bool:
    """Whether an installed distribution may declare entry points in ``group``.

    Reads the ``entry_points.txt`` of the ``*.dist-info`` and ``*.egg-info`` folders on
    ``sys.path``, where the standard path finder finds installed distributions' metadata,
    as :func:`importlib.metadata.entry_points` does, without importing importlib.metadata
    (which takes about as long as the rest of ``hdrjax --help``). Where metadata may live
    elsewhere (a zip file on ``sys.path``, an import hook that finds distributions)
    importlib.metadata answers. A group heading without entries counts: the answer may
    be a false "yes" (the live registry is read, only slower), never a false "no".
    """
    import importlib.machinery

    finders = [f for f in sys.meta_path if hasattr(f, "find_distributions")]
    if any(f is not importlib.machinery.PathFinder for f in finders):
        return _importlib_entry_points(group)
    heading = f"[{group}]"
    for root in sys.path:
        root = os.fspath(root) or "."
        try:
            children = os.listdir(root)
        except OSError:
            if os.path.isfile(root):  # a zip file
                return _importlib_entry_points(group)
            continue
        egg = os.path.basename(root).lower().endswith(".egg")
        for child in children:
            low = child.lower()
            if not (low.endswith((".dist-info", ".egg-info")) or (egg and low == "egg-info")):
                continue
            try:
                with open(os.path.join(root, child, "entry_points.txt"), encoding="utf-8") as f:
                    text = f.read()
            except OSError:
                continue  # none, or an .egg-info file
            except ValueError:
                return True  # undecodable: let the registry's loader decide
            if any(line.strip() == heading for line in text.splitlines()):
                return True
    return False


def _importlib_entry_points(group: str) -> bool:
    import importlib.metadata

    return bool(importlib.metadata.entry_points(group=group))


@functools.cache
def manifest_operators() -> tuple[OperatorEntry, ...]:
    """The built-in operators as recorded in ``_manifest.py``."""
    from . import _manifest

    recorded: tuple[dict[str, Any], ...] = _manifest.OPERATORS
    return tuple(
        OperatorEntry(**{**op, "parameters": tuple(ParameterEntry(**p) for p in op["parameters"])})
        for op in recorded
    )


def live_operators(builtin: bool = False) -> tuple[OperatorEntry, ...]:
    """Every operator of the live registry (imports it, and JAX), sorted by name;
    ``builtin``: the package's own only (what the manifest records)."""
    from ..operators import get_operator, operator_names

    classes = [get_operator(name) for name in operator_names()]
    if builtin:
        classes = [c for c in classes if c.__module__.startswith("hdrjax.operators.")]
    return tuple(operator_entry(c) for c in classes)


def operator_entry(cls) -> OperatorEntry:
    """An operator class as the command line shows it (:func:`hdrjax.operators.parameter_info`
    and its class attributes)."""
    from ..operators import parameter_info

    return OperatorEntry(
        name=cls.name,
        summary=summary(cls),
        reference=cls.reference,
        per_channel=bool(cls.per_channel),
        scale_invariant=bool(cls.scale_invariant),
        default_fit_params=tuple(cls.default_fit_params),
        parameters=tuple(
            ParameterEntry(
                name=info.name,
                help=info.help,
                unit=info.unit,
                default=_default_text(info),
                range=None if info.range is None else tuple(float(v) for v in info.range),
                range_text=info.range_text(),
                choices=info.choices,
                estimated=info.estimated,
                pooling=info.pooling,
                static=info.static,
            )
            for info in parameter_info(cls)
        ),
    )


def summary(cls) -> str:
    """The first paragraph of an operator's docstring, on one line, without markup."""
    import inspect

    doc = inspect.cleandoc(cls.__doc__ or "").split("\n\n")[0]
    return " ".join(doc.replace("``", "").split())


def _default_text(info) -> str:
    if info.required:
        return "required"
    v = info.default
    if v is None:
        return "estimated" if info.estimated else "none"
    if isinstance(v, tuple):
        try:
            return "(" + ", ".join(f"{x:.4g}" for x in v) + ")"
        except (TypeError, ValueError):  # a plug-in's tuple of names: every page still prints
            return str(v)
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def live_constants() -> dict[str, Any]:
    """The attributes of :data:`CONSTANT_NAMES` read from their modules (imports them)."""
    out = {}
    for name in CONSTANT_NAMES:
        module, _, attr = name.rpartition(".")
        out[name] = getattr(importlib.import_module(module), attr)
    return out


# ----------------------------------------------------------------------------- generator


def manifest_text() -> str:
    """The source of ``_manifest.py`` for the live registry's built-in operators (plug-ins
    are left out) and :func:`live_constants`."""
    ops = [entry._asdict() for entry in live_operators(builtin=True)]
    for op in ops:
        op["parameters"] = tuple(p._asdict() for p in op["parameters"])
    lines = [
        '"""The built-in operators and the constants the command line shows, recorded so that',
        "``hdrjax --help`` and ``hdrjax operators`` run without importing JAX (see",
        "``_registry.py``). Generated by ``python -m hdrjax.cli._registry``: do not edit.",
        '"""',
        "",
        "# ruff: noqa: E501",
        "from math import inf",
        "",
        f"OPERATORS = {_literal(tuple(ops), 0)}",
        "",
        f"CONSTANTS = {_literal(live_constants(), 0)}",
        "",
    ]
    return "\n".join(lines)


def write_manifest(path: str = MANIFEST_PATH) -> bool:
    """Rewrite ``_manifest.py`` from the live registry; whether it changed."""
    text = manifest_text()
    if os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            if f.read() == text:
                return False
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return True


def _literal(value: Any, depth: int) -> str:
    """Python source for ``value``: nested dicts and tuples one item a line, short tuples of
    plain values on one, strings quoted as ``ruff format`` quotes them (the file stays as
    ruff formats it); ``inf`` reads back through the manifest's ``from math import inf``."""
    pad, inner = "    " * depth, "    " * (depth + 1)
    if isinstance(value, dict):
        items = [f"{inner}{_literal(k, 0)}: {_literal(v, depth + 1)}," for k, v in value.items()]
        return "{\n" + "\n".join(items) + f"\n{pad}}}"
    if isinstance(value, tuple):
        if not value:
            return "()"
        if all(isinstance(v, (str, int, float)) for v in value):
            flat = ", ".join(_literal(v, 0) for v in value)
            flat = f"({flat},)" if len(value) == 1 else f"({flat})"
            if len(pad) + len(flat) < 60:
                return flat
        items = [f"{inner}{_literal(v, depth + 1)}," for v in value]
        return "(\n" + "\n".join(items) + f"\n{pad})"
    if isinstance(value, str):
        text = repr(value)  # single quotes unless the text holds one
        if text.startswith("'") and '"' not in value:
            text = '"' + text[1:-1].replace("\\'", "'") + '"'
        return text
    if isinstance(value, (bool, int, float)) or value is None:
        return repr(value)
    raise TypeError(f"manifest: cannot record {value!r} ({type(value).__name__})")


if __name__ == "__main__":
    changed = write_manifest()
    print(f"{MANIFEST_PATH}: {'rewritten' if changed else 'up to date'}")
