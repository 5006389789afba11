"""Drago, Myszkowski, Annen, Chiba 2003 adaptive logarithmic mapping.

Reference:
    Drago, Myszkowski, Annen, Chiba. "Adaptive logarithmic mapping for displaying high
    contrast scenes." Computer Graphics Forum 22(3) (Eurographics 2003).
    https://doi.org/10.1111/1467-8659.00689

The paper's Eq. 4, on luminance divided by the world adaptation luminance ``L_wa`` (the
log-average ``exp(mean(ln(L + δ)))``):
    ``x = L / L_wa``, ``x_max = L_max / L_wa``, ``p = ln b / ln 0.5``,
    ``L_d = (L_dmax / 100) / log10(1 + x_max) · ln(1 + x) / ln(2 + 8 (L / L_max)^p)``,
colour kept (``C_out = C · L_d / L``). The maximum maps to ``L_dmax / 100`` (1 for the
paper's 100 cd/m² display). The bias ``b`` sets the base of the logarithm between log2 for
dark pixels and log10 at the maximum. The paper divides ``L_wa`` by ``(1 + b − 0.85)^5``
so that a change of bias leaves the brightness about the same (1 at the default 0.85).
"""

import math
from typing import ClassVar, Literal

import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._scale import divide
from .._stats import Statistics
from ._base import (
    AbstractLuminanceCurve,
    Prepared,
    StatisticsSettings,
    bound_stats,
    estimated,
    fill,
    max_luminance,
    parameter,
    register,
    scale_by_luminance,
    weights_field,
)

REFERENCE = (
    "Drago, Myszkowski, Annen, Chiba 2003, Adaptive logarithmic mapping for displaying high"
    " contrast scenes, Computer Graphics Forum 22(3), https://doi.org/10.1111/1467-8659.00689"
)
PFSTMO_DELTA = 1e-4
"""pfstmo's offset inside the log-average (``ln(Y + 1e-4)``), image units."""


@register("drago2003")
class Drago2003(AbstractLuminanceCurve):
    """Drago et al. 2003 adaptive logarithmic mapping of luminance (module docstring),
    with pfstmo's defaults and normalisation (``pfstmo_drago03``: bias 0.85, luminance
    divided by the log-average with offset 1e-4, maximum mapped to 1).

    Input: linear RGB; the paper's luminance is in cd/m², but only ``delta`` (an absolute
    offset inside the log-average) depends on the scale. Output: display-referred linear
    RGB, ``L_d ∈ [0, L_dmax / 100]`` (channels of saturated colours exceed it and clip when
    encoded). The paper's display step (a gamma curve with a linear toe) is display
    encoding, not part of the operator (:mod:`hdrjax.display`).

    ``compat="pfstmo"``: pfstmo (like OpenCV's ``TonemapDrago``) leaves out the paper's
    bias adjustment of ``L_wa``, ``(1 + b − 0.85)^5``, so a bias other than 0.85 also
    changes the overall brightness there; the default (``"paper"``) applies it, as the
    paper, Banterle's HDR Toolbox and Zeltner's tonemapper do. At the default bias both
    are the same. Not reproduced: pfstmo writes NaN for black pixels (0/0) and its
    statistics are NaN with negative luminance (black here, clamped to 0).

    OpenCV's ``TonemapDrago`` maps the same curve after stretching the input to [0, 1]
    (min–max over all channel values), uses Rec.601 luma, a log-average floored at 1e-4
    instead of offset, no ``1 / log10(1 + x_max)`` factor, and stretches the output to
    [0, 1] before its gamma and saturation: with those steps around it, this operator
    gives OpenCV's result.

    Attributes:
        bias: ``b`` of the bias power function, 0 … 1 (0.85; 0.7–0.9 the useful range).
        L_dmax: the display's maximum luminance: ``L_max`` maps to ``L_dmax / 100``.
        log_average: world adaptation luminance ``L_wa``; ``None`` → measured with delta.
        L_max: the largest world luminance; ``None`` → measured.
        delta: offset inside the log-average (pfstmo's 1e-4, image units).
        compat: ``"paper"`` or ``"pfstmo"`` (see above).
        weights: luminance weights of the image's primaries.
    """

    reference: ClassVar[str] = REFERENCE
    default_fit_params: ClassVar[tuple[str, ...]] = ("bias", "log_average")

    bias: Array = parameter(
        0.85, help="bias b: the logarithm's base from log2 (dark) to log10 (max)", range="(0, 1)"
    )
    L_dmax: Array = parameter(
        100.0,
        help="display's maximum luminance: the image's maximum maps to L_dmax / 100",
        unit="cd/m²",
        range="(0, inf)",
    )
    log_average: Array | None = estimated(
        "world adaptation luminance L_wa, the log-average; None: measured with delta",
        unit="image units",
        pooling="log_mean",
    )
    L_max: Array | None = estimated(
        "largest world luminance; None: measured", unit="image units", pooling="max"
    )
    delta: float = parameter(
        PFSTMO_DELTA,
        help="offset inside the log-average (pfstmo's 1e-4)",
        unit="image units",
        range="[0, inf)",
        static=True,
    )
    compat: Literal["paper", "pfstmo"] = parameter(
        "paper",
        help="paper: L_wa / (1 + b - 0.85)^5; pfstmo: L_wa as measured (pfstmo_drago03)",
        static=True,
        choices=("paper", "pfstmo"),
    )
    weights: tuple[float, float, float] = weights_field()

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings(delta=self.delta) if self.unset() else None

    def bind(self, stats: Statistics | None) -> "Drago2003":
        if not self.unset():
            return self
        st = bound_stats(self, stats)
        measured = {"log_average": st.log_average, "L_max": max_luminance(st)}
        return fill(self, **{k: v for k, v in measured.items() if getattr(self, k) is None})

    def _curve(self, L: Array) -> Array:
        return self._relative_curve(L / self.L_max)

    def _relative_curve(self, x: Array) -> Array:
        """``L_d`` of ``x = L / L_max`` (``> 0``): the curve depends on ``L`` only through
        ``x`` and ``x_max = L_max / L_wa``."""
        assert self.log_average is not None and self.L_max is not None
        ln_wa = jnp.log(self.log_average)
        if self.compat == "paper":
            ln_wa = ln_wa - 5.0 * jnp.log(1.0 + self.bias - 0.85)
        ln_x_max = jnp.log(self.L_max) - ln_wa
        top = jnp.finfo(x.dtype).max
        x_max = jnp.exp(jnp.minimum(ln_x_max, math.log(top)))
        p = jnp.log(self.bias) / math.log(0.5)
        # ln(1 + x x_max): x ≤ 1 but for pixels above a given L_max, so x x_max overflows
        # only where x_max nearly does; (x^p) with its exponent capped below exp's overflow
        numerator = jnp.log1p(jnp.minimum(x * x_max, top))
        base = jnp.log(2.0 + 8.0 * jnp.exp(jnp.minimum(p * jnp.log(x), 80.0)))
        norm = jax.nn.softplus(ln_x_max) / math.log(10.0)  # log10(1 + x_max), no overflow
        tiny = jnp.finfo(numerator.dtype).tiny
        return (self.L_dmax / 100.0) * numerator / (base * jnp.maximum(norm, tiny))

    def _apply(self, p: Prepared) -> Array:
        # the curve on L / L_max (as Schlick1994 does): the shared mapping's luminance floor
        # is then relative to the image's maximum. On L itself, an image dimmer than the
        # floor (1.1e-19 in float32) had its ratio L_d / L taken at a floor far above
        # L_max, where (L / L_max)^p is no longer small: wrong, and Inf in float32.
        return scale_by_luminance(
            divide(p.rgb, self.L_max), divide(p.L, self.L_max), self._relative_curve
        )


__all__ = ["PFSTMO_DELTA", "Drago2003"]
