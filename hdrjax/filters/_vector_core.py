"""The vector median (see :mod:`._median`): the window pixel with the smallest sum of
Euclidean distances to the other pixels of the window (Astola, Haavisto & Neuvo 1990,
"Vector median filters", Proc. IEEE 78(4), doi:10.1109/5.54807).

O(k⁴) work per pixel (every pair of window pixels), done as a loop over the k² candidate
offsets on padded strips; O(k²·strip) memory. Pixels with a non-finite channel are never
chosen and add no distance; a window without any finite pixel keeps its centre pixel.
"""

import functools

import jax
import jax.numpy as jnp
from jax import Array

from ._radix import padded_strips


def _strip(k: int, w: int, block: Array, src_rows: Array, src_cols: Array) -> Array:
    R, W = block.shape[0] - k + 1, block.shape[1] - k + 1
    finite = jnp.all(jnp.isfinite(block), axis=-1)
    safe = jnp.where(finite[..., None], block, 0)

    def window(a, i, j):
        return jax.lax.dynamic_slice(a, (i, j) + (0,) * (a.ndim - 2), (R, W) + a.shape[2:])

    def candidate(u, best):
        best_sum, best_u = best
        # the barrier ties the blocks to the loop state: without it XLA hoists all k² static
        # window views out of the loop and stores each one
        (pts, ok), _ = jax.lax.optimization_barrier(((safe, finite), best_sum))
        pu, fu = window(pts, u // k, u % k), window(ok, u // k, u % k)
        total = jnp.zeros((R, W), block.dtype)
        for i in range(k):
            for j in range(k):
                d = jnp.sqrt(jnp.sum(jnp.square(pu - window(pts, i, j)), axis=-1))
                total = total + jnp.where(window(ok, i, j), d, 0)
        total = jnp.where(fu, total, jnp.inf)
        better = total < best_sum  # strict: ties keep the earlier candidate
        return jnp.where(better, total, best_sum), jnp.where(better, u, best_u)

    init = (jnp.full((R, W), jnp.inf, block.dtype), jnp.full((R, W), (k * k) // 2, jnp.int32))
    _, best_u = jax.lax.fori_loop(0, k * k, candidate, init)
    y = jax.lax.broadcasted_iota(jnp.int32, (R, W), 0) + best_u // k
    x = jax.lax.broadcasted_iota(jnp.int32, (R, W), 1) + best_u % k
    return jnp.take(src_rows, y) * w + jnp.take(src_cols, x)


def argvector_plane(img: Array, k: int, mode: str, rows: int | None = None) -> Array:
    """For each pixel of an (H, W, C) image, the flat index ``y·W + x`` of its window's
    vector median; ties go to the first candidate in row-major window order."""
    img = jax.lax.stop_gradient(img)  # only the choice is computed here
    strip = functools.partial(_strip, k, img.shape[1])
    return padded_strips(img, k, mode, rows, strip, jnp.int32)
