"""The same steps on a ``dask.array`` (``map_overlap``), e.g. on a distributed cluster.

``map_overlap`` with ``depth = halo`` and ``boundary="none"`` hands each chunk to the step
with ``halo`` neighbouring pixels on its inner sides and nothing beyond the image, which is
what :mod:`._layout` windows are: the step's own rule handles the true image edges and the
result equals the whole-image computation like :func:`hdrjax.tile.apply`'s. Chunks must be at
least the halo (dask's rule too); windows differ in shape at the image edges, so a worker
compiles a few shapes.
"""

import importlib
import sys
from collections.abc import Sequence

import numpy as np

from .._stats import DEFAULT_BINS, DEFAULT_DELTA, LuminanceStats, Statistics
from ..operators._base import AbstractOperator, StatisticsSettings
from ._apply import check_glare, check_image, check_step, resolve_halo
from ._stats import call_host, merge_blocks, stats_dtype, summary
from ._steps import AbstractStep


def _dask():
    try:
        import dask
        import dask.array as da
    except ImportError as e:  # pragma: no cover - dask is an optional dependency
        raise ImportError("hdrjax.tile's dask functions need dask[array]") from e
    return dask, da


def _run_blocks(darr):
    """A runner over the chunks, each padded with NaN to the largest chunk shape in the
    worker (as the in-process tiles are): one compilation per worker instead of one per
    edge-chunk shape (a 15000² image in 2048² chunks has four), and NaN pixels are left out
    of every statistic."""
    dask, _ = _dask()
    blocks = list(darr.to_delayed().ravel())
    full = (max(darr.chunks[0]), max(darr.chunks[1]))

    def run(fn, args, kwargs):
        ref = _reference(fn)
        tasks = [dask.delayed(_padded_call)(ref, b, full, *args, **kwargs) for b in blocks]
        return list(dask.compute(*tasks))

    return run


def _reference(fn):
    """``(module, name)`` of a module-level function, which a worker imports: a jitted
    function sent by value (cloudpickle copies it) arrives with an empty compilation cache,
    and every chunk compiled anew (a 2-worker cluster took 5× as long)."""
    module, name = getattr(fn, "__module__", None), getattr(fn, "__name__", None)
    if module and name and getattr(sys.modules.get(module), name, None) is fn:
        return module, name
    return fn


def _padded_call(ref, block, full, *args, **kwargs):
    fn = getattr(importlib.import_module(ref[0]), ref[1]) if isinstance(ref, tuple) else ref
    block = np.asarray(block, dtype=kwargs["dtype"])
    if block.shape[:2] != full:
        pad = [(0, full[0] - block.shape[0]), (0, full[1] - block.shape[1])]
        block = np.pad(block, pad + [(0, 0)] * (block.ndim - 2), constant_values=np.nan)
    return call_host(fn, block, *args, **kwargs)


def _check_darr(darr):
    _, da = _dask()
    if not isinstance(darr, da.Array):
        raise ValueError(f"darr: expected a dask.array.Array, got {type(darr).__name__}")
    shape = check_image(darr)
    if len(shape) == 3 and len(darr.chunks[2]) != 1:
        darr = darr.rechunk({2: -1})  # a pixel's channels belong together
    return darr, shape


def dask_statistics(
    darr,
    *,
    weights: Sequence[float] | None = None,
    delta: float = DEFAULT_DELTA,
    bins: int = DEFAULT_BINS,
) -> LuminanceStats:
    """:func:`hdrjax.tile.statistics` over a dask array's chunks (one compute)."""
    if isinstance(bins, bool) or int(bins) != bins or bins < 2:
        raise ValueError(f"bins: expected an integer >= 2, got {bins!r}")
    darr, shape = _check_darr(darr)
    settings = StatisticsSettings("histogram", int(bins), float(delta))
    return summary(_merged(darr, shape, weights, settings))


def _merged(darr, shape, weights, settings) -> tuple[Statistics, float]:
    """The chunks' :class:`~hdrjax._stats.Statistics` (one compute), merged on the host."""
    if len(shape) == 3 and shape[-1] not in (1, 3):
        raise ValueError(f"darr: expected 1 or 3 channels, got shape {shape}")
    return merge_blocks(
        _run_blocks(darr), shape[0] * shape[1], darr.dtype, weights=weights, settings=settings
    )


def dask_operator_statistics(op: AbstractOperator, darr) -> Statistics | None:
    """:func:`hdrjax.tile.operator_statistics` over a dask array's chunks (one compute):
    ``op.statistics`` of each chunk, merged; ``None`` when the operator needs none."""
    if not isinstance(op, AbstractOperator):
        raise ValueError(f"op: expected an hdrjax operator, got {type(op).__name__}")
    settings = op.statistics_settings()
    if settings is None:
        return None
    darr, shape = _check_darr(darr)
    if len(shape) != 3 or shape[-1] != 3:
        raise ValueError(f"darr: expected (H, W, 3) RGB, got shape {shape}")
    return _merged(darr, shape, op.weights_, settings)[0]


class _Window:
    """Picklable chunk function for ``map_overlap`` (jit caches live in each worker)."""

    def __init__(self, step: AbstractStep, dtype):
        self.step, self.dtype = step, np.dtype(dtype)

    def __call__(self, block):
        if block.size == 0:
            return np.empty(block.shape, self.dtype)
        return np.asarray(self.step(np.asarray(block, self.dtype)), self.dtype)


def to_dask(
    step: AbstractStep,
    darr,
    *,
    halo: int | Sequence[int] | None = None,
    stats: Statistics | None = None,
):
    """A lazy ``dask.array`` of ``step`` applied to ``darr`` via ``map_overlap``.

    Args:
        step: a tile step (see :func:`hdrjax.tile.apply`).
        darr: ``(H, W)`` or ``(H, W, C)`` float dask array; every chunk at least the halo
            (the channel axis is put in one chunk).
        halo: overlap depth; default (and minimum) the step's own.
        stats: whole-image statistics for steps with global parameters (for
            :class:`~hdrjax.tile.Tonemap`, the :class:`~hdrjax._stats.Statistics` its
            operator binds); ``None`` computes them now from the chunks (one compute).

    Returns:
        A dask array of the result (float32, or float64 for float64 input under x64), same
        chunks; compute it, or ``store`` it chunk by chunk.

    Raises:
        ValueError: if a chunk is smaller than the halo or the step cannot be tiled.
    """
    step = check_step(step)
    darr, shape = _check_darr(darr)
    check_glare(step, shape, (min(darr.chunks[0]), min(darr.chunks[1])))
    hy, hx = resolve_halo(step, shape, halo)
    for ax, hh in ((0, hy), (1, hx)):
        small = min(darr.chunks[ax])
        if hh > small and len(darr.chunks[ax]) > 1:
            name = ("rows", "columns")[ax]
            raise ValueError(
                f"darr: chunks of {small} {name} are smaller than the step's halo of {hh} {name};"
                " rechunk to larger chunks"
            )
    request = step.statistics_settings()
    if stats is None and request is not None:
        stats = _merged(darr, shape, *request)[0]
    bound = step.bind(shape, stats)
    dtype = stats_dtype(darr.dtype)
    depth = {0: hy, 1: hx} if len(shape) == 2 else {0: hy, 1: hx, 2: 0}
    return darr.map_overlap(
        _Window(bound, dtype),
        depth=depth,
        boundary="none",
        trim=True,
        dtype=dtype,
        meta=np.empty((0,) * len(shape), dtype),
    )


__all__ = ["dask_operator_statistics", "dask_statistics", "to_dask"]
