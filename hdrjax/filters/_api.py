"""Shared argument handling and compilation for the public filters."""

import functools
from collections.abc import Callable

import jax
import jax.numpy as jnp
from jax import Array

from .. import _check

# AVX-512 machines run the integer networks twice as wide with 512-bit vectors; XLA's
# default prefers 256. Region analysis in copy insertion drops the copies XLA otherwise
# makes of the strip loops' carried buffers in every iteration (the median's loop had 4;
# 5×5 median at 4096²: ~85 → ~75 ms of CPU time). Applied to hdrjax's own jit only (inside
# a caller's jit the caller's settings win); harmless on CPUs without AVX-512.
_CPU_OPTIONS = {
    "xla_cpu_prefer_vector_width": 512,
    "xla_cpu_copy_insertion_use_region_analysis": True,
}


def float_image(image) -> Array:
    """The image as a float32 array (float64 when x64 is on and the input is float64)."""
    _check.real(image, "image")
    x = jnp.asarray(image)
    if not jnp.issubdtype(x.dtype, jnp.floating) or x.dtype in (jnp.float16, jnp.bfloat16):
        x = x.astype(jnp.result_type(float))
    return x


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
    """``jax.jit(fn)``, with hdrjax's CPU compiler options when ``options``."""
    return jax.jit(fn, static_argnames=static, compiler_options=_CPU_OPTIONS if options else None)


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
