"""Side-by-side comparison of tone-mapping operators on one image: :func:`compare`.

Each operator's rendition is scored with :mod:`hdrjax.metrics` (TMQI, Yeganeh & Wang 2013,
with its structural fidelity and naturalness; PU-SSIM, Mantiuk & Azimi 2021, against a
reference rendition when one is given), its clipped pixels and mean display luminance,
and timed (compilation and warm runs measured separately). The result is a
:class:`ComparisonTable`: rows as dicts or JSON, and a self-contained HTML page
(:meth:`ComparisonTable.to_html`, ``hdrjax compare`` on the command line) sortable by any
column.

Numeric contract: the image is linear RGB ``(H, W, 3)`` (relative or cd/m², as the
operators expect: see ``scale``); renditions are sRGB-encoded (IEC 61966-2-1) display
values in [0, 1]; a reference rendition is display-encoded sRGB too.
"""

from ._compare import (
    DEFAULT_METHODS as DEFAULT_METHODS,
    FIT_TARGETS as FIT_TARGETS,
    ComparisonRow as ComparisonRow,
    ComparisonTable as ComparisonTable,
    compare as compare,
    fit_target as fit_target,
)

__all__ = [
    "DEFAULT_METHODS",
    "FIT_TARGETS",
    "ComparisonRow",
    "ComparisonTable",
    "compare",
    "fit_target",
]
