"""Parameters of a frame sequence: shared over all frames, or smoothed over time.

Measuring pass (:func:`measure_batch`, compiled, ``vmap`` over frames): each frame gives
its mergeable :class:`~hdrjax._stats.Statistics` (those the operator's
:meth:`~hdrjax.operators.AbstractOperator.bind` reads, with its
:meth:`~hdrjax.operators.AbstractOperator.statistics_settings`) and the values ``bind``
gives its unset parameters. Nothing here knows an operator: every estimated parameter
comes from the operator's own ``bind``, and pools as its
:func:`~hdrjax.operators.parameter_info` declares.

Shared (``"same"``): ``op.bind`` of the statistics of all frames merged
(:meth:`Statistics.merge <hdrjax._stats.Statistics.merge>`), as if the frames were one
image: counts, extrema, the log-average and the fixed-grid histogram are exact, so
log-averages, minima and maxima are those of all pixels; percentiles come from the merged
histogram (relative error at most ``rel_error_bound``, 0.098 % with the default bins) and
band log-averages (the JGT trimmed log-average, Tumblin's trimmed adaptation) are
estimated from it (``hdrjax._stats`` module docstring). Counts and sums are merged on the
host in 64 bits, so long sequences of large frames do not overflow. Statistics measured
with ``percentile_method="exact"`` (a sort) do not merge: that mode needs the histogram.

Smoothed (``"smooth"``): per-frame parameters ``p_t`` (each frame's own ``bind``), then a
centred exponential moving average ``p̃_t = Σ_k w_k p_{t+k} / Σ_k w_k`` with
``w_k = exp(−|k| / τ)`` over ``|k| ≤ ⌈4τ⌉`` and over the frames that exist (the sum is
renormalised at the ends). A parameter declared with ``pooling="mean"`` (an average such
as the channel means) is averaged as it is; the others (``"log_mean"``, ``"max"``,
``"min"``: luminance levels and scales) are averaged in ``ln p`` when every ``p_t > 0``
(so a parameter twice as large counts as much as one half as large). A moving maximum or
minimum would jump where a bright or dark frame enters or leaves the window, which is the
flicker this mode removes, so over time these are averaged too. ``τ``
(``smooth_frames``) is the time constant in frames: a step in the scene is spread over
about ``2τ`` frames, and a flicker with a period of ``P`` frames keeps the fraction
``Σ_k w_k cos(2πk/P) / Σ_k w_k`` of its amplitude (without the truncation
``(1 − a)² / (1 − 2a cos(2π/P) + a²)``, ``a = e^{−1/τ}``): with the default ``τ = 5``, a
frame-to-frame alternation (``P = 2``) is divided by 85, a 10-frame cycle by 10 and a
20-frame cycle by 3.4.
"""

import math
from collections.abc import Sequence
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._colour import luminance
from .._stats import LuminanceStats, Statistics
from ..operators._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    parameter_info,
    prepare,
    statistics_of,
)
from ._pipeline import Pipeline, map_frames


def statistics_settings(op: AbstractOperator, pooled: bool) -> StatisticsSettings | None:
    """``op``'s statistics settings; with ``pooled``, a ``ValueError`` unless they merge."""
    settings = op.statistics_settings()
    if settings is None:
        return None
    settings = StatisticsSettings(*settings)
    if pooled and settings.method != "histogram":
        raise ValueError(
            f"parameters: 'same' merges the frames' histograms; {op.name} has"
            f" percentile_method={settings.method!r} (a sort per image): use 'histogram'"
        )
    return settings


def _frame_measure(op: AbstractOperator, x, pooled: bool, clean: bool):
    if clean:
        L = luminance(x, op.weights_)
        p = Prepared(x, L, L, clean=True)
    else:
        p = prepare(x, op.weights_)
    st = statistics_of(p, statistics_settings(op, pooled))
    bound = op.bind(st)
    values = {n: getattr(bound, n) for n in op.unset() if getattr(bound, n) is not None}
    out: dict[str, Any] = {"values": values}
    if pooled:
        out["stats"] = None if st is None else st.without_source()
    return out


@eqx.filter_jit
def _measure_batch(pipeline: Pipeline, frames, pooled: bool, clean: bool):
    x = pipeline.prepare_batch(frames)
    op = pipeline.operator
    return map_frames(pipeline, lambda f: _frame_measure(op, f, pooled, clean), x, clean)


def host_statistics(st: Statistics) -> Statistics:
    """Statistics as NumPy leaves: integers in int64, floats in float64 (exact sums over
    long sequences)."""

    def leaf(v):
        v = np.asarray(v)
        return v.astype(np.int64 if np.issubdtype(v.dtype, np.integer) else np.float64)

    return jax.tree.map(leaf, st)


def measure_batch(
    pipeline: Pipeline, frames: np.ndarray, pooled: bool, clean: bool = False
) -> list[dict]:
    """Per-frame measurements of a batch ``(B, H, W, 3)`` as NumPy records (``clean``: see
    :func:`~hdrjax.batch.render_batch`).

    Each record has ``values`` (estimated parameter → array, from the operator's
    ``bind`` of the frame's statistics) and, when ``pooled``, ``stats``: the frame's
    mergeable :class:`~hdrjax._stats.Statistics` (NumPy leaves; ``None`` for an operator
    that reads none).
    """
    statistics_settings(pipeline.operator, pooled)  # a one-line error before compiling
    res = jax.device_get(_measure_batch(pipeline, frames, pooled, clean))
    out = []
    for i in range(frames.shape[0]):
        rec: dict[str, Any] = {"values": {k: np.asarray(v)[i] for k, v in res["values"].items()}}
        if pooled:
            st = res["stats"]
            st = None if st is None else jax.tree.map(lambda v, i=i: v[i], st)
            rec["stats"] = None if st is None else host_statistics(st)
        out.append(rec)
    return out


def merge_statistics(records: Sequence[dict], into: Statistics | None = None) -> Statistics | None:
    """``into`` merged with the statistics of frame records (which are dropped from the
    records, so that memory stays bounded); ``None`` when there are none."""
    for r in records:
        st = r.pop("stats", None)
        if st is not None:
            into = st if into is None else host_statistics(into.merge(st))
    return into


def _on_device(st: Statistics) -> Statistics:
    # 64-bit host counts may exceed int32: the float dtype holds them (to 2^-24 relative)
    dt = jnp.result_type(float)
    return jax.tree.map(lambda v: jnp.asarray(v, dt), st)


@eqx.filter_jit
def _bind(op: AbstractOperator, st: Statistics | None) -> AbstractOperator:
    return op.bind(st)


def pooled_stats(stats: Statistics | Sequence[Statistics]) -> LuminanceStats:
    """:class:`LuminanceStats` of all pixels of all frames from their statistics (merged
    records of :func:`measure_batch`, or a sequence of them; see the module docstring)."""
    if isinstance(stats, Statistics):
        merged = stats
    else:
        merged = merge_statistics([{"stats": s} for s in stats])
        if merged is None:
            raise ValueError("stats: expected at least one Statistics, got none")
    return jax.jit(lambda s: s.luminance_stats())(_on_device(merged))


def estimated_values(op: AbstractOperator, bound: AbstractOperator) -> dict[str, np.ndarray]:
    out = {}
    for n in op.unset():
        v = getattr(bound, n)
        if v is not None:
            out[n] = np.asarray(v)
    return out


def shared_values(op: AbstractOperator, merged: Statistics | None) -> dict[str, np.ndarray]:
    """Parameters for every frame from the whole sequence (``"same"``): ``op.bind`` of the
    merged statistics of all frames (:func:`merge_statistics`)."""
    if not op.unset():
        return {}
    st = None if merged is None else _on_device(merged)
    return estimated_values(op, jax.device_get(_bind(op, st)))


def smooth_series(values: np.ndarray, tau: float, log: bool | None = None) -> np.ndarray:
    """Centred exponential moving average over axis 0 (see the module docstring); in
    ``ln`` when ``log`` (``None``: when every value is positive)."""
    v = np.asarray(values, np.float64)
    if tau <= 0 or v.shape[0] < 2:
        return v
    log = bool(np.all(v > 0)) if log is None else bool(log and np.all(v > 0))
    x = np.log(v) if log else v
    r = int(math.ceil(4 * tau))
    k = np.exp(-np.abs(np.arange(-r, r + 1)) / tau)
    flat = x.reshape(x.shape[0], -1)
    ones = np.ones(x.shape[0])
    norm = np.convolve(ones, k, mode="same") if x.shape[0] >= k.size else None
    cols = []
    for j in range(flat.shape[1]):
        if norm is not None:
            cols.append(np.convolve(flat[:, j], k, mode="same") / norm)
        else:  # fewer frames than the kernel: the direct sum
            n = x.shape[0]
            idx = np.arange(n)
            w = np.exp(-np.abs(idx[:, None] - idx[None, :]) / tau)
            w = np.where(np.abs(idx[:, None] - idx[None, :]) <= r, w, 0.0)
            cols.append(w @ flat[:, j] / w.sum(axis=1))
    y = np.stack(cols, axis=1).reshape(x.shape)
    return np.exp(y) if log else y


def smoothed_values(op: AbstractOperator, records: Sequence[dict], tau: float) -> list[dict]:
    """Per-frame parameters smoothed over time (``"smooth"``), in the records' order, each
    as its ``pooling`` declares (module docstring)."""
    per = [r["values"] for r in records]
    if not per:
        return []
    pooling = {p.name: p.pooling for p in parameter_info(op)}
    out: list[dict] = [{} for _ in per]
    for n in per[0]:
        series = np.stack([np.asarray(p[n], np.float64) for p in per])
        smoothed = smooth_series(series, tau, log=pooling.get(n) != "mean")
        for i, o in enumerate(out):
            o[n] = smoothed[i]
    return out


def with_values(op: AbstractOperator, values: dict[str, Any]) -> AbstractOperator:
    """``op`` with the given parameters set (in JAX's default float dtype)."""
    if not values:
        return op
    dt = jnp.result_type(float)
    names = tuple(values)
    return eqx.tree_at(
        lambda o: tuple(getattr(o, n) for n in names),
        op,
        tuple(np.asarray(values[n], dt) for n in names),
        is_leaf=lambda x: x is None,
    )


def stack_operators(op: AbstractOperator, values: Sequence[dict]) -> AbstractOperator:
    """One operator whose array leaves have a leading frame axis (one entry per frame)."""
    ops = [with_values(op, v) for v in values]
    return jax.tree.map(lambda *xs: np.stack([np.asarray(x) for x in xs]), *ops)


__all__ = [
    "estimated_values",
    "host_statistics",
    "measure_batch",
    "merge_statistics",
    "pooled_stats",
    "shared_values",
    "smooth_series",
    "smoothed_values",
    "stack_operators",
    "with_values",
]
