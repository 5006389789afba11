"""Tiled processing of huge images: neighbourhood steps on tiles with halos.

Numeric contract: float images ``(H, W)`` or channels-last ``(H, W, C)``, any units (the
steps' own). :func:`apply` runs a step in-process, one window at a time, into a
preallocated (or memory-mapped) array; :func:`to_dask` builds the same computation as a
``dask.array.map_overlap`` graph for a cluster. Steps that need global image statistics
(Reinhard's key, white and log-average) bind the whole image's statistics, merged from the
tiles' (:func:`operator_statistics`: ``op.statistics(image)`` tile by tile);
:func:`statistics` / :func:`dask_statistics` summarise them as
:func:`hdrjax._stats.measure` does on the whole image.

Results equal the whole-image computation: bit for bit for :class:`Median` and
:class:`Mean`; to float rounding for :class:`Glare` with a truncated PSF and for
:class:`Tonemap` (FFTs of another size for the local Reinhard operator, whose discrete
scale choice may then differ at pixels with an activity within rounding of its
threshold). See :mod:`._layout` for the window geometry that makes this hold at the image
edges.
"""

from ._apply import (
    DEFAULT_TILE as DEFAULT_TILE,
    apply as apply,
    operator_statistics as operator_statistics,
    statistics as statistics,
)
from ._chunks import (
    CHUNK as CHUNK,
    bind_compiled as bind_compiled,
    chunkable as chunkable,
    map_chunked as map_chunked,
    measure_chunked as measure_chunked,
    statistics_chunked as statistics_chunked,
    tonemap_chunked as tonemap_chunked,
)
from ._dask import (
    dask_operator_statistics as dask_operator_statistics,
    dask_statistics as dask_statistics,
    to_dask as to_dask,
)
from ._steps import (
    TILE_MODES as TILE_MODES,
    AbstractStep as AbstractStep,
    Glare as Glare,
    Mean as Mean,
    Median as Median,
    Neighbourhood as Neighbourhood,
    Tonemap as Tonemap,
)

__all__ = [
    "CHUNK",
    "DEFAULT_TILE",
    "TILE_MODES",
    "AbstractStep",
    "Glare",
    "Mean",
    "Median",
    "Neighbourhood",
    "Tonemap",
    "apply",
    "bind_compiled",
    "chunkable",
    "dask_operator_statistics",
    "dask_statistics",
    "map_chunked",
    "measure_chunked",
    "operator_statistics",
    "statistics",
    "statistics_chunked",
    "to_dask",
    "tonemap_chunked",
]
