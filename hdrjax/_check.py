"""Argument validation shared by the public functions: shapes, dtypes and parameter ranges.

Every check reads only what is static under ``jax.jit`` — an array's shape and dtype, and
Python numbers — so it runs once at trace time and costs nothing in the compiled function.
A traced *value* (a parameter passed as a jnp array inside ``jit``) cannot be checked that
way and is let through; concrete values (Python numbers, NumPy arrays, eager JAX arrays)
are checked.

Each failure is a ``ValueError`` whose message starts with the argument's name and says the
expected form, on one line (the command line prints it as ``hdrjax CMD: error: ...``)::

    rgb: expected shape (..., H, W, 3), got shape (4, 5)
    rgb: expected a real-valued array (floating point; integers and bools are promoted to
    float), got dtype complex64
    size: expected an integer >= 1, got -3

Policy (the conformance suite, ``tests/conformance/test_bad_input.py``, holds every public
function to it):

- **dtype**: floating point; integer and bool arrays are promoted to JAX's default float
  (as NumPy ufuncs do), float16/bfloat16 are computed in it; complex, string and object
  arrays are rejected — a complex image is a mistake (an FFT result passed on), and
  silently dropping its imaginary part hides it.
- **shape**: images are channels last; a function states its form, e.g. ``(..., H, W, 3)``.
- **empty**: an image needs at least one row and one column: ``H == 0`` or ``W == 0`` is an
  error (:func:`nonempty`), raised at trace time like every shape error —
  ``rgb: expected a non-empty image (..., H, W, 3) with H, W >= 1, got shape (0, 8, 3)``.
  A batch axis of size 0 is not: ``(0, H, W, 3)`` frames give an empty batch of results,
  as ``jax.vmap`` and NumPy do. Functions of values rather than images (per-value formulas
  of any shape such as :func:`hdrjax.display.srgb_encode`, per-pixel ones of shape
  ``(..., 3)`` such as :func:`hdrjax.luminance`, and percentiles of a pooled set) take
  empty arrays as NumPy ufuncs do: an empty result of the matching shape (NaN percentiles:
  no value qualifies).
"""

import numbers
import re
from collections.abc import Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np


def dtype_of(x: Any) -> np.dtype:
    """The dtype ``jnp.asarray(x)`` would have, without converting ``x``."""
    dt = getattr(x, "dtype", None)
    if dt is not None:
        return np.dtype(dt)
    return np.asarray(x).dtype


def real(x: Any, name: str) -> None:
    """Raise unless ``x`` is real-valued: floating point, integer or bool (promoted)."""
    dt = dtype_of(x)
    if not (
        jnp.issubdtype(dt, jnp.floating)
        or jnp.issubdtype(dt, jnp.integer)
        or jnp.issubdtype(dt, jnp.bool_)
    ):
        raise ValueError(
            f"{name}: expected a real-valued array (floating point; integers and bools are"
            f" promoted to float), got dtype {dt}"
        )


def as_float(x: Any) -> jax.Array:
    """``x`` as a JAX float array in the policy's dtype: floating point kept, float16,
    bfloat16, integers and bools computed in JAX's default float (float32, float64 under
    x64). Checks nothing: call :func:`real` first where the dtype comes from the user."""
    x = jnp.asarray(x)
    if not jnp.issubdtype(x.dtype, jnp.floating) or x.dtype in (jnp.float16, jnp.bfloat16):
        x = x.astype(jnp.result_type(float))
    return x


def rgb_pixels(x: Any, name: str = "rgb") -> jax.Array:
    """Channels-last RGB ``(..., 3)`` as a float array (:func:`as_float`'s dtypes), for
    functions of each pixel; one-line ``ValueError`` naming ``name`` otherwise."""
    real(x, name)
    x = jnp.asarray(x)
    if x.ndim < 1 or x.shape[-1] != 3:
        raise ValueError(f"{name}: expected channels-last RGB (..., 3), got shape {x.shape}")
    return as_float(x)


def form(channels: int | None = 3, ndim: int | None = None, min_ndim: int = 3) -> str:
    """The expected shape as the messages write it, e.g. ``(..., H, W, 3)``."""
    c = "C" if channels is None else str(channels)
    axes = ["B", "H", "W", c][-min(ndim or min_ndim, 4) :]
    lead = "" if ndim is not None else "..., "
    return f"({lead}{', '.join(axes)})"


def shape(
    x: Any,
    name: str,
    *,
    channels: int | None = 3,
    ndim: int | None = None,
    min_ndim: int = 3,
) -> tuple[int, ...]:
    """Validate an image's shape and dtype without converting it; return its shape.

    Args:
        x: the argument (any array-like, or a ``jax.ShapeDtypeStruct``; only its shape and
            dtype are read).
        name: the argument's name, for the message.
        channels: required size of the last axis, ``None`` for any.
        ndim: exact number of axes (e.g. 3 for one ``(H, W, C)`` image); ``None`` allows
            leading batch axes.
        min_ndim: least number of axes when ``ndim`` is ``None``.
    """
    s = tuple(int(v) for v in getattr(x, "shape", None) or np.shape(x))
    bad_rank = len(s) != ndim if ndim is not None else len(s) < min_ndim
    if bad_rank or (channels is not None and (not s or s[-1] != channels)):
        raise ValueError(f"{name}: expected shape {form(channels, ndim, min_ndim)}, got shape {s}")
    if (ndim or min_ndim) >= 3:  # the form has H and W
        nonempty(s, name, form(channels, ndim, min_ndim))
    real(x, name)
    return s


def nonempty(
    s: Sequence[int], name: str, expected: str = "(..., H, W, 3)", axes: Sequence[int] = (-3, -2)
) -> None:
    """Raise unless the image axes ``axes`` of shape ``s`` (``H`` and ``W``: by default the
    two before the channels) have at least one element each; a batch axis may be 0.

    ``expected`` is the form the message states, e.g. ``(..., H, W, 3)`` or ``(H, W)``.
    Reads only the shape (static under ``jax.jit``): the error comes at trace time, before
    anything compiles.
    """
    s = tuple(int(v) for v in s)
    if any(s[a] < 1 for a in axes if -len(s) <= a < len(s)):
        raise ValueError(
            f"{name}: expected a non-empty image {expected} with H, W >= 1, got shape {s}"
        )


def cube(
    faces: Any, name: str = "faces", *, channels: int | None = 3, batch: bool = True
) -> tuple[int, ...]:
    """Validate ``(..., 6, S, S, C)`` cube faces (``(6, S, S, C)`` unless ``batch``), shape
    and dtype; return the shape."""
    s = tuple(int(v) for v in np.shape(faces))
    ok = (len(s) >= 4 if batch else len(s) == 4) and s[-4] == 6 and s[-3] == s[-2]
    c = "C" if channels is None else str(channels)
    lead = "..., " if batch else ""
    if not ok or (channels is not None and s[-1] != channels):
        raise ValueError(
            f"{name}: expected cube faces of shape ({lead}6, S, S, {c}), got shape {s}"
        )
    if s[-3] < 1:
        raise ValueError(
            f"{name}: expected non-empty cube faces ({lead}6, S, S, {c}) with S >= 1, got shape {s}"
        )
    real(faces, name)
    return s


def image_size(size: Any, name: str = "shape") -> tuple[int, int]:
    """``(H, W)`` of an image shape given as ``(H, W)`` or ``(H, W, 3)``."""
    try:
        s = tuple(int(v) for v in size)
    except TypeError:
        s = ()
    if len(s) not in (2, 3) or (len(s) == 3 and s[2] != 3):
        raise ValueError(f"{name}: expected an image size (H, W) or (H, W, 3), got {size!r}")
    if min(s[:2]) < 1:
        raise ValueError(
            f"{name}: expected a non-empty image size (H, W) or (H, W, 3) with H, W >= 1,"
            f" got {size!r}"
        )
    return s[0], s[1]


def _concrete(value: Any) -> np.ndarray | None:
    """``value`` as a NumPy array, or ``None`` when it is traced (not checkable)."""
    if isinstance(value, jax.core.Tracer):
        return None
    return np.asarray(value)


def positive(
    value: Any, name: str, *, integer: bool = False, zero: bool = False, finite: bool = True
) -> Any:
    """Raise unless ``value`` is a positive (or, with ``zero``, non-negative) number, finite
    unless ``finite=False`` (NaN never passes), an integer when ``integer``; every element
    of an array. ``None`` (a default meaning "estimate it") passes. Returns ``value``."""
    if value is None:
        return value
    what = ("a non-negative" if zero else "a positive") + (" integer" if integer else " number")
    what += "" if finite else " (inf allowed)"
    if integer and (isinstance(value, bool) or not isinstance(value, numbers.Integral)):
        raise ValueError(f"{name}: expected {what}, got {value!r}")
    v = _concrete(value)
    if v is None:
        return value
    if not np.issubdtype(v.dtype, np.number) or np.iscomplexobj(v):
        raise ValueError(f"{name}: expected {what}, got {value!r}")
    ok = v >= 0 if zero else v > 0
    if not np.all(ok & (np.isfinite(v) | (not finite))):
        raise ValueError(f"{name}: expected {what}, got {value!r}")
    return value


def integer(value: Any, name: str, minimum: int = 1) -> int:
    """Raise unless ``value`` is an integer (not a bool) ``>= minimum``; return it as int."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {value!r}")
    return int(value)


def in_range(value: Any, name: str, lo: float, hi: float) -> Any:
    """Raise unless every element of ``value`` lies in ``[lo, hi]`` (``None`` passes)."""
    v = None if value is None else _concrete(value)
    if v is None:
        return value
    if (
        not np.issubdtype(v.dtype, np.number)
        or np.iscomplexobj(v)
        or not np.all((v >= lo) & (v <= hi))
    ):
        raise ValueError(f"{name}: expected numbers in [{lo:g}, {hi:g}], got {value!r}")
    return value


def weights(value: Any, name: str = "weights") -> Any:
    """Raise unless ``value`` is ``None`` or three finite numbers (RGB luminance weights)."""
    if value is None:
        return value
    try:
        w = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        w = np.zeros(0)
    if w.shape != (3,) or not np.all(np.isfinite(w)):
        raise ValueError(f"{name}: expected three finite numbers (w_r, w_g, w_b), got {value!r}")
    return value


def name_key(name: str) -> str:
    """A name compared case- and separator-insensitively (``"ITU-R BT.2020"`` →
    ``"iturbt2020"``): colour spaces, displays, observers."""
    return re.sub(r"[^0-9a-z]", "", name.lower())


def one_of(value: Any, name: str, options: Sequence[str]) -> Any:
    """Raise unless ``value`` is one of ``options``. Returns ``value``."""
    if value not in options:
        raise ValueError(f"{name}: expected one of {', '.join(map(repr, options))}, got {value!r}")
    return value


__all__ = [
    "as_float",
    "cube",
    "dtype_of",
    "form",
    "image_size",
    "in_range",
    "nonempty",
    "one_of",
    "positive",
    "real",
    "shape",
    "weights",
]
