"""First pass: whole-image luminance statistics from per-tile partial results.

Reproduces :func:`hdrjax._stats.measure` (histogram percentiles) on an image read tile by
tile, in three sub-passes over the tiles, because each needs the previous one's result:

1. counts of finite and positive pixels, extrema, ``Σ ln(δ + max(L, 0))``;
2. the histogram of ``ln L`` on the *global* grid ``[ln min_positive, ln max]`` with the
   same bins, so every pixel falls in the same bin as in the whole-image histogram;
3. the trimmed log-average's sum over the pixels ``≤ p99``.

Counts, extrema, the histogram and hence ``p01``, ``p99`` and ``rel_error_bound`` equal
``measure``'s bit for bit; the two log-averages are sums of per-tile float32 sums taken in
float64, so they differ from the whole-image float32 reduction by float32 rounding only
(below 1e-5 relative; ``measure`` itself carries an error of that size).
"""

import functools
from collections.abc import Callable, Iterable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._colour import REC709_WEIGHTS, luminance
from .._stats import DEFAULT_BINS, DEFAULT_DELTA, LuminanceStats, _hist_quantiles, accurate_sum


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


@functools.partial(jax.jit, static_argnames=("weights", "bins", "dtype"))
def _pass2(block, lo, width, *, weights, bins, dtype):
    Ls = _lum(block.astype(dtype), weights)
    Lz, _, posf = _masks(Ls)
    lnL = jnp.log(jnp.maximum(Lz, jnp.finfo(Lz.dtype).tiny))
    # the index formula of hdrjax._stats._histogram_percentiles, on the global grid
    idx = jnp.clip(((lnL - lo) / width).astype(jnp.int32), 0, bins - 1)
    idx = idx + (1 - posf.astype(jnp.int32)) * bins
    return jnp.zeros(bins, jnp.int32).at[idx.reshape(-1)].add(1, mode="drop")


@functools.partial(jax.jit, static_argnames=("weights", "dtype"))
def _pass3(block, p99, *, weights, dtype):
    Ls = _lum(block.astype(dtype), weights)
    Lz, _, posf = _masks(Ls)
    lnL = jnp.log(jnp.maximum(Lz, jnp.finfo(Lz.dtype).tiny))
    keptf = posf * (Lz <= p99).astype(Lz.dtype)
    return jnp.sum(keptf.astype(jnp.int32)), accurate_sum(lnL * keptf)


@functools.partial(jax.jit, static_argnames=("bins",))
def _grid(minpos, lmax, n_pos, *, bins):
    """``lo``, ``hi`` and the bin width exactly as ``measure`` derives them."""
    any_pos = n_pos > 0
    lo = jnp.log(minpos)
    hi = jnp.log(jnp.where(any_pos, jnp.maximum(lmax, minpos), 1.0))
    lo = jnp.where(any_pos, lo, 0.0)
    hi = jnp.where(any_pos, hi, 0.0)
    return lo, hi, jnp.maximum(hi - lo, 1e-20) / bins


@jax.jit
def _percentiles(counts, lo, hi, width, n_pos):
    qs = jnp.array([0.01, 0.99], lo.dtype)
    vals = jnp.clip(_hist_quantiles(counts, lo, width, qs), jnp.exp(lo), jnp.exp(hi))
    any_pos = n_pos > 0
    vals = jnp.where(any_pos, vals, jnp.nan)
    err = jnp.where(any_pos, jnp.expm1(width), 0.0)
    return jnp.where(any_pos, vals, 1.0), err


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
    """Merge per-block partial results (``run`` visits every block once per sub-pass)."""
    if isinstance(bins, bool) or int(bins) != bins or bins < 2:
        raise ValueError(f"bins: expected an integer >= 2, got {bins!r}")
    bins = int(bins)
    w = REC709_WEIGHTS if weights is None else tuple(float(v) for v in weights)
    dt = stats_dtype(dtype)
    big = float(np.finfo(dt).max)
    p1 = run(_pass1, (), dict(weights=w, delta=float(delta), dtype=dt))
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
    lo, hi, width = _grid(jnp.asarray(minpos, dt), jnp.asarray(lmax, dt), n_pos, bins=bins)
    counts = np.zeros(bins, np.int64)
    for c in run(_pass2, (lo, width), dict(weights=w, bins=bins, dtype=dt)):
        counts += np.asarray(c, np.int64)
    (p01, p99), err = _percentiles(jnp.asarray(counts, jnp.int32), lo, hi, width, n_pos)
    p3 = run(_pass3, (p99,), dict(weights=w, dtype=dt))
    n_kept = sum(int(p[0]) for p in p3)
    kept_sum = float(np.sum([np.float64(p[1]) for p in p3]))
    trimmed = np.exp(kept_sum / max(n_kept, 1)) if n_kept > 0 else 1.0
    i32 = jnp.int32
    return LuminanceStats(
        n_pixels=jnp.asarray(n_pixels, i32),
        n_nonfinite=jnp.asarray(n_pixels - n_fin, i32),
        n_positive=jnp.asarray(n_pos, i32),
        min=jnp.asarray(lmin, dt),
        min_positive=jnp.asarray(minpos, dt),
        max=jnp.asarray(lmax, dt),
        log_average=jnp.asarray(np.exp(log_sum / max(n_fin, 1)), dt),
        p01=p01,
        p99=p99,
        log_average_trimmed=jnp.asarray(trimmed, dt),
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
