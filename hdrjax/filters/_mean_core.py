"""The box (mean) filter: separable shifted sums (see :mod:`._mean`).

Two schedules compute the same sums in the same order, so their results are bit-identical:

- **one pass** (windows up to :data:`FUSED_MAX`, no ``strip_rows``): the interior is one
  fused elementwise computation over the whole image, written straight into the output
  (padded by the edge bands' width, which are then written in place). XLA:CPU computes each
  output element independently, so the k vertical sums are recomputed under each of the k
  horizontal taps (k·(k−1) + k − 1 additions per pixel instead of 2(k − 1)), but there is no
  temporary, no zero-filled output to overwrite and no per-strip loop overhead: for a 5×5
  window at 4096² this is ~25 % less time than the strips, and memory stays bounded by the
  output itself.
- **strips** (larger windows, or ``strip_rows`` given): row strips read in place, the
  vertical sums of a strip materialised once, then the horizontal sums.
"""

import jax
import jax.numpy as jnp
from jax import Array

from ._strips import edge_bands, padded_block, strip_rows

FUSED_MAX = 7
"""Largest window done in one fused pass (beyond it the recomputed vertical sums cost more
than the strip loop saves)."""

MEAN_STRIP_BYTES = 1024 * 1024
"""Default strip size of the strip schedule (input rows of one strip): its per-pixel work
is a few additions, so the per-iteration cost of the loop matters more than for the median
(64 rows at 4096 columns: ~10 % less time than 16 rows)."""


def _tree_sum(terms: list[Array]) -> Array:
    """Pairwise sum: rounding error grows with log2(n), not n."""
    while len(terms) > 1:
        nxt = [terms[i] + terms[i + 1] for i in range(0, len(terms) - 1, 2)]
        if len(terms) % 2:
            nxt.append(terms[-1])
        terms = nxt
    return terms[0]


def _box(block: Array, k: int, rows: int, cols: int, materialise: bool = True) -> Array:
    """Mean over k×k windows of a block padded by k // 2 → (rows, cols).

    With ``materialise`` the vertical sums are kept in memory (an optimization barrier)
    instead of being fused into, and recomputed under, each horizontal tap. Either way the
    values are the same: the barrier changes the schedule, not the arithmetic.
    """
    width = block.shape[1]
    c = headroom(k)
    block = block * jnp.asarray(c, block.dtype)
    v = _tree_sum([jax.lax.slice(block, (i, 0), (i + rows, width)) for i in range(k)])
    if materialise:
        v = jax.lax.optimization_barrier(v)
    s = _tree_sum([jax.lax.slice(v, (0, j), (rows, j + cols)) for j in range(k)])
    return s / jnp.asarray(k * k * c, s.dtype)


def headroom(k: int) -> float:
    """``2^-e`` with ``2^e ≥ k²``: the terms of a k×k sum are scaled by it as they are read
    (and the divisor ``k²`` with them), so that a window of values near the float maximum
    sums without overflow. A power of two scales exactly, so the means are bit-identical
    to the unscaled sums' for every input above ``2^e`` times the smallest normal float
    (7.5e-37 in float32 for k ≤ 7); below that the scaled terms are subnormal, which
    XLA:CPU flushes to zero. Per term it is one multiplication inside the fused loop, no
    extra pass over the image."""
    return 2.0 ** -(k * k - 1).bit_length()


def mean_block(x: Array, k: int, mode: str, r0: int, r1: int, c0: int, c1: int) -> Array:
    """Mean of output rows ``r0..r1-1`` × columns ``c0..c1-1`` from a padded copy of their
    inputs: for edge bands and small images."""
    return _box(padded_block(x, k // 2, mode, r0, r1, c0, c1), k, r1 - r0, c1 - c0)


def mean_plane(x: Array, k: int, mode: str, rows: int | None = None) -> Array:
    """k×k mean of one (H, W) float plane with the given edge mode.

    The interior (pixels at least ``r = k // 2`` from every edge) reads the input in place:
    a pairwise sum of ``k`` shifted rows, then of ``k`` shifted columns, divided by ``k²``
    (about ``2 ceil(log2 k) + 1`` roundings, so below 1e-6 relative error in float32 for
    k ≤ 15 on non-negative data; a float32 summed-area table loses up to 6 % on HDR images),
    in one fused pass or in row strips (module docstring). The edge bands use
    :func:`mean_block`.
    """
    h, w = x.shape
    r = k // 2
    if k == 1:
        return x
    hi, wi = h - 2 * r, w - 2 * r
    if hi < 1 or wi < 1 or h * w <= 4096:
        return mean_block(x, k, mode, 0, h, 0, w)
    bands = edge_bands(h, w, r, hi)
    band_vals = [mean_block(x, k, mode, *b) for b in bands]
    if rows is None and k <= FUSED_MAX:
        inner = _box(x, k, hi, wi, materialise=False)
        out = jax.lax.pad(inner, jnp.zeros((), x.dtype), [(r, r, 0), (r, r, 0)])
    else:
        out = _strip_interior(x, k, rows, hi, wi)
    for (r0, _, c0, _), vals in zip(bands, band_vals, strict=True):
        out = jax.lax.dynamic_update_slice(out, vals, (r0, c0))
    return out


def _strip_interior(x: Array, k: int, rows: int | None, hi: int, wi: int) -> Array:
    """(H, W) array holding the interior means (zeros in the edge bands), by row strips."""
    h, w = x.shape
    r = k // 2
    if rows is None:  # the mean streams: bigger strips, fewer loop iterations
        rows = max(8, MEAN_STRIP_BYTES // max(1, w * x.dtype.itemsize))
    R = strip_rows(hi, w, x.dtype.itemsize, even=False, rows=rows)
    n, tail = divmod(hi, R)

    def strip(first, count):  # mean of output rows first..first+count-1, interior columns
        block = jax.lax.dynamic_slice_in_dim(x, first - r, count + 2 * r, axis=0)
        return _box(block, k, count, wi)

    def body(i, out):
        first = r + i * R
        return jax.lax.dynamic_update_slice(out, strip(first, R), (first, r))

    out = jax.lax.fori_loop(0, n, body, jnp.zeros_like(x))
    if tail:
        out = jax.lax.dynamic_update_slice(out, strip(r + n * R, tail), (r + n * R, r))
    return out
