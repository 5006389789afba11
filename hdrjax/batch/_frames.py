"""Frame I/O and the batched work on a group of frames, shared by the in-process runner and
the Dask tasks (both go through :func:`dispatch_render` and :func:`measure_frames`, so their
outputs are byte-identical).

Every compiled call sees exactly ``batch_size`` frames of one shape: a short group is padded
with copies of its last frame (the copies are computed and dropped), so one compilation
serves every batch of a shape, and a frame gives the same bytes whichever batch it lands in
(its result does not depend on the other frames of the compiled call)."""

import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import jax
import numpy as np

from .. import io as hio
from ._pipeline import Pipeline, frame_is_clean, render_batch, render_sequence_batch
from ._sequence import (
    estimated_values,
    host_statistics,
    measure_batch,
    merge_statistics,
    stack_operators,
    statistics_settings,
    with_values,
)


class FrameError(ValueError):
    """A frame that cannot be processed (unreadable file, NaN pixels, failed write)."""


def failure(err: BaseException) -> str:
    """An exception as one line for a failed frame: its message, or its type when it has
    none (a bare ``AssertionError`` once printed "processing failed: " and nothing else)."""
    text = " ".join(str(err).split())
    return text or type(err).__name__


def read_frame(
    path: str | os.PathLike, *, allow_nan: bool = False
) -> tuple[np.ndarray, tuple[float, ...] | None]:
    """Linear RGB ``(H, W, 3)`` float32 in the file's own primaries, and those primaries
    (OpenEXR's chromaticities 8-tuple, ``None`` for Rec.709/D65): the pipeline converts
    the frame into its working space on the device (:meth:`Pipeline.for_source`).

    The file is read once (an EXR's parts all come from the one open file); sidecar files
    are not looked up. Raises :class:`FrameError` naming the file.
    """
    name = os.fspath(path)
    try:
        img = hio.read(path, sidecars=False)
        rgb = np.ascontiguousarray(img.native_rgb(), np.float32)
        source = None if img.space.is_rec709 else img.space.chromaticities
    except (ValueError, OSError, KeyError, IndexError, EOFError) as e:
        msg = str(e) or type(e).__name__
        raise FrameError(msg if os.path.basename(name) in msg else f"{name}: {msg}") from None
    if not allow_nan and np.isnan(rgb.max(initial=-np.inf)):  # max propagates NaN: one fast pass
        n_nan = int(np.count_nonzero(np.isnan(rgb).any(axis=-1)))
        if n_nan:
            raise FrameError(
                f"{name}: {n_nan} of {rgb.shape[0] * rgb.shape[1]} pixel(s) are NaN "
                "(pass allow_nan=True / --allow-nan to render them black)"
            )
    return rgb, source


def write_frame(pipeline: Pipeline, data: np.ndarray, out: str | os.PathLike) -> None:
    """Write one pipeline output atomically (``FrameError`` on failure)."""
    try:
        if pipeline.encoded:
            hio.write_display(
                out,
                data,
                bits=pipeline.bits,
                compression=pipeline.compression,
                display=pipeline.output_display,
            )
        else:
            hio.write(out, np.asarray(data, np.float32))
    except (ValueError, OSError) as e:
        raise FrameError(f"{out}: cannot write: {e}") from None


def _padded(frames: Sequence[np.ndarray], batch_size: int) -> np.ndarray:
    frames = list(frames)
    frames += [frames[-1]] * (batch_size - len(frames))
    return np.stack(frames)


def group_key(rgb: np.ndarray, source: tuple | None, pipeline: Pipeline | None = None) -> tuple:
    """Frames that can share one compiled batch: same shape, primaries (:func:`read_frame`)
    and cleanliness (all pixels finite, :func:`~hdrjax.batch.frame_is_clean`). Frames of a
    :func:`chunked` pipeline group by primaries alone: each goes through the same programs
    whatever its size."""
    if pipeline is not None and chunked(pipeline):
        return (None, source, None)
    return (rgb.shape, source, frame_is_clean(rgb))


def chunked(pipeline: Pipeline) -> bool:
    """Whether the pipeline maps frames in fixed-shape chunks of pixels
    (:func:`hdrjax.tile.tonemap_chunked`: one compiled program for every frame size): no
    steps before the operator, and a pointwise operator whose estimates merge."""
    from ..tile import chunkable

    return not pipeline.steps and chunkable(pipeline.operator, (1, 1, 3))


def _chunk_matrix(p: Pipeline) -> np.ndarray | None:
    """The pipeline's conversion and ``scale`` as one matrix (``None``: the identity)."""
    if p.matrix is None and p.scale == 1.0:
        return None
    m = np.eye(3) if p.matrix is None else np.asarray(p.matrix, np.float64)
    return m * p.scale


def _render_chunked(p: Pipeline, rgb: np.ndarray, values: dict | None) -> np.ndarray:
    from ..tile import tonemap_chunked

    op = p.operator if values is None else with_values(p.operator, values)
    return tonemap_chunked(op, rgb, _chunk_matrix(p), finish=p.finish)[1]


def _measure_chunked(p: Pipeline, rgb: np.ndarray, pooled: bool) -> dict:
    """:func:`~hdrjax.batch._sequence.measure_batch`'s record of one frame, from the
    statistics of fixed-shape chunks."""
    from ..tile import bind_compiled, statistics_chunked

    op = p.operator
    statistics_settings(op, pooled)  # a one-line error for statistics that do not merge
    st = statistics_chunked(op, rgb, _chunk_matrix(p))
    bound = jax.device_get(bind_compiled(op, st)) if op.unset() else op
    rec: dict[str, Any] = {"values": estimated_values(op, bound)}
    if pooled:
        rec["stats"] = None if st is None else host_statistics(st)
    return rec


def dispatch_render(
    pipeline: Pipeline,
    frames: Sequence[np.ndarray],
    key: tuple,
    values: Sequence[dict] | None,
    batch_size: int,
) -> Any:
    """Start the compiled pipeline on up to ``batch_size`` equal-shape frames.

    ``key``: the frames' :func:`group_key`. ``values``: per-frame parameters (sequence
    modes) or ``None`` (measured per frame).
    Returns the device array (asynchronous); its first ``len(frames)`` entries are the
    outputs. A :func:`chunked` pipeline returns the list of the frames' outputs (NumPy,
    frames of any sizes).
    """
    n = len(frames)
    if not 1 <= n <= batch_size:
        raise ValueError(f"frames: expected 1..{batch_size} frames, got {n}")
    _, source, clean = key
    p = pipeline.for_source(source)
    if chunked(p):
        vals = [None] * n if values is None else list(values)
        return [_render_chunked(p, f, v) for f, v in zip(frames, vals, strict=True)]
    ops = None
    if values is not None:
        vals = list(values) + [values[-1]] * (batch_size - n)
        ops = stack_operators(p.operator, vals)
    return render_batch(p, ops, _padded(frames, batch_size), clean)


def dispatch_sequence(
    pipeline: Pipeline,
    frames: Sequence[np.ndarray],
    source: tuple | None,
    fps: float,
    state: Any,
    batch_size: int,
) -> tuple[Any, Any]:
    """Start the compiled pipeline with the operator's time course on up to ``batch_size``
    consecutive equal-shape frames in ``source`` primaries, from ``state`` (``None``:
    adapted to the first frame). Returns the device outputs (the first ``len(frames)``
    are the frames') and the state to carry to the next frames."""
    n = len(frames)
    if not 1 <= n <= batch_size:
        raise ValueError(f"frames: expected 1..{batch_size} frames, got {n}")
    p = pipeline.for_source(source)
    return render_sequence_batch(p, _padded(frames, batch_size), np.int32(n), float(fps), state)


def measure_frames(
    pipeline: Pipeline, frames: Sequence[np.ndarray], key: tuple, batch_size: int, pooled: bool
) -> list[dict]:
    """Per-frame measurement records (``hdrjax.batch._sequence.measure_batch``) of frames
    sharing the :func:`group_key` ``key``."""
    _, source, clean = key
    p = pipeline.for_source(source)
    if chunked(p):
        return [_measure_chunked(p, f, pooled) for f in frames]
    return measure_batch(p, _padded(frames, batch_size), pooled, clean)[: len(frames)]


# ------------------------------------------------------------------------- Dask tasks


_IO_THREADS = 2  # file reading and PNG compression release the GIL for the most part


def _read_or_error(path: str, allow_nan: bool):
    try:
        return read_frame(path, allow_nan=allow_nan)
    except FrameError as e:
        return e


def _groups(items, allow_nan, pipeline):
    """Read ``items`` (``(index, path, ...)``, in threads) and group them by shape;
    failures listed apart."""
    groups: dict[tuple, list] = {}
    failed: dict[int, str] = {}
    with ThreadPoolExecutor(_IO_THREADS) as ex:
        results = list(ex.map(lambda it: _read_or_error(it[1], allow_nan), items))
    for item, res in zip(items, results, strict=True):
        if isinstance(res, FrameError):
            failed[item[0]] = str(res)
            continue
        rgb, w = res
        groups.setdefault(group_key(rgb, w, pipeline), []).append((item, rgb, w))
    return groups, failed


def measure_task(
    items: Sequence[tuple[int, str]],
    pipeline: Pipeline,
    batch_size: int,
    pooled: bool,
    allow_nan: bool,
) -> dict:
    """Dask task: measure a chunk. Returns ``{"records": {index: record}, "stats": ...,
    "failed": {index: message}}`` (the chunk's statistics already merged, ``None`` unless
    ``pooled``)."""
    groups, failed = _groups(items, allow_nan, pipeline)
    records: dict[int, dict] = {}
    for key, members in groups.items():
        for start in range(0, len(members), batch_size):
            part = members[start : start + batch_size]
            recs = measure_frames(pipeline, [m[1] for m in part], key, batch_size, pooled)
            for m, r in zip(part, recs, strict=True):
                records[m[0][0]] = r
    merged = merge_statistics(list(records.values())) if pooled else None
    return {"records": records, "stats": merged, "failed": failed}


def render_task(
    items: Sequence[tuple[int, str, str, dict | None]],
    pipeline: Pipeline,
    batch_size: int,
    allow_nan: bool,
) -> dict[int, str | None]:
    """Dask task: read, render and write a chunk of ``(index, input, output, values)``.

    Returns ``{index: None (written) or error message}``. Outputs are written atomically
    on the worker, so a killed worker leaves no partial file and its chunk can be re-run.
    """
    groups, failed = _groups(items, allow_nan, pipeline)
    result: dict[int, str | None] = dict(failed)
    for key, members in groups.items():
        for start in range(0, len(members), batch_size):
            part = members[start : start + batch_size]
            values = None if part[0][0][3] is None else [m[0][3] for m in part]
            try:
                out = dispatch_render(pipeline, [m[1] for m in part], key, values, batch_size)
                out = out if isinstance(out, list) else np.asarray(out)
            except Exception as e:  # a failed batch fails its frames, not the run
                for m in part:
                    result[m[0][0]] = f"{m[0][1]}: processing failed: {failure(e)}"
                continue
            with ThreadPoolExecutor(_IO_THREADS) as ex:
                futures = [
                    ex.submit(_write_or_error, pipeline, out[i], m[0][2])
                    for i, m in enumerate(part)
                ]
                errors = [f.result() for f in futures]
            for m, err in zip(part, errors, strict=True):
                result[m[0][0]] = err
    return result


def _write_or_error(pipeline: Pipeline, data: np.ndarray, out: str) -> str | None:
    try:
        write_frame(pipeline, data, out)
    except FrameError as e:
        return str(e)
    return None


def output_path(path: str | os.PathLike, out_dir: str | os.PathLike, ext: str) -> Path:
    """``out_dir/<stem><ext>`` for an input frame."""
    p = Path(path)
    return Path(out_dir) / (p.name[: -len(p.suffix)] + ext if p.suffix else p.name + ext)


__all__ = [
    "FrameError",
    "dispatch_render",
    "measure_frames",
    "measure_task",
    "output_path",
    "read_frame",
    "render_task",
    "write_frame",
]
