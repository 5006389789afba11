"""Human vision: simulate only the effects a scene calls for.

Numeric contract: linear RGB in absolute units (cd/m²), channels last, one image
``(H, W, 3)`` for the spatial effects (``jax.vmap`` for batches); outputs in cd/m² (display
cd/m² after ``contrast``; :class:`Budak2005` returns display values in [0, 1]).

- :func:`analyze` reports the adaptation luminance (global and foveal), the 5th percentile,
  the range, and for every effect whether it applies and why (Radiance pcond's rules).
- :func:`simulate` applies the selected effects in pcond's order — acuity loss, veiling
  glare (Spencer et al. 1995 PSF by FFT, or pcond's veil), night colour loss (pcond) or
  blue shift (Jensen et al. 2001), contrast-sensitivity scaling (pcond TVI / Ward 1994) —
  and returns the image and the report; ``simulate(..., then=op)`` also tone-maps it (for a
  scene that calls for no effect, the analysis and a global operator run as one program:
  about the cost of the tone mapping alone); :class:`HumanVision` is the same step as an
  equinox Module for ``jax.jit``/``vmap``/``grad`` and pipelines.
- :class:`Budak2005` is Budak & Petrovichev 2005's perceptual colour-contrast reproduction
  as a display step (the registered operator ``budak2005`` with gamma; documented stand-ins
  for the formulas that are not published: :mod:`hdrjax.operators._budak2005`).
- The formulas are public for reuse and testing: :func:`tvi`, :func:`tvi_photopic`,
  :func:`tvi_scotopic`, :func:`acuity`, :func:`mesopic_weight`, :func:`scotopic_luminance`,
  :func:`blue_shift_weight`, :func:`spencer1995_psf`, :func:`glare_kernel`,
  :func:`contrast_scale`, :func:`ward1994_scale`, :func:`fechner_brightness`.
"""

from .._photometry import (
    BOT_MESOPIC as BOT_MESOPIC,
    LMAX as LMAX,
    LMIN as LMIN,
    SWNORM as SWNORM,
    TOP_MESOPIC as TOP_MESOPIC,
    scotopic_luminance as scotopic_luminance,
)
from .._thresholds import (
    tvi_photopic as tvi_photopic,
    tvi_scotopic as tvi_scotopic,
    ward1994_scale as ward1994_scale,
)
from ..operators._budak2005 import (
    AbstractContrastSpace as AbstractContrastSpace,
    ConeOpponentSpace as ConeOpponentSpace,
    fechner_brightness as fechner_brightness,
    fechner_luminance as fechner_luminance,
)
from ._acuity import acuity_loss as acuity_loss, sample_spacing as sample_spacing
from ._budak2005 import Budak2005 as Budak2005, perceptual_reproduction as perceptual_reproduction
from ._contrast import (
    DISPLAY_MAX as DISPLAY_MAX,
    DISPLAY_RANGE as DISPLAY_RANGE,
    contrast as contrast,
    contrast_scale as contrast_scale,
    display_adaptation as display_adaptation,
)
from ._jensen2001 import blue_shift as blue_shift, blue_shift_weight as blue_shift_weight
from ._pcond import (
    acuity as acuity,
    colour_loss as colour_loss,
    mesopic_weight as mesopic_weight,
    tvi as tvi,
    veil as veil,
)
from ._report import EFFECTS as EFFECTS, Decision as Decision, SceneReport as SceneReport
from ._simulate import (
    HumanVision as HumanVision,
    analyze as analyze,
    simulate as simulate,
)
from ._spencer1995 import (
    WAVELENGTHS_RGB as WAVELENGTHS_RGB,
    WEIGHTS as SPENCER1995_WEIGHTS,
    glare as glare,
    glare_kernel as glare_kernel,
    spencer1995_psf as spencer1995_psf,
)
from ._view import DEFAULT_FOV as DEFAULT_FOV, ResolvedView as ResolvedView, View as View

__all__ = [
    "BOT_MESOPIC",
    "DEFAULT_FOV",
    "DISPLAY_MAX",
    "DISPLAY_RANGE",
    "EFFECTS",
    "LMAX",
    "LMIN",
    "SPENCER1995_WEIGHTS",
    "SWNORM",
    "TOP_MESOPIC",
    "WAVELENGTHS_RGB",
    "AbstractContrastSpace",
    "Budak2005",
    "ConeOpponentSpace",
    "Decision",
    "HumanVision",
    "ResolvedView",
    "SceneReport",
    "View",
    "acuity",
    "acuity_loss",
    "analyze",
    "blue_shift",
    "blue_shift_weight",
    "colour_loss",
    "contrast",
    "contrast_scale",
    "display_adaptation",
    "fechner_brightness",
    "fechner_luminance",
    "glare",
    "glare_kernel",
    "mesopic_weight",
    "perceptual_reproduction",
    "sample_spacing",
    "scotopic_luminance",
    "simulate",
    "spencer1995_psf",
    "tvi",
    "tvi_photopic",
    "tvi_scotopic",
    "veil",
    "ward1994_scale",
]
