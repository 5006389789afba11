"""hdrjax: JIT-compiled, differentiable HDR tone mapping and analysis in JAX.

Numeric contract: images are linear-light RGB, channels last ``(..., H, W, 3)``, relative or
absolute (cd/m²); operators return display-referred linear RGB, nominally [0, 1], which
:func:`hdrjax.display.encode` turns into sRGB. float32 by default, float64 with x64 enabled.

Subpackages are imported on first use (``hdrjax.fit`` pulls in optimistix, ``hdrjax.vision``
its FFT code): ``import hdrjax`` and the command line start faster, and every name below is
still an attribute of the package.
"""

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_SUBMODULES = {
    "batch": ".batch",
    "display": ".display",
    "estimate": ".estimate",
    "filters": ".filters",
    "fit": ".fit",
    "io": ".io",
    "layers": ".layers",
    "lights": ".lights",
    "measure": ".measure",
    "merge": ".merge",
    "metrics": ".metrics",
    "operators": ".operators",
    "panorama": ".panorama",
    "plot": ".plot",
    "report": ".report",
    "spaces": ".spaces",
    "spectral": ".spectral",
    "stats": "._stats",
    "study": ".study",
    "targets": ".targets",
    "tile": ".tile",
    "vision": ".vision",
}

_ATTRIBUTES = {
    "REC709_CHROMATICITIES": "._colour",
    "REC709_WEIGHTS": "._colour",
    "luminance": "._colour",
    "luminance_weights": "._colour",
    "compare": ".report",
    "desaturate_highlights": ".display",
    "false_color": ".display",
    "mean_filter": ".filters",
    "median_filter": ".filters",
    "get_operator": ".operators",
    "make_operator": ".operators",
    "operator_names": ".operators",
    "tonemap": ".operators",
    "show": "._show",
    "tune_memory": "._memory",
}

__all__ = sorted([*_SUBMODULES, *_ATTRIBUTES, "__version__"])


def __getattr__(name: str) -> Any:
    if name in _SUBMODULES:
        value = importlib.import_module(_SUBMODULES[name], __name__)
    elif name in _ATTRIBUTES:
        value = getattr(importlib.import_module(_ATTRIBUTES[name], __name__), name)
    else:
        raise AttributeError(f"module 'hdrjax' has no attribute {name!r}")
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # static analysers and IDEs see the eager imports
    from . import (
        _stats as stats,  # noqa: F401  (public name: hdrjax.stats)
        batch as batch,
        display as display,
        estimate as estimate,
        filters as filters,
        fit as fit,
        io as io,
        layers as layers,
        lights as lights,
        measure as measure,
        merge as merge,
        metrics as metrics,
        operators as operators,
        panorama as panorama,
        plot as plot,
        report as report,
        spaces as spaces,
        spectral as spectral,
        study as study,
        targets as targets,
        tile as tile,
        vision as vision,
    )
    from ._colour import (
        REC709_CHROMATICITIES as REC709_CHROMATICITIES,
        REC709_WEIGHTS as REC709_WEIGHTS,
        luminance as luminance,
        luminance_weights as luminance_weights,
    )
    from ._memory import tune_memory as tune_memory
    from ._show import show as show
    from .display import (
        desaturate_highlights as desaturate_highlights,
        false_color as false_color,
    )
    from .filters import (
        mean_filter as mean_filter,
        median_filter as median_filter,
    )
    from .operators import (
        get_operator as get_operator,
        make_operator as make_operator,
        operator_names as operator_names,
        tonemap as tonemap,
    )
    from .report import compare as compare
