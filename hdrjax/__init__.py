"""hdrjax: JIT-compiled, differentiable HDR tone mapping and analysis in JAX.

Numeric contract: images are linear-light RGB, channels last ``(..., H, W, 3)``, relative or
absolute (cd/m²); operators return display-referred linear RGB, nominally [0, 1], which
:func:`hdrjax.display.encode` turns into sRGB. float32 by default, float64 with x64 enabled.
"""

from . import (
    _stats as stats,  # noqa: F401  (public name: hdrjax.stats)
    display as display,
    filters as filters,
    fit as fit,
    io as io,
    layers as layers,
    lights as lights,
    measure as measure,
    operators as operators,
    panorama as panorama,
    targets as targets,
    vision as vision,
)
from ._colour import (
    REC709_CHROMATICITIES as REC709_CHROMATICITIES,
    REC709_WEIGHTS as REC709_WEIGHTS,
    luminance as luminance,
    luminance_weights as luminance_weights,
)
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

__version__ = "0.1.0"
