"""Shared argument handling and compilation for the public filters."""

import functools
from collections.abc import Callable

import jax
import jax.numpy as jnp
from jax import Array

from .. import _check
from ._xla_options import CPU_COMPILER_OPTIONS


def float_image(image) -> Array:
    """The image as a float32 array (float64 when x64 is on and the input is float64)."""
    _check.real(image, "image")
    return _check.as_float(image)


def check_size(size) -> int:
    if isinstance(size, bool) or int(size) != size or size < 1 or size % 2 == 0:
        raise ValueError(f"size: expected an odd integer >= 1, got {size!r}")
    return int(size)


def check_passes(passes) -> int:
    if isinstance(passes, bool) or int(passes) != passes or passes < 0:
        raise ValueError(f"passes: expected an integer >= 0, got {passes!r}")
    return int(passes)


def check_strip_rows(rows) -> int | None:
    if rows is None:
        return None
    if isinstance(rows, bool) or int(rows) != rows or rows < 1:
        raise ValueError(f"strip_rows: expected an integer >= 1 or None, got {rows!r}")
    return int(rows)


def check_layout(x: Array, channel_axis: int | None) -> None:
    if channel_axis not in (-1, None):
        raise ValueError(f"channel_axis: expected -1 (channels last) or None, got {channel_axis!r}")
    need = 2 if channel_axis is None else 3
    what = "(..., H, W)" if channel_axis is None else "(..., H, W, C)"
    if x.ndim < need:
        raise ValueError(f"image: expected shape {what}, got {x.shape}")
    _check.nonempty(x.shape, "image", what, (-2, -1) if channel_axis is None else (-3, -2))


@functools.cache
def compiled(fn: Callable, static: tuple[str, ...], options: bool) -> Callable:
    """``jax.jit(fn)``, with hdrjax's CPU compiler options (:mod:`._xla_options`) when
    ``options``."""
    opts = CPU_COMPILER_OPTIONS if options else None
    return jax.jit(fn, static_argnames=static, compiler_options=opts)


def call(fn: Callable, static: tuple[str, ...], *args, **kwargs):
    """Run ``fn`` jitted; XLA options only at top level on CPU (JAX refuses them nested)."""
    top = not any(isinstance(a, jax.core.Tracer) for a in args)
    return compiled(fn, static, top and jax.default_backend() == "cpu")(*args, **kwargs)


def eager_cpu(x: Array) -> bool:
    """Whether ``x`` is a concrete array (not being traced) and XLA runs on the CPU: there,
    a filter may split its work into several compiled stages (``SMALL_PIXELS`` in
    ``_median_core``); inside a caller's ``jit``, ``vmap`` or ``grad`` it is one computation."""
    return not isinstance(x, jax.core.Tracer) and jax.default_backend() == "cpu"


def map_planes(fn: Callable[[Array], Array], x: Array, lead: int) -> Array:
    """Apply ``fn`` to every (H, W) plane: the ``lead`` leading axes are batch axes."""
    if lead == 0:
        return fn(x)
    flat = x.reshape((-1,) + x.shape[lead:])
    return jax.vmap(fn)(flat).reshape(x.shape[:lead] + flat.shape[1:])


def map_channels(fn: Callable[[Array], Array], x: Array, planes: bool) -> Array:
    """Apply ``fn`` to every (H, W) plane of ``(..., H, W)`` planes or of the channels of a
    channels-last ``(..., H, W, C)`` image."""
    if planes:
        return map_planes(fn, x, x.ndim - 2)
    moved = jnp.moveaxis(x, -1, -3)  # (..., C, H, W)
    return jnp.moveaxis(map_planes(fn, moved, moved.ndim - 2), -3, -1)
