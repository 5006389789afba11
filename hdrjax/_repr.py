"""How hdrjax objects show themselves: one-line ``__repr__`` texts and notebook HTML views.

Values are shown as values: scalars as numbers (4 significant digits) with their unit where
one is known, short vectors as lists, larger arrays as dtype, shape and finite range (never
a full dump, never an abstract ``f32[]``), traced values as what they are. The HTML views
are a title, an optional thumbnail and a table, with no external resources.

Imports NumPy only (Pillow when a thumbnail is made); the classes that use it import it
inside their ``__repr__`` and ``_repr_html_`` methods.
"""

import base64
import dataclasses
import html
import io
import sys
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

SHORT = 4
"""Arrays with at most this many elements are shown element by element."""

ITEMS = 8
"""Tuples and dicts show at most this many entries."""

TEXT = 80
"""Longest fallback ``repr`` of an unknown object (characters)."""


def _traced(x: Any) -> bool:
    jax_core = sys.modules.get("jax.core")  # not imported: nothing can be traced
    return jax_core is not None and isinstance(x, jax_core.Tracer)


def concrete(*xs: Any) -> bool:
    """Whether none of ``xs`` is a traced value (a repr inside ``jit`` shows no numbers)."""
    return not any(_traced(x) for x in xs)


def short_unit(unit: str) -> str:
    """A unit as a one-line text shows it: without its parenthesised remark, and empty for
    ``"image units"`` (relative luminance: a number needs no unit)."""
    unit = unit.split(" (")[0].strip()
    return "" if unit == "image units" else unit


def number(v: Any, unit: str = "") -> str:
    """``v`` (a Python or NumPy scalar) as text: ``0.18``, ``1e+04``, ``12``, ``True``; with
    `` unit`` after it when one is given."""
    if isinstance(v, bool | np.bool_):
        text = str(bool(v))
    elif isinstance(v, int | np.integer):
        text = str(int(v))
    elif isinstance(v, float | np.floating):
        text = f"{float(v):.4g}"
    elif isinstance(v, complex | np.complexfloating):
        text = f"{complex(v):.4g}"
    else:
        text = str(v)
    return f"{text} {unit}" if unit else text


def array(x: Any, unit: str = "") -> str:
    """An array (NumPy or JAX) as text: a number when it has one element and no axis, the
    elements when it has at most :data:`SHORT`, else ``float32 (32, 32, 3), 0.01 to 4.2``
    (the range of its finite values)."""
    if _traced(x):
        return f"traced {np.dtype(x.dtype).name} {tuple(x.shape)}"
    a = np.asarray(x)
    if a.ndim == 0:
        return number(a.item(), unit)
    tail = f" {unit}" if unit else ""
    if a.size <= SHORT and a.ndim == 1:
        return "[" + ", ".join(number(v) for v in a.tolist()) + "]" + tail
    head = f"{a.dtype.name} {tuple(a.shape)}"
    if a.size == 0 or a.dtype.kind not in "biuf":
        return head
    finite = a[np.isfinite(a)] if a.dtype.kind == "f" else a.reshape(-1)
    if finite.size == 0:
        return f"{head}, no finite value"
    lo, hi = finite.min(), finite.max()
    rest = "" if finite.size == a.size else f", {a.size - finite.size} non-finite"
    if lo == hi:
        return f"{head}, all {number(lo.item())}{tail}{rest}"
    return f"{head}, {number(lo.item())} to {number(hi.item())}{tail}{rest}"


def is_array(x: Any) -> bool:
    """A NumPy or JAX array (concrete or traced)."""
    return isinstance(x, np.ndarray | np.generic) or (
        hasattr(x, "shape") and hasattr(x, "dtype") and not isinstance(x, type)
    )


def value(x: Any, unit: str = "", depth: int = 2) -> str:
    """Any field value as short text: numbers and arrays (:func:`array`), ``None``, names,
    tuples, lists and dicts (their first :data:`ITEMS` entries), modules and dataclasses
    (:func:`call`, ``depth`` levels deep), else a ``repr`` cut to :data:`TEXT` characters."""
    if x is None:
        return "None"
    if isinstance(x, str):
        return repr(x)
    if isinstance(x, bool | int | float | np.number | np.bool_):
        return number(x, unit)
    if is_array(x):
        return array(x, unit)
    if isinstance(x, tuple | list):
        parts = [value(v, unit, depth - 1) for v in x[:ITEMS]]
        more = [f"… {len(x) - ITEMS} more"] if len(x) > ITEMS else []
        o, c = ("(", ",)" if len(x) == 1 else ")") if isinstance(x, tuple) else ("[", "]")
        return o + ", ".join(parts + more) + c
    if isinstance(x, Mapping):
        parts = [f"{k}: {value(v, '', depth - 1)}" for k, v in list(x.items())[:ITEMS]]
        more = [f"… {len(x) - ITEMS} more"] if len(x) > ITEMS else []
        return "{" + ", ".join(parts + more) + "}"
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        if _own_repr(x):
            return repr(x)
        return call(x, depth=depth) if depth > 0 else f"{type(x).__name__}(…)"
    text = repr(x)
    return text if len(text) <= TEXT else text[: TEXT - 1] + "…"


def _own_repr(x: Any) -> bool:
    """Whether ``x``'s class has a ``__repr__`` written for it in hdrjax (not one that
    ``dataclasses`` generated, which wraps it, nor equinox's, which shows ``f32[]``)."""
    for cls in type(x).__mro__:
        if "__repr__" in vars(cls):
            fn = vars(cls)["__repr__"]
            own = getattr(fn, "__module__", "") or ""
            return own.startswith("hdrjax") and not hasattr(fn, "__wrapped__")
    return False


def fields(x: Any) -> list[tuple[str, Any]]:
    """``(name, value)`` of a dataclass's (or equinox Module's) fields shown in a repr."""
    return [(f.name, getattr(x, f.name)) for f in dataclasses.fields(x) if f.repr]


def call(
    x: Any,
    items: Iterable[tuple[str, Any]] | None = None,
    units: Mapping[str, str] | None = None,
    depth: int = 2,
) -> str:
    """``Name(a=0.18, b=[1, 2, 3], c=None)``: ``items`` (default: the dataclass fields of
    ``x``), values through :func:`value` with their ``units``."""
    units = units or {}
    items = fields(x) if items is None else items
    body = ", ".join(f"{k}={value(v, units.get(k, ''), depth - 1)}" for k, v in items)
    return f"{type(x).__name__}({body})"


def fields_repr(self: Any) -> str:
    """A ``__repr__`` for a Module or dataclass: ``Name(field=value, …)`` (:func:`call`)."""
    return call(self)


def fields_html(self: Any) -> str:
    """A ``_repr_html_`` for a Module or dataclass: its name over a table of its fields."""
    return view(type(self).__name__, table([(k, value(v)) for k, v in fields(self)]))


def table(rows: Iterable[Iterable[Any]], header: Iterable[str] | None = None) -> str:
    """An HTML table of text cells (escaped); the first cell of each row is a heading."""
    out = ["<table>"]
    if header is not None:
        cells = "".join(f"<th style='text-align:left'>{html.escape(str(h))}</th>" for h in header)
        out.append(f"<tr>{cells}</tr>")
    for row in rows:
        first, *rest = (html.escape(str(c)) for c in row)
        out.append(
            f"<tr><th style='text-align:left'>{first}</th>"
            + "".join(f"<td style='text-align:left'>{c}</td>" for c in rest)
            + "</tr>"
        )
    out.append("</table>")
    return "".join(out)


def thumbnail(rgb8: np.ndarray, size: int = 256) -> str:
    """An ``<img>`` element of an 8-bit RGB array (a PNG data URI), at most ``size`` pixels
    wide."""
    return f'<img src="{png_data_uri(rgb8)}" style="max-width:{size}px">'


def preformatted(text: str) -> str:
    """The HTML view of an object that has only its text (a traced or batched one)."""
    return f"<pre>{html.escape(text)}</pre>"


def png_data_uri(rgb8: np.ndarray) -> str:
    """A ``data:image/png;base64,…`` URI of an 8-bit RGB array."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(rgb8)).save(buf, format="PNG")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def view(title: str, body: str, image: str = "", note: str = "") -> str:
    """A notebook view: a bold ``title`` (escaped), then an ``image`` element (see
    :func:`thumbnail`) beside the ``body`` (HTML, e.g. :func:`table`), then a ``note``
    (escaped text)."""
    note_html = f"<div><small>{html.escape(note)}</small></div>" if note else ""
    return (
        f"<div><b>{html.escape(title)}</b><div style='display:flex;gap:1em'>"
        f"{image}{body}</div>{note_html}</div>"
    )


__all__ = [
    "array",
    "call",
    "concrete",
    "fields",
    "is_array",
    "number",
    "png_data_uri",
    "preformatted",
    "short_unit",
    "table",
    "thumbnail",
    "value",
    "view",
]
