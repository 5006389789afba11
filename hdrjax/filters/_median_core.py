"""Exact rank selection over k×k windows with comparator networks (see :mod:`._median`).

Two entry points share one engine: :func:`median_plane` (the median of a float plane, bit
exact: the same values as ``scipy.ndimage.median_filter``) and :func:`argmedian_plane` (for
each pixel, the image position of the window's median under an int64 key — the luminance
criterion). Values become order-preserving integer keys (:mod:`._keys`) so that min/max are
single integer instructions.

Engine layout: pixels at least ``r = k // 2`` from every edge run through
:func:`pair_network` in row strips of ``R`` rows read in place from the input; the four edge
bands of width ``r`` (the bottom one also takes the rows below the last full strip) gather
a padded copy of their few rows or columns and go through :func:`pixel_network` together,
as one computation. Temporaries are a few strips; the output is the only image-sized
allocation.

Two XLA behaviours shape the strip loop. XLA:CPU computes each element of a fused
computation independently, so two outputs that share work must leave the fusion as one
element: a row pair's two medians travel as one complex number (real part: even row,
imaginary part: odd row). And XLA fuses producers into consumers even when that repeats
work (the network into the unpacking, which reads each complex value twice; the key
conversion into every network input), so the loop is software-pipelined: values that must
be computed once are carried to the next iteration, where they cannot be fused.
"""

import functools
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from ._keys import from_key, to_key
from ._network import Network
from ._radix import padded_strips, radix_select, window_views
from ._strips import map_index, padded_block, strip_rows

NETWORK_MAX = 7
"""Largest window done with comparator networks; larger ones use :mod:`._radix` (a 9×9
network takes ~10 s to compile, 15×15 minutes)."""

SMALL_PIXELS = 1 << 21
"""Largest plane (pixels) that an eager call filters in two compiled stages, without strips
(:func:`median_pairs`, then :func:`median_finish`): no strip loop and no zero-filled
output, ~45 kernel launches per call instead of ~280 at 1366×768 (XLA splits each across
its threads), for one plane-sized temporary. Larger planes, and calls being traced, use
the strip engine; the values are the same."""


@functools.cache
def pixel_network(k: int) -> tuple[Network, int]:
    """Median of a k×k window: sort the k columns, then merge them with forgetting.

    Leaves are ``(row offset, column offset)``; 206 min/max for 5×5.
    """
    net = Network()
    cols = [net.sort([net.leaf((i, c)) for i in range(k)]) for c in range(k)]
    return net, net.select(cols, (k * k - 1) // 2)


@functools.cache
def pair_network(k: int) -> tuple[Network, tuple[int, int]]:
    """Medians of two vertically adjacent k×k windows sharing k−1 rows.

    Leaves are ``(column offset, row offset)`` with row offsets ``0..k``; output 0 uses rows
    ``0..k-1``, output 1 rows ``1..k``. The k−1 shared rows are merged once, keeping only the
    ranks that can still become either median (``m−k .. m``), then each output merges its own
    row: 216 min/max for two 5×5 medians instead of 2 × 206.
    """
    net = Network()
    m = (k * k - 1) // 2
    rows = [net.sort([net.leaf((i, c)) for i in range(k)]) for c in range(k + 1)]
    lo = max(0, m - k)
    shared = net.select_range(rows[1:k], lo, m)
    return net, (net.select([shared, rows[0]], m - lo), net.select([shared, rows[k]], m - lo))


def _pixel_keys(keys: Array, k: int, h: int, w: int) -> Array:
    """Per-pixel network on keys padded by ``k // 2`` on each side → (h, w) keys."""
    net, out = pixel_network(k)

    def leaf(key):
        i, c = key
        return jax.lax.slice(keys, (i, c), (i + h, c + w))

    return net.emit([out], leaf, jnp.minimum, jnp.maximum)[0]


def _pair_keys(keys: Array, k: int, pairs: int, w: int) -> tuple[Array, Array]:
    """Median keys of ``2 * pairs`` rows (even rows, odd rows) from their key rows."""
    net, outs = pair_network(k)

    def leaf(key):
        ci, ri = key
        return jax.lax.slice(keys, (ri, ci), (ri + 2 * (pairs - 1) + 1, ci + w), (2, 1))

    a, b = net.emit(list(outs), leaf, jnp.minimum, jnp.maximum)
    return a, b


_FLOAT_OF = {4: jnp.float32, 8: jnp.float64}


def _as_float(v: Array) -> Array:
    return (
        v
        if jnp.issubdtype(v.dtype, jnp.floating)
        else (jax.lax.bitcast_convert_type(v, _FLOAT_OF[v.dtype.itemsize]))
    )


def _from_float(v: Array, dtype) -> Array:
    return v if v.dtype == dtype else jax.lax.bitcast_convert_type(v, dtype)


def _unpack(c: Array, dtype) -> Array:
    """(T, W) complex → (2T, W) ``dtype``: real parts on even rows, imaginary on odd rows."""
    t, w = c.shape
    # a concatenation along the middle axis: each output row takes one part, uniformly
    # along the row (vectorised), where selecting per element would compute both parts
    rows = jnp.concatenate([jnp.real(c)[:, None, :], jnp.imag(c)[:, None, :]], axis=1)
    return _from_float(rows.reshape(2 * t, w), dtype)


def _bands(
    block_keys: Callable[[int, int, int, int], Array],
    k: int,
    bands: list[tuple[int, int, int, int]],
    finish: Callable[[Array], Array],
) -> list[Array]:
    """Values of several output blocks with one per-pixel network: their padded key blocks
    (tall ones transposed — a square window's median does not change) are padded to one
    height and laid side by side; outputs whose window straddles two blocks are dropped."""
    r = k // 2
    blocks, flip = [], []
    for r0, r1, c0, c1 in bands:
        kb = block_keys(r0, r1, c0, c1)
        flip.append(r1 - r0 > c1 - c0)
        blocks.append(kb.T if flip[-1] else kb)
    height = max(b.shape[0] for b in blocks)
    blocks = [jnp.pad(b, ((0, height - b.shape[0]), (0, 0)), mode="edge") for b in blocks]
    joined = jnp.concatenate(blocks, axis=1)
    out = finish(_pixel_keys(joined, k, height - 2 * r, joined.shape[1] - 2 * r))
    vals, at = [], 0
    for (r0, r1, c0, c1), b, f in zip(bands, blocks, flip, strict=True):
        bh, bw = (c1 - c0, r1 - r0) if f else (r1 - r0, c1 - c0)
        v = out[:bh, at : at + bw]
        vals.append(v.T if f else v)
        at += b.shape[1]
    return vals


def _engine(
    shape: tuple[int, int],
    k: int,
    rows: int | None,
    strip_keys: Callable[[Array, int], Array],
    block_keys: Callable[[int, int, int, int], Array],
    finish: Callable[[Array], Array],
    out_dtype,
) -> Array:
    """Rank-``m`` selection for every pixel; see the module docstring.

    Args:
        shape: ``(H, W)`` of the output.
        k: odd window size ≥ 3.
        rows: strip height (``None``: about :data:`~._strips.STRIP_BYTES` of keys).
        strip_keys: ``(first, count)`` → keys of input rows ``first − r .. first + count + r``
            (all inside the image), all columns; ``first`` may be traced.
        block_keys: ``(r0, r1, c0, c1)`` → edge-mapped keys of the inputs of that output block.
        finish: selected keys → output values (32- or 64-bit, ``out_dtype``).
    """
    h, w = shape
    r = k // 2
    hi, wi = h - 2 * r, w - 2 * r  # interior output rows and columns
    if hi < 2 or wi < 1 or h * w <= 4096:
        return _bands(block_keys, k, [(0, h, 0, w)], finish)[0]
    cdt = jnp.complex64 if jnp.dtype(out_dtype).itemsize == 4 else jnp.complex128
    R = strip_rows(hi - hi % 2, w, jnp.dtype(out_dtype).itemsize, even=True, rows=rows)
    n = hi // R  # full strips; the rows below them join the bottom band
    b0 = r + n * R
    bands = [(0, r, 0, w), (b0, h, 0, w), (r, b0, 0, r), (r, b0, w - r, w)]
    band_vals = _bands(block_keys, k, bands, finish)

    def start(i):  # first output row of strip i (int32: vmap's scatter clamps in one dtype)
        return jnp.asarray(r + i * R, jnp.int32)

    def pairs(keys):  # packed medians of the R output rows whose key rows are `keys`
        a, b = _pair_keys(keys, k, R // 2, wi)
        return jax.lax.complex(_as_float(finish(a)), _as_float(finish(b)))

    # Two-stage pipeline: iteration i converts strip i+1's rows to keys, runs the network
    # on strip i (keys converted the iteration before) and stores strip i−1. Carrying the
    # keys and the packed medians across iterations keeps both materialised: XLA fuses
    # freely within an iteration, and would otherwise recompute the key conversion at every
    # network input (and lose vectorisation) or duplicate the network in the unpacking.
    def body(i, carry):
        out, prev, keys = carry
        nxt = strip_keys(start(jnp.minimum(i + 1, n - 1)), R)
        cur = pairs(keys)
        at = (start(jnp.maximum(i - 1, 0)), jnp.int32(r))
        out = jax.lax.dynamic_update_slice(out, _unpack(prev, out_dtype), at)
        return out, cur, nxt

    # iteration 0 stores the zero `prev` over strip 0; iteration 1 stores the real one
    init = (jnp.zeros((h, w), out_dtype), jnp.zeros((R // 2, wi), cdt), strip_keys(start(0), R))
    out, last, _ = jax.lax.fori_loop(0, n, body, init)
    out = jax.lax.dynamic_update_slice(out, _unpack(last, out_dtype), (start(n - 1), jnp.int32(r)))
    for (r0, _, c0, _), vals in zip(bands, band_vals, strict=True):
        out = jax.lax.dynamic_update_slice(out, vals, (jnp.int32(r0), jnp.int32(c0)))
    return out


def median_plane(x: Array, k: int, mode: str, rows: int | None = None) -> Array:
    """Exact k×k median of one (H, W) float32/float64 plane; NaN sorts above +Inf."""
    if k == 1:
        return x
    r = k // 2
    m = (k * k - 1) // 2
    if k > NETWORK_MAX:

        def strip(block, *_):
            views = functools.partial(window_views, k=k)
            return from_key(radix_select(views, (to_key(block),), m), x.dtype)

        return padded_strips(x, k, mode, rows, strip, x.dtype)

    def strip_keys(first, count):
        return to_key(jax.lax.dynamic_slice_in_dim(x, first - r, count + 2 * r, axis=0))

    def block_keys(r0, r1, c0, c1):
        return to_key(padded_block(x, r, mode, r0, r1, c0, c1))

    return _engine(
        x.shape, k, rows, strip_keys, block_keys, lambda kk: from_key(kk, x.dtype), x.dtype
    )


def median_pairs(x: Array, k: int) -> Array:
    """Stage 1 of the two-stage schedule for small planes (k ≤ :data:`NETWORK_MAX`,
    more than ``k`` rows and columns): :func:`pair_network` over the interior, all at once
    (no strips, no loop) → ``(P, W − 2r)`` complex, the medians of interior rows
    ``r, r + 2, ...`` in the real part and of the rows after them in the imaginary part,
    ``P = (H − 2r) // 2``.

    Compiled apart from :func:`median_finish` because XLA would fuse the network into the
    unpacking (which reads each pair twice) and run it twice. Each output is the exact
    median of its window, so the result is bit-identical to :func:`median_plane`.
    """
    h, w = x.shape
    r = k // 2
    a, b = _pair_keys(to_key(x), k, (h - 2 * r) // 2, w - 2 * r)
    return jax.lax.complex(_as_float(from_key(a, x.dtype)), _as_float(from_key(b, x.dtype)))


def median_finish(pairs: Array, x: Array, k: int, mode: str) -> Array:
    """Stage 2: the ``(H, W)`` median plane from :func:`median_pairs` and the edge bands
    (per-pixel network on edge-mapped copies of their inputs, as in the strip engine)."""
    h, w = x.shape
    r = k // 2
    b0 = r + 2 * pairs.shape[0]  # first row of the bottom band
    bands = [(0, r, 0, w), (b0, h, 0, w), (r, b0, 0, r), (r, b0, w - r, w)]

    def block_keys(r0, r1, c0, c1):
        return to_key(padded_block(x, r, mode, r0, r1, c0, c1))

    vals = _bands(block_keys, k, bands, lambda kk: from_key(kk, x.dtype))
    out = jax.lax.pad(_unpack(pairs, x.dtype), jnp.zeros((), x.dtype), [(r, h - b0, 0), (r, r, 0)])
    for (r0, _, c0, _), v in zip(bands, vals, strict=True):
        out = jax.lax.dynamic_update_slice(out, v, (r0, c0))
    return out


def argmedian_plane(lum: Array, k: int, mode: str, rows: int | None = None) -> Array:
    """For each pixel, the flat index ``y·W + x`` of its window's median by luminance.

    The key is ``(luminance, flat index)`` compared lexicographically (int64, so 64-bit
    types are enabled locally), which makes the choice unique: ties in luminance go to the
    earlier pixel in row-major order. NaN luminance sorts above +Inf.
    """
    h, w = lum.shape
    r = k // 2
    if h * w >= 2**31:
        raise ValueError(f"image of {h}×{w} pixels: the luminance median indexes < 2³¹ pixels")
    if k > NETWORK_MAX:
        strip = functools.partial(_argmedian_radix, k, w)
        return padded_strips(lum.astype(jnp.float32), k, mode, rows, strip, jnp.int32)
    with jax.enable_x64(True):
        lk = to_key(lum.astype(jnp.float32)).astype(jnp.int64) << 32

        def strip_keys(first, count):
            rows_ = jax.lax.dynamic_slice_in_dim(lk, first - r, count + 2 * r, axis=0)
            y = first - r + jax.lax.broadcasted_iota(jnp.int64, rows_.shape, 0)
            xx = jax.lax.broadcasted_iota(jnp.int64, rows_.shape, 1)
            return rows_ | (y * w + xx)

        def block_keys(r0, r1, c0, c1):
            ys = map_index(np.arange(r0 - r, r1 + r), h, mode)
            xs = map_index(np.arange(c0 - r, c1 + r), w, mode)
            pos = jnp.asarray((ys[:, None] * w + xs[None, :]).astype(np.int64))
            return padded_block(lk, r, mode, r0, r1, c0, c1) | pos

        def finish(kk):
            return (kk & 0xFFFFFFFF).astype(jnp.int32)

        return _engine((h, w), k, rows, strip_keys, block_keys, finish, jnp.int32)


def _argmedian_radix(k: int, w: int, block: Array, src_rows: Array, src_cols: Array) -> Array:
    """Large windows: the median luminance key by radix select, then, among the window pixels
    with that luminance, the one of the right rank by flat position (positions are unique,
    so the two selections equal one selection on the pair (luminance, position))."""
    m = (k * k - 1) // 2
    keys = to_key(block)
    best = radix_select(functools.partial(window_views, k=k), (keys,), m)
    below = sum((v < best).astype(jnp.int32) for v in window_views(keys, k))
    pos = src_rows[:, None] * w + src_cols[None, :]
    big = jnp.iinfo(jnp.int32).max  # pixels with another luminance rank after every position

    def views(keys, pos, best):
        lum, p = window_views(keys, k), window_views(pos, k)
        return [jnp.where(v == best, q, big) for v, q in zip(lum, p, strict=True)]

    return radix_select(views, (keys, pos, best), m - below)
