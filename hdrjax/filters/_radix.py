"""Rank selection by binary search on key bits, for windows too large for a network.

A k×k comparator network for k ≥ 9 has thousands of min/max in one fused loop, which XLA
compiles in tens of seconds to minutes (k = 15: four minutes). Here the rank-``m`` key of
every window is found bit by bit instead: with the keys biased to unsigned order, the answer
has bit ``b`` set exactly when fewer than ``m + 1`` window keys lie below
``prefix | 2^b``. 32 rounds of ``k²`` compare-and-count per pixel, in a loop whose body is
``k²`` operations: compile time stays small for any k; the work is O(32·k²) per pixel.

Strips here are padded copies (edge rows and columns mapped by the mode), so this module
also serves the vector median.
"""

from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from ._strips import map_index, strip_rows

_UINT = {jnp.dtype(jnp.int32): jnp.uint32, jnp.dtype(jnp.int64): jnp.uint64}


def window_views(block: Array, k: int) -> list[Array]:
    """The k² shifted (R, W) views of a padded (R + k − 1, W + k − 1) block, row-major."""
    R, W = block.shape[0] - k + 1, block.shape[1] - k + 1
    return [jax.lax.slice(block, (i, j), (i + R, j + W)) for i in range(k) for j in range(k)]


def radix_select(views: Callable[..., list[Array]], inputs: tuple, rank) -> Array:
    """Per pixel, the key of rank ``rank`` (0-based; an int or per-pixel array) among the
    window elements ``views(*inputs)`` returns (equal-shape int32 or int64 arrays, one each).

    The views are made inside the loop body from ``inputs`` passed through an optimization
    barrier together with the loop state: views made from loop-invariant values would be
    hoisted out of the loop by XLA and stored, all k² of them, each as its own kernel.
    """
    first = jax.eval_shape(lambda *a: views(*a)[0], *inputs)
    shape, dtype = first.shape, first.dtype
    ut = _UINT[dtype]
    nbits = jnp.iinfo(ut).bits
    sign = jnp.array(1, ut) << (nbits - 1)
    rank = jnp.asarray(rank, jnp.int32)

    def bit(b, prefix):
        cand = prefix | (jnp.array(1, ut) << (nbits - 1 - b).astype(ut))
        fresh, _ = jax.lax.optimization_barrier((inputs, prefix))
        # signed order → unsigned order by flipping the sign bit
        flags = [(jax.lax.bitcast_convert_type(v, ut) ^ sign) < cand for v in views(*fresh)]
        below = sum(f.astype(jnp.int32) for f in flags)
        return jnp.where(below <= rank, cand, prefix)

    prefix = jax.lax.fori_loop(0, nbits, bit, jnp.zeros(shape, ut))
    return jax.lax.bitcast_convert_type(prefix ^ sign, dtype)


def padded_strips(
    x: Array, k: int, mode: str, rows: int | None, fn: Callable[..., Array], dtype
) -> Array:
    """``fn(block, src_rows, src_cols)`` on every strip: ``block`` is the edge-mapped padded
    strip ``(R + k − 1, W + k − 1, ...)`` of some R output rows, ``src_rows``/``src_cols``
    the image rows and columns its rows and columns come from; ``fn`` returns the strip's
    ``(R, W)`` values of ``dtype``, assembled into the ``(H, W)`` result."""
    h, w = x.shape[:2]
    r = k // 2
    R = strip_rows(h, w, 4 * int(np.prod(x.shape[2:], dtype=int)), even=False, rows=rows)
    n = -(-h // R)
    cols = map_index(np.arange(-r, w + r), w, mode)
    src_cols = jnp.asarray(cols.astype(np.int32))

    def body(i, out):
        first = jnp.minimum(i * R, h - R)  # the last strip may overlap the one before
        src = map_index(first - r + jnp.arange(R + 2 * r, dtype=jnp.int32), h, mode)
        block = jnp.take(jnp.take(x, src, axis=0), cols, axis=1)
        return jax.lax.dynamic_update_slice(out, fn(block, src, src_cols), (first, 0))

    return jax.lax.fori_loop(0, n, body, jnp.zeros((h, w), dtype))
