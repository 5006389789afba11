"""Ward 1994 contrast-based scale factor: one multiplier that keeps threshold visibility.

Reference:
    G. Ward. "A contrast-based scalefactor for luminance display." In P. S. Heckbert (ed.),
    Graphics Gems IV, Academic Press, 1994, pp. 415–421.
    https://doi.org/10.1016/B978-0-12-336156-1.50054-9

Equations (luminance in cd/m²): Blackwell's threshold ``ΔL(L_a) ∝ (1.219 + L_a^0.4)^2.5``
is matched between the world, adapted to ``L_wa``, and a display adapted to
``L_da = L_dmax / 2``, which gives the multiplier
``m = [(1.219 + L_da^0.4) / (1.219 + L_wa^0.4)]^2.5`` of display over world luminance, and
the display value ``m L_w / L_dmax``; each channel is multiplied by the same factor.

``L_wa`` is measured as the log-average luminance ``exp(mean(ln(L + 10⁻⁶)))`` (cd/m²) of the
finite pixels, the estimate of HDR Toolbox's ``WardGlobalTMO`` (its ``logMean``).
"""

from typing import Any, ClassVar

import jax.numpy as jnp
from jaxtyping import Array

from .._stats import Statistics
from .._thresholds import ward1994_scale
from ._base import (
    AbstractLuminanceCurve,
    StatisticsSettings,
    bound_stats,
    estimated,
    fill,
    parameter,
    register,
    weights_field,
)

WARD1994 = (
    "Ward 1994, A contrast-based scalefactor for luminance display, Graphics Gems IV,"
    " pp. 415-421, https://doi.org/10.1016/B978-0-12-336156-1.50054-9"
)


def display_maximum() -> Any:
    """``L_dmax``, the display's maximum luminance (100 cd/m²), of the adaptation operators."""
    return parameter(100.0, help="display maximum luminance", unit="cd/m²", range="(0, inf)")


def log_average_adaptation() -> Any:
    """``L_wa``, the world adaptation luminance (cd/m²), measured as the log-average."""
    return estimated(
        "world adaptation luminance; None: the log-average luminance",
        unit="cd/m²",
        pooling="log_mean",
    )


def ward1994_factor(L_wa: Array, L_dmax: Array) -> Array:
    """``m / L_dmax``: the display value of 1 cd/m² of world luminance (Ward 1994)."""

    return ward1994_scale(L_wa, 0.5 * L_dmax) / L_dmax


@register("ward1994")
class Ward1994(AbstractLuminanceCurve):
    """Ward 1994 contrast-based scale factor (module docstring): ``m L_w / L_dmax``.

    Input: absolute RGB in cd/m² (a relative image must first be multiplied by its cd/m²
    per unit; HDR Toolbox's ``WardGlobalTMO`` likewise reads pixel values as cd/m²).
    Output: display-relative linear RGB, 1 at ``L_dmax``; the operator is linear, so
    bright pixels exceed 1 (HDR Toolbox clamps its output to [0, 1]; hdrjax leaves that to
    the display encoding, as for the other operators).

    Attributes:
        L_dmax: display maximum luminance, cd/m² (100; the display adaptation is half of it).
        L_wa: world adaptation luminance, cd/m²; ``None`` → the log-average
            ``exp(mean(ln(L + 10⁻⁶)))`` of the finite pixels.
        weights: luminance weights of the image's primaries (Rec.709 default).
    """

    reference: ClassVar[str] = WARD1994
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_wa",)

    L_dmax: Array = display_maximum()
    L_wa: Array | None = log_average_adaptation()
    weights: tuple[float, float, float] = weights_field()

    def statistics_settings(self) -> StatisticsSettings | None:
        # the default delta, 1e-6, is HDR Toolbox's logMean offset
        return None if self.L_wa is not None else StatisticsSettings()

    def bind(self, stats: Statistics | None) -> "Ward1994":
        if self.L_wa is not None:
            return self
        return fill(self, L_wa=bound_stats(self, stats).log_average)

    def _curve(self, L: Array) -> Array:
        assert self.L_wa is not None
        k = ward1994_factor(self.L_wa, self.L_dmax).astype(L.dtype)
        # k exceeds 1 only for a dim display (L_dmax below about 2 cd/m²) and a dim world;
        # there the brightest floats saturate instead of overflowing
        return jnp.minimum(L * k, jnp.finfo(L.dtype).max)


__all__ = [
    "WARD1994",
    "Ward1994",
    "display_maximum",
    "log_average_adaptation",
    "ward1994_factor",
]
