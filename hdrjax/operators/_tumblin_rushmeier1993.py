"""The original Tumblin–Rushmeier operator (1993): brightness preserved through Stevens' law.

Reference:
    J. Tumblin, H. Rushmeier. "Tone reproduction for realistic images." IEEE Computer
    Graphics and Applications 13(6), 1993, pp. 42–48. https://doi.org/10.1109/38.252554

Equations. Stevens & Stevens' brightness of a luminance ``L`` seen at adaptation ``L_a``
is ``B = 10^β(L_a) L^α(L_a)``, with, for luminances in lamberts (1 L = 10⁴/π cd/m²) and
``x = log10 L_a``:

- ``α(L_a) = 0.4 x + 2.92``,
- ``β(L_a) = -0.4 x² - 2.584 x + 2.0208``.

Equal brightness for the world observer (adapted to ``L_wa``) and the display observer
(adapted to ``L_da = L_dmax / √C_max``) gives the display luminance
``L_d = L_w^(α_w/α_d) · 10^((β_w − β_d)/α_d)`` (lamberts throughout), and the display value
``n = L_d / L_dmax − 1/C_max``: the display's own minimum ``L_dmax / C_max`` is subtracted,
and values below it are black (0); display values saturate at 10¹⁸. Colour ratios are
kept (each channel times ``n / L_w`` in display units). The paper's final ``(·)^(1/γ)`` is
the display encoding, left to :mod:`hdrjax.display`. Computed, without changing its value, as
``n = (L_w / L_wa)^(α_w/α_d) · n_a − 1/C_max`` with ``n_a`` the display value (plus
``1/C_max``) of ``L_wa``: the power of a luminance near the float maximum saturates
instead of overflowing (:func:`~hdrjax.operators._tumblin.ratio_power`, shared with the
1999 revision), and its product with ``n_a`` saturates at 10¹⁸.

``L_wa`` is measured as by hdrjax's ``tumblin1999`` (the revision of this operator), the
log-average ``exp(mean(ln(L + 2.3·10⁻⁵)))`` of the finite pixels (cd/m²).

Departure from the paper: ``α`` is held at 10⁻³ where it would fall below (adaptation
luminances under 1.6·10⁻⁴ cd/m², far below Stevens' data); the paper's ``α`` changes sign
there, which would turn the curve upside down (brighter world, darker display).
"""

import math
from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array

from .._stats import DEFAULT_BINS, Statistics
from ._base import (
    AbstractLuminanceCurve,
    StatisticsSettings,
    checked_statistics,
    fill,
    parameter,
    register,
    weights_field,
)
from ._tumblin import adaptation_luminance, adaptation_settings, ratio_power
from ._ward1994 import display_maximum, log_average_adaptation

TUMBLIN_RUSHMEIER1993 = (
    "Tumblin, Rushmeier 1993, Tone reproduction for realistic images, IEEE Computer"
    " Graphics and Applications 13(6), https://doi.org/10.1109/38.252554"
)
LAMBERT = 1e4 / math.pi
"""cd/m² per lambert, the unit of Stevens' brightness data."""
ALPHA_FLOOR = 1e-3
"""Smallest Stevens exponent ``α`` used (module docstring)."""
DISPLAY_CAP = 1e18
"""Largest display value (1 is ``L_dmax``): the exponent ``α_w/α_d`` grows without bound
with the world's adaptation, and the mapping multiplies each channel by ``n / L_w``,
which must stay finite for a channel up to 1/0.0722 times the luminance."""


def stevens_alpha_beta(L_a: Array) -> tuple[Array, Array]:
    """Stevens' ``(α, β)`` at adaptation luminance ``L_a > 0`` (cd/m², converted to
    lamberts), ``α`` held at :data:`ALPHA_FLOOR` or above."""
    x = jnp.log10(L_a) - math.log10(LAMBERT)
    alpha = 0.4 * x + 2.92
    beta = -0.4 * x * x - 2.584 * x + 2.0208
    return jnp.maximum(alpha, ALPHA_FLOOR), beta


def tumblin_rushmeier1993_terms(L_wa: Array, L_dmax: Array, C_max: Array) -> tuple[Array, Array]:
    """``(α_w / α_d, n_a)``: the exponent and the display value ``L_d(L_wa) / L_dmax``."""
    a_w, b_w = stevens_alpha_beta(L_wa)
    a_d, b_d = stevens_alpha_beta(L_dmax / jnp.sqrt(C_max))
    exponent = a_w / a_d
    ln_n_a = (
        exponent * (jnp.log(L_wa) - math.log(LAMBERT))
        + (b_w - b_d) / a_d * math.log(10.0)
        - (jnp.log(L_dmax) - math.log(LAMBERT))
    )
    # an adaptation luminance at an end of the float range: n_a stays a normal float
    dt = ln_n_a.dtype
    lo, hi = math.log(float(jnp.finfo(dt).tiny)), math.log(float(jnp.finfo(dt).max)) - 1.0
    return exponent, jnp.exp(jnp.clip(ln_n_a, lo, hi))


@register("tumblin_rushmeier1993")
class TumblinRushmeier1993(AbstractLuminanceCurve):
    """Tumblin & Rushmeier 1993 brightness-preserving operator (module docstring).

    Input: absolute RGB in cd/m² (Stevens' law depends on absolute luminance: a relative
    image must first be multiplied by its cd/m² per unit). Output: display-relative linear
    RGB, 0 at the display's minimum and 1 at ``L_dmax``; brighter pixels exceed 1.

    Attributes:
        L_dmax: display maximum luminance, cd/m² (100).
        C_max: display contrast ``L_dmax / L_dmin`` (100); the display adaptation is
            ``L_dmax / √C_max``.
        L_wa: world adaptation luminance, cd/m²; ``None`` → the log-average
            ``exp(mean(ln(L + 2.3·10⁻⁵)))`` of the finite pixels.
        weights: luminance weights of the image's primaries (Rec.709 default).
    """

    reference: ClassVar[str] = TUMBLIN_RUSHMEIER1993
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_wa", "L_dmax")

    L_dmax: Array = display_maximum()
    C_max: Array = parameter(100.0, help="display contrast L_dmax / L_dmin", range="[1, inf)")
    L_wa: Array | None = log_average_adaptation()
    weights: tuple[float, float, float] = weights_field()

    def statistics_settings(self) -> StatisticsSettings | None:
        return None if self.L_wa is not None else adaptation_settings(DEFAULT_BINS)

    def bind(self, stats: Statistics | None) -> "TumblinRushmeier1993":
        if self.L_wa is not None:
            return self
        stats = checked_statistics(self, stats)
        return fill(self, L_wa=adaptation_luminance(stats, "log_average"))

    def _curve(self, L: Array) -> Array:
        assert self.L_wa is not None
        exponent, n_a = tumblin_rushmeier1993_terms(self.L_wa, self.L_dmax, self.C_max)
        # n_a may be below 1: it multiplies the saturated power, not inside ratio_power
        n = jnp.minimum(n_a * ratio_power(L, self.L_wa, exponent, 0.0), DISPLAY_CAP)
        return jnp.maximum(n - 1.0 / self.C_max, 0.0)


__all__ = [
    "ALPHA_FLOOR",
    "DISPLAY_CAP",
    "LAMBERT",
    "TUMBLIN_RUSHMEIER1993",
    "TumblinRushmeier1993",
    "stevens_alpha_beta",
    "tumblin_rushmeier1993_terms",
]
