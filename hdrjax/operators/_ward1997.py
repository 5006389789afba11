"""Ward Larson, Rushmeier, Piatko 1997 histogram adjustment (the tone curve of Radiance's
``pcond``) with the linear or the human-contrast ceiling.

Reference:
    G. Ward Larson, H. Rushmeier, C. Piatko. "A visibility matching tone reproduction
    operator for high dynamic range scenes." IEEE Transactions on Visualization and
    Computer Graphics 3(4), 1997, pp. 291–306. https://doi.org/10.1109/2945.646233

Equations (luminance in cd/m², ``ln`` natural logarithms):

* brightness ``B_w = ln L_w``; a histogram ``f(b_i)`` of ``B_w`` with ``N`` equal bins
  (the paper's 100) over ``[ln L_min, ln L_max]``, bin width ``Δb``, total ``T = Σ f``;
* the linear ceiling: no bin may hold more than
  ``f(b_i) ≤ T Δb / (ln L_dmax − ln L_dmin)``, so that nowhere does the tone curve's slope
  ``d ln L_d / d ln L_w`` exceed 1 (no contrast is exaggerated beyond a linear mapping).
  Truncating bins lowers ``T`` and so the ceiling: the truncation is repeated until the
  pixels trimmed in one step are at most 2.5 % of the histogram's original total;
* the human-contrast ceiling (``ceiling="human"``): no contrast is more visible
  on the display than in the world, ``f(b_i) ≤ T Δb [ΔL_t(L_d) / ΔL_t(L_w)] L_w /
  (L_d (ln L_dmax − ln L_dmin))`` with ``L_w = e^{b_i}`` the bin's centre, ``L_d`` its
  display luminance under the current curve (the cumulative count at the bin's middle) and
  ``ΔL_t`` the combined rod and cone threshold-versus-intensity curve of Ferwerda et al.
  1996 (:func:`hdrjax._photometry.tvi`, pcond's ``htcontrs``); ``L_d`` is recomputed at
  every truncation step;
* the cumulative distribution ``P(b) = Σ_{b_i < b} f(b_i) / T`` as tone curve:
  ``ln L_d = ln L_dmin + (ln L_dmax − ln L_dmin) P(ln L_w)``;
* display value ``(L_d − L_dmin) / (L_dmax − L_dmin)`` (as ``pcond`` and HDR Toolbox
  write it), colour kept: ``C_out = C_in · value / L_w``.

Relation to :mod:`hdrjax.vision`: Radiance's ``pcond`` applies this histogram adjustment
after its human-vision effects (veiling glare, loss of acuity and of colour vision in the
dark), which hdrjax implements separately in :mod:`hdrjax.vision` (``veil``, ``acuity``,
``colour_loss``, with the same threshold curve ``tvi``): apply those to the cd/m² image
first and this operator (``ceiling="human"``) to the result for pcond's pipeline. Not
reproduced from ``pcond``: its sampling of the histogram (foveal samples plus random
pixels; here every pixel counts), its world limits 10⁻⁷–10⁷ cd/m², its ``L_max`` × 1.01,
and its fall-back to a linear mapping when the scene's range fits the display or the
truncation empties the histogram (here, as in HDR Toolbox, the curve is what is left).
"""

from collections.abc import Callable
from typing import ClassVar, Literal

import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._interp import table_lerp
from .._photometry import tvi
from .._scale import divide
from .._stats import Statistics, coarse_counts
from ._base import (
    AbstractLuminanceCurve,
    Prepared,
    StatisticsSettings,
    bound_stats,
    checked_statistics,
    estimated,
    fill,
    max_luminance,
    parameter,
    register,
    scale_by_luminance,
    traced,
    weights_field,
)

REFERENCE = (
    "Ward Larson, Rushmeier, Piatko 1997, A visibility matching tone reproduction operator"
    " for high dynamic range scenes, IEEE TVCG 3(4), pp. 291-306,"
    " https://doi.org/10.1109/2945.646233"
)
TOLERANCE = 0.025
"""The ceiling's truncation stops once one step trims at most this fraction of the pixels."""
MAX_STEPS = 64
"""Steps of the truncation loop (a fixed count, so reverse-mode gradients exist); steps
after convergence leave the histogram as it is (real images converge in fewer than 20)."""
MIN_SPAN = 1e-4
"""Smallest ``ln(L_max / L_min)`` (an image of one luminance), so the bins have a width."""


@register("ward1997")
class Ward1997(AbstractLuminanceCurve):
    """Ward Larson et al. 1997 histogram adjustment (module docstring).

    Input: RGB in cd/m² (the human-contrast ceiling and the display range are absolute;
    with the linear ceiling the curve depends on the image only through ``L / L_min`` and
    the histogram). Output: display-relative linear RGB, ``(L_d − L_dmin) / (L_dmax −
    L_dmin) ∈ [0, 1]``; channels of saturated colours exceed 1 and clip when encoded.

    The histogram comes from the mergeable image statistics (:class:`hdrjax._stats.Statistics`,
    a fixed grid of 1024 bins per octave, ``counts``): each fine bin is assigned, at its
    geometric centre, to one of the ``n_bins`` bins between the measured ``L_min`` and
    ``L_max`` (a pixel is off by at most half a fine bin, 0.05 % in luminance), so tiles,
    chunks and frames merge exactly. Pixels with ``L ≤ 0`` are not counted (and are black).
    Because of that fine grid the operator is scale invariant only to one fine bin.

    Tone curve and gradients: the curve is the cumulative histogram interpolated linearly
    between its nodes, evaluated at each pixel's ``ln L``; gradients with respect to the
    image flow through that interpolation (the local slope of the curve) and through the
    measured ``L_min`` and ``L_max`` (the bin edges); the histogram's counts are constants
    for ``jax.grad`` (the paper's histogram is piecewise constant in the pixels). The
    truncation runs a fixed :data:`MAX_STEPS` steps (converged steps change nothing), so it
    is differentiable in ``L_dmin``, ``L_dmax`` and the extrema.

    ``compat``:

    * ``"paper"`` (default): the cumulative distribution at the ``n_bins + 1`` bin edges,
      0 at ``L_min`` and 1 at ``L_max``, interpolated linearly between (as Radiance's
      ``pcond`` does).
    * ``"hdrtoolbox"``: HDR Toolbox's ``WardHistAdjTMO``: the cumulative count up to and
      including bin ``i`` placed at ``ln L_min + i (ln L_max − ln L_min) / (n_bins − 1)``
      (``n_bins`` nodes, the first one above 0).

    Departures from HDR Toolbox: it bins ``ln(L + 10⁻⁶)`` (a black pixel sets ``L_min`` to
    10⁻⁶ cd/m²; here black pixels are left out of the range and the histogram), leaves
    pixels dimmer than ``L_min + 10⁻⁶`` out of its curve's range (NaN, written as black;
    here they take the curve's lowest value) and adds 10⁻⁶ to ``L_dmin`` and ``L_dmax``
    inside the logarithms. The paper's foveal downsampling of the image before the
    histogram (Toolbox option ``bDownsampling``, off by default) is not applied.

    Attributes:
        n_bins: histogram bins over ``[ln L_min, ln L_max]`` (the paper's 100).
        L_dmin, L_dmax: the display's darkest and brightest luminance, cd/m² (HDR Toolbox's
            1 and 100).
        L_min, L_max: the range of the histogram, cd/m²; ``None`` → the smallest positive
            and the largest finite luminance.
        ceiling: ``"linear"`` (the default, as HDR Toolbox) or ``"human"`` (the paper's
            human-contrast ceiling, as ``pcond -h``).
        cdf: the tone curve's table, the (truncated) cumulative histogram (``n_bins + 1``
            values for ``"paper"``, ``n_bins`` for ``"hdrtoolbox"``); ``None`` → measured.
        compat: ``"paper"`` or ``"hdrtoolbox"`` (see above).
        weights: luminance weights of the image's primaries.
    """

    reference: ClassVar[str] = REFERENCE
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_dmin",)
    cheap_curve: ClassVar[bool] = False  # a table lookup per pixel

    n_bins: int = parameter(
        100,
        help="histogram bins over [ln L_min, ln L_max] (the paper's 100)",
        range="[2, inf)",
        static=True,
        converter=int,
    )
    L_dmin: Array = parameter(
        1.0, help="display's darkest luminance", unit="cd/m²", range="(0, inf)"
    )
    L_dmax: Array = parameter(
        100.0, help="display's brightest luminance", unit="cd/m²", range="(0, inf)"
    )
    L_min: Array | None = estimated(
        "lower end of the histogram; None: the smallest positive luminance",
        unit="cd/m²",
        pooling="min",
    )
    L_max: Array | None = estimated(
        "upper end of the histogram; None: the largest luminance", unit="cd/m²", pooling="max"
    )
    cdf: Array | None = estimated(
        "the tone curve's table, the truncated cumulative histogram; None: measured",
        range="[0, 1]",
        pooling="mean",
        shape=None,
    )
    ceiling: Literal["linear", "human"] = parameter(
        "linear",
        help="linear: no contrast above a linear mapping's; human: no contrast more visible"
        " than in the world (threshold-versus-intensity of the world and display luminance)",
        static=True,
        choices=("linear", "human"),
    )
    compat: Literal["paper", "hdrtoolbox"] = parameter(
        "paper",
        help="paper: the cumulative histogram at the bin edges (as pcond); hdrtoolbox: at"
        " HDR Toolbox WardHistAdjTMO's nodes",
        static=True,
        choices=("paper", "hdrtoolbox"),
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        if self.n_bins < 2:
            raise ValueError(f"n_bins: expected an integer of at least 2, got {self.n_bins}")
        if not traced(self.L_dmin, self.L_dmax) and not bool(jnp.all(self.L_dmin < self.L_dmax)):
            raise ValueError(
                f"L_dmin: expected less than L_dmax ({float(self.L_dmax)} cd/m²), got"
                f" {float(self.L_dmin)}"
            )

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings() if self.unset() else None

    def bind(self, stats: Statistics | None) -> "Ward1997":
        if not self.unset():
            return self
        st = bound_stats(self, stats)
        L_min = st.min_positive if self.L_min is None else self.L_min
        L_max = max_luminance(st) if self.L_max is None else self.L_max
        measured = {"L_min": L_min, "L_max": L_max}
        if self.cdf is None:
            full = checked_statistics(self, stats)
            assert full.counts is not None and full.m is not None
            measured["cdf"] = self._cdf(
                full.counts, full.m, jnp.log(L_min), self._span(L_min, L_max)
            )
        return fill(self, **{k: v for k, v in measured.items() if getattr(self, k) is None})

    @staticmethod
    def _span(L_min: Array, L_max: Array) -> Array:
        """``ln(L_max / L_min)``, at least :data:`MIN_SPAN`."""
        return jnp.maximum(jnp.log(L_max) - jnp.log(L_min), MIN_SPAN)

    def _cdf(self, counts: Array, m: int, ln_min: Array, span: Array) -> Array:
        """The tone curve's table from the fixed-grid histogram (class docstring)."""
        dt = ln_min.dtype
        n = self.n_bins
        hist = coarse_counts(counts, m, ln_min, span, n)
        db = span / n
        B_d = jnp.log(self.L_dmax / self.L_dmin).astype(dt)  # B_dmax - B_dmin
        if self.ceiling == "linear":
            hist = _truncate(hist, lambda h: jnp.sum(h) * db / B_d)
        else:
            ln_w = ln_min + (jnp.arange(n, dtype=dt) + 0.5) * db  # bin centres
            t_w = jnp.log(tvi(jnp.exp(ln_w)))
            ln_dmin = jnp.log(self.L_dmin).astype(dt)

            def human(h):
                total = jnp.sum(h)
                mid = (jnp.cumsum(h) - 0.5 * h) / jnp.where(total > 0, total, 1.0)
                ln_d = ln_dmin + B_d * mid
                # [t(L_d) / t(L_w)] L_w / L_d, in logarithms (L_w spans the floats)
                ratio = jnp.exp(jnp.log(tvi(jnp.exp(ln_d))) - t_w + ln_w - ln_d)
                return total * db * ratio / B_d

            hist = _truncate(hist, human)
        cum = jnp.cumsum(hist)
        if self.compat == "paper":
            cum = jnp.concatenate([jnp.zeros((1,), dt), cum])
        total = cum[-1]
        return jnp.where(total > 0, cum / jnp.where(total > 0, total, 1.0), 0.0)

    def _curve(self, L: Array) -> Array:
        assert self.L_max is not None
        return self._relative_curve(divide(L, self.L_max))

    def _relative_curve(self, x: Array) -> Array:
        """Display value of ``x = L / L_max > 0``."""
        assert self.L_min is not None and self.L_max is not None and self.cdf is not None
        dt = x.dtype
        cdf = self.cdf.astype(dt)
        k = cdf.shape[-1] - 1
        span = self._span(self.L_min, self.L_max).astype(dt)
        ln_min = (jnp.log(self.L_min) - jnp.log(self.L_max)).astype(dt)  # ln(L_min / L_max)
        P = table_lerp(cdf, (jnp.log(x) - ln_min) / span * k)
        ln_r = jnp.log(self.L_dmin / self.L_dmax).astype(dt)  # ≤ 0
        rel = jnp.exp((1.0 - P) * ln_r)  # L_d / L_dmax
        r = jnp.exp(ln_r)
        return (rel - r) / (1.0 - r)  # (L_d - L_dmin) / (L_dmax - L_dmin)

    def _apply(self, p: Prepared) -> Array:
        # the curve on L / L_max (as Drago2003 does): the shared mapping's luminance floor
        # is then relative to the image's maximum, so that images at any scale keep their
        # darkest pixels on the curve
        assert self.L_max is not None
        return scale_by_luminance(
            divide(p.rgb, self.L_max),
            divide(p.L, self.L_max),
            self._relative_curve,
            per_channel=False,
        )


def _truncate(hist: Array, ceiling: Callable[[Array], Array]) -> Array:
    """Bins above their ``ceiling(h)`` (of the current histogram ``h``) cut to it until one
    step trims at most :data:`TOLERANCE` of the original total, or the total falls below
    that (the paper's iteration, as in Radiance's ``pcond`` and HDR Toolbox's
    ``histogram_ceiling``)."""
    tol = TOLERANCE * jnp.sum(hist)

    def step(_, state):
        h, done = state
        exhausted = jnp.sum(h) < tol
        cut = jnp.minimum(h, ceiling(h))
        trimmed = jnp.sum(h - cut)
        active = ~done & ~exhausted
        return jnp.where(active, cut, h), done | exhausted | (trimmed <= tol)

    return jax.lax.fori_loop(0, MAX_STEPS, step, (hist, jnp.zeros((), bool)))[0]


__all__ = ["MAX_STEPS", "TOLERANCE", "Ward1997"]
