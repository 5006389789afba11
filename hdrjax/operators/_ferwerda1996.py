"""Ferwerda, Pattanaik, Shirley & Greenberg 1996: a model of visual adaptation, as an operator.

Reference:
    J. A. Ferwerda, S. N. Pattanaik, P. Shirley, D. P. Greenberg. "A model of visual
    adaptation for realistic image synthesis." SIGGRAPH 1996, pp. 249–258.
    https://doi.org/10.1145/237170.237262

Equations (luminance in cd/m²). Threshold-versus-intensity curves of the cones and rods,
``ΔL = 10^t(log10 L_a)`` (:func:`hdrjax.vision.tvi_photopic`, :func:`~hdrjax.vision.tvi_scotopic`):

- cones: ``t_p = -0.72`` for ``x ≤ -2.6``, ``x - 1.255`` for ``x ≥ 1.9``, else
  ``(0.249 x + 0.65)^2.7 - 0.72``;
- rods: ``t_s = -2.86`` for ``x ≤ -3.94``, ``x - 0.395`` for ``x ≥ -1.44``, else
  ``(0.405 x + 1.6)^2.18 - 2.86`` (LuminanceHDR's port swaps the arguments of this power,
  ``2.18^(0.405 x + 1.6)``; this is the paper's form).

Matching thresholds between the world, adapted to ``L_wa``, and the display, adapted to
``L_da = L_dmax / 2``, gives the scale factors ``m_p = ΔL_p(L_da) / ΔL_p(L_wa)`` and
``m_s = ΔL_s(L_da) / ΔL_s(L_wa)``; the display luminance is
``L_d = m_p L_w + k m_s L_ws``, the cones' term in colour (``m_p`` times each channel) and
the rods' term achromatic, grey of luminance ``k m_s L_ws``, with ``L_ws`` the scotopic
luminance of the pixel (:func:`hdrjax.vision.scotopic_luminance`: Ward Larson et al.
1997's ``Y (1.33 (1 + (Y + Z)/X) − 1.68)``, from the image's primaries). The display value
is ``L_d / L_dmax``. ``L_wa`` defaults to half the largest world luminance, as in the paper.

Mesopic blend: ``k`` falls from 1 (rods alone) to 0 as the world adaptation rises; the
paper gives no formula, so hdrjax uses HDR Toolbox's default, Walraven & Valeton's rod
saturation ``k = max(0, (σ − L_wa/4) / (σ + L_wa))`` with ``σ = 100`` cd/m²: ``k = 0`` from
``L_wa = 400`` cd/m² up. The scale factor ``m_s`` is the one of HDR Toolbox and RenderPark
(both thresholds from the rod curve); tizian/tonemapper's 2022 version divides the cone
threshold at the display by the rod threshold of the world instead.

Departures of HDR Toolbox's ``FerwerdaTMO`` from the paper, reproduced by
``compat="hdrtoolbox"`` (for users comparing with it): the rods' term is computed from the
*photopic* luminance ``L_w`` instead of the scotopic one, and it is tinted per channel by
Durand & Dorsey 2000's night blue shift ``(1.05, 0.97, 1.27)`` instead of being grey.
"""

from typing import ClassVar, Literal

import jax.numpy as jnp
from jaxtyping import Array

from .._colour import luminance_weights
from .._photometry import scotopic_luminance
from .._stats import Statistics
from .._thresholds import tvi_photopic, tvi_scotopic
from ._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    bound_stats,
    chromaticities_field,
    estimated,
    fill,
    max_luminance,
    parameter,
    register,
)
from ._ward1994 import display_maximum

FERWERDA1996 = (
    "Ferwerda, Pattanaik, Shirley, Greenberg 1996, A model of visual adaptation for"
    " realistic image synthesis, SIGGRAPH 1996, https://doi.org/10.1145/237170.237262"
)
ROD_SATURATION = 100.0
"""cd/m²: ``σ`` of the Walraven–Valeton mesopic factor (HDR Toolbox ``WalravenValeton_k``)."""
BLUE_SHIFT = (1.05, 0.97, 1.27)
"""Durand & Dorsey 2000's tint of the rods' term (HDR Toolbox ``FerwerdaTMO``)."""
COMPAT = ("paper", "hdrtoolbox")


def walraven_valeton_k(L_wa: Array) -> Array:
    """Share of the rods' term, ``max(0, (σ − L_wa/4) / (σ + L_wa))``, ``σ = 100`` cd/m²."""
    return jnp.maximum((ROD_SATURATION - 0.25 * L_wa) / (ROD_SATURATION + L_wa), 0.0)


def ferwerda1996_factors(L_wa: Array, L_dmax: Array) -> tuple[Array, Array]:
    """``(m_p / L_dmax, k m_s / L_dmax)``: the display values of 1 cd/m² of photopic and of
    scotopic world luminance (module docstring)."""

    L_da = 0.5 * L_dmax
    m_p = tvi_photopic(L_da) / tvi_photopic(L_wa)
    m_s = tvi_scotopic(L_da) / tvi_scotopic(L_wa)
    return m_p / L_dmax, walraven_valeton_k(L_wa) * m_s / L_dmax


@register("ferwerda1996")
class Ferwerda1996(AbstractOperator):
    """Ferwerda et al. 1996 visual adaptation (module docstring): cones in colour, rods grey.

    Input: absolute RGB in cd/m² (HDR Toolbox's ``FerwerdaTMO`` also reads pixel values
    as cd/m²). Output: display-relative linear RGB, 1 at ``L_dmax``; linear in the pixel,
    so bright pixels exceed 1 (HDR Toolbox clamps to [0, 1]; hdrjax leaves that to the
    display encoding). Pixels with luminance ≤ 0 are black.

    Attributes:
        L_dmax: display maximum luminance, cd/m² (100; the display adaptation is half of it).
        L_wa: world adaptation luminance, cd/m²; ``None`` → half the largest finite
            luminance (the paper's choice, which HDR Toolbox notes may give dark images).
        compat: ``"paper"`` (default) or ``"hdrtoolbox"``: the rods' term from the photopic
            luminance, tinted ``(1.05, 0.97, 1.27)``, as HDR Toolbox's ``FerwerdaTMO``.
        chromaticities: the image's primaries as OpenEXR's 8-tuple (``None``: Rec.709 with
            D65); they give the luminance weights and the XYZ of the scotopic luminance.
    """

    reference: ClassVar[str] = FERWERDA1996
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_wa",)

    L_dmax: Array = display_maximum()
    L_wa: Array | None = estimated(
        "world adaptation luminance; None: half the largest luminance",
        unit="cd/m²",
        pooling="max",
    )
    compat: Literal["paper", "hdrtoolbox"] = parameter(
        "paper",
        help="paper, or hdrtoolbox: rods' term from the photopic luminance with a blue tint",
        static=True,
        choices=COMPAT,
    )
    chromaticities: tuple[float, ...] | None = chromaticities_field()

    @property
    def weights_(self) -> tuple[float, float, float]:
        return luminance_weights(self.chromaticities)

    def statistics_settings(self) -> StatisticsSettings | None:
        return None if self.L_wa is not None else StatisticsSettings()

    def bind(self, stats: Statistics | None) -> "Ferwerda1996":
        if self.L_wa is not None:
            return self
        return fill(self, L_wa=0.5 * max_luminance(bound_stats(self, stats)))

    def _apply(self, p: Prepared) -> Array:
        assert self.L_wa is not None
        dt = p.rgb.dtype
        cones, rods = (f.astype(dt) for f in ferwerda1996_factors(self.L_wa, self.L_dmax))
        if self.compat == "hdrtoolbox":
            tint = jnp.asarray(BLUE_SHIFT, dt).reshape((1,) * p.L.ndim + (3,))
            rod = p.L[..., None] * tint
        else:
            rod = scotopic_luminance(p.rgb, chromaticities=self.chromaticities)[..., None]
        top = jnp.finfo(dt).max
        # each term is finite; their sum may pass the float maximum: it saturates
        out = jnp.clip(cones * p.rgb + rods * rod, -top, top)
        return jnp.where((p.L > 0)[..., None], out, 0.0)


__all__ = [
    "BLUE_SHIFT",
    "FERWERDA1996",
    "ROD_SATURATION",
    "Ferwerda1996",
    "ferwerda1996_factors",
    "walraven_valeton_k",
]
