"""Revised Tumblin–Rushmeier (Tumblin 1999) and the Barladian et al. nonlinear operator.

References:
    Tumblin, Hodgins, Guenter. "Two methods for display of high contrast images." ACM TOG
    18(1), 1999. https://doi.org/10.1145/300776.300783
    Birukov, Barladian, Denisov, Voloboy. "Implementation of high dynamic range image
    processing module as a part of lighting simulation software system." GraphiCon 2022
    (formulas 1 and 2).
    Reinhard et al. 2002, https://doi.org/10.1145/566654.566575 (formula 2).

Formula 1 (Tumblin, Hodgins & Guenter 1999's revised Tumblin–Rushmeier operator, as
Birukov et al. 2022 use it), absolute luminance in cd/m²:
    ``γ(L) = 2.655`` for L > 100 cd/m², else ``1.855 + 0.4 log10(L + 2.3·10⁻⁵)``;
    ``γ_w = γ(L_wa)``, ``γ_d = γ(L_da)``, ``γ_wd = γ_w / (1.855 + 0.4 ln L_da)``,
    ``m = C_max^((γ_wd − 1) / 2)``, ``L_d = m L_da (L_w / L_wa)^(γ_w / γ_d)``.

The natural log in ``γ_wd`` is deliberate: colour-hdri, HDR Toolbox and RenderPark all use
``ln`` there, and matching them (to 1e-7 in the tests) matters more to users switching tools
than the paper's typesetting, which is unverified; with ``log10`` the denominator would be
``γ_d`` itself for ``L_da ≤ 100``. ``gamma_log="log10"`` selects the other reading.
"""

import math
from typing import ClassVar, Literal

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._scale import divide
from .._stats import Statistics
from ._base import (
    AbstractLuminanceCurve,
    StatisticsSettings,
    checked_statistics,
    estimated,
    fill,
    max_luminance,
    parameter,
    register,
    safe_log,
    traced,
    weights_field,
)
from ._reinhard2002 import reinhard_curve

STEVENS_EPS = 2.3e-5
TUMBLIN1999 = (
    "Tumblin, Hodgins, Guenter 1999, Two methods for display of high contrast images,"
    " ACM TOG 18(1), https://doi.org/10.1145/300776.300783"
)


def _world_adaptation():
    return estimated(
        "world adaptation luminance; None: measured (adaptation)", unit="cd/m²", pooling="log_mean"
    )


def stevens_gamma(L: Array) -> Array:
    """Stevens' contrast-sensitivity exponent ``γ(L)`` (cd/m²)."""
    return jnp.where(L > 100, 2.655, 1.855 + 0.4 * jnp.log10(jnp.maximum(L, 0.0) + STEVENS_EPS))


def tumblin_curve(
    L_w: Array, L_wa: Array, L_da: Array, C_max: Array, gamma_log: str = "ln"
) -> Array:
    """Formula 1: display luminance (cd/m²) of world luminance ``L_w`` (cd/m², ≥ 0)."""
    g_w = stevens_gamma(L_wa)
    g_d = stevens_gamma(L_da)
    den = 1.855 + 0.4 * (jnp.log(L_da) if gamma_log == "ln" else jnp.log10(L_da))
    g_wd = g_w / den
    # m L_da in logarithms: C_max^((γ_wd − 1) / 2) overflows for a dim display adaptation
    # (γ_wd grows as the denominator nears 0, at L_da ≈ 0.0097 cd/m² with ln)
    ln_scale = (g_wd - 1.0) / 2.0 * jnp.log(C_max) + jnp.log(L_da)
    return ratio_power(L_w, L_wa, g_w / g_d, ln_scale)


def ratio_power(L_w: Array, L_wa: Array, exponent: Array, ln_scale: Array) -> Array:
    """``e^ln_scale · (L_w / L_wa)^exponent`` for ``L_w ≥ 0`` (0 at ``L_w = 0``), the power
    law of both Tumblin–Rushmeier operators, evaluated as one exponential that saturates
    1 % below the float maximum: finite for every ``L_w`` of the float type and every
    scale (an exponent above 1, an adaptation brighter than the display's, or a large
    scale would otherwise leave the float range; a no-op for every representable result)."""
    ratio = divide(jnp.maximum(L_w, 0.0), L_wa)  # no reciprocal of L_wa: it may be subnormal
    pos = ratio > 0
    big = jnp.log(jnp.finfo(ratio.dtype).max) - 0.01
    ln_out = exponent * safe_log(ratio) + ln_scale
    return jnp.where(pos, jnp.exp(jnp.minimum(ln_out, big)), 0.0)


def adaptation_terms(stats: Statistics, method: str) -> tuple[Array, dict[str, Array]]:
    """:func:`adaptation_luminance` and the statistics it used: ``n_pixels`` (the pixels
    averaged) and, for ``"trimmed"``, ``p01``/``p99`` (the kept range) and their
    ``rel_error_bound`` (histogram percentiles). ``stats``: measured with
    ``delta=STEVENS_EPS`` (:func:`adaptation_settings`)."""
    st = stats.luminance_stats()
    if method == "log_average":
        n = jnp.maximum(stats.n_finite, 1)
        return st.log_average, {"n_pixels": n}
    value, n_kept, p01, p99 = stats.band_log_average(0.01, 0.99)
    terms = {"n_pixels": n_kept, "p01": p01, "p99": p99}
    return value, {**terms, "rel_error_bound": st.rel_error_bound}


def adaptation_settings(bins: int) -> StatisticsSettings:
    """The statistics :func:`adaptation_terms` reads."""
    return StatisticsSettings(bins=bins, delta=STEVENS_EPS)


def adaptation_luminance(stats: Statistics, method: str) -> Array:
    """World adaptation luminance: ``exp(mean(ln(L + 2.3e-5)))`` over finite pixels
    (colour-hdri, HDR Toolbox), or ``"trimmed"``: the log-average of the positive pixels
    between the 1st and 99th percentiles (robust to a few lamps or dark corners), from the
    histogram."""
    return adaptation_terms(stats, method)[0]


_ADAPT = ("log_average", "trimmed")


class _AbstractTumblin(AbstractLuminanceCurve):
    """Settings shared by the two Tumblin–Rushmeier operators (display side and estimation)."""

    reference: ClassVar[str] = TUMBLIN1999
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_wa",)

    L_da: Array = parameter(
        20.0, help="display adaptation luminance (10-30 typical)", unit="cd/m²", range="(0, inf)"
    )
    C_max: Array = parameter(100.0, help="display contrast L_max / L_min", range="[1, inf)")
    adaptation: Literal["log_average", "trimmed"] = parameter(
        "log_average",
        help="how L_wa is measured: log_average, or trimmed (P1-P99 log-average)",
        static=True,
        choices=_ADAPT,
    )
    gamma_log: Literal["ln", "log10"] = parameter(
        "ln",
        help="logarithm in γ_wd's denominator: ln (colour-hdri, HDR Toolbox) or log10",
        static=True,
        choices=("ln", "log10"),
    )
    bins: int = parameter(
        8192,
        help="histogram resolution of the trimmed adaptation's percentiles",
        range="[1, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        if traced(self):
            return
        # γ_wd's denominator 1.855 + 0.4 log(L_da) must be positive
        pole = math.exp(-1.855 / 0.4) if self.gamma_log == "ln" else 10 ** (-1.855 / 0.4)
        L_da = np.asarray(self.L_da)
        if np.any(L_da <= pole):
            raise ValueError(
                f"L_da: expected a display adaptation above {pole:.3g} cd/m² (gamma_log"
                f"={self.gamma_log!r}: 1.855 + 0.4 {self.gamma_log}(L_da) must be positive),"
                f" got {', '.join(f'{v:.3g}' for v in L_da.ravel())}"
            )


@register("tumblin1999")
class Tumblin1999(_AbstractTumblin):
    """Revised Tumblin–Rushmeier operator, formula 1 only, display value ``L_d / L_max``.

    Same function as colour-hdri's ``tonemapping_operator_Tumblin1999`` (its ``L_max`` is
    the display's maximum luminance). Input: absolute RGB in cd/m². Output: display-relative
    linear RGB (may exceed 1: this operator does not compress highlights).

    Attributes:
        L_da: display adaptation luminance, cd/m² (20).
        C_max: display contrast (100).
        L_max: display maximum luminance, cd/m² (100).
        L_wa: world adaptation luminance, cd/m²; ``None`` → measured (``adaptation``).
    """

    default_fit_params: ClassVar[tuple[str, ...]] = ("L_wa", "L_max")

    L_max: Array = parameter(
        100.0, help="display maximum luminance", unit="cd/m²", range="(0, inf)"
    )
    L_wa: Array | None = _world_adaptation()

    def statistics_settings(self) -> StatisticsSettings | None:
        return None if self.L_wa is not None else adaptation_settings(self.bins)

    def bind(self, stats: Statistics | None) -> "Tumblin1999":
        if self.L_wa is not None:
            return self
        stats = checked_statistics(self, stats)
        return fill(self, L_wa=adaptation_luminance(stats, self.adaptation))

    def _curve(self, L: Array) -> Array:
        assert self.L_wa is not None
        return tumblin_curve(L, self.L_wa, self.L_da, self.C_max, self.gamma_log) / self.L_max


@register("tumblin_reinhard")
class TumblinReinhard(_AbstractTumblin):
    """Birukov et al. 2022 nonlinear operator: formula 1 followed by Reinhard's formula 2.

    ``L_d = T(L_w) / L_dmax`` with ``T`` the revised Tumblin–Rushmeier curve (formula 1),
    then ``L_df = L_d (1 + L_d / L_white²) / (1 + L_d)`` (formula 2). The user controls the
    two quantities Birukov et al. name: the scene adaptation luminance ``L_wa`` and the
    maximum world luminance that is not clipped, ``L_max``; by default
    ``L_white = T(L_max) / L_dmax`` so that exactly ``L_max`` maps to display white (1.0)
    and brighter pixels clip.

    Input: absolute RGB in cd/m² (relative images work, but ``L_wa`` then changes the
    contrast exponent: pass a scale). Output: display-referred linear RGB in [0, 1] for
    ``L_w ≤ L_max``.

    Attributes:
        L_wa: world adaptation luminance, cd/m²; ``None`` → measured (``adaptation``).
        L_max: largest world luminance not clipped, cd/m²; ``None`` → the image maximum.
        L_white: formula 2's white in display units; ``None`` → ``T(L_max) / L_dmax``.
        L_da: display adaptation luminance, cd/m² (20; Birukov et al. 2022 quote 10–30).
        C_max: display contrast (100). L_dmax: display maximum luminance, cd/m² (100).
        adaptation: ``"log_average"`` (default) or ``"trimmed"`` (P1–P99 log-average).
        gamma_log: ``"ln"`` (default; see module docstring) or ``"log10"``.
    """

    reference: ClassVar[str] = (
        TUMBLIN1999 + "; Reinhard et al. 2002, https://doi.org/10.1145/566654.566575;"
        " Birukov, Barladian, Denisov, Voloboy 2022, GraphiCon 2022"
    )
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_wa", "L_white")
    only_feeds: ClassVar[dict[str, str]] = {"L_max": "L_white"}

    L_wa: Array | None = _world_adaptation()
    L_max: Array | None = estimated(
        "largest world luminance not clipped; None: the image maximum", unit="cd/m²", pooling="max"
    )
    L_white: Array | None = estimated(
        "formula 2's white; None: T(L_max) / L_dmax",
        unit="display units",
        range="(0, inf]",
        pooling="log_mean",
    )
    L_dmax: Array = parameter(
        100.0, help="display maximum luminance", unit="cd/m²", range="(0, inf)"
    )

    def statistics_settings(self) -> StatisticsSettings | None:
        if self.L_wa is not None and self.L_max is not None:
            return None  # (L_white follows from them)
        return adaptation_settings(self.bins)

    def bind(self, stats: Statistics | None) -> "TumblinReinhard":
        if not self.unset():
            return self
        L_wa, L_max = self.L_wa, self.L_max
        if L_wa is None or L_max is None:
            stats = checked_statistics(self, stats)
            if L_wa is None:
                L_wa = adaptation_luminance(stats, self.adaptation)
            if L_max is None:
                L_max = max_luminance(stats.luminance_stats())
        L_white = self.L_white
        if L_white is None:
            t = tumblin_curve(L_max, L_wa, self.L_da, self.C_max, self.gamma_log) / self.L_dmax
            L_white = jnp.maximum(t, jnp.finfo(t.dtype).tiny)
        return fill(self, L_wa=L_wa, L_max=L_max, L_white=L_white)

    def _curve(self, L: Array) -> Array:
        assert self.L_wa is not None and self.L_white is not None
        L_d = tumblin_curve(L, self.L_wa, self.L_da, self.C_max, self.gamma_log)
        return reinhard_curve(L_d / self.L_dmax, self.L_white)


__all__ = [
    "STEVENS_EPS",
    "Tumblin1999",
    "TumblinReinhard",
    "adaptation_luminance",
    "adaptation_terms",
    "ratio_power",
    "stevens_gamma",
    "tumblin_curve",
]
