"""First pass: whole-image statistics merged from per-tile :class:`~hdrjax._stats.Statistics`.

Each tile gives the statistics an operator measures of an image
(:meth:`~hdrjax.operators.AbstractOperator.statistics`: RGB through
:func:`~hdrjax.operators._base.rgb_statistics`, a luminance plane through
:func:`~hdrjax._stats.summarise`), jit-compiled once per tile shape; they merge with
:meth:`Statistics.merge <hdrjax._stats.Statistics.merge>` into the statistics of the whole
image. Counts, extrema and the fixed-grid histogram merge exactly (every pixel falls in the
same bin as in the whole-image histogram); the log sum is a sum of per-tile sums, taken on
the host in float64, so it differs from the whole-image float32 reduction by float32
rounding only. Edge tiles are padded with NaN to one shape (one compilation): NaN pixels are
left out of every statistic, and the pixel count is the image's.
"""

import dataclasses
import functools
from collections.abc import Callable, Iterable, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .._colour import REC709_WEIGHTS
from .._scale import ln_max
from .._stats import LuminanceStats, Statistics, summarise
from ..operators._base import StatisticsSettings, rgb_statistics


def stats_dtype(dtype) -> np.dtype:
    """The float type statistics are computed in (float32, or float64 under x64)."""
    dt = np.dtype(dtype)
    if dt == np.float64 and jax.config.jax_enable_x64:
        return dt
    return np.dtype(np.float32)


@functools.partial(jax.jit, static_argnames=("weights", "settings", "dtype"))
def block_statistics(
    block: Array,
    *,
    weights: tuple[float, float, float],
    settings: StatisticsSettings,
    dtype,
) -> Statistics:
    """The statistics of one tile: ``op.statistics(tile)`` for ``(h, w, 3)`` RGB, those of
    the luminance for an ``(h, w)`` or ``(h, w, 1)`` plane (NaN pixels left out)."""
    x = block.astype(dtype)
    if x.ndim == 3 and x.shape[-1] == 3:
        return rgb_statistics(x, weights, settings)
    L = x[..., 0] if x.ndim == 3 else x
    method, bins, delta = settings.key
    return summarise(L, delta=delta, method=method, bins=bins, keep_source=False)[1]  # type: ignore[arg-type]


Runner = Callable[[Callable, tuple, dict], list]
"""``runner(fn, args, kwargs)`` → ``[fn(block, *args, **kwargs) for every block]`` (NumPy)."""


def _host(x):
    return jax.tree.map(np.asarray, x)


def settings_for(
    weights: Sequence[float] | None, settings: StatisticsSettings | tuple
) -> tuple[tuple[float, float, float], StatisticsSettings]:
    """Hashable ``(weights, settings)`` for :func:`block_statistics` (static arguments)."""
    w = REC709_WEIGHTS if weights is None else tuple(float(v) for v in weights)
    s = StatisticsSettings(*settings)
    s = StatisticsSettings(s.method, int(s.bins), float(s.delta), bool(s.channels))
    return w, s  # type: ignore[return-value]


def merge_blocks(
    run: Runner,
    n_pixels: int,
    dtype,
    *,
    weights: Sequence[float] | None,
    settings: StatisticsSettings | tuple,
) -> tuple[Statistics, float]:
    """The whole image's statistics, merged from every block's (``run`` visits each once),
    and their log sum in float64.

    The merge runs on the host: the log sums add in float64 (``Statistics.merge`` adds
    whatever it holds), the rest exactly; ``n_pixels`` is the image's (not the padding's).
    """
    w, s = settings_for(weights, settings)
    if s.method != "histogram":
        raise ValueError(
            "percentile_method: tiles merge histogram statistics; 'exact' sorts the whole"
            " image (use percentile_method='histogram', or run the whole image)"
        )
    parts = run(block_statistics, (), dict(weights=w, settings=s, dtype=stats_dtype(dtype)))
    return merge_parts(parts, n_pixels)


def merge_parts(parts: Iterable[Statistics], n_pixels: int) -> tuple[Statistics, float]:
    """Statistics of the parts of one image (NumPy leaves) merged on the host as
    :meth:`Statistics.merge <hdrjax._stats.Statistics.merge>` merges them (counts in 64
    bits, the log sums in float64; NumPy, not one small device call per leaf), with the
    image's pixel count ``n_pixels`` (padding left out), and their log sum in float64."""
    parts = list(parts)
    assert parts, "an image has at least one tile"
    first = parts[0]
    for p in parts[1:]:
        if (p.delta, p.m, p.channel_sum is None) != (
            first.delta,
            first.m,
            first.channel_sum is None,
        ):
            raise ValueError("parts: statistics measured with different settings")
        if p.exact is not None:
            raise ValueError("parts: percentile_method='exact' statistics do not merge")
    total = lambda name, dt: sum(np.asarray(getattr(p, name), dt) for p in parts)  # noqa: E731
    log_sum = float(total("log_sum", np.float64))
    dt = np.dtype(np.asarray(first.min).dtype)
    merged = dataclasses.replace(
        first,
        n_pixels=np.int32(n_pixels),
        n_finite=np.asarray(total("n_finite", np.int64), np.asarray(first.n_finite).dtype),
        n_positive=np.asarray(total("n_positive", np.int64), np.asarray(first.n_positive).dtype),
        min=np.min([np.asarray(p.min) for p in parts]).astype(dt),
        max=np.max([np.asarray(p.max) for p in parts]).astype(dt),
        min_positive=np.min([np.asarray(p.min_positive) for p in parts]).astype(dt),
        log_sum=np.asarray(log_sum, dt),
        counts=None
        if first.counts is None
        else total("counts", np.int64).astype(np.asarray(first.counts).dtype),
        channel_sum=None
        if first.channel_sum is None
        else total("channel_sum", np.float64).astype(np.asarray(first.channel_sum).dtype),
    )
    return jax.tree.map(jnp.asarray, merged), log_sum


@jax.jit
def _luminance_stats(stats: Statistics) -> LuminanceStats:
    return stats.luminance_stats()


def summary(merged: tuple[Statistics, float]) -> LuminanceStats:
    """:meth:`Statistics.luminance_stats` of :func:`merge_blocks`' result (compiled: one
    program), the log-average from the float64 log sum (a float32 mean of 599 equal terms
    ``ln 1e-6`` was 2e-6 off)."""
    stats, log_sum = merged
    out = _luminance_stats(stats)
    dt = np.dtype(stats.min.dtype)
    mean = log_sum / max(int(stats.n_finite), 1)
    log_average = np.asarray(np.exp(min(mean, ln_max(dt))), dt)
    return eqx.tree_at(lambda t: t.log_average, out, jnp.asarray(log_average))


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


__all__ = [
    "block_statistics",
    "call_host",
    "merge_blocks",
    "merge_parts",
    "numpy_runner",
    "settings_for",
    "summary",
    "stats_dtype",
]
