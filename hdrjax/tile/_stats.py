"""First pass: whole-image luminance statistics from per-tile partial results.

Reproduces :func:`hdrjax._stats.measure` (histogram percentiles) on an image read tile by
tile, in one sweep over the tiles: each tile gives its counts of finite and positive
pixels, its extrema, ``Σ ln(δ + max(L, 0))`` and its histogram on the fixed float-bit-
pattern grid of :func:`hdrjax._stats._histogram` (range independent, so tile histograms
merge by plain addition and every pixel falls in the same bin as in the whole-image
histogram). The percentiles and the trimmed log-average then come from the merged
histogram through the same function as ``measure``'s.

Counts, extrema, the histogram and ``rel_error_bound`` equal ``measure``'s bit for bit;
``p01``, ``p99`` and the trimmed log-average are the same function of the same counts,
compiled apart (a few ulp); the log-average is a sum of per-tile float32 sums taken in
float64, so it differs from the whole-image float32 reduction by float32 rounding only
(below 1e-5 relative; ``measure`` itself carries an error of that size).
"""

import functools
from collections.abc import Callable, Iterable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._colour import REC709_WEIGHTS, luminance
from .._scale import ln_max
from .._stats import (
    DEFAULT_BINS,
    DEFAULT_DELTA,
    LuminanceStats,
    _from_counts,
    _histogram,
    accurate_sum,
    grid_size,
    mantissa_bits,
    rel_error_bound,
)


def stats_dtype(dtype) -> np.dtype:
    """The float type statistics are computed in (float32, or float64 under x64)."""
    dt = np.dtype(dtype)
    if dt == np.float64 and jax.config.jax_enable_x64:
        return dt
    return np.dtype(np.float32)


def _lum(block: Array, weights: tuple[float, float, float]) -> Array:
    """Luminance with NaN at non-finite pixels, as the operators' statistics see it."""
    if block.ndim == 2:
        return block
    if block.shape[-1] == 1:
        return block[..., 0]
    finite = jnp.all(jnp.isfinite(block), axis=-1)
    L = luminance(jnp.where(finite[..., None], block, 0.0), weights)
    return jnp.where(finite, L, jnp.nan)


def _masks(Ls: Array):
    dt = Ls.dtype
    finite = jnp.isfinite(Ls)
    Lz = jnp.where(finite, Ls, 0.0)
    posf = (Lz >= jnp.finfo(dt).tiny).astype(dt)  # as measure: subnormals count as 0
    return Lz, finite.astype(dt), posf


@functools.partial(jax.jit, static_argnames=("weights", "delta", "dtype"))
def _pass1(block, *, weights, delta, dtype):
    Ls = _lum(block.astype(dtype), weights)
    Lz, finf, posf = _masks(Ls)
    big = float(jnp.finfo(Ls.dtype).max)
    log_terms = jnp.log(delta + jnp.maximum(Lz, 0.0)) * finf
    return (
        jnp.sum(finf.astype(jnp.int32)),
        jnp.sum(posf.astype(jnp.int32)),
        jnp.min(Lz + (1 - finf) * big),
        jnp.max(Lz - (1 - finf) * big),
        jnp.min(Lz + (1 - posf) * big),
        accurate_sum(log_terms),
    )


@functools.partial(jax.jit, static_argnames=("weights", "m", "dtype"))
def _pass_hist(block, *, weights, m, dtype):
    Ls = _lum(block.astype(dtype), weights)  # NaN at non-finite pixels: outside the grid
    return _histogram(Ls, None, m)


@functools.partial(jax.jit, static_argnames=("m",))
def _percentiles(counts, minpos, lmax, n_pos, *, m):
    """``p01``, ``p99``, the bound and the trimmed log-average exactly as ``measure``."""
    dt = minpos.dtype
    any_pos = n_pos > 0
    mx = jnp.where(any_pos, jnp.maximum(lmax, minpos), 1.0)
    qs = jnp.array([0.01, 0.99], dt)
    vals, n_kept, kept_sum = _from_counts(counts, qs, minpos, mx, m)
    vals = jnp.where(any_pos, vals, 1.0)
    err = jnp.where(any_pos, jnp.asarray(rel_error_bound(m, dt), dt), 0.0)
    # clamped as measure clamps: exp of a rounded mean of logarithms may pass the largest float
    trimmed = jnp.exp(jnp.minimum(kept_sum / jnp.maximum(n_kept, 1e-30), ln_max(dt)))
    return vals, err, jnp.where(any_pos & (n_kept > 0), trimmed, 1.0)


def _sweep(block, *, weights, delta, m, dtype):
    """Every per-tile result, from one visit of the tile: ``(_pass1, histogram)``."""
    return (
        _pass1(block, weights=weights, delta=delta, dtype=dtype),
        _pass_hist(block, weights=weights, m=m, dtype=dtype),
    )


Runner = Callable[[Callable, tuple, dict], list]
"""``runner(fn, args, kwargs)`` → ``[fn(block, *args, **kwargs) for every block]`` (NumPy)."""


def _host(x):
    return jax.tree.map(np.asarray, x)


def measure_blocks(
    run: Runner,
    n_pixels: int,
    dtype,
    *,
    weights: Sequence[float] | None = None,
    delta: float = DEFAULT_DELTA,
    bins: int = DEFAULT_BINS,
) -> LuminanceStats:
    """Merge per-block partial results (``run`` visits every block once)."""
    if isinstance(bins, bool) or int(bins) != bins or bins < 2:
        raise ValueError(f"bins: expected an integer >= 2, got {bins!r}")
    bins = int(bins)
    w = REC709_WEIGHTS if weights is None else tuple(float(v) for v in weights)
    dt = stats_dtype(dtype)
    big = float(np.finfo(dt).max)
    m = mantissa_bits(bins)
    parts = run(_sweep, (), dict(weights=w, delta=float(delta), m=m, dtype=dt))
    p1 = [p[0] for p in parts]
    n_fin = sum(int(p[0]) for p in p1)
    n_pos = sum(int(p[1]) for p in p1)
    lmin = min((dt.type(p[2]) for p in p1), default=dt.type(big))
    lmax = max((dt.type(p[3]) for p in p1), default=dt.type(-big))
    minpos = min((dt.type(p[4]) for p in p1), default=dt.type(big))
    log_sum = float(np.sum([np.float64(p[5]) for p in p1]))
    if n_fin == 0:
        lmin, lmax = dt.type(0), dt.type(0)
    if n_pos == 0:
        minpos = dt.type(1)
    counts = np.zeros(grid_size(m), np.int64)
    for p in parts:
        counts += np.asarray(p[1], np.int64)
    (p01, p99), err, trimmed = _percentiles(
        jnp.asarray(counts, jnp.int32), jnp.asarray(minpos, dt), jnp.asarray(lmax, dt), n_pos, m=m
    )
    i32 = jnp.int32
    return LuminanceStats(
        n_pixels=jnp.asarray(n_pixels, i32),
        n_nonfinite=jnp.asarray(n_pixels - n_fin, i32),
        n_positive=jnp.asarray(n_pos, i32),
        min=jnp.asarray(lmin, dt),
        min_positive=jnp.asarray(minpos, dt),
        max=jnp.asarray(lmax, dt),
        log_average=jnp.asarray(np.exp(min(log_sum / max(n_fin, 1), ln_max(dt))), dt),
        p01=p01,
        p99=p99,
        log_average_trimmed=trimmed,
        rel_error_bound=err,
    )


def numpy_runner(blocks: Callable[[], Iterable[np.ndarray]]) -> Runner:
    """A runner over blocks read one at a time (``blocks()`` starts a new sweep)."""

    def run(fn, args, kwargs):
        out, pending = [], None
        for b in blocks():
            b = np.asarray(b, dtype=kwargs["dtype"])
            nxt = fn(jnp.asarray(b), *args, **kwargs)  # dispatched asynchronously
            if pending is not None:
                out.append(_host(pending))
            pending = nxt
        if pending is not None:
            out.append(_host(pending))
        return out

    return run


def call_host(fn, block, *args, **kwargs):
    """``fn`` on one block, results as NumPy (for dask workers)."""
    return _host(fn(jnp.asarray(np.asarray(block, dtype=kwargs["dtype"])), *args, **kwargs))


__all__ = ["call_host", "measure_blocks", "numpy_runner", "stats_dtype"]
