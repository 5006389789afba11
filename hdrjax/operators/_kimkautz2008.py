"""Kim, Kautz 2008 consistent tone reproduction: a Gaussian-weighted compression of log
luminance around its mean.

Reference:
    M. H. Kim, J. Kautz. "Consistent tone reproduction." Proceedings of the IASTED
    International Conference on Computer Graphics and Imaging (CGIM 2008). (No DOI.)

With ``x = ln(L + δ)`` the log luminance, ``μ`` its mean over the image, ``x_min``, ``x_max``
its extremes and ``d₀ = x_max − x_min``:

    ``k₁ = (ln L_dmax − ln L_dmin) / d₀``  (the display's log range over the image's),
    ``σ = d₀ / c₁``,  ``w(x) = exp(−(x − μ)² / (2σ²))``,
    ``k₂(x) = (1 − k₁) w(x) + k₁``,
    ``L_d = exp(c₂ k₂(x) (x − μ) + μ)``:

log luminance near the mean keeps more of its contrast (``k₂ → 1``), the tails are
compressed to the display's range (``k₂ → k₁``). These are the equations of HDR Toolbox's
``KimKautzConsistentTMO``, the reference peer, where ``L_d`` is then clamped to its values
at the 1st and 99th percentiles and stretched linearly to [0, 1]; colour is kept, ``C_out =
C · L_d / L``.
"""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array

from .._stats import DEFAULT_DELTA, Statistics
from ._base import (
    AbstractLuminanceCurve,
    StatisticsSettings,
    bound_stats,
    estimated,
    fill,
    max_luminance,
    parameter,
    register,
    weights_field,
)

REFERENCE = (
    "Kim, Kautz 2008, Consistent tone reproduction, Proceedings of the IASTED International"
    " Conference on Computer Graphics and Imaging (CGIM 2008)"
)


@register("kimkautz2008")
class KimKautz2008(AbstractLuminanceCurve):
    """Kim & Kautz 2008 consistent tone reproduction (module docstring), with HDR Toolbox's
    defaults (``KimKautzConsistentTMO``: display range 0.3–300 cd/m², ``c₁ = 3`` and
    ``c₂ = 0.5``, which it gives as the paper's, ``δ = 10⁻⁶`` inside the logarithm).

    Input: linear RGB, relative or cd/m²: the result depends on the image's log luminance
    only through differences and on the display only through ``L_dmax / L_dmin``, so the
    image's scale matters only through ``δ`` (with ``δ = 0`` the operator is scale
    invariant). Output: display-referred linear RGB; luminance in [0, 1] (the Toolbox
    applies display gamma separately, as :mod:`hdrjax.display` does).

    Departures from HDR Toolbox: its clamping values are the 1st and 99th percentiles of
    ``L_d`` over all pixels (sorted, the ``round(0.01 n)``-th value); here ``L_d`` of the
    1st and 99th percentiles of the positive luminance (histogram percentiles, relative
    error below 0.1 %, which merge over tiles and frames). The two agree where ``L_d``
    rises with ``L`` on the image's range, which holds whenever ``k₁ ≥ 0.31`` (an image
    spanning less than about 32 stops at the default display range) or the mean is far
    enough from both ends. Pixels whose luminance is 0 are black (the Toolbox divides 0 by
    0 and sets the NaN to 0: the same). An image whose two percentiles coincide (one
    luminance, or a lamp in the dark) maps that luminance to 1 where the Toolbox divides
    by zero and returns black.

    Attributes:
        L_dmax, L_dmin: the display's largest and smallest luminance, cd/m² (300, 0.3);
            only their ratio matters.
        c1: ``c₁``: the Gaussian weight's width is the image's log range over ``c₁`` (3).
        c2: ``c₂``: overall contrast of the log luminance (0.5).
        log_average: ``exp(μ)``, the log-average ``exp(mean(ln(L + δ)))``; ``None`` →
            measured.
        L_min, L_max: smallest and largest luminance (``x_min = ln(L_min + δ)``);
            ``None`` → measured.
        L_low, L_high: luminances whose ``L_d`` map to 0 and 1; ``None`` → the 1st and
            99th percentiles of the positive luminance.
        delta: ``δ``, offset inside the logarithm (HDR Toolbox's 1e-6), image units.
        weights: luminance weights of the image's primaries (Rec.709 default).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("c1", "c2")

    L_dmax: Array = parameter(
        300.0, help="display's largest luminance", unit="cd/m²", range="(0, inf)"
    )
    L_dmin: Array = parameter(
        0.3, help="display's smallest luminance", unit="cd/m²", range="(0, inf)"
    )
    c1: Array = parameter(
        3.0, help="c1: Gaussian weight's width is the image's log range over c1", range="(0, inf)"
    )
    c2: Array = parameter(0.5, help="c2: overall contrast of log luminance", range="(0, inf)")
    log_average: Array | None = estimated(
        "log-average exp(mean(ln(L + delta))); None: measured",
        unit="image units",
        pooling="log_mean",
    )
    L_min: Array | None = estimated(
        "smallest luminance; None: measured", unit="image units", range="[0, inf)", pooling="min"
    )
    L_max: Array | None = estimated(
        "largest luminance; None: measured", unit="image units", pooling="max"
    )
    L_low: Array | None = estimated(
        "luminance whose L_d maps to 0; None: 1st percentile",
        unit="image units",
        pooling="log_mean",
    )
    L_high: Array | None = estimated(
        "luminance whose L_d maps to 1; None: 99th percentile",
        unit="image units",
        pooling="log_mean",
    )
    delta: float = parameter(
        DEFAULT_DELTA,
        help="offset inside the logarithm (HDR Toolbox's 1e-6)",
        unit="image units",
        range="[0, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings(delta=self.delta) if self.unset() else None

    def bind(self, stats: Statistics | None) -> "KimKautz2008":
        if not self.unset():
            return self
        st = bound_stats(self, stats)
        measured = {
            "log_average": st.log_average,
            "L_min": jnp.maximum(st.min, 0.0),
            "L_max": max_luminance(st),
            "L_low": st.p01,
            "L_high": st.p99,
        }
        return fill(self, **{k: v for k, v in measured.items() if getattr(self, k) is None})

    def _log(self, L: Array) -> Array:
        """``ln(L + δ)``, floored where it would be ``ln 0``."""
        tiny = jnp.finfo(jnp.result_type(L)).tiny
        return jnp.log(jnp.maximum(L + self.delta, tiny))

    def _exponent(self, x: Array) -> Array:
        """``c₂ k₂(x) (x − μ)``: ``ln L_d − μ`` of log luminance ``x``."""
        assert self.log_average is not None and self.L_min is not None
        assert self.L_max is not None
        dtype = jnp.result_type(x)
        tiny = jnp.finfo(dtype).tiny
        mu = jnp.log(jnp.maximum(self.log_average.astype(dtype), tiny))
        d0 = self._log(self.L_max.astype(dtype)) - self._log(self.L_min.astype(dtype))
        ok = d0 > 0
        d0 = jnp.where(ok, d0, 1.0)
        k1 = jnp.where(ok, (jnp.log(self.L_dmax) - jnp.log(self.L_dmin)).astype(dtype) / d0, 1.0)
        sigma = d0 / self.c1.astype(dtype)
        u = x - mu
        w = jnp.exp(-0.5 * jnp.square(u / sigma))
        return self.c2.astype(dtype) * ((1.0 - k1) * w + k1) * u

    def _curve(self, L: Array) -> Array:
        assert self.L_low is not None and self.L_high is not None
        dtype = L.dtype
        g_lo = self._exponent(self._log(self.L_low.astype(dtype)))
        g_hi = self._exponent(self._log(self.L_high.astype(dtype)))
        g = jnp.clip(self._exponent(self._log(L)), g_lo, g_hi)
        # (L_d − L_d,lo) / (L_d,hi − L_d,lo) with exp(μ) divided out of all three
        span = -jnp.expm1(g_lo - g_hi)
        ok = span > 0
        out = (jnp.exp(g - g_hi) - jnp.exp(g_lo - g_hi)) / jnp.where(ok, span, 1.0)
        return jnp.where(ok, jnp.clip(out, 0.0, 1.0), 1.0)


__all__ = ["KimKautz2008"]
