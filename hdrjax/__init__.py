"""hdrjax: JIT-compiled, differentiable HDR tone mapping and analysis in JAX."""

from . import _stats as stats
from ._colour import (
    REC709_CHROMATICITIES as REC709_CHROMATICITIES,
    REC709_WEIGHTS as REC709_WEIGHTS,
    luminance as luminance,
    luminance_weights as luminance_weights,
)

__version__ = "0.1.0"
