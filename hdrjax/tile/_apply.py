"""In-process tiled execution: windows one at a time, results into a preallocated array."""

from collections.abc import Iterator, Sequence

import jax.numpy as jnp
import numpy as np

from .. import _check, _progress
from .._progress import progress_bar, wait_ready
from .._stats import DEFAULT_BINS, DEFAULT_DELTA, LuminanceStats, Statistics
from ..operators._base import AbstractOperator, StatisticsSettings
from ._layout import Span, check_tile, spans
from ._stats import merge_blocks, numpy_runner, stats_dtype, summary
from ._steps import AbstractStep, Glare

DEFAULT_TILE = (1024, 1024)


def check_image(image) -> tuple[int, ...]:
    _check.real(image, "image")
    shape = tuple(int(s) for s in np.shape(image))
    if len(shape) not in (2, 3):
        raise ValueError(f"image: expected shape (H, W) or (H, W, C), got {shape}")
    _check.nonempty(shape, "image", "(H, W) or (H, W, C)", (0, 1))
    return shape


def check_step(step) -> AbstractStep:
    if not isinstance(step, AbstractStep):
        raise ValueError(
            f"step: expected an hdrjax.tile step (Median, Mean, Tonemap, Glare, Neighbourhood),"
            f" got {type(step).__name__}"
        )
    return step


def tile_grid(shape, tile, halo) -> list[tuple[Span, Span]]:
    """``(row span, column span)`` of every tile, row-major."""
    ty, tx = check_tile(tile)
    hy, hx = halo
    return [
        (r, c) for r in spans(shape[0], ty, hy, "rows") for c in spans(shape[1], tx, hx, "columns")
    ]


def _blocks(image, tile) -> Iterator[np.ndarray]:
    """Tiles without halo, edge tiles padded with NaN to one shape (one compilation): NaN
    pixels are left out of every statistic, and ``n_pixels`` comes from the image shape."""
    shape = np.shape(image)
    ty, tx = check_tile(tile)
    full = (min(ty, shape[0]), min(tx, shape[1])) + tuple(shape[2:])
    for r, c in tile_grid(shape, tile, (0, 0)):
        block = np.asarray(image[r.out, c.out])
        if block.shape != full:
            pad = [(0, full[0] - block.shape[0]), (0, full[1] - block.shape[1])]
            block = np.pad(block, pad + [(0, 0)] * (block.ndim - 2), constant_values=np.nan)
        yield block


def _merged(image, tile, weights, settings) -> tuple[Statistics, float]:
    """The whole image's :class:`~hdrjax._stats.Statistics`, merged from its tiles', and
    their log sum in float64."""
    shape = check_image(image)
    check_tile(tile)
    if len(shape) == 3 and shape[-1] not in (1, 3):
        raise ValueError(f"image: expected 1 or 3 channels, got shape {shape}")
    return merge_blocks(
        numpy_runner(lambda: _blocks(image, tile)),
        shape[0] * shape[1],
        np.asarray(image[:1, :1]).dtype,
        weights=weights,
        settings=settings,
    )


def statistics(
    image,
    *,
    tile: int | Sequence[int] = DEFAULT_TILE,
    weights: Sequence[float] | None = None,
    delta: float = DEFAULT_DELTA,
    bins: int = DEFAULT_BINS,
) -> LuminanceStats:
    """Whole-image luminance statistics computed tile by tile (the first pass).

    Args:
        image: ``(H, W, 3)`` linear RGB (statistics of its luminance, non-finite pixels
            excluded as the operators do), or an ``(H, W)`` / ``(H, W, 1)`` luminance;
            any array NumPy can slice (``np.memmap`` for images larger than memory).
        tile: tile size (rows, columns), or one integer for square tiles.
        weights: luminance weights (Rec.709 by default).
        delta: offset in the log-average (as :func:`hdrjax._stats.measure`).
        bins: histogram bins for the percentiles (as ``measure``).

    Returns:
        The :class:`~hdrjax._stats.LuminanceStats` that ``measure`` returns for the whole
        image's luminance: counts, extrema, ``p01``, ``p99`` and their error bound
        identical; the two log-averages to float32 rounding (see :mod:`._stats`). They are
        the tiles' merged :class:`~hdrjax._stats.Statistics`
        (:func:`operator_statistics`), summarised.
    """
    if isinstance(bins, bool) or int(bins) != bins or bins < 2:
        raise ValueError(f"bins: expected an integer >= 2, got {bins!r}")
    settings = StatisticsSettings("histogram", int(bins), float(delta))
    return summary(_merged(image, tile, weights, settings))


def operator_statistics(
    op: AbstractOperator, image, *, tile: int | Sequence[int] = DEFAULT_TILE
) -> Statistics | None:
    """``op.statistics(image)`` computed tile by tile: the tiles' statistics merged
    (:meth:`Statistics.merge <hdrjax._stats.Statistics.merge>`), for ``apply(Tonemap(op),
    image, stats=...)`` or ``op.bind``; ``None`` when the operator needs none.

    Args:
        op: any hdrjax operator.
        image: ``(H, W, 3)`` linear RGB (any array NumPy can slice).
        tile: tile size (rows, columns), or one integer for square tiles.

    Returns:
        Counts, extrema and histogram equal to ``op.statistics(image)``'s; the log sum to
        float32 rounding (a float64 sum of the tiles' sums).
    """
    if not isinstance(op, AbstractOperator):
        raise ValueError(f"op: expected an hdrjax operator, got {type(op).__name__}")
    settings = op.statistics_settings()
    if settings is None:
        return None
    shape = check_image(image)
    if len(shape) != 3 or shape[-1] != 3:
        raise ValueError(f"image: expected (H, W, 3) RGB, got shape {shape}")
    return _merged(image, tile, op.weights_, settings)[0]


def resolve_halo(step: AbstractStep, shape, halo) -> tuple[int, int]:
    need = tuple(int(v) for v in step.halo(shape))
    if halo is None:
        return need  # type: ignore[return-value]
    h = (halo, halo) if isinstance(halo, int) else tuple(halo)
    if len(h) != 2 or any(isinstance(v, bool) or int(v) != v for v in h):
        raise ValueError(f"halo: expected one or two integers, got {halo!r}")
    if h[0] < need[0] or h[1] < need[1]:
        raise ValueError(
            f"halo: the step reads {need} pixels (rows, columns) beyond a tile; got {h}"
        )
    return int(h[0]), int(h[1])


def bind(step: AbstractStep, image, shape, stats, tile) -> AbstractStep:
    request = step.statistics_settings()
    if stats is None and request is not None:
        stats = _merged(image, tile, *request)[0]
    return step.bind(shape, stats)


def check_glare(step, shape, tile) -> None:
    if isinstance(step, Glare) and step.radius_deg is None:
        ty, tx = check_tile(tile)
        if ty < shape[0] or tx < shape[1]:
            raise ValueError(
                "Glare: the full Spencer PSF spans the whole image, so tiles would each need"
                " the whole image; set radius_deg (a truncated PSF) or one tile for the image"
            )


def apply(
    step: AbstractStep,
    image,
    *,
    tile: int | Sequence[int] = DEFAULT_TILE,
    halo: int | Sequence[int] | None = None,
    stats: Statistics | None = None,
    out: np.ndarray | None = None,
    progress: bool = True,
) -> np.ndarray:
    """Run a neighbourhood ``step`` on an image tile by tile, with halos.

    Each tile's window (the tile and ``halo`` pixels around it, shifted inside the image at
    its edges) is mapped by the step's jit-compiled function — one compilation, as every
    window has the same shape — and its tile written into ``out``. The filters give the
    whole-image result bit for bit; see each step for the others.

    Memory: the input, ``out`` and two windows with the step's temporaries (one in flight
    while the previous one is copied out). With ``np.memmap`` input and output the image
    need not fit in memory. ``out`` may be ``image`` itself, also for a step with a halo:
    then the input rows that later windows still read are copied before their results
    overwrite them (a band of one row of windows, and the rows above it that the next
    band reads), so the run needs the image once plus about two bands, not twice the image.

    Args:
        step: :class:`Median`, :class:`Mean`, :class:`Tonemap`, :class:`Glare` or
            :class:`Neighbourhood`.
        image: ``(H, W)`` or ``(H, W, C)`` float image (any array NumPy can slice).
        tile: output tile size (rows, columns) or one integer; must be at least the halo
            unless it spans the image.
        halo: pixels read beyond each tile; default (and minimum) the step's own.
        stats: whole-image statistics for steps with global parameters (Reinhard's key):
            for :class:`Tonemap`, the :class:`~hdrjax._stats.Statistics` its operator binds
            (:func:`operator_statistics`, ``op.statistics(image)``, or those of parts
            merged); ``None`` computes them from the tiles first (a first pass).
        out: preallocated result (e.g. ``np.memmap``), the image's shape; a new float32
            (float64 for float64 input under x64) array by default. May be ``image``
            itself (in place; the result equals the one into a separate array).
        progress: a progress bar over the tiles (tqdm) where a person watches: a
            terminal or a Jupyter notebook (never in a pipe or a log), and only for a run
            that lasts over a second. Ctrl-C stops the run between two tiles.

    Returns:
        ``out``.

    Raises:
        ValueError: on a bad tile (not positive, or smaller than the halo), a halo smaller
            than the step's, or an ``out`` of another shape.
    """
    step = check_step(step)
    shape = check_image(image)
    check_glare(step, shape, tile)
    h = resolve_halo(step, shape, halo)
    grid = tile_grid(shape, tile, h)
    if out is None:
        out = np.empty(shape, stats_dtype(np.asarray(image[:1, :1]).dtype))
    elif tuple(out.shape) != shape:
        raise ValueError(f"out: expected shape {shape}, got {tuple(out.shape)}")
    bound = bind(step, image, shape, stats, tile)
    cdt = stats_dtype(np.asarray(image[:1, :1]).dtype)  # the filters' float promotion
    read = _window_reader(image, grid, cdt, in_place=h != (0, 0) and _in_place(out, image))
    pending = None
    bar = progress_bar(
        grid, enabled=progress, unit="tile", desc=type(step).__name__, delay=_progress.DELAY_S
    )
    for r, c in bar:
        window = jnp.asarray(read(r, c))
        result = bound(window)  # dispatched asynchronously: overlaps the copy-out below
        if pending is not None:
            _store(out, *pending)
        pending = (result, r, c)
    if pending is not None:
        _store(out, *pending)
    return out


def _in_place(out, image) -> bool:
    """Whether ``out`` is ``image`` (same memory, same layout); a ``ValueError`` when it
    overlaps it otherwise."""
    if not (isinstance(image, np.ndarray) and np.shares_memory(out, image)):
        return False
    if (
        out.__array_interface__["data"][0] != image.__array_interface__["data"][0]
        or out.strides != image.strides
    ):
        raise ValueError(
            "out: overlaps image without being image itself; pass image (in place) or a"
            " separate array"
        )
    return True


def _window_reader(image, grid: list[tuple[Span, Span]], dtype, in_place: bool):
    """``read(r, c)``: the window of tile ``(r, c)`` from the input as it was before the run.

    Out of place the image is read directly; in place (a step with a halo writing into its
    own input) through :class:`_Originals`."""
    if not in_place:
        return lambda r, c: np.asarray(image[r.window, c.window], dtype=dtype)
    return _Originals(image, grid, dtype).read


class _Originals:
    """The input's original rows for an in-place run, in the grid's row-major order: each
    band (one row span) is copied whole before any of its tiles is written, and the rows of
    it that a later band's windows still read (their top halo, or more where the last window
    is shifted inside the image) are kept from that copy; rows not yet written are read from
    the image."""

    def __init__(self, image, grid: list[tuple[Span, Span]], dtype):
        self.image, self.dtype = image, dtype
        # band start → the lowest window row of every later band
        self.later: dict[int, int] = {}
        lowest = int(np.shape(image)[0])
        for r, _ in reversed(grid):
            if r.start not in self.later:
                self.later[r.start] = lowest
                lowest = min(lowest, r.w_start)
        self.start = -1
        self.band = np.empty((0,))
        self.kept = np.empty((0,))  # originals of rows [kept_lo, written)
        self.kept_lo = 0
        self.written = 0  # rows above this hold results once the band's tiles are stored

    def _load(self, r: Span) -> None:
        lo, hi = r.w_start, r.w_start + r.w_len
        parts = []
        if lo < self.written:  # rows already overwritten: their kept originals
            parts.append(self.kept[lo - self.kept_lo : self.written - self.kept_lo])
        parts.append(np.array(self.image[max(lo, self.written) : hi], dtype=self.dtype))
        band = parts[0] if len(parts) == 1 else np.concatenate(parts)
        # the originals of rows [future, r.stop) that later bands read
        future = self.later[r.start]
        keep = []
        if future < lo:
            keep.append(self.kept[future - self.kept_lo : lo - self.kept_lo])
        if max(future, lo) < r.stop:
            keep.append(band[max(future, lo) - lo : r.stop - lo])
        self.kept = np.concatenate(keep) if keep else np.empty((0,))
        self.kept_lo, self.written = future, r.stop
        self.start, self.band = r.start, band

    def read(self, r: Span, c: Span) -> np.ndarray:
        if r.start != self.start:
            self._load(r)
        return self.band[:, c.window]


def _store(out, result, r: Span, c: Span) -> None:
    out[r.out, c.out] = np.asarray(wait_ready(result))[r.crop, c.crop]


__all__ = ["DEFAULT_TILE", "apply", "operator_statistics", "statistics", "tile_grid"]
