"""``run``: a pipeline over many frames, in this process or on a Dask cluster.

In-process (the default): frames are read by a thread pool ahead of the computation, grouped
by shape (and luminance weights) into batches of ``batch_size``, pushed through one compiled
function per shape that maps the pipeline over the frames (``lax.map`` or ``vmap``, see
:class:`~hdrjax.batch.Pipeline`; XLA runs it asynchronously), and written by another thread
pool while the next batch computes. With ``workers`` or ``scheduler``, the same work goes to
Dask: one task per chunk of ``batch_size`` frames reads, renders and writes its frames on a
worker; a task whose worker dies is re-run elsewhere by the scheduler (``retries`` more
times for other failures). Both paths run the same batch code, so their outputs are
byte-identical.

Sequence parameters (``parameters="same"`` or ``"smooth"``) take a measuring pass over *all*
frames first (outputs that already exist included, so that a resumed run uses the same
parameters), then a rendering pass. In-process, the frames read by the first pass are kept
in memory for the second when they fit in ``cache_bytes``; otherwise (and on Dask) frames
are read twice.

Time-dependent adaptation (``fps``): an operator that declares a time course
(:class:`~hdrjax.operators.AbstractTimeDependentOperator`: its ``sequence`` method) maps the
frames as a video shown at ``fps`` frames per second. The frames go through in their order,
in batches of ``batch_size``, each batch starting from the observer's state the previous
one ended with, so the result equals one scan over the whole sequence. Every frame is
computed (the state needs them all); with ``resume``, outputs that exist are not rewritten.
A frame that cannot be read is left out of the time course (the next frame follows the
previous one after ``1 / fps``). It runs in this process (not on Dask) and measures nothing
across frames (``parameters="per-frame"``): the operator adapts to each frame itself.
"""

import dataclasses
import functools
import glob
import logging
import os
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any, Literal

import numpy as np

from .._progress import progress_bar
from .._stats import Statistics
from ..io._atomic import remove_stale_temporaries
from ..operators._time import has_time_course, time_dependent_names
from ._frames import (
    FrameError,
    dispatch_render,
    dispatch_sequence,
    failure,
    group_key,
    measure_frames,
    measure_task,
    output_path,
    read_frame,
    render_task,
    write_frame,
)
from ._pipeline import Pipeline
from ._sequence import merge_statistics, shared_values, smoothed_values, statistics_settings

Parameters = Literal["per-frame", "same", "smooth"]
PARAMETER_MODES = ("per-frame", "same", "smooth")


@dataclasses.dataclass(frozen=True)
class BatchSummary:
    """What a batch run did.

    Attributes:
        done: input frames whose outputs were written by this run.
        skipped: input frames whose outputs already existed (``resume=True``).
        failed: input frame → one-line error message (unreadable file, NaN pixels, ...).
        seconds: wall time of the whole run.
    """

    done: tuple[str, ...]
    skipped: tuple[str, ...]
    failed: dict[str, str]
    seconds: float

    @property
    def ok(self) -> bool:
        """No frame failed."""
        return not self.failed

    @property
    def frames_per_second(self) -> float:
        """Frames written per second of wall time."""
        return len(self.done) / self.seconds if self.seconds > 0 else 0.0

    def __str__(self) -> str:
        return (
            f"{len(self.done)} done, {len(self.skipped)} skipped, {len(self.failed)} failed"
            f" in {self.seconds:.1f} s ({self.frames_per_second:.2f} frames/s)"
        )


@dataclasses.dataclass
class _Entry:
    index: int
    path: str
    out: Path


def expand_paths(paths: str | os.PathLike | Iterable[str | os.PathLike]) -> list[str]:
    """Input frames: a glob pattern (expanded and sorted), a file, or a list of either
    (patterns expanded in place, order kept). A pattern that matches nothing raises."""
    items = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    out: list[str] = []
    for item in items:
        s = os.fspath(item)
        if glob.has_magic(s) and not os.path.exists(s):
            found = sorted(p for p in glob.glob(s) if os.path.isfile(p))
            if not found:
                raise FileNotFoundError(f"{s}: no file matches this pattern")
            out += found
        else:
            out.append(s)
    return out


def _entries(paths: list[str], out_dir: Path, ext: str) -> list[_Entry]:
    entries: list[_Entry] = []
    seen: dict[Path, str] = {}
    for i, p in enumerate(paths):
        out = output_path(p, out_dir, ext)
        if out in seen:
            raise ValueError(
                f"paths: {seen[out]} and {p} would both be written to {out}; "
                "give the frames distinct names"
            )
        seen[out] = p
        entries.append(_Entry(i, p, out))
    return entries


def _progress(total: int, enabled: bool, desc: str):
    return progress_bar(total=total, unit="frame", desc=desc, enabled=enabled)


def _reader(
    entries: Sequence[_Entry], allow_nan: bool, threads: int, ahead: int
) -> Iterator[tuple[_Entry, Any]]:
    """``(entry, (rgb, weights))`` or ``(entry, FrameError)`` in order, read ``ahead``."""
    with ThreadPoolExecutor(max(1, threads), thread_name_prefix="hdrjax-read") as ex:
        it = iter(entries)
        queue: deque = deque()

        def push() -> None:
            e = next(it, None)
            if e is not None:
                queue.append((e, ex.submit(read_frame, e.path, allow_nan=allow_nan)))

        for _ in range(max(1, ahead)):
            push()
        while queue:
            e, fut = queue.popleft()
            push()
            try:
                yield e, fut.result()
            except FrameError as err:
                yield e, err


class _HostBatch:
    """A device batch fetched to NumPy once, by whichever writer asks first."""

    def __init__(self, out: Any) -> None:
        self._out = out
        self._host: np.ndarray | list[np.ndarray] | None = None
        self._lock = threading.Lock()

    def get(self) -> np.ndarray | list[np.ndarray]:
        with self._lock:
            if self._host is None:
                out = self._out
                self._host = out if isinstance(out, list) else np.asarray(out)
                self._out = None
            return self._host


class _Collector:
    """Thread-safe results and progress."""

    def __init__(self, bar: Any, report: Callable[[str], None] | None) -> None:
        self.done: dict[int, str] = {}
        self.failed: dict[int, tuple[str, str]] = {}
        self._bar = bar
        self._report = report
        self._lock = threading.Lock()

    def ok(self, e: _Entry) -> None:
        with self._lock:
            self.done[e.index] = e.path
            self._bar.update(1)

    def fail(self, e: _Entry, msg: str, count: bool = True) -> None:
        with self._lock:
            self.failed[e.index] = (e.path, msg)
            if count:
                self._bar.update(1)
            if self._report is not None:
                self._report(msg)


# ---------------------------------------------------------------------- in-process


def _measure_local(
    pipeline: Pipeline,
    entries: Sequence[_Entry],
    batch_size: int,
    pooled: bool,
    allow_nan: bool,
    readers: int,
    cache_bytes: int,
    keep: set[int],
    col: _Collector,
) -> tuple[dict[int, dict], Statistics | None, dict[int, Any]]:
    records: dict[int, dict] = {}
    merged: list[Statistics | None] = [None]
    cache: dict[int, Any] = {}
    cached = 0
    buffers: dict[tuple, list] = {}

    def flush(key: tuple) -> None:
        members = buffers.pop(key)
        recs = measure_frames(pipeline, [m[1] for m in members], key, batch_size, pooled)
        for m, r in zip(members, recs, strict=True):
            records[m[0].index] = r
        merged[0] = merge_statistics(recs, merged[0])

    for e, res in _reader(entries, allow_nan, readers, 2 * batch_size):
        if isinstance(res, FrameError):
            col.fail(e, str(res), count=False)
            continue
        rgb, w = res
        if e.index in keep and cached + rgb.nbytes <= cache_bytes:
            cache[e.index] = res
            cached += rgb.nbytes
        key = group_key(rgb, w, pipeline)
        buffers.setdefault(key, []).append((e, rgb))
        if len(buffers[key]) == batch_size:
            flush(key)
    for key in list(buffers):
        flush(key)
    return records, merged[0], cache


def _write(pipeline: Pipeline, col: _Collector, e: _Entry, hb: _HostBatch, i: int) -> None:
    """Write output ``i`` of a computed batch for ``e`` and record the outcome."""
    try:
        write_frame(pipeline, hb.get()[i], e.out)
    except FrameError as err:
        col.fail(e, str(err))
    except Exception as err:  # the computation itself failed: every frame of it fails
        col.fail(e, f"{e.path}: processing failed: {failure(err)}")
    else:
        col.ok(e)


def _render_local(
    pipeline: Pipeline,
    entries: Sequence[_Entry],
    values: dict[int, dict] | None,
    batch_size: int,
    allow_nan: bool,
    readers: int,
    writers: int,
    cache: dict[int, Any],
    col: _Collector,
) -> None:
    buffers: dict[tuple, list] = {}
    in_flight: deque[list[Future]] = deque()
    write = functools.partial(_write, pipeline, col)

    with ThreadPoolExecutor(max(1, writers), thread_name_prefix="hdrjax-write") as wx:

        def flush(key: tuple) -> None:
            members = buffers.pop(key)
            vals = None if values is None else [values[m[0].index] for m in members]
            try:
                out = dispatch_render(pipeline, [m[1] for m in members], key, vals, batch_size)
            except Exception as err:
                for m in members:
                    col.fail(m[0], f"{m[0].path}: processing failed: {failure(err)}")
                return
            hb = _HostBatch(out)
            in_flight.append([wx.submit(write, m[0], hb, i) for i, m in enumerate(members)])
            while len(in_flight) > 2:  # bounded memory: at most 3 batches not yet written
                for f in in_flight.popleft():
                    f.result()

        def frames() -> Iterator[tuple[_Entry, Any]]:
            uncached = [e for e in entries if e.index not in cache]
            read = _reader(uncached, allow_nan, readers, 2 * batch_size)
            for e in entries:
                yield (e, cache.pop(e.index)) if e.index in cache else next(read)

        for e, res in frames():
            if isinstance(res, FrameError):
                col.fail(e, str(res))
                continue
            rgb, w = res
            key = group_key(rgb, w, pipeline)
            buffers.setdefault(key, []).append((e, rgb))
            if len(buffers[key]) == batch_size:
                flush(key)
        for key in list(buffers):
            flush(key)
        for batch in in_flight:
            for f in batch:
                f.result()


def _render_in_order(
    pipeline: Pipeline,
    entries: Sequence[_Entry],
    skip: set[int],
    fps: float,
    batch_size: int,
    allow_nan: bool,
    readers: int,
    writers: int,
    col: _Collector,
) -> None:
    """The frames in order with the operator's time course (module docstring): the state
    after each batch is the next batch's initial state."""
    state: list[Any] = [None]
    chunk: list[tuple[_Entry, np.ndarray]] = []
    first: list[tuple] = []  # the first frame's shape and primaries
    write = functools.partial(_write, pipeline, col)

    with ThreadPoolExecutor(max(1, writers), thread_name_prefix="hdrjax-write") as wx:
        pending: deque[Future] = deque()

        def flush() -> None:
            members = chunk[:]
            chunk.clear()
            try:
                out, state[0] = dispatch_sequence(
                    pipeline, [m[1] for m in members], first[0][1], fps, state[0], batch_size
                )
            except Exception as err:
                for e, _ in members:
                    col.fail(
                        e, f"{e.path}: processing failed: {failure(err)}", count=e.index not in skip
                    )
                return
            hb = _HostBatch(out)
            for i, (e, _) in enumerate(members):
                if e.index not in skip:
                    pending.append(wx.submit(write, e, hb, i))
            while len(pending) > 3 * batch_size:  # bounded memory
                pending.popleft().result()

        for e, res in _reader(entries, allow_nan, readers, 2 * batch_size):
            if isinstance(res, FrameError):
                col.fail(e, str(res), count=e.index not in skip)
                continue
            rgb, source = res
            if not first:
                first.append((rgb.shape, source))
            elif (rgb.shape, source) != first[0]:
                col.fail(
                    e,
                    f"{e.path}: fps carries the adaptation from frame to frame: every frame"
                    f" needs the first frame's size {first[0][0][1]}x{first[0][0][0]} and"
                    " primaries",
                    count=e.index not in skip,
                )
                continue
            chunk.append((e, rgb))
            if len(chunk) == batch_size:
                flush()
        if chunk:
            flush()
        for f in pending:
            f.result()


def check_time_course(pipeline: Pipeline) -> None:
    """A one-line ``ValueError`` unless the pipeline's operator declares a time course."""
    if not has_time_course(pipeline.operator):
        raise ValueError(
            f"fps: {pipeline.operator.name} has no time course; operators with one:"
            f" {', '.join(time_dependent_names())}"
        )


# ---------------------------------------------------------------------------- Dask


def _client(workers: int | None, scheduler: Any):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ImportError(
            "workers/scheduler need dask.distributed: pip install 'hdrjax[dask]'"
        ) from None

    if scheduler is not None:
        if isinstance(scheduler, Client):
            return scheduler, None, False
        return Client(scheduler), None, True
    import jax

    # workers reuse this process's persistent XLA cache, if any (compile once per machine)
    cache = jax.config.jax_compilation_cache_dir
    env = {"JAX_COMPILATION_CACHE_DIR": cache} if cache else {}
    cluster = LocalCluster(
        n_workers=int(workers or 1),
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=":0",
        silence_logs=logging.ERROR,
        env=env,
    )
    client = Client(cluster)
    from ._cores import pin_workers, tune_workers

    pin_workers(client, int(workers or 1))  # one XLA thread pool per core group
    tune_workers(client)  # the workers' memory as this process's (hdrjax.tune_memory)
    return client, cluster, True


def _chunks(items: list, size: int) -> list[list]:
    return [items[i : i + size] for i in range(0, len(items), size)]


def _measure_dask(client, pipeline, entries, batch_size, pooled, allow_nan, retries, col):
    chunks = _chunks([(e.index, e.path) for e in entries], batch_size)
    # keyword arguments through partial: ``batch_size`` is also an argument of client.map
    task = functools.partial(
        measure_task, pipeline=pipeline, batch_size=batch_size, pooled=pooled, allow_nan=allow_nan
    )
    futures = client.map(task, chunks, retries=retries, pure=False)
    by_index = {e.index: e for e in entries}
    records: dict[int, dict] = {}
    merged = None
    for res in client.gather(futures):
        records.update(res["records"])
        for i, msg in res["failed"].items():
            col.fail(by_index[i], msg, count=False)
        merged = merge_statistics([{"stats": res["stats"]}], merged)
    return records, merged


def _render_dask(client, pipeline, entries, values, batch_size, allow_nan, retries, col):
    from distributed import as_completed

    items = [
        (e.index, e.path, str(e.out), None if values is None else values[e.index]) for e in entries
    ]
    task = functools.partial(
        render_task, pipeline=pipeline, batch_size=batch_size, allow_nan=allow_nan
    )
    futures = client.map(task, _chunks(items, batch_size), retries=retries, pure=False)
    by_index = {e.index: e for e in entries}
    for fut in as_completed(futures):
        for i, msg in fut.result().items():
            if msg is None:
                col.ok(by_index[i])
            else:
                col.fail(by_index[i], msg)


# ----------------------------------------------------------------------------- run


def _values_for(
    pipeline: Pipeline,
    parameters: str,
    records: dict[int, dict],
    merged: Statistics | None,
    smooth_frames: float,
) -> dict[int, dict]:
    order = sorted(records)
    recs = [records[i] for i in order]
    if parameters == "same":
        if not order:
            return {}
        shared = shared_values(pipeline.operator, merged)
        return {i: shared for i in order}
    smoothed = smoothed_values(pipeline.operator, recs, smooth_frames)
    return dict(zip(order, smoothed, strict=True))


def run(
    paths: str | os.PathLike | Iterable[str | os.PathLike],
    pipeline: Pipeline | str,
    out_dir: str | os.PathLike,
    *,
    parameters: Parameters = "per-frame",
    smooth_frames: float = 5.0,
    fps: float | None = None,
    batch_size: int = 8,
    workers: int | None = None,
    scheduler: Any = None,
    progress: bool = True,
    resume: bool = True,
    allow_nan: bool = False,
    readers: int = 2,
    writers: int = 2,
    cache_bytes: int = 1 << 30,
    retries: int = 2,
    report: Callable[[str], None] | None = None,
) -> BatchSummary:
    """Run ``pipeline`` over frames and write ``out_dir/<stem>.<format>`` for each.

    Args:
        paths: a glob pattern (``"frames/*.exr"``, expanded and sorted), a file, or a list
            of files/patterns (order kept: it is the time order for ``"smooth"``).
        pipeline: a :class:`Pipeline`, or an operator name (PNG, sRGB, 8 bit).
        out_dir: output folder (created if missing).
        parameters: how the operator's unset (``None``) parameters are measured:
            ``"per-frame"`` (each frame by itself), ``"same"`` (statistics of all frames
            together, one set of parameters), ``"smooth"`` (per frame, then a centred
            exponential moving average over time; see :mod:`hdrjax.batch._sequence`).
        smooth_frames: the time constant ``τ`` of ``"smooth"``, in frames.
        fps: map the frames as a video shown at this many frames per second, with the
            operator's time course of adaptation (module docstring; an operator without
            one raises ``ValueError``). ``None``: each frame as a still image.
        batch_size: frames per compiled call (and per Dask task).
        workers: run on a new local Dask cluster with this many worker processes (they are
            spawned: a script that passes ``workers`` needs the usual
            ``if __name__ == "__main__":`` guard).
        scheduler: address of a running Dask scheduler (``"tcp://host:8786"``) or a
            ``distributed.Client``; workers need hdrjax installed and must see the input
            and output paths.
        progress: show a progress bar (tqdm, frames/s) on a terminal or in a Jupyter
            notebook, and on Dask
            the cluster's dashboard address (on stderr).
        resume: skip frames whose output file exists (outputs are written atomically, so an
            existing output is complete). ``False`` rewrites them.
        allow_nan: render frames with NaN pixels (black) instead of failing them.
        readers, writers: threads reading and writing frames in-process.
        cache_bytes: in-process sequence modes keep frames up to this size in memory
            between the measuring and the rendering pass.
        retries: Dask retries of a failed task (a task lost with its worker is re-run
            anyway).
        report: called with each failure's message (default: printed to stderr).

    Returns:
        A :class:`BatchSummary`. A bad frame (unreadable, NaN pixels, failed write) is
        recorded in ``failed`` and the others complete.

    Raises:
        ValueError: bad arguments, or two inputs that would write the same output.
        FileNotFoundError: a pattern that matches nothing.
    """
    t0 = time.perf_counter()
    if parameters not in PARAMETER_MODES:
        raise ValueError(
            f"parameters: expected one of {', '.join(PARAMETER_MODES)}, got {parameters!r}"
        )
    if isinstance(batch_size, bool) or int(batch_size) != batch_size or batch_size < 1:
        raise ValueError(f"batch_size: expected an integer >= 1, got {batch_size!r}")
    if not smooth_frames >= 0:
        raise ValueError(f"smooth_frames: expected a number >= 0, got {smooth_frames!r}")
    if workers is not None and (int(workers) != workers or workers < 1):
        raise ValueError(f"workers: expected an integer >= 1, got {workers!r}")
    if not isinstance(pipeline, Pipeline):
        pipeline = Pipeline(pipeline)
    if fps is not None:
        if isinstance(fps, bool) or not float(fps) > 0 or not np.isfinite(float(fps)):
            raise ValueError(f"fps: expected frames per second > 0, got {fps!r}")
        check_time_course(pipeline)
        if workers is not None or scheduler is not None:
            raise ValueError("fps: the frames go through in order in this process, not on Dask")
        if parameters != "per-frame":
            raise ValueError(
                f"fps: the time course adapts to each frame itself; parameters={parameters!r}"
                " does not apply"
            )
    if parameters == "same":
        statistics_settings(pipeline.operator, pooled=True)  # statistics that merge
    batch_size = int(batch_size)
    out = Path(out_dir)
    entries = _entries(expand_paths(paths), out, pipeline.extension)
    out.mkdir(parents=True, exist_ok=True)
    skipped = [e for e in entries if resume and e.out.is_file()]
    skip_ids = {e.index for e in skipped}
    todo = [e for e in entries if e.index not in skip_ids]
    if report is None:

        def report(msg: str) -> None:
            from tqdm.auto import tqdm

            tqdm.write(f"hdrjax batch: error: {msg}", file=sys.stderr)

    sequence = parameters != "per-frame" and bool(pipeline.operator.unset())
    pooled = parameters == "same"
    dask = (workers is not None or scheduler is not None) and bool(todo)
    client = cluster = None
    own_client = False
    bar = _progress(len(todo), progress, "frames")
    col = _Collector(bar, report)
    try:
        if fps is not None:
            if not todo:  # every output exists: nothing to compute
                return _summary(skipped, col, t0)
            _render_in_order(
                pipeline,
                entries,
                skip_ids,
                float(fps),
                batch_size,
                allow_nan,
                readers,
                writers,
                col,
            )
            return _summary(skipped, col, t0)
        if dask:
            client, cluster, own_client = _client(workers, scheduler)
            link = getattr(client, "dashboard_link", None)
            if progress and link:  # where to watch the cluster work (bokeh, the [dask] extra)
                from tqdm.auto import tqdm

                tqdm.write(f"hdrjax batch: Dask dashboard: {link}", file=sys.stderr)
        values = None
        cache: dict[int, Any] = {}
        if sequence and todo:
            if dask:
                records, merged = _measure_dask(
                    client, pipeline, entries, batch_size, pooled, allow_nan, retries, col
                )
            else:
                records, merged, cache = _measure_local(
                    pipeline,
                    entries,
                    batch_size,
                    pooled,
                    allow_nan,
                    readers,
                    cache_bytes,
                    {e.index for e in todo},
                    col,
                )
            values = _values_for(pipeline, parameters, records, merged, smooth_frames)
            gone = set(col.failed)
            for e in todo:
                if e.index in gone:
                    bar.update(1)
            todo = [e for e in todo if e.index not in gone]
        if dask:
            _render_dask(client, pipeline, todo, values, batch_size, allow_nan, retries, col)
        else:
            _render_local(
                pipeline, todo, values, batch_size, allow_nan, readers, writers, cache, col
            )
    finally:
        bar.close()
        if own_client and client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
        # temporaries a killed writer (this run's or an earlier one's) left next to the
        # outputs; those of another run writing into this folder now are left alone
        remove_stale_temporaries([e.out for e in entries])
    return _summary(skipped, col, t0)


def _summary(skipped: Sequence[_Entry], col: _Collector, t0: float) -> BatchSummary:
    failed = {
        path: msg for _, (path, msg) in sorted(col.failed.items()) if path not in col.done.values()
    }
    return BatchSummary(
        done=tuple(col.done[i] for i in sorted(col.done)),
        skipped=tuple(e.path for e in skipped),
        failed=failed,
        seconds=time.perf_counter() - t0,
    )


__all__ = ["PARAMETER_MODES", "BatchSummary", "expand_paths", "run"]
