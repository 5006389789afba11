"""Batch processing: one pipeline over many frames, in-process or on a Dask cluster.

A :class:`Pipeline` describes once what happens to every frame (scale, optional filter /
desaturation / vision steps, tone mapping, display encoding, output format); :func:`run`
applies it to a sequence of files, in batches of equal-shape frames pushed through one
compiled function per shape, with reading and writing overlapped with the computation
(threads), or on a Dask cluster (``workers=`` / ``scheduler=``). Operator parameters left
unset are measured per frame, shared over the sequence, or smoothed over time.
"""

from ._frames import FrameError as FrameError, read_frame as read_frame
from ._pipeline import (
    DISPLAY_FORMATS as DISPLAY_FORMATS,
    HDR_FORMATS as HDR_FORMATS,
    Pipeline as Pipeline,
    Step as Step,
    render_batch as render_batch,
    step as step,
)
from ._run import (
    PARAMETER_MODES as PARAMETER_MODES,
    BatchSummary as BatchSummary,
    expand_paths as expand_paths,
    run as run,
)
from ._sequence import (
    pooled_stats as pooled_stats,
    smooth_series as smooth_series,
)
