"""The box (mean) filter: separable shifted sums over row strips (see :mod:`._mean`)."""

import jax
import jax.numpy as jnp
from jax import Array

from ._strips import edge_bands, padded_block, strip_rows


def _tree_sum(terms: list[Array]) -> Array:
    """Pairwise sum: rounding error grows with log2(n), not n."""
    while len(terms) > 1:
        nxt = [terms[i] + terms[i + 1] for i in range(0, len(terms) - 1, 2)]
        if len(terms) % 2:
            nxt.append(terms[-1])
        terms = nxt
    return terms[0]


def _box(block: Array, k: int, rows: int, cols: int) -> Array:
    """Mean over k×k windows of a block padded by k // 2 → (rows, cols)."""
    width = block.shape[1]
    v = _tree_sum([jax.lax.slice(block, (i, 0), (i + rows, width)) for i in range(k)])
    s = _tree_sum([jax.lax.slice(v, (0, j), (rows, j + cols)) for j in range(k)])
    return s / jnp.asarray(k * k, s.dtype)


def mean_block(x: Array, k: int, mode: str, r0: int, r1: int, c0: int, c1: int) -> Array:
    """Mean of output rows ``r0..r1-1`` × columns ``c0..c1-1`` from a padded copy of their
    inputs: for edge bands and small images."""
    return _box(padded_block(x, k // 2, mode, r0, r1, c0, c1), k, r1 - r0, c1 - c0)


def mean_plane(x: Array, k: int, mode: str, rows: int | None = None) -> Array:
    """k×k mean of one (H, W) float plane with the given edge mode.

    The interior (pixels at least ``r = k // 2`` from every edge) runs in row strips that
    read the input in place: a pairwise sum of ``k`` shifted rows, then of ``k`` shifted
    columns, divided by ``k²`` (about ``2 ceil(log2 k) + 1`` roundings, so below 1e-6
    relative error in float32 for k ≤ 15 on non-negative data; a float32 summed-area table
    loses up to 6 % on HDR images). The edge bands use :func:`mean_block`.
    """
    h, w = x.shape
    r = k // 2
    if k == 1:
        return x
    hi, wi = h - 2 * r, w - 2 * r
    if hi < 1 or wi < 1 or h * w <= 4096:
        return mean_block(x, k, mode, 0, h, 0, w)
    R = strip_rows(hi, w, x.dtype.itemsize, even=False, rows=rows)
    n, tail = divmod(hi, R)
    bands = edge_bands(h, w, r, hi)
    band_vals = [mean_block(x, k, mode, *b) for b in bands]

    def strip(first, count):  # mean of output rows first..first+count-1, interior columns
        block = jax.lax.dynamic_slice_in_dim(x, first - r, count + 2 * r, axis=0)
        return _box(block, k, count, wi)

    def body(i, out):
        first = r + i * R
        return jax.lax.dynamic_update_slice(out, strip(first, R), (first, r))

    out = jax.lax.fori_loop(0, n, body, jnp.zeros_like(x))
    if tail:
        out = jax.lax.dynamic_update_slice(out, strip(r + n * R, tail), (r + n * R, r))
    for (r0, _, c0, _), vals in zip(bands, band_vals, strict=True):
        out = jax.lax.dynamic_update_slice(out, vals, (r0, c0))
    return out
