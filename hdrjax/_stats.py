"""Luminance statistics: log-averages, extrema and percentiles without a full sort.

Numeric contract: input is luminance (any units, relative or cd/m²), any float dtype.
Pixels whose value is NaN or ±Inf are *excluded* from every statistic (and counted in
``n_nonfinite``); statistics of logarithms use only the pixels with finite, strictly
positive luminance, except the paper's log-average, which clamps negatives to zero and adds
``delta`` (Reinhard et al. 2002, Eq. 1).

Percentiles default to a histogram instead of a sort (XLA's CPU sort runs on one core at
~0.7 Mpixel/s, so a 4096² sort costs ~20 s). The grid is fixed and needs no range: a
pixel's bin is its float32 bit pattern shifted right by ``23 − m`` (the exponent and the
top ``m`` mantissa bits; ``m = ceil(log2 bins) − 3``, 10 for the default 8192 bins, i.e.
1024 bins per octave). So the histogram needs no min/max pass first, comes from the same
pass as the other statistics, and histograms of tiles or frames merge by addition. A bin
spans ``[e, e (1 + 2^-m / (1 + f))]`` (``f`` the mantissa of its lower edge ``e``), at most
a factor ``1 + 2^-m``. Within the bin that holds the requested rank the value is
interpolated linearly in ``ln L``; the true percentile (the order statistic
``x_(floor(q (n-1)))``) lies in the same bin, so the relative error is at most ``2^-m``
(0.098 % by default, for any dynamic range) — returned as ``rel_error_bound``.
float64 luminance is binned after rounding to float32 (values beyond float32's range are
clamped to it; the bound becomes ``(1 + 2^-m)(1 + 2^-24) − 1`` inside that range).
(``numpy.percentile`` also interpolates towards the next order statistic; that step is not
reproduced, which matters only where two consecutive values are further apart than a bin,
i.e. for tiny pixel counts.) ``method="exact"`` sorts (the same linear interpolation as
``numpy.percentile``) and is differentiable; the histogram result is a constant for
``jax.grad``.

The JGT trimmed log-average (pixels ``≤ p99``) also comes from the histogram, with no
further pass: the pixels of each full bin below p99's bin count at the bin's geometric
centre (at most half a bin off in ``ln L``: ``ln(1 + 2^-m) / 2``, 0.049 %), and p99's own
bin contributes the interpolated fraction of its ``c_b`` pixels. Its error in ``ln`` is at
most ``ln(1 + 2^-m) / 2 + c_b (a + 2w − ln min_positive) / N_F`` (``a``, ``w``: the boundary
bin's lower edge and width in ``ln L``; ``N_F`` the pixels of the full bins), as each
boundary pixel counted in or out moves the mean by at most ``(a + 2w − ln min) / N_F``; for
a 16-Mpixel image the second term is ~1e-5. Its gradient is that of the exact formula.
``method="exact"`` keeps the exact definitions (sorted percentiles, a pass over the pixels
``≤ p99``).

Speed on XLA:CPU (what shapes the code): XLA:CPU runs the operations of a compiled
function one after another (two independent loops do not overlap), a loop runs on one
core, and only large element-wise fusions are split over the cores. Its reductions to a
scalar are slow (~6 ms per reduction over a 64 MB image), a reduction over a mask or a
select is not vectorised, and every intermediate that feeds a scatter or an unfusable
reduction becomes a fresh full-size buffer. So :func:`measure` reads ``L`` once, in a loop
over 16 K-element blocks (:func:`_one_pass`): each block goes into the histogram (a
scatter, the one serial part, ~13 ms per 16 Mpixel) and into running minima, maxima and
sums kept per lane (element-wise ``minimum``/``maximum``/``+`` on cache-resident
vectors, reduced once at the end), with no mask: NaN, ±Inf and negative values have bit
patterns past the grid's end, zero and subnormals fall in bins that are ignored, and a
running ``Σ L·0`` tells whether every pixel was finite. Only an image with NaN or ±Inf
pixels takes a second, masked pass for its extrema and sums. At 4096² this is ~35 ms of
CPU against ~50 for the former plain reductions plus a separate histogram loop. The
operators (``hdrjax.operators._base.dispatch``) decide their clean path on that same pass.
Luminance computed inside such a loop (slices or ``x @ w`` per block) costs more than the
separate 2-core element-wise luminance image. The masked extrema pass and the exact
trimmed sum are ``custom_jvp`` functions whose derivatives are those of the plain ``jnp``
formulas (extrema: shared by tied pixels; log-averages: the chain rule), so gradients are
unchanged.
"""

import functools
import math
from collections.abc import Callable
from typing import Any, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int

from . import _check
from ._scale import ln_max as ln_max_of

DEFAULT_BINS = 8192
DEFAULT_DELTA = 1e-6
"""Offset in the paper's log-average ``exp(mean(ln(delta + L)))`` (HDR Toolbox ``logMean``)."""


def _float(x: ArrayLike) -> Array:
    x = jnp.asarray(x)
    if not jnp.issubdtype(x.dtype, jnp.floating) or x.dtype in (jnp.float16, jnp.bfloat16):
        x = x.astype(jnp.result_type(float))
    return x


def accurate_sum(x: Array, where: Array | None = None) -> Array:
    """Sum of all elements in two stages (blocks, then block sums).

    A single float32 reduction over 16 M pixels can lose ~1e-4 relative; summing blocks of
    4096 first keeps the error near ``sqrt(n) * eps``.
    """
    x = x.reshape(-1)
    if where is not None:
        x = jnp.where(where.reshape(-1), x, 0)
    n = x.shape[0]
    block = 4096
    if n <= 2 * block or n % block:
        return jnp.sum(x)  # small, or ragged: one reduction (a pad would copy the image)
    return jnp.sum(jnp.sum(x.reshape(-1, block), axis=1))


class LuminanceStats(eqx.Module):
    """Statistics of one luminance image (a pytree; batched under ``jax.vmap``).

    Attributes:
        n_pixels: number of pixels.
        n_nonfinite: pixels that are NaN or ±Inf (excluded from everything below).
        n_positive: pixels with finite luminance > 0.
        min: smallest finite luminance (may be ≤ 0; 0 if no finite pixel).
        min_positive: smallest finite positive luminance (1 if none).
        max: largest finite luminance (0 if none).
        log_average: ``exp(mean(ln(delta + max(L, 0))))`` over finite pixels (Reinhard 2002).
        p01, p99: 1st and 99th percentiles of the finite positive luminance.
        log_average_trimmed: ``exp(mean(ln L))`` over finite positive pixels with
            ``L <= p99`` (JGT 2002 key estimation, "remove extreme values as in the paper").
        rel_error_bound: bound on the relative error of ``p01``/``p99`` (0 for exact;
            ``2^-m`` for the histogram, module docstring; the trimmed log-average's own
            bound is given there).
    """

    n_pixels: Int[Array, ""]
    n_nonfinite: Int[Array, ""]
    n_positive: Int[Array, ""]
    min: Float[Array, ""]
    min_positive: Float[Array, ""]
    max: Float[Array, ""]
    log_average: Float[Array, ""]
    p01: Float[Array, ""]
    p99: Float[Array, ""]
    log_average_trimmed: Float[Array, ""]
    rel_error_bound: Float[Array, ""]

    @property
    def dynamic_range_stops(self) -> Array:
        """``log2(max / min_positive)``: the full dynamic range in stops (0 if no light)."""
        mx = jnp.where(self.n_positive > 0, self.max, 1.0)
        return jnp.where(self.n_positive > 0, jnp.log2(mx) - jnp.log2(self.min_positive), 0.0)

    def _rows(self) -> list[tuple[str, Any]]:
        from . import _repr

        rows = _repr.fields(self)
        if _repr.concrete(self.max):
            rows.append(("dynamic_range", self.dynamic_range_stops))
        return rows

    def __repr__(self) -> str:
        """The statistics as numbers (luminance in the image's units), with the dynamic
        range in stops."""
        from . import _repr

        return _repr.call(self, self._rows(), units={"dynamic_range": "stops"})

    def _repr_html_(self) -> str:
        """A notebook's view: a table of the statistics."""
        from . import _repr

        unit = {"dynamic_range": "stops"}
        rows = [(k, _repr.value(v, unit.get(k, ""))) for k, v in self._rows()]
        return _repr.view("LuminanceStats (luminance in the image's units)", _repr.table(rows))


BLOCK = 1 << 18
"""Elements per block of the blocked passes (1 MiB of float32)."""


def _blockwise(fn: Callable, carry: Any, *arrays: Array, part: tuple[int, int] = (0, 1)):
    """``carry, out = fn(carry, *blocks)`` over consecutive :data:`BLOCK`-element blocks of
    the flattened ``arrays`` (then the ragged tail); the per-block outputs are stacked.
    ``part=(k, m)`` visits only the k-th of m equal runs of blocks (the tail goes with the
    last), so that m independent loops can run on m cores.

    Why blocks: XLA:CPU materialises every intermediate that feeds a scatter or a reduction
    it cannot fuse (a mask, ``ln L``, bin indices, the scatter's ones), each a fresh
    full-size buffer whose page faults and writes cost more than the arithmetic. Inside a
    loop over blocks these temporaries are 1 MiB, reused and cache-resident.
    """
    flat = [a.reshape(-1) for a in arrays]
    n = flat[0].shape[0]
    nb, rest = divmod(n, BLOCK)
    k, m = part
    first, last = nb * k // m, nb * (k + 1) // m
    outs = []
    if last > first:

        def body(c, i):
            return fn(c, *(jax.lax.dynamic_slice_in_dim(a, i * BLOCK, BLOCK) for a in flat))

        carry, ys = jax.lax.scan(body, carry, jnp.arange(first, last, dtype=jnp.int32))
        outs.append(ys)
    if k == m - 1 and (rest or not outs):
        carry, y = fn(carry, *(a[nb * BLOCK :] for a in flat))
        outs.append(jax.tree.map(lambda v: jnp.asarray(v)[None], y))
    if len(outs) < 2:
        return carry, (outs[0] if outs else None)
    return carry, jax.tree.map(lambda a, b: jnp.concatenate([a, b]), *outs)


MAX_MANTISSA_BITS = 13
"""Finest grid: 2¹³ bins per octave (``bins ≥ 65536``)."""


def mantissa_bits(bins: int) -> int:
    """Mantissa bits ``m`` the histogram keeps for ``bins``: ``ceil(log2 bins) − 3``, clipped
    to ``[0, 13]`` — 2^m bins per octave, as many as ``bins`` equal bins give over 8 octaves
    (10 bits, 1024 per octave, for the default 8192)."""
    return int(np.clip(math.ceil(math.log2(max(int(bins), 1))) - 3, 0, MAX_MANTISSA_BITS))


def grid_size(m: int) -> int:
    """Bins of the fixed grid with ``m`` mantissa bits: every float32 bit pattern below +Inf
    (exponent field 0…254); bins ``0 … 2^m − 1`` hold zero and subnormals and are ignored."""
    return 255 << m


def rel_error_bound(m: int, dtype) -> float:
    """Relative error bound of a histogram percentile with ``m`` mantissa bits: a bin spans
    ``[e, e (1 + 2^-m (1 + f)^-1)]`` for mantissa ``f ∈ [0, 1)``, at most a factor
    ``1 + 2^-m``. float64 values are binned after rounding to float32 (relative error
    ``2^-24``), hence ``(1 + 2^-m)(1 + 2^-24) − 1`` for them."""
    b = 2.0**-m
    return b if np.dtype(dtype).itemsize <= 4 else (1 + b) * (1 + 2.0**-24) - 1


def _as_f32_for_bins(L: Array) -> Array:
    """float32 luminance for the bit-pattern bins: float64 finite values ``≥ tiny`` are
    clamped to float32's positive normal range; NaN, ±Inf, zero, negatives stay outside it."""
    if L.dtype == jnp.float32:
        return L
    t64, b64 = float(jnp.finfo(L.dtype).tiny), float(jnp.finfo(L.dtype).max)
    f32 = np.finfo(np.float32)
    ok = (L >= t64) & (L <= b64)
    return jnp.where(ok, jnp.clip(L, float(f32.tiny), float(f32.max)), L).astype(jnp.float32)


def _bin_index(L32: Array, m: int) -> Array:
    """Bin of each float32 value on the fixed grid: its bit pattern shifted right by
    ``23 − m`` (exponent and the top ``m`` mantissa bits), so bins are ``2^-m`` octave-
    relative wide and need no range. NaN, +Inf and negative values (sign bit set: large as
    unsigned) map to ``grid_size(m)``, one past the end (hdrjax.tile reproduces this)."""
    bits = jax.lax.bitcast_convert_type(L32, jnp.uint32) >> (23 - m)
    return jnp.minimum(bits, grid_size(m)).astype(jnp.int32)


def _histogram(L: Array, valid: Array | None, m: int) -> Array:
    """Counts on the fixed bit-pattern grid (``grid_size(m)`` bins) of the pixels of ``L``
    (and ``valid``); only bins ``≥ 2^m`` (finite, ``≥ tiny``) are used by the callers."""
    L = _as_f32_for_bins(jax.lax.stop_gradient(L))
    nb = grid_size(m)

    def block(counts, Lb, *vb):
        idx = _bin_index(Lb, m)
        if vb:
            idx = jnp.where(vb[0], idx, nb)
        return counts.at[idx].add(1, mode="drop"), None

    args = (L,) if valid is None else (L, valid)
    return _blockwise(block, jnp.zeros(nb + 1, jnp.int32), *args)[0][:nb]


def bin_edges(m: int, dtype) -> tuple[Array, Array]:
    """``ln`` of the lower edge of every bin of the grid and of the next bin's (float32
    patterns ``b << (23 − m)``; the last upper edge is float32's max)."""
    nb = grid_size(m)
    b = np.arange(nb + 1, dtype=np.uint64) << np.uint64(23 - m)
    e = b.astype(np.uint32).view(np.float32).astype(np.float64)
    e[-1] = np.finfo(np.float32).max
    with np.errstate(divide="ignore"):
        ln = np.log(np.maximum(e, np.finfo(np.float32).tiny))
    return jnp.asarray(ln[:-1], dtype), jnp.asarray(ln[1:], dtype)


def coarse_counts(counts: Array, m: int, ln_lo: ArrayLike, span: ArrayLike, n: int) -> Array:
    """The positive pixels' counts in ``n`` equal bins of ``ln L`` from ``ln_lo`` to
    ``ln_lo + span``, from the counts on the fixed grid (operators whose curve is made from
    a coarser histogram: ``mai2011``, ``ward1997``).

    Each grid bin goes whole to the coarse bin that holds its centre in ``ln L`` (its
    geometric centre), so at each coarse edge at most one grid bin (a factor ``1 + 2^-m``)
    lands in the neighbouring bin; grid bins below ``ln_lo`` count in the first bin, those
    above in the last. Zero, negative and subnormal pixels are not counted. ``ln_lo`` and
    ``span`` may be traced (bins from the image's own range); the counts are constants for
    ``jax.grad``.
    """
    ln_lo, span = jnp.asarray(ln_lo), jnp.asarray(span)
    dt = jnp.result_type(ln_lo, span, float)
    lo, hi = bin_edges(m, dt)
    centre = 0.5 * (lo + hi)
    idx = jnp.clip(jnp.floor((centre - ln_lo) / span * n), 0, n - 1).astype(jnp.int32)
    fine = jax.lax.stop_gradient(counts).at[: 1 << m].set(0).astype(dt)  # zero, subnormals
    return jax.ops.segment_sum(fine, idx, num_segments=n)


def _from_counts(counts: Array, qs: Array, lmin: Array, lmax: Array, m: int):
    """Percentiles ``qs`` of the positive pixels, clipped to ``[lmin, lmax]`` (their
    extrema), and ``(n_kept, Σ ln L)`` estimated for the pixels ``≤`` the last percentile
    (the JGT trimmed log-average), from counts on the fixed grid.

    Rank ``q (n − 1)`` as :func:`numpy.percentile`; inside the bin that holds it the value
    is interpolated linearly in ``ln L`` (fraction ``(rank − before + ½) / count``). For the
    trimmed sum every pixel of a full bin below counts at its bin's geometric centre (error
    at most half a bin in ``ln L``), and the boundary bin contributes that same fraction of
    its pixels at the centre of the part below the percentile.
    """
    dt = lmin.dtype
    c = counts.at[: 1 << m].set(0)  # zero and subnormals
    lo, hi = bin_edges(m, dt)
    n = jnp.sum(c)
    cum = jnp.cumsum(c)
    rank = qs * jnp.maximum(n - 1, 0).astype(dt)
    # a rank within rounding of an integer is that integer: q = 99 % of 10001 pixels is
    # rank 9900, which float32 may give as 9899.9995 (``q / 100`` rounded either way, jit or
    # not); its floor would pick the previous order statistic and its bin
    near = jnp.round(rank)
    rank = jnp.where(jnp.abs(rank - near) <= 8 * jnp.finfo(dt).eps * near, near, rank)
    b = jnp.searchsorted(cum, jnp.floor(rank).astype(cum.dtype), side="right")
    b = jnp.clip(b, 0, c.shape[0] - 1)
    before = jnp.where(b > 0, cum[jnp.maximum(b - 1, 0)], 0).astype(dt)
    inside = jnp.maximum(c[b], 1).astype(dt)
    frac = jnp.clip((rank - before + 0.5) / inside, 0.0, 1.0)
    # every pixel lies in [lmin, lmax]: clip the bins' ln range to it (exact for a
    # constant image; the bounds still hold)
    lnmin, lnmax = jnp.log(lmin), jnp.log(lmax)
    lo, hi = jnp.clip(lo, lnmin, lnmax), jnp.clip(hi, lnmin, lnmax)
    lnv = lo[b] + frac * (hi[b] - lo[b])
    vals = jnp.clip(jnp.exp(lnv), lmin, lmax)
    # trimmed sum below the last percentile
    bt, ft = b[-1], frac[-1]
    cf = c.astype(dt)
    centre = 0.5 * (lo + hi)
    below = jnp.arange(c.shape[0]) < bt
    n_kept = jnp.sum(jnp.where(below, cf, 0.0)) + ft * cf[bt]
    s_kept = jnp.sum(jnp.where(below, cf * centre, 0.0))
    s_kept = s_kept + ft * cf[bt] * (lo[bt] + 0.5 * (lnv[-1] - lo[bt]))
    return vals, n_kept, s_kept


def _histogram_percentiles(
    L: Array,
    valid: Array | None,
    n: Array,
    lo: Array,
    hi: Array,
    qs: Array,
    bins: int,
) -> tuple[Array, Array]:
    """Percentiles from the fixed-grid histogram (``mantissa_bits(bins)``) of the pixels
    ``valid`` (default: all; only finite ones ``≥ tiny`` count); ``n`` is their number and
    ``lo``/``hi`` their extrema, which clip the result (module docstring). The extrema
    themselves, not their logarithms: ``exp(ln max)`` of the largest float rounds to +Inf."""
    m = mantissa_bits(bins)
    counts = _histogram(L, valid, m)
    mn = jnp.where(n > 0, lo, 1.0)
    mx = jnp.where(n > 0, hi, 1.0)
    vals = _from_counts(counts, qs, mn, mx, m)[0]
    err = jnp.asarray(rel_error_bound(m, L.dtype), L.dtype)
    return jnp.where(n > 0, vals, jnp.nan), jnp.where(n > 0, err, 0.0)


def _positive_range(
    L: Array, valid: Array | None, known_finite: bool = False
) -> tuple[Array, Array, Array, Array]:
    """``(n_valid, n_positive, min, max)``: the valid pixels (finite, and in ``valid`` when
    given) and, among them, those ``≥ tiny`` with their extrema (1 when there are none).
    Constants for ``jax.grad``. Without a mask an image whose pixels are all finite and
    ``≥ tiny`` takes plain reductions; otherwise one blocked pass. ``known_finite``: the
    caller has checked that every pixel is finite (skips the sum that tells)."""
    L = jax.lax.stop_gradient(L)
    dt = L.dtype
    big, tiny = float(jnp.finfo(dt).max), float(jnp.finfo(dt).tiny)
    i32 = jnp.int32

    def block(c, Lb, *vb):
        fin = (Lb >= -big) & (Lb <= big)
        if vb:
            fin = fin & vb[0]
        pos = fin & (Lb >= tiny)
        return c, (
            jnp.sum(fin, dtype=i32),
            jnp.sum(pos, dtype=i32),
            jnp.min(jnp.where(pos, Lb, big), initial=big),
            jnp.max(jnp.where(pos, Lb, 0.0), initial=0.0),
        )

    def masked(*args):
        _, (nv, n, mn, mx) = _blockwise(block, None, *args)
        nv, n = jnp.sum(nv, dtype=i32), jnp.sum(n, dtype=i32)
        return nv, n, jnp.where(n > 0, jnp.min(mn), 1.0), jnp.where(n > 0, jnp.max(mx), 1.0)

    if valid is not None:
        return masked(L, valid)
    # XLA:CPU's min/max skip NaN in large arrays: the sum tells NaN and ±Inf apart
    lmin, lmax = jnp.min(L, initial=big), jnp.max(L, initial=tiny)
    clean = lmin >= tiny if known_finite else (lmin >= tiny) & jnp.isfinite(jnp.sum(L))
    n_pix = jnp.asarray(L.size, i32)

    def fast(L, lmin, lmax):
        return n_pix, n_pix, lmin, lmax

    return jax.lax.cond(clean, fast, lambda L, *_: masked(L), L, lmin, lmax)


def percentile(
    L: Float[ArrayLike, "..."],
    q: Float[ArrayLike, "*Q"],
    *,
    method: Literal["histogram", "exact"] = "histogram",
    bins: int = DEFAULT_BINS,
    where: ArrayLike | None = None,
) -> tuple[Float[Array, "*Q"], Float[Array, ""]]:
    """Percentiles of the finite, strictly positive values of ``L``.

    Args:
        L: luminance (or any positive quantity), any shape; all elements are pooled.
        q: percentiles in [0, 100].
        method: ``"histogram"`` (default; fast, error bounded as in the module docstring) or
            ``"exact"`` (sorts; differentiable; slow on CPU for large images).
        bins: histogram resolution: ``2^(ceil(log2 bins) − 3)`` bins per octave (1024 for
            the default 8192, at most 8192 per octave); the bound is ``2^-m`` (module
            docstring).
        where: optional boolean mask of the pixels to use (e.g. a region).

    Returns:
        ``(values, rel_error_bound)``; values are NaN when no pixel qualifies.
    """
    _check.in_range(q, "q", 0, 100)
    _check.real(L, "L")
    if method not in ("histogram", "exact"):
        raise ValueError(f"method: expected 'histogram' or 'exact', got {method!r}")
    if int(bins) < 2:
        raise ValueError(f"bins: expected an integer >= 2, got {bins!r}")
    L = _float(L)
    qs = jnp.asarray(q, dtype=L.dtype) / 100.0
    if L.size == 0:  # an empty pool: no pixel qualifies (a sort or histogram of nothing fails)
        return jnp.full(qs.shape, jnp.nan, L.dtype), jnp.zeros((), L.dtype)
    mask = None if where is None else jnp.broadcast_to(jnp.asarray(where, bool), L.shape)
    if method == "exact":
        # "positive" means at least the smallest normal float: XLA:CPU flushes subnormals
        valid = jnp.isfinite(L) & (L >= jnp.finfo(L.dtype).tiny)
        if mask is not None:
            valid = valid & mask
        n = jnp.sum(valid)
        vals = jnp.nanquantile(jnp.where(valid, L, jnp.nan).reshape(-1), qs)
        return jnp.where(n > 0, vals, jnp.nan), jnp.zeros((), L.dtype)
    _, n, mn, mx = _positive_range(L, mask)
    return _histogram_percentiles(L, mask, n, mn, mx, qs, int(bins))


def _extrema_and_sums(L: Array, assume_finite: bool, delta: float):
    """One blocked pass: ``(n_finite, n_positive, min, max, min_positive, Σ log-terms)``
    over the finite pixels, the log-terms being ``ln(delta + max(L, 0))``."""
    dt = L.dtype
    big, tiny = float(jnp.finfo(dt).max), float(jnp.finfo(dt).tiny)

    def block(c, Lb):
        if assume_finite:
            n_fin = jnp.asarray(Lb.size, jnp.int32)
            Lz = Lb
            lmin, lmax = jnp.min(Lb, initial=big), jnp.max(Lb, initial=-big)
            terms = jnp.log(delta + jnp.maximum(Lb, 0.0))
        else:
            fin = jnp.isfinite(Lb)
            Lz = jnp.where(fin, Lb, 0.0)
            n_fin = jnp.sum(fin, dtype=jnp.int32)
            lmin = jnp.min(jnp.where(fin, Lb, big), initial=big)
            lmax = jnp.max(jnp.where(fin, Lb, -big), initial=-big)
            terms = jnp.where(fin, jnp.log(delta + jnp.maximum(Lz, 0.0)), 0.0)
        pos = Lz >= tiny  # subnormals are flushed to 0 on CPU
        return c, (
            n_fin,
            jnp.sum(pos, dtype=jnp.int32),
            lmin,
            lmax,
            jnp.min(jnp.where(pos, Lz, big), initial=big),
            _row_sum(terms),
        )

    _, (n_fin, n_pos, lmin, lmax, minpos, s) = _blockwise(block, None, L)
    i32 = jnp.int32
    n_fin, n_pos = jnp.sum(n_fin, dtype=i32), jnp.sum(n_pos, dtype=i32)
    return n_fin, n_pos, jnp.min(lmin), jnp.max(lmax), jnp.min(minpos), jnp.sum(s)


def _row_sum(v: Array) -> Array:
    """Sum of a vector as a tree of pairwise sums (halves added element-wise, zero-padded):
    XLA:CPU's plain 1-D float32 sum of a few hundred terms runs in sequence and can end
    several ulp per term off (the log sums of small images and tiles); the tree is within
    about one. Element-wise adds, not nested reductions, which XLA would merge back."""
    v = v.reshape(-1)
    while v.shape[0] > 1:
        if v.shape[0] % 2:
            v = jnp.concatenate([v, jnp.zeros(1, v.dtype)])
        half = v.shape[0] // 2
        v = v[:half] + v[half:]
    return v.reshape(()) if v.shape[0] == 1 else jnp.sum(v)


LANES = 1 << 14
"""Block of the single statistics pass (:func:`_one_pass`): 16 K elements, whose running
per-lane extrema and sums (64 KiB each) stay in the core's cache."""


def _one_pass(L: Array, m: int | None, delta: float | None):
    """``(counts, min, max, min_positive, Σ ln(δ + max(L, 0)), Σ L·0)`` in ONE blocked pass,
    with no mask: the fixed-grid histogram (``m`` mantissa bits; ``None``: none) and
    running extrema and sums kept per lane of a :data:`LANES`-element block (plain
    element-wise ``min``/``max``/``+``, which XLA:CPU vectorises; the lanes are reduced
    once at the end).

    Exact for an image whose pixels are all finite (zeros and negatives included:
    ``min_positive`` takes the pixels ``≥ tiny``); the last sum, ``Σ L·0``, is 0 then and
    NaN as soon as one pixel is NaN or ±Inf, which is how callers tell (the other values
    are then meaningless, except the histogram, which has no bin for NaN, ±Inf or
    negative values). ``delta=None``: no log sum (0). Constants for ``jax.grad``
    (:func:`_summary` gives the derivatives).
    """
    L = jax.lax.stop_gradient(L).reshape(-1)
    dt = L.dtype
    big, tiny = float(jnp.finfo(dt).max), float(jnp.finfo(dt).tiny)
    nb = grid_size(m) if m is not None else 0

    def reduce_lanes(cnt, mn, mx, mp, s, f):
        mn, mx, mp = jnp.min(mn, initial=big), jnp.max(mx, initial=-big), jnp.min(mp, initial=big)
        return cnt, mn, mx, mp, _row_sum(s), jnp.sum(f)

    def part(c, Lb, lanes: bool, log: bool = True):
        """Fold block ``Lb`` into ``c``: lane by lane, or (``lanes=False``) reduced;
        ``log=False``: without the log sum (the caller adds it)."""
        cnt = c[0]
        if m is not None:
            cnt = cnt.at[_bin_index(_as_f32_for_bins(Lb), m)].add(1, mode="drop")
        vals = (
            Lb,
            Lb,
            jnp.where(Lb >= tiny, Lb, big),  # subnormals are flushed to 0 on CPU
            jnp.log(delta + jnp.maximum(Lb, 0.0))
            if log and delta is not None
            else jnp.zeros((), dt),
            Lb * 0,
        )
        if not lanes:
            vals = reduce_lanes(None, *vals)[1:]
        _, mn, mx, mp, s, f = c
        return (
            cnt,
            jnp.minimum(mn, vals[0]),
            jnp.maximum(mx, vals[1]),
            jnp.minimum(mp, vals[2]),
            s + vals[3],
            f + vals[4],
        )

    n = L.shape[0]
    nblk = n // LANES

    def init(k):
        return tuple(jnp.full((k,), v, dt) for v in (big, -big, big, 0.0, 0.0))

    c = (jnp.zeros(nb + 1, jnp.int32), *init(1))
    if nblk:

        def body(c, i):
            block = jax.lax.dynamic_slice_in_dim(L, i * LANES, LANES)
            return part(c, block, True, log=False), None

        c = jax.lax.scan(body, (c[0], *init(LANES)), jnp.arange(nblk, dtype=jnp.int32))[0]
        # lane sums of ``n / LANES`` terms each, then a sum of the lanes
        c = (c[0], *(v[None] for v in reduce_lanes(*c)[1:]))
        if delta is not None:
            # the log sum outside the loop: a row reduction (rows of LANES terms, then the
            # sum of the rows) that XLA:CPU runs on both cores, while the loop runs on one;
            # the logarithm is the loop's most expensive element-wise step (~10 of 37 ms
            # CPU at 4096²; 31 against 37 ms wall for the pass)
            rows = L[: nblk * LANES].reshape(nblk, LANES)
            s = jnp.sum(jnp.sum(jnp.log(delta + jnp.maximum(rows, 0.0)), axis=1))
            c = (*c[:4], c[4] + s, c[5])
    if n > nblk * LANES:
        c = part(c, L[nblk * LANES :], False)
    cnt, mn, mx, mp, s, f = c
    return cnt[:nb], mn[0], mx[0], mp[0], s[0], f[0]


def _positive_count(counts: Array, m: int) -> Array:
    """Pixels in the grid's bins ``≥ 2^m``: the finite values ``≥ tiny`` (float64: of the
    clamp :func:`_as_f32_for_bins`, which keeps ``≥ tiny`` in that range)."""
    return jnp.sum(counts[1 << m :], dtype=jnp.int32)


def _tie_weights(L: Array, value: Array, mask: Array) -> Array:
    """JAX's derivative of a min/max reduction: shared equally by the tied elements."""
    hit = mask & (L == value)
    return hit / jnp.maximum(jnp.sum(hit), 1).astype(L.dtype)


@functools.partial(jax.custom_jvp, nondiff_argnums=(1, 2, 3))
def _summary(L: Array, assume_finite: bool, delta: float, m: int | None = None):
    """``(n_finite, n_positive, min, max, min_positive, Σ ln(delta + max(L, 0)), counts,
    finite)`` over the finite pixels, with the derivatives of the plain ``jnp`` formulas;
    ``counts`` is the fixed-grid histogram with ``m`` mantissa bits (``None``: an empty
    array) and ``finite`` whether every pixel is finite (measured even with
    ``assume_finite``).

    One pass over ``L`` (:func:`_one_pass`), exact when every pixel is finite; otherwise
    (``Σ L·0`` is NaN) the extrema and sums come from the masked blocked pass
    :func:`_extrema_and_sums` (the histogram needs no mask). ``assume_finite`` (the
    caller has checked) skips that test and the masked branch.
    """
    n_pix = jnp.asarray(L.size, jnp.int32)
    counts, lmin, lmax, minpos, log_sum, f = _one_pass(L, m, delta)
    if m is not None:
        n_pos = _positive_count(counts, m)
    else:  # no histogram to count them: the exact method's images take the masked pass
        n_pos = jnp.where(lmin >= float(jnp.finfo(L.dtype).tiny), n_pix, -1)
    fast = (n_pix, n_pos, lmin, lmax, minpos, log_sum)
    finite = jnp.isfinite(f)
    if assume_finite and m is not None:
        return (*fast, counts, finite)
    ok = (n_pos >= 0) if assume_finite else finite & (n_pos >= 0)

    def masked(L, *_):
        return _extrema_and_sums(L, assume_finite, delta)

    out = jax.lax.cond(ok, lambda L, *a: a, masked, L, *fast)
    return (*out, counts, finite)


@_summary.defjvp
def _summary_jvp(assume_finite, delta, m, primals, tangents):
    (L,), (t,) = primals, tangents
    out = _summary(L, assume_finite, delta, m)
    _, _, lmin, lmax, minpos, _, counts, finite = out
    dt = L.dtype
    fin = jnp.isfinite(L)
    Lz = jnp.where(fin, L, 0.0)
    t = jnp.where(fin, t, 0.0)
    # d/dx max(x, 0) is 1/2 at 0 in JAX; the tangent of ln(delta + max(L, 0))
    slope = jnp.where(Lz > 0, 1.0, jnp.where(Lz == 0, 0.5, 0.0)).astype(dt)
    pos = Lz >= jnp.finfo(dt).tiny
    zero_i = np.zeros((), jax.dtypes.float0)
    dots = (
        jnp.sum(t * _tie_weights(Lz, lmin, fin)),
        jnp.sum(t * _tie_weights(Lz, lmax, fin)),
        jnp.sum(t * _tie_weights(Lz, minpos, pos)),
        jnp.sum(t * slope / (delta + jnp.maximum(Lz, 0.0))),
    )
    zeros = (np.zeros(counts.shape, jax.dtypes.float0), np.zeros((), jax.dtypes.float0))
    return out, (zero_i, zero_i, *dots, *zeros)


@functools.partial(jax.custom_jvp, nondiff_argnums=(2,))
def _kept_sum(L: Array, p99: Array, assume_finite: bool) -> tuple[Array, Array]:
    """Count and ``Σ ln L`` of the finite pixels with ``tiny ≤ L ≤ p99``, in one blocked
    pass; the derivative is that of the plain formula (``p99`` enters only a comparison)."""
    tiny = float(jnp.finfo(L.dtype).tiny)

    def block(c, Lb):
        kept = (Lb >= tiny) & (Lb <= p99)  # NaN compares false, +Inf exceeds p99
        if assume_finite:  # ln of the clipped value: finite, and exact where kept
            lnL = jnp.log(jnp.clip(Lb, tiny, p99))
        else:  # a select keeps NaN out of the dot product
            lnL = jnp.where(kept, jnp.log(jnp.maximum(Lb, tiny)), 0.0)
        # a sum and a dot product of materialised (cache-resident) operands, not masked
        # sums: XLA:CPU does not vectorise a select inside a reduction
        keptf, lnL = jax.lax.optimization_barrier((kept.astype(Lb.dtype), lnL))
        return c, (jnp.sum(keptf).astype(jnp.int32), jnp.dot(keptf, lnL))

    _, (n, s) = _blockwise(block, None, L)
    return jnp.sum(n, dtype=jnp.int32), jnp.sum(s)


@_kept_sum.defjvp
def _kept_sum_jvp(assume_finite, primals, tangents):
    (L, p99), (t, _) = primals, tangents
    out = _kept_sum(L, p99, assume_finite)
    tiny = jnp.finfo(L.dtype).tiny
    kept = (L >= tiny) & (L <= p99)
    # d/dx ln(max(x, tiny)) is 1/x above tiny and 1/(2 tiny) at it (JAX's tie rule)
    slope = jnp.where(L > tiny, 1.0, 0.5) / jnp.where(kept, L, 1.0)
    return out, (np.zeros((), jax.dtypes.float0), jnp.sum(jnp.where(kept, t * slope, 0.0)))


@jax.custom_jvp
def _band_log_mean(L: Array, lo: Array, hi: Array, estimate: Array) -> Array:
    """``estimate`` (the histogram's mean ``ln L`` of the kept pixels) with the derivative of
    the plain formula ``mean(ln L | max(tiny, lo) ≤ L ≤ hi)`` in ``L``, as an exact pass
    gives."""
    return jax.lax.stop_gradient(estimate)


@_band_log_mean.defjvp
def _band_log_mean_jvp(primals, tangents):
    (L, lo, hi, est), (t, _, _, _) = primals, tangents
    tiny = jnp.finfo(L.dtype).tiny
    kept = (L >= tiny) & (L >= lo) & (L <= hi)
    slope = jnp.where(L > tiny, 1.0, 0.5) / jnp.where(kept, L, 1.0)
    n = jnp.maximum(jnp.sum(kept), 1).astype(L.dtype)
    return _band_log_mean(L, lo, hi, est), jnp.sum(jnp.where(kept, t * slope, 0.0)) / n


class Statistics(eqx.Module):
    """Mergeable statistics of an image's luminance: what every automatic parameter is
    computed from (:meth:`luminance_stats`), and what frames, tiles, chunks of pixels and
    sequences combine exactly with :meth:`merge`.

    Counts and sums add, extrema combine, and the histogram lies on the package's one
    fixed grid (module docstring), so ``a.merge(b)`` of two parts of an image holds the
    same counts, extrema and histogram as the statistics of the whole, and a log sum that
    differs by float rounding. ``merge`` is associative and commutative.

    Attributes:
        n_pixels: pixels seen.
        n_finite: pixels whose luminance is finite.
        n_positive: finite pixels with luminance ``≥`` the smallest normal float.
        min, max: extrema of the finite luminance (``±`` the largest float when none).
        min_positive: smallest finite luminance ``≥`` tiny (the largest float when none).
        log_sum: ``Σ ln(delta + max(L, 0))`` over the finite pixels.
        counts: histogram of the positive pixels on the fixed grid (``m`` mantissa bits);
            ``None`` for ``method="exact"``.
        channel_sum: ``Σ RGB`` over the finite pixels (when asked for), else ``None``.
        exact: ``(p01, p99, trimmed log-average)`` from a sort (``method="exact"``: these
            do not merge), else ``None``.
        source: the luminance image itself (statistics of one image, inside the operators)
            so that the trimmed log-average has the derivative of its exact formula; merged
            and public statistics drop it (that value is then a constant for ``jax.grad``,
            as the histogram percentiles always are).
        delta: the offset of the log sum (static).
        m: histogram mantissa bits, ``None`` for the exact method (static).
    """

    n_pixels: Int[Array, ""]
    n_finite: Int[Array, ""]
    n_positive: Int[Array, ""]
    min: Float[Array, ""]
    max: Float[Array, ""]
    min_positive: Float[Array, ""]
    log_sum: Float[Array, ""]
    counts: Int[Array, " G"] | None = None
    channel_sum: Float[Array, " C"] | None = None
    exact: Float[Array, " 3"] | None = None
    source: Array | None = None
    delta: float = eqx.field(static=True, default=DEFAULT_DELTA)
    m: int | None = eqx.field(static=True, default=None)

    def __repr__(self) -> str:
        """The counts, extrema and sums as numbers, the histogram and source summarised."""
        from . import _repr

        return _repr.call(self)

    def _repr_html_(self) -> str:
        """A notebook's view: a table of the fields."""
        from . import _repr

        rows = [(k, _repr.value(v)) for k, v in _repr.fields(self)]
        return _repr.view("Statistics (luminance in the image's units)", _repr.table(rows))

    def merge(self, other: "Statistics") -> "Statistics":
        """The statistics of both parts together (exact: counts, extrema and histogram;
        the log sum to float rounding)."""
        if not isinstance(other, Statistics):
            raise ValueError(f"other: expected Statistics, got {type(other).__name__}")
        if (self.delta, self.m) != (other.delta, other.m):
            raise ValueError(
                f"other: statistics measured with different settings (delta {self.delta} vs"
                f" {other.delta}, histogram bits {self.m} vs {other.m})"
            )
        if self.exact is not None or other.exact is not None:
            raise ValueError(
                "other: percentile_method='exact' statistics do not merge (a sort of each"
                " part); use percentile_method='histogram'"
            )
        if (self.channel_sum is None) != (other.channel_sum is None):
            raise ValueError("other: one of the statistics has channel sums, the other not")
        add = lambda a, b: None if a is None else a + b  # noqa: E731
        return Statistics(
            self.n_pixels + other.n_pixels,
            self.n_finite + other.n_finite,
            self.n_positive + other.n_positive,
            jnp.minimum(self.min, other.min),
            jnp.maximum(self.max, other.max),
            jnp.minimum(self.min_positive, other.min_positive),
            self.log_sum + other.log_sum,
            add(self.counts, other.counts),
            add(self.channel_sum, other.channel_sum),
            None,
            None,
            self.delta,
            self.m,
        )

    def without_source(self) -> "Statistics":
        """The same statistics without the luminance image (small, to keep or return)."""
        if self.source is None:
            return self
        return eqx.tree_at(lambda s: s.source, self, None)

    @property
    def channel_average(self) -> Array:
        """Mean RGB over the finite pixels (statistics measured with channels)."""
        if self.channel_sum is None:
            raise ValueError("statistics: measured without channel sums (channels=True)")
        return self.channel_sum / jnp.maximum(self.n_finite, 1).astype(self.channel_sum.dtype)

    def band_log_average(self, q_lo: float = 0.01, q_hi: float = 0.99):
        """``(exp(mean(ln L)), n_kept, p_lo, p_hi)`` over the positive pixels between the
        ``q_lo`` and ``q_hi`` quantiles (fractions; histogram percentiles), 1 when no pixel
        is kept. The statistics of one image (with ``source``) average its pixels in the
        band exactly; merged ones estimate the mean from the histogram: each full bin at
        its geometric centre, the boundary bins by the interpolated fraction of their
        pixels (error in ``ln`` within half a bin plus the boundary bins' share, as the
        trimmed log-average's, module docstring). Histogram statistics only."""
        if self.counts is None:
            raise ValueError("statistics: a band log-average needs histogram statistics")
        return _band_log_average(self, q_lo, q_hi)

    def range_log_average(self, lo: float, hi: float) -> tuple[Array, Array]:
        """``(exp(mean(ln L)), n)`` over the finite pixels with ``lo < L < hi`` (fixed
        luminances, ``0 < lo < hi``: a visible range such as pcond's 1e-7–1e5 cd/m²); 1 and
        0 when no pixel lies inside. From the histogram, so that the statistics of parts
        merge to the whole's: every bin whose
        geometric centre lies inside counts at that centre, so the mean ``ln L`` is within
        one bin (a factor ``1 + 2^-m``, :func:`rel_error_bound`) of the exact one. The
        statistics of one image (with ``source``) have the exact mean's derivative in the
        pixels; merged ones are constants for ``jax.grad``. Histogram statistics only."""
        if self.counts is None:
            raise ValueError("statistics: a range log-average needs histogram statistics")
        if not 0 < lo < hi:
            raise ValueError(f"lo, hi: expected 0 < lo < hi, got {lo!r}, {hi!r}")
        return _range_log_average(self, float(lo), float(hi))

    def luminance_stats(self) -> LuminanceStats:
        """Percentiles, log-averages and extrema (:class:`LuminanceStats`) from these
        statistics; histogram percentiles within ``rel_error_bound``."""
        dt = self.min.dtype
        any_finite = self.n_finite > 0
        any_pos = self.n_positive > 0
        lmin = jnp.where(any_finite, self.min, 0.0)
        lmax = jnp.where(any_finite, self.max, 0.0)
        minpos = jnp.where(any_pos, self.min_positive, 1.0)
        # a mean of logarithms is at most ln(max); exp of its rounding may exceed the largest
        # float (an image at float32's maximum): clamp, so the log-averages stay finite
        ln_max = ln_max_of(dt)
        n_fin = jnp.maximum(self.n_finite, 1).astype(dt)
        log_avg = jnp.exp(jnp.minimum(self.log_sum / n_fin, ln_max))
        if self.exact is not None:
            p01, p99, trimmed = self.exact[0], self.exact[1], self.exact[2]
            err = jnp.zeros((), dt)
        else:
            m = self.m
            qs = jnp.array([0.01, 0.99], dt)
            mx = jnp.where(any_pos, jnp.maximum(lmax, minpos), 1.0)
            (p01, p99), n_kept, kept_sum = _from_counts(
                self.counts, qs, jax.lax.stop_gradient(minpos), jax.lax.stop_gradient(mx), m
            )
            p01 = jnp.where(any_pos, p01, 1.0)
            p99 = jnp.where(any_pos, p99, 1.0)
            err = jnp.where(any_pos, jnp.asarray(rel_error_bound(m, dt), dt), 0.0)
            mean_ln = kept_sum / jnp.maximum(n_kept, 1e-30)
            if self.source is not None:
                zero = jnp.zeros((), dt)
                mean_ln = _band_log_mean(self.source, zero, jax.lax.stop_gradient(p99), mean_ln)
            else:
                mean_ln = jax.lax.stop_gradient(mean_ln)
            trimmed = jnp.exp(jnp.minimum(mean_ln, ln_max))
            trimmed = jnp.where(any_pos & (n_kept > 0), trimmed, 1.0)
        return LuminanceStats(
            n_pixels=self.n_pixels,
            n_nonfinite=self.n_pixels - self.n_finite,
            n_positive=self.n_positive,
            min=lmin,
            min_positive=minpos,
            max=lmax,
            log_average=log_avg,
            p01=p01,
            p99=p99,
            log_average_trimmed=trimmed,
            rel_error_bound=err,
        )

    def quantile(self, q: Float[ArrayLike, "*Q"]) -> tuple[Float[Array, "*Q"], Float[Array, ""]]:
        """Quantiles ``q`` (fractions in [0, 1]) of the positive pixels, from the histogram.

        The values :func:`percentile` gives for ``100 q`` from the same pixels (rank
        ``q (n_positive − 1)``, interpolated in ``ln L`` inside the bin that holds it,
        clipped to ``[min_positive, max]``), but from statistics that may be merged, with no
        further pass over the pixels. ``q`` may be traced (a rank computed from the counts).
        Constants for ``jax.grad``.

        Returns:
            ``(values, rel_error_bound)``; values are NaN when no pixel is positive.
        """
        if self.counts is None:
            raise ValueError("statistics: quantiles need histogram statistics")
        _check.in_range(q, "q", 0, 1)
        dt = self.min.dtype
        any_pos = self.n_positive > 0
        lmax = jnp.where(self.n_finite > 0, self.max, 0.0)
        minpos = jax.lax.stop_gradient(jnp.where(any_pos, self.min_positive, 1.0))
        mx = jax.lax.stop_gradient(jnp.where(any_pos, jnp.maximum(lmax, minpos), 1.0))
        qs = jnp.asarray(q, dt)
        vals = _from_counts(self.counts, qs.reshape(-1), minpos, mx, self.m)[0].reshape(qs.shape)
        err = jnp.asarray(rel_error_bound(self.m, dt), dt)
        return jnp.where(any_pos, vals, jnp.nan), jnp.where(any_pos, err, 0.0)


def _range_log_average(st: Statistics, lo: float, hi: float) -> tuple[Array, Array]:
    """:meth:`Statistics.range_log_average` (histogram statistics)."""
    dt = st.min.dtype
    e_lo, e_hi = bin_edges(st.m, dt)
    centre = 0.5 * (e_lo + e_hi)
    inside = (centre > math.log(lo)) & (centre < math.log(hi))
    inside = inside & (jnp.arange(centre.shape[0]) >= (1 << st.m))  # not zero/subnormal
    counts = jnp.where(inside, st.counts, 0)
    n = jnp.sum(counts)
    mean_ln = jnp.sum(counts.astype(dt) * centre) / jnp.maximum(n, 1).astype(dt)
    if st.source is not None:  # one image: the derivative of the exact mean
        mean_ln = _range_log_mean(st.source, lo, hi, mean_ln)
    else:
        mean_ln = jax.lax.stop_gradient(mean_ln)
    value = jnp.exp(jnp.minimum(mean_ln, ln_max_of(dt)))
    return jnp.where(n > 0, value, 1.0), n


@functools.partial(jax.custom_jvp, nondiff_argnums=(1, 2))
def _range_log_mean(L: Array, lo: float, hi: float, estimate: Array) -> Array:
    """``estimate`` (the histogram's mean ``ln L`` over ``lo < L < hi``) with the derivative
    of the plain formula in ``L``, as an exact pass gives."""
    return jax.lax.stop_gradient(estimate)


@_range_log_mean.defjvp
def _range_log_mean_jvp(lo, hi, primals, tangents):
    (L, est), (t, _) = primals, tangents
    kept = (L > lo) & (L < hi)
    n = jnp.maximum(jnp.sum(kept), 1).astype(L.dtype)
    slope = 1.0 / jnp.where(kept, L, 1.0)
    return _range_log_mean(L, lo, hi, est), jnp.sum(jnp.where(kept, t * slope, 0.0)) / n


def _band_log_average(st: Statistics, q_lo: float, q_hi: float):
    """:meth:`Statistics.band_log_average` (histogram statistics)."""
    dt = st.min.dtype
    any_pos = st.n_positive > 0
    lmax = jnp.where(st.n_finite > 0, st.max, 0.0)
    minpos = jax.lax.stop_gradient(jnp.where(any_pos, st.min_positive, 1.0))
    mx = jax.lax.stop_gradient(jnp.where(any_pos, jnp.maximum(lmax, minpos), 1.0))
    (p_lo, p_hi), n_hi, s_hi = _from_counts(
        st.counts, jnp.array([q_lo, q_hi], dt), minpos, mx, st.m
    )
    _, n_lo, s_lo = _from_counts(st.counts, jnp.array([q_lo], dt), minpos, mx, st.m)
    if st.source is not None:
        # one image: the exact mean over its pixels in the band (a second pass)
        L = st.source
        keep = (L >= p_lo) & (L <= p_hi) & (L >= float(jnp.finfo(dt).tiny))  # NaN: False
        n_kept = jnp.sum(keep)
        lnL = jnp.log(jnp.where(keep, L, 1.0))
        mean_ln = jnp.sum(jnp.where(keep, lnL, 0.0)) / jnp.maximum(n_kept, 1).astype(dt)
    else:
        n_kept = jnp.maximum(n_hi - n_lo, 0.0)
        mean_ln = jax.lax.stop_gradient((s_hi - s_lo) / jnp.maximum(n_kept, 1e-30))
    value = jnp.exp(jnp.minimum(mean_ln, ln_max_of(dt)))
    ok = any_pos & (n_kept > 0)
    p_lo, p_hi = jnp.where(any_pos, p_lo, 1.0), jnp.where(any_pos, p_hi, 1.0)
    return jnp.where(ok, value, 1.0), n_kept, p_lo, p_hi


def summarise(
    L: Float[ArrayLike, "H W"],
    *,
    delta: float = DEFAULT_DELTA,
    method: Literal["histogram", "exact"] = "histogram",
    bins: int = DEFAULT_BINS,
    assume_finite: bool = False,
    keep_source: bool = True,
) -> tuple[Array, Statistics]:
    """``(finite, statistics)`` of one luminance image in one pass (module docstring,
    "Speed"), ``finite`` telling whether every pixel is finite. With
    ``assume_finite=True`` the statistics are those of a finite image (exact only when
    ``finite`` is True) and ``finite`` is still measured. ``keep_source``: keep ``L`` in the
    statistics for the trimmed log-average's exact derivative (one image, not merged)."""
    _check.positive(delta, "delta", zero=True)
    _check.integer(bins, "bins", 2)
    _check.one_of(method, "method", ("histogram", "exact"))
    _check.real(L, "L")
    _check.nonempty(np.shape(L), "L", "(H, W)", (-2, -1))
    L = _float(L)
    m = mantissa_bits(bins) if method == "histogram" else None
    n_fin, n_pos, lmin, lmax, minpos, log_sum, counts, finite = _summary(
        L, bool(assume_finite), float(delta), m
    )
    if assume_finite:
        # an image that is not finite after all gives meaningless sums and extrema (NaN or
        # ±Inf), which its caller discards (``finite`` is False); they must still be finite
        # values, or the derivative of what is computed from them (``exp`` of a NaN sum) is
        # NaN, and a zero cotangent times NaN poisons every pixel's gradient in reverse mode
        lmin, lmax, minpos, log_sum = (
            jnp.where(finite, v, 1.0) for v in (lmin, lmax, minpos, log_sum)
        )
    exact = None
    if m is None:
        dt = L.dtype
        any_pos = n_pos > 0
        qs = jnp.array([0.01, 0.99], dt)
        (p01, p99), _ = percentile(L, 100 * qs, method="exact")
        p01 = jnp.where(any_pos, p01, 1.0)
        p99 = jnp.where(any_pos, p99, 1.0)
        n_kept, kept_sum = _kept_sum(L, jax.lax.stop_gradient(p99), bool(assume_finite))
        mean_ln = kept_sum / jnp.maximum(n_kept, 1).astype(dt)
        trimmed = jnp.exp(jnp.minimum(mean_ln, ln_max_of(dt)))
        trimmed = jnp.where(n_kept > 0, trimmed, 1.0)
        exact = jnp.stack([p01, p99, trimmed])
    st = Statistics(
        jnp.asarray(L.size, jnp.int32),
        n_fin,
        n_pos,
        lmin,
        lmax,
        minpos,
        log_sum,
        counts if m is not None else None,
        None,
        exact,
        L if keep_source and m is not None else None,
        float(delta),
        m,
    )
    return finite, st


def measure(
    L: Float[ArrayLike, "H W"],
    *,
    delta: float = DEFAULT_DELTA,
    method: Literal["histogram", "exact"] = "histogram",
    bins: int = DEFAULT_BINS,
    assume_finite: bool = False,
) -> LuminanceStats:
    """Measure the luminance statistics the automatic operators need.

    ``L`` is one image's luminance (``vmap`` for batches). Gradients flow through the
    extrema and log-averages; histogram percentiles are constants (see module docstring).
    ``assume_finite=True`` skips the NaN/Inf masking (the operators check this first).

    One pass over ``L`` (module docstring, "Speed"): the fixed-grid histogram, from which
    come ``p01``, ``p99`` and the trimmed log-average, and the extrema and the log-average
    (a second, masked pass only for an image with NaN or ±Inf pixels;
    ``method="exact"``: a sort and a pass over the pixels ``≤ p99``). The same as
    ``summarise(L)[1].luminance_stats()``.
    """
    return measure_checked(L, delta=delta, method=method, bins=bins, assume_finite=assume_finite)[1]


def measure_checked(
    L: Float[ArrayLike, "H W"],
    *,
    delta: float = DEFAULT_DELTA,
    method: Literal["histogram", "exact"] = "histogram",
    bins: int = DEFAULT_BINS,
    assume_finite: bool = False,
) -> tuple[Array, LuminanceStats]:
    """``(finite, measure(L, ...))`` with ``finite`` whether every pixel of ``L`` is finite,
    from the same pass (:func:`summarise`)."""
    finite, st = summarise(L, delta=delta, method=method, bins=bins, assume_finite=assume_finite)
    return finite, st.luminance_stats()


def summarise_histogram(
    L: Float[ArrayLike, "H W"], *, bins: int = DEFAULT_BINS
) -> tuple[Array, Statistics]:
    """``(finite, statistics)`` of one luminance image from :func:`summarise`'s single pass
    without its log sum, for callers that need only the histogram, the counts and the
    extrema (the logarithm of every pixel is the pass's most expensive step; module
    docstring, "Speed").

    The statistics are exact when ``finite`` is True (every pixel finite); otherwise only
    the histogram is (its grid has no bin for NaN or ±Inf) and the rest is meaningless, as
    with ``summarise(L, assume_finite=True)``. ``log_sum`` is NaN (so are log-averages
    computed from it); ``n_positive`` is counted on the histogram; no ``source`` is kept.
    Constants for ``jax.grad``.
    """
    _check.integer(bins, "bins", 2)
    _check.real(L, "L")
    _check.nonempty(np.shape(L), "L", "(H, W)", (-2, -1))
    L = _float(L)
    m = mantissa_bits(bins)
    counts, lmin, lmax, minpos, _, f = _one_pass(L, m, None)
    n = jnp.asarray(L.size, jnp.int32)
    return jnp.isfinite(f), Statistics(
        n_pixels=n,
        n_finite=n,
        n_positive=_positive_count(counts, m),
        min=lmin,
        max=lmax,
        min_positive=minpos,
        log_sum=jnp.full((), jnp.nan, L.dtype),
        counts=counts,
        delta=DEFAULT_DELTA,
        m=m,
    )


def selection_range(q: ArrayLike) -> tuple[float | None, float | None] | None:
    """``(max q < 50, min q ≥ 50)`` of concrete percentiles ``q``: the ``select`` hint of
    :func:`percentile_by_selection`, fixed where ``q`` is known (``None`` when it is
    traced)."""
    try:
        v = [float(x) for x in np.asarray(q).reshape(-1)]
    except (TypeError, jax.errors.ConcretizationTypeError, jax.errors.TracerArrayConversionError):
        return None
    lo = [x for x in v if x < 50.0]
    hi = [x for x in v if x >= 50.0]
    return (max(lo) if lo else None, min(hi) if hi else None)


def percentile_by_selection(
    L: Float[ArrayLike, "..."],
    q: Float[ArrayLike, " Q"],
    *,
    select: tuple[float | None, float | None] | None,
    where: ArrayLike | None = None,
) -> Float[Array, " Q"]:
    """``percentile(L, q, method="exact", where=where)[0]`` (the same values, up to the
    rounding of the final interpolation, and gradients) by partial selection where it is
    cheaper than the sort: ``P_q`` with ``q ≥ 50`` lies among the ``⌊(N − 1)(1 − q/100)⌋
    + 3`` largest of ``N`` values (one more per Mpixel, for rounding; ``jax.lax.top_k``,
    ~15× faster than XLA:CPU's sort for ``P99`` of 2048 values), ``q < 50`` among the
    smallest.

    ``select`` (:func:`selection_range` of the ``q`` the selection sizes are made for,
    static) fixes those sizes; a traced ``q`` outside them, ``select=None``, or a selection
    larger than a quarter of the values sorts instead. NaN with no finite positive value.
    """

    def by_sort():
        return percentile(L, q, method="exact", where=where)[0]

    L = _float(L)
    N = L.size
    if select is None or N < 16:
        return by_sort()
    lo_q, hi_q = select
    # the ranks needed for any count n ≤ N of valid pixels, with spare places for the
    # rounding of q·(n − 1) in the image's dtype
    spare = 3 + N // 1_000_000
    k_lo = 0 if lo_q is None else min(N, int((N - 1) * max(lo_q, 0.0) / 100.0) + spare)
    k_hi = 0 if hi_q is None else min(N, int((N - 1) * (1.0 - min(hi_q, 100.0) / 100.0)) + spare)
    if max(k_lo, k_hi) > N // 4:
        return by_sort()
    x = L.reshape(-1)
    valid = jnp.isfinite(x) & (x >= jnp.finfo(x.dtype).tiny)
    if where is not None:
        valid = valid & jnp.broadcast_to(jnp.asarray(where, bool), L.shape).reshape(-1)
    n = jnp.sum(valid)
    qs = jnp.asarray(q, x.dtype) / 100.0
    pos = qs * (n - 1).astype(x.dtype)
    j0 = jnp.floor(pos).astype(jnp.int32)
    frac = pos - j0.astype(x.dtype)
    j1 = jnp.minimum(j0 + 1, n - 1)
    lower = qs < 0.5
    v0 = v1 = jnp.zeros_like(qs)
    # the selections cover q ≤ lo_q and q ≥ hi_q for every n; the test depends on q only,
    # so under a vmap over frames (one shared target) the cond below stays a branch
    q_pct = jnp.asarray(q)
    ok = jnp.where(
        lower, q_pct <= (-1.0 if lo_q is None else lo_q), q_pct >= (101.0 if hi_q is None else hi_q)
    )
    if k_lo:  # the k_lo smallest, ascending: rank j is at j
        small = -jax.lax.top_k(jnp.where(valid, -x, -jnp.inf), k_lo)[0]
        v0 = jnp.where(lower, jnp.take(small, jnp.clip(j0, 0, k_lo - 1)), v0)
        v1 = jnp.where(lower, jnp.take(small, jnp.clip(j1, 0, k_lo - 1)), v1)
    if k_hi:  # the k_hi largest, descending: rank j is at n − 1 − j
        large = jax.lax.top_k(jnp.where(valid, x, -jnp.inf), k_hi)[0]
        v0 = jnp.where(lower, v0, jnp.take(large, jnp.clip(n - 1 - j0, 0, k_hi - 1)))
        v1 = jnp.where(lower, v1, jnp.take(large, jnp.clip(n - 1 - j1, 0, k_hi - 1)))
    vals = jnp.where(n > 0, v0 + frac * (v1 - v0), jnp.nan)
    # a q moved outside the selection after construction: sort (cond runs one branch)
    return jax.lax.cond(jnp.all(ok), lambda: vals, by_sort)


__all__ = [
    "DEFAULT_BINS",
    "DEFAULT_DELTA",
    "LuminanceStats",
    "Statistics",
    "measure",
    "percentile",
    "percentile_by_selection",
    "selection_range",
    "summarise",
    "summarise_histogram",
]
