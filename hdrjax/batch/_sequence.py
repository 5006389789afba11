"""Parameters of a frame sequence: shared over all frames, or smoothed over time.

Measuring pass (:func:`measure_batch`, compiled, ``vmap`` over frames): each frame gives its
measured operator (``op.measure``), its :class:`~hdrjax._stats.LuminanceStats` and, for
shared parameters, a histogram of ``ln L`` on a fixed grid with the sum of ``ln L`` in each
bin, which add up exactly over frames (histogram merging).

Shared (``"same"``): statistics of all pixels of all frames, as if the frames were one
image. The Reinhard 2002 family (``reinhard2002``, ``reinhard2002_local``,
``reinhard2002_auto``) gets its key, white and log-average from the pooled statistics:

- log-average ``exp(Σ_f n_f ln L̄_f / Σ_f n_f)`` with ``n_f`` the finite pixels of frame
  ``f`` (exact: it is the log-average over all pixels);
- min, max, smallest positive luminance: extrema over frames (exact);
- 1st/99th percentiles from the merged histogram (``HIST_BINS`` bins over ``ln L`` in
  ``[HIST_LO, HIST_HI]``, linear interpolation in the bin; relative error at most
  ``expm1(bin width)`` = 0.15 %), and the trimmed log-average (pixels ``≤ L_99``) from the
  per-bin sums, with the bin of ``L_99`` counted in proportion;
- key (JGT Eq. 4) and white (JGT Eq. 5) from these, as for one image.

Other operators pool their measured parameters with the rule that makes them exact:
``L_max`` → maximum over frames, ``L_min`` → minimum, ``log_average`` and ``L_wa``
(log-averages) → pixel-weighted geometric mean, ``channel_average`` → pixel-weighted mean.
Any other measured parameter (e.g. ``L_wa`` with ``adaptation="trimmed"``) is the
pixel-weighted geometric mean of the per-frame values (arithmetic if one is ≤ 0): an
approximation of the pooled estimate.

Smoothed (``"smooth"``): per-frame parameters ``p_t``, then a centred exponential moving
average ``p̃_t = Σ_k w_k p_{t+k} / Σ_k w_k`` with ``w_k = exp(−|k| / τ)`` over
``|k| ≤ ⌈4τ⌉`` and over the frames that exist (the sum is renormalised at the ends), in
``ln p`` when every ``p_t > 0`` (so a parameter twice as large counts as much as one half
as large). ``τ`` (``smooth_frames``) is the time constant in frames: a step in the scene
is spread over about ``2τ`` frames, and a flicker with a period of ``P`` frames keeps the
fraction ``Σ_k w_k cos(2πk/P) / Σ_k w_k`` of its amplitude (without the truncation
``(1 − a)² / (1 − 2a cos(2π/P) + a²)``, ``a = e^{−1/τ}``): with the default ``τ = 5``, a
frame-to-frame alternation (``P = 2``) is divided by 85, a 10-frame cycle by 10 and a
20-frame cycle by 3.4.
"""

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._colour import luminance
from .._stats import LuminanceStats, _hist_quantiles, measure
from ..operators._base import AbstractOperator, Prepared
from ..operators._reinhard2002 import jgt_key, jgt_white
from ._pipeline import Pipeline, map_frames

HIST_LO = -50.0
HIST_HI = 50.0
HIST_BINS = 1 << 16
"""Fixed ``ln L`` grid of the mergeable histogram (L from 2e-22 to 5e21)."""

_REINHARD = ("reinhard2002", "reinhard2002_local", "reinhard2002_auto")
_STAT_FIELDS = tuple(f.name for f in dataclasses.fields(LuminanceStats))


def _frame_measure(pipeline: Pipeline, x, pooled: bool, clean: bool):
    op = pipeline.operator
    L = luminance(x, op.weights_)
    kw: dict[str, Any] = {}
    if hasattr(op, "percentile_method"):
        kw = {"method": op.percentile_method, "bins": op.bins}  # type: ignore[attr-defined]
    if clean:
        finite = jnp.ones(L.shape, bool)
        st = measure(L, assume_finite=True, **kw)
    else:
        finite = jnp.all(jnp.isfinite(x), axis=-1) & jnp.isfinite(L)
        st = measure(jnp.where(finite, L, jnp.nan), **kw)
    measured = op
    if op.unset() and op.name not in _REINHARD:
        measured = op._measure(Prepared(x, L, L, clean=True)) if clean else op.measure(x)
    values = {n: getattr(measured, n) for n in op.unset() if getattr(measured, n) is not None}
    out: dict[str, Any] = {"stats": st, "values": values}
    if pooled:
        dt = L.dtype
        pos = finite & (L >= jnp.finfo(dt).tiny)
        lnL = jnp.log(jnp.where(pos, L, 1.0))
        width = (HIST_HI - HIST_LO) / HIST_BINS
        idx = jnp.clip(jnp.floor((lnL - HIST_LO) / width), 0, HIST_BINS - 1).astype(jnp.int32)
        idx = jnp.where(pos, idx, HIST_BINS).reshape(-1)  # out of range: dropped
        out["counts"] = jnp.zeros(HIST_BINS, jnp.int32).at[idx].add(1, mode="drop")
        out["lnsum"] = jnp.zeros(HIST_BINS, dt).at[idx].add(lnL.reshape(-1), mode="drop")
    return out


@eqx.filter_jit
def _measure_batch(pipeline: Pipeline, frames, pooled: bool, clean: bool):
    x = pipeline.prepare_batch(frames)
    return map_frames(pipeline, lambda f: _frame_measure(pipeline, f, pooled, clean), x, clean)


def measure_batch(
    pipeline: Pipeline, frames: np.ndarray, pooled: bool, clean: bool = False
) -> list[dict]:
    """Per-frame measurements of a batch ``(B, H, W, 3)`` as NumPy records (``clean``: see
    :func:`~hdrjax.batch.render_batch`).

    Each record has ``stats`` (field → float), ``values`` (measured parameter → array) and,
    when ``pooled``, the histogram ``counts`` (int64) and ``lnsum`` (float64) of the frame.
    """
    res = jax.device_get(_measure_batch(pipeline, frames, pooled, clean))
    out = []
    for i in range(frames.shape[0]):
        rec: dict[str, Any] = {
            "stats": {k: float(np.asarray(getattr(res["stats"], k))[i]) for k in _STAT_FIELDS},
            "values": {k: np.asarray(v)[i] for k, v in res["values"].items()},
        }
        if pooled:
            rec["counts"] = np.asarray(res["counts"][i], np.int64)
            rec["lnsum"] = np.asarray(res["lnsum"][i], np.float64)
        out.append(rec)
    return out


def merge_histograms(records: Sequence[dict]) -> dict:
    """Sum the histograms of frame records (and drop them from the records)."""
    counts = np.zeros(HIST_BINS, np.int64)
    lnsum = np.zeros(HIST_BINS, np.float64)
    for r in records:
        if "counts" in r:
            counts += r.pop("counts")
            lnsum += r.pop("lnsum")
    return {"counts": counts, "lnsum": lnsum}


def _n_finite(st: dict) -> float:
    return st["n_pixels"] - st["n_nonfinite"]


_quantiles = jax.jit(_hist_quantiles)


def pooled_stats(stats: Sequence[dict], hist: dict) -> LuminanceStats:
    """:class:`LuminanceStats` of all pixels of all frames (see the module docstring)."""
    dt = jnp.result_type(float)
    n_fin = np.array([_n_finite(s) for s in stats], np.float64)
    n_pos = sum(s["n_positive"] for s in stats)
    n_pix = sum(s["n_pixels"] for s in stats)
    has_fin = n_fin > 0
    has_pos = np.array([s["n_positive"] > 0 for s in stats])
    lav = np.array([s["log_average"] for s in stats], np.float64)
    log_avg = math.exp(float(np.sum(n_fin * np.log(lav)) / max(float(np.sum(n_fin)), 1.0)))
    lmin = min((s["min"] for s, ok in zip(stats, has_fin, strict=True) if ok), default=0.0)
    lmax = max((s["max"] for s, ok in zip(stats, has_fin, strict=True) if ok), default=0.0)
    minpos = min(
        (s["min_positive"] for s, ok in zip(stats, has_pos, strict=True) if ok), default=1.0
    )
    counts, lnsum = hist["counts"], hist["lnsum"]
    width = (HIST_HI - HIST_LO) / HIST_BINS
    if n_pos > 0:
        q = _quantiles(
            np.asarray(counts, np.float64 if dt == jnp.float64 else np.float32),
            np.asarray(HIST_LO, dt),
            np.asarray(width, dt),
            np.asarray([0.01, 0.99], dt),
        )
        p01, p99 = (float(np.clip(v, minpos, max(lmax, minpos))) for v in np.asarray(q))
        b = int(np.clip(math.floor((math.log(p99) - HIST_LO) / width), 0, HIST_BINS - 1))
        frac = float(np.clip((math.log(p99) - (HIST_LO + b * width)) / width, 0.0, 1.0))
        n_kept = float(counts[:b].sum()) + frac * float(counts[b])
        s_kept = float(lnsum[:b].sum()) + frac * float(lnsum[b])
        trimmed = math.exp(s_kept / n_kept) if n_kept > 0 else 1.0
    else:
        p01 = p99 = trimmed = 1.0
    f = lambda v: jnp.asarray(v, dt)  # noqa: E731
    return LuminanceStats(
        n_pixels=jnp.asarray(n_pix, jnp.int32),
        n_nonfinite=jnp.asarray(n_pix - int(np.sum(n_fin)), jnp.int32),
        n_positive=jnp.asarray(n_pos, jnp.int32),
        min=f(lmin),
        min_positive=f(minpos),
        max=f(lmax),
        log_average=f(log_avg),
        p01=f(p01),
        p99=f(p99),
        log_average_trimmed=f(trimmed),
        rel_error_bound=f(math.expm1(width) if n_pos > 0 else 0.0),
    )


def _stats_of_record(st: dict) -> LuminanceStats:
    dt = jnp.result_type(float)
    ints = ("n_pixels", "n_nonfinite", "n_positive")
    return LuminanceStats(
        **{k: jnp.asarray(v, jnp.int32 if k in ints else dt) for k, v in st.items()}
    )


@eqx.filter_jit
def _reinhard_from_stats(op: AbstractOperator, st: LuminanceStats) -> dict[str, Any]:
    lbar = st.log_average if op.log_average is None else op.log_average  # type: ignore
    key = jgt_key(st) if op.key is None else op.key  # type: ignore[attr-defined]
    out = {"key": key, "log_average": lbar}
    if "L_white" in op.unset():
        out["L_white"] = jgt_white(st, key / lbar)
    return out


def reinhard_values(op: AbstractOperator, st: LuminanceStats) -> dict[str, np.ndarray]:
    """Key, white and log-average of the Reinhard family from statistics (JGT 2002)."""
    unset = set(op.unset())
    out = jax.device_get(_reinhard_from_stats(op, st))
    return {k: np.asarray(v) for k, v in out.items() if k in unset}


def _pool(name: str, values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    w = weights.reshape((-1,) + (1,) * (values.ndim - 1)) / max(float(weights.sum()), 1.0)
    if name == "L_max":
        return values.max(axis=0)
    if name == "L_min":
        return values.min(axis=0)
    if name == "channel_average" or np.any(values <= 0):
        return (w * values).sum(axis=0)
    return np.exp((w * np.log(values)).sum(axis=0))


def _frame_values(op: AbstractOperator, rec: dict) -> dict[str, np.ndarray]:
    if op.name in _REINHARD:
        return reinhard_values(op, _stats_of_record(rec["stats"]))
    return rec["values"]


def shared_values(op: AbstractOperator, records: Sequence[dict], hist: dict) -> dict:
    """Parameters for every frame from the whole sequence (``"same"``)."""
    if op.name in _REINHARD:
        return reinhard_values(op, pooled_stats([r["stats"] for r in records], hist))
    weights = np.array([_n_finite(r["stats"]) for r in records], np.float64)
    names = records[0]["values"].keys() if records else ()
    return {
        n: _pool(n, np.stack([np.asarray(r["values"][n], np.float64) for r in records]), weights)
        for n in names
    }


def smooth_series(values: np.ndarray, tau: float) -> np.ndarray:
    """Centred exponential moving average over axis 0 (see the module docstring)."""
    v = np.asarray(values, np.float64)
    if tau <= 0 or v.shape[0] < 2:
        return v
    log = bool(np.all(v > 0))
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
    """Per-frame parameters smoothed over time (``"smooth"``), in the records' order."""
    per = [_frame_values(op, r) for r in records]
    if not per:
        return []
    out: list[dict] = [{} for _ in per]
    for n in per[0]:
        series = smooth_series(np.stack([np.asarray(p[n], np.float64) for p in per]), tau)
        for i, o in enumerate(out):
            o[n] = series[i]
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
    "HIST_BINS",
    "measure_batch",
    "merge_histograms",
    "pooled_stats",
    "shared_values",
    "smooth_series",
    "smoothed_values",
    "stack_operators",
    "with_values",
]
