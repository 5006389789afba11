"""Shape-independent execution: an image's pixels in chunks of one fixed shape.

A pointwise operator (halo 0: each output pixel depends on its own pixel and on image
statistics) does not care where a pixel lies, so the pixels of any image, taken in memory
order, are cut into chunks of :data:`CHUNK` pixels; the last is padded (with NaN, which
every statistic leaves out, for the statistics; with copies of a pixel, whose outputs are
dropped, for the mapping). Two programs serve every image size (per operator, dtype and
working space):

1. statistics of one chunk, merged on the host (counts in 64 bits, log sums in float64:
   :func:`~hdrjax.tile._stats.merge_parts`) and bound by the operator
   (:meth:`~hdrjax.operators.AbstractOperator.bind`, one more small program);
2. the bound operator on one chunk (the padding's outputs are dropped).

A folder of images of many sizes then compiles each operator once instead of once per size
(about 1 s each on XLA:CPU, 0.4 s from the persistent cache). The result equals the
whole-image call to float rounding: counts, extrema and the histogram merge exactly, the
log sum is summed in float64, and statistics the operators estimate from the histogram once
merged (a trimmed or a range log-average) stay within their stated bound
(:class:`~hdrjax._stats.Statistics`). Chunks are dispatched asynchronously: the next one
computes while the previous one is copied out.
"""

import dataclasses
from collections.abc import Callable, Iterator

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import _check, _progress
from .._stats import Statistics
from ..operators._base import AbstractOperator, StatisticsSettings, rgb_statistics
from ._stats import merge_parts

CHUNK: tuple[int, int] = (512, 1024)
"""Pixels of one chunk as ``(rows, columns)``: 2^19 pixels (6 MB of float32 RGB), a
1024×512 frame in one chunk, a 4096² image in 32."""


def chunkable(op: AbstractOperator, shape: tuple[int, ...]) -> bool:
    """Whether ``op`` maps an image of ``shape`` chunk by chunk with the whole image's
    result: pointwise (:meth:`~hdrjax.operators.AbstractOperator.halo` 0), and its
    estimated parameters bound from mergeable statistics (the operator's own
    :meth:`~hdrjax.operators.AbstractOperator.bind`, histogram percentiles)."""
    if tuple(op.halo(tuple(shape))) != (0, 0):
        return False
    if not op.unset():
        return True
    if type(op)._measure is not AbstractOperator._measure:
        return False
    settings = op.statistics_settings()
    return settings is None or StatisticsSettings(*settings).method == "histogram"


def _checked(
    op: AbstractOperator, rgb, chunk, name: str = "rgb"
) -> tuple[np.ndarray, tuple[int, int]]:
    """``rgb`` as a float NumPy image (float16 and integers promoted to float32, as the
    operators do) and ``chunk`` as two ints; ``ValueError`` naming the argument."""
    if not isinstance(op, AbstractOperator):
        raise ValueError(f"op: expected an hdrjax operator, got {type(op).__name__}")
    _check.shape(rgb, name, channels=3, ndim=3)
    if not (isinstance(chunk, (tuple, list)) and len(chunk) == 2):
        raise ValueError(f"chunk: expected (rows, columns), two integers >= 1, got {chunk!r}")
    chunk = tuple(_check.integer(v, "chunk") for v in chunk)
    x = np.asarray(rgb)
    if x.dtype not in (np.float32, np.float64):
        x = x.astype(np.float32)
    if not chunkable(op, x.shape):
        raise ValueError(
            f"op: expected a pointwise operator with mergeable estimates, got"
            f" {op.name or type(op).__name__} (halo {tuple(op.halo(x.shape))},"
            f" {_method(op)} statistics): map it on the whole image or with"
            " hdrjax.tile.apply"
        )
    return x, chunk  # type: ignore[return-value]


def _method(op: AbstractOperator) -> str:
    settings = op.statistics_settings()
    return "no" if settings is None else f"{StatisticsSettings(*settings).method!r}"


def _chunks(
    rgb: np.ndarray, chunk: tuple[int, int], fill: float | None = None
) -> Iterator[tuple[slice, np.ndarray]]:
    """``(pixel slice, chunk)`` over the pixels of ``rgb`` in memory order; the last chunk
    padded with ``fill`` (``None``: copies of its first pixel, a value of the image)."""
    c = rgb.shape[-1]
    flat = np.reshape(rgb, (-1, c))
    size = chunk[0] * chunk[1]
    for start in range(0, flat.shape[0], size):
        part = flat[start : start + size]
        n = part.shape[0]
        if n < size:
            pad = part[:1] if fill is None else np.full((1, c), fill, part.dtype)
            part = np.concatenate([part, np.broadcast_to(pad, (size - n, c))])
        yield slice(start, start + n), part.reshape(chunk + (c,))


@eqx.filter_jit
def _chunk_statistics(op: AbstractOperator, chunk, matrix):
    """The statistics of a chunk: the last one is padded with NaN, which every statistic
    leaves out (that chunk takes the masked path; taking copies of a pixel out of the sums
    afterwards instead loses the float sums of a small image to cancellation)."""
    x = chunk
    if matrix is not None:
        from ..spaces import convert

        x = convert(x, matrix)
    settings = op.statistics_settings()
    if settings is None:
        raise ValueError(f"{op.name}: measures nothing from the image; no chunk statistics")
    return rgb_statistics(x, op.weights_, StatisticsSettings(*settings))


@eqx.filter_jit
def bind_compiled(op: AbstractOperator, stats: Statistics | None) -> AbstractOperator:
    """``op.bind(stats)``, compiled (one small program per operator)."""
    return op.bind(stats)


def statistics_chunked(
    op: AbstractOperator,
    rgb: np.ndarray,
    matrix: np.ndarray | None = None,
    *,
    chunk: tuple[int, int] = CHUNK,
) -> Statistics | None:
    """``op.statistics`` of ``rgb`` converted by ``matrix`` (``None``: as it is), merged
    from fixed-shape chunks of its pixels: one program for every image size; ``None`` for
    an operator that reads no statistics."""
    rgb, chunk = _checked(op, rgb, chunk)
    settings = op.statistics_settings()
    if settings is None:
        return None
    stats_op, stats_matrix = op, matrix
    if matrix is not None and not StatisticsSettings(*settings).channels and _has_weights(op):
        # the luminance of the converted pixels is that of the file's with the weights w M
        w = tuple(float(v) for v in np.asarray(op.weights_, np.float64) @ np.asarray(matrix))
        stats_op, stats_matrix = dataclasses.replace(op, weights=w), None  # type: ignore[call-arg]
    m = None if stats_matrix is None else jnp.asarray(stats_matrix, rgb.dtype)
    parts, pending = [], None
    for _, part in _chunks(rgb, chunk, np.nan):
        nxt = _chunk_statistics(stats_op, jnp.asarray(part), m)  # asynchronous
        if pending is not None:
            parts.append(jax.device_get(pending))
        pending = nxt
    parts.append(jax.device_get(pending))
    return merge_parts(parts, rgb.shape[0] * rgb.shape[1])[0]


def measure_chunked(
    op: AbstractOperator,
    rgb: np.ndarray,
    matrix: np.ndarray | None = None,
    *,
    chunk: tuple[int, int] = CHUNK,
) -> AbstractOperator:
    """``op.measure(rgb)`` (``rgb`` converted by ``matrix`` first, as
    :func:`hdrjax.operators.measure_in_space`), bound to :func:`statistics_chunked`
    (:func:`chunkable` operators only): the same programs for every image size.

    Args:
        op: the operator, its unset parameters to estimate.
        rgb: ``(H, W, 3)`` float image (NumPy).
        matrix: 3×3 conversion into the operator's working space, or ``None``.
        chunk: pixels per chunk, ``(rows, columns)``.
    """
    rgb, chunk = _checked(op, rgb, chunk)
    if not op.unset():
        return op
    return bind_compiled(op, statistics_chunked(op, rgb, matrix, chunk=chunk))


def _has_weights(op: AbstractOperator) -> bool:
    return "weights" in {f.name for f in dataclasses.fields(op)}


def map_chunked(
    fn: Callable[[jax.Array], jax.Array],
    rgb: np.ndarray,
    *,
    chunk: tuple[int, int] = CHUNK,
    out: np.ndarray | None = None,
    progress: bool = True,
) -> np.ndarray:
    """``fn`` (a compiled pointwise function of ``(rows, columns, C)`` images) over the
    fixed-shape chunks of ``rgb``'s pixels, assembled into ``out`` (a new array of the
    image's rows and columns and ``fn``'s channels and dtype by default). ``progress``: a
    bar over the chunks where a person watches (:func:`hdrjax.tile.apply`'s); Ctrl-C stops
    the run between two chunks."""
    shape = _check.shape(rgb, "rgb", channels=None, ndim=3)
    if not (isinstance(chunk, (tuple, list)) and len(chunk) == 2):
        raise ValueError(f"chunk: expected (rows, columns), two integers >= 1, got {chunk!r}")
    chunk = tuple(_check.integer(v, "chunk") for v in chunk)  # type: ignore[assignment]
    if out is not None and tuple(out.shape[:2]) != shape[:2]:
        raise ValueError(f"out: expected {shape[:2]} rows and columns, got shape {out.shape}")
    pending = None
    total = -(-shape[0] * shape[1] // (chunk[0] * chunk[1]))
    bar = _progress.progress_bar(
        _chunks(rgb, chunk),
        total=total,
        enabled=progress,
        unit="chunk",
        delay=_progress.DELAY_S,
    )
    for where, part in bar:
        res = fn(jnp.asarray(part))  # dispatched asynchronously: overlaps the copy below
        if out is None:
            out = np.empty(rgb.shape[:-1] + res.shape[2:], res.dtype)
        if pending is not None:
            _store(out, *pending)
        pending = (where, res)
    assert out is not None and pending is not None, "an image has at least one pixel"
    _store(out, *pending)
    return out


def _store(out: np.ndarray, where: slice, res) -> None:
    flat = out.reshape((-1,) + out.shape[2:])
    res = np.asarray(_progress.wait_ready(res))  # Ctrl-C is seen while it runs
    flat[where] = res.reshape((-1,) + out.shape[2:])[: where.stop - where.start]


def tonemap_chunked(
    op: AbstractOperator,
    rgb: np.ndarray,
    matrix: np.ndarray | None = None,
    *,
    finish: Callable[[jax.Array], jax.Array] | None = None,
    chunk: tuple[int, int] = CHUNK,
    progress: bool = True,
) -> tuple[AbstractOperator, np.ndarray]:
    """``(measured operator, output)``: :func:`measure_chunked`, then the operator and
    ``finish`` (e.g. a display encoding; pointwise, traceable) on each chunk, one compiled
    program (:func:`map_chunked`, which draws the ``progress`` bar)."""
    rgb, chunk = _checked(op, rgb, chunk)
    measured = measure_chunked(op, rgb, matrix, chunk=chunk)
    m = None if matrix is None else tuple(map(tuple, np.asarray(matrix, np.float64).tolist()))
    render = lambda x: _render(measured, x, m, finish)  # noqa: E731
    return measured, map_chunked(render, rgb, chunk=chunk, progress=progress)


@eqx.filter_jit
def _render(op: AbstractOperator, x, matrix: tuple | None, finish):
    # the matrix is static (a tuple): the operator's luminance weights in the file's
    # primaries come from it in NumPy (apply_in_space)
    from ..operators import apply_in_space

    y = apply_in_space(op, x, None if matrix is None else np.asarray(matrix))
    return y if finish is None else finish(y)


__all__ = [
    "CHUNK",
    "bind_compiled",
    "chunkable",
    "map_chunked",
    "measure_chunked",
    "statistics_chunked",
    "tonemap_chunked",
]
