"""Human vision: simulate only the effects a scene calls for.

Numeric contract: linear RGB in absolute units (cd/m²), channels last, one image
``(H, W, 3)`` for the spatial effects (``jax.vmap`` for batches); outputs in cd/m² (display
cd/m² after ``contrast``; :class:`Budak2005` returns display values in [0, 1]).

- :func:`analyze` reports the adaptation luminance (global and foveal), the 5th percentile,
  the range, and for every effect whether it applies and why (Radiance pcond's rules).
- :func:`simulate` applies the selected effects in pcond's order — acuity loss, veiling
  glare (Spencer et al. 1995 PSF by FFT, or pcond's veil), night colour loss (pcond) or
  blue shift (Jensen et al. 2001), contrast-sensitivity scaling (pcond TVI / Ward 1994) —
  and returns the image and the report; :class:`HumanVision` is the same step as an
  equinox Module for ``jax.jit``/``vmap``/``grad`` and pipelines.
- :class:`Budak2005` is seed 002's perceptual colour-contrast reproduction (with documented
  stand-ins for the formulas that are not published; see its module docstring).
- The formulas are public for reuse and testing: :func:`tvi`, :func:`tvi_photopic`,
  :func:`tvi_scotopic`, :func:`acuity`, :func:`mesopic_weight`, :func:`scotopic_luminance`,
  :func:`blue_shift_weight`, :func:`spencer1995_psf`, :func:`glare_kernel`,
  :func:`contrast_scale`, :func:`ward1994_scale`, :func:`fechner_brightness`.
"""

from ._acuity import acuity_loss as acuity_loss
from ._acuity import sample_spacing as sample_spacing
from ._budak2005 import (
    AbstractContrastSpace as AbstractContrastSpace,
)
from ._budak2005 import (
    Budak2005 as Budak2005,
)
from ._budak2005 import (
    ConeOpponentSpace as ConeOpponentSpace,
)
from ._budak2005 import (
    fechner_brightness as fechner_brightness,
)
from ._budak2005 import (
    fechner_luminance as fechner_luminance,
)
from ._budak2005 import (
    perceptual_reproduction as perceptual_reproduction,
)
from ._contrast import (
    DISPLAY_MAX as DISPLAY_MAX,
)
from ._contrast import (
    DISPLAY_RANGE as DISPLAY_RANGE,
)
from ._contrast import (
    contrast as contrast,
)
from ._contrast import (
    contrast_scale as contrast_scale,
)
from ._contrast import (
    display_adaptation as display_adaptation,
)
from ._contrast import (
    ward1994_scale as ward1994_scale,
)
from ._ferwerda1996 import tvi_photopic as tvi_photopic
from ._ferwerda1996 import tvi_scotopic as tvi_scotopic
from ._jensen2001 import blue_shift as blue_shift
from ._jensen2001 import blue_shift_weight as blue_shift_weight
from ._pcond import (
    acuity as acuity,
)
from ._pcond import (
    colour_loss as colour_loss,
)
from ._pcond import (
    mesopic_weight as mesopic_weight,
)
from ._pcond import (
    tvi as tvi,
)
from ._pcond import (
    veil as veil,
)
from ._photometry import (
    BOT_MESOPIC as BOT_MESOPIC,
)
from ._photometry import (
    LMAX as LMAX,
)
from ._photometry import (
    LMIN as LMIN,
)
from ._photometry import (
    SWNORM as SWNORM,
)
from ._photometry import (
    TOP_MESOPIC as TOP_MESOPIC,
)
from ._photometry import (
    scotopic_luminance as scotopic_luminance,
)
from ._report import EFFECTS as EFFECTS
from ._report import Decision as Decision
from ._report import SceneReport as SceneReport
from ._simulate import (
    HumanVision as HumanVision,
)
from ._simulate import (
    analyze as analyze,
)
from ._simulate import (
    simulate as simulate,
)
from ._spencer1995 import (
    WAVELENGTHS_RGB as WAVELENGTHS_RGB,
)
from ._spencer1995 import (
    WEIGHTS as SPENCER1995_WEIGHTS,
)
from ._spencer1995 import (
    glare as glare,
)
from ._spencer1995 import (
    glare_kernel as glare_kernel,
)
from ._spencer1995 import (
    spencer1995_psf as spencer1995_psf,
)
from ._view import DEFAULT_FOV as DEFAULT_FOV
from ._view import ResolvedView as ResolvedView
from ._view import View as View

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
