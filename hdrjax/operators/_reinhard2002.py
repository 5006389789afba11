"""Reinhard et al. 2002 photographic tone reproduction, with JGT 2002 automatic parameters.

References:
    Reinhard, Stark, Shirley, Ferwerda. "Photographic tone reproduction for digital images."
    ACM TOG 21(3), 2002. https://doi.org/10.1145/566654.566575
    Reinhard. "Parameter estimation for photographic tone reproduction." Journal of Graphics
    Tools 7(1), 2002. https://doi.org/10.1080/10867651.2002.10487554

Global operator (paper Eqs. 1–4):
    ``L̄_w = exp(mean(ln(δ + L_w)))``, ``L = a L_w / L̄_w``,
    ``L_d = L (1 + L / L_white²) / (1 + L)``, colour scaled by ``L_d / L_w``.

Automatic parameters (Reinhard 2002, JGT 7(1), Eqs. 4 and 5), on the finite positive
luminance:
    key (Eq. 4): ``a = 0.18 · 4^((2 log2 L̄ − log2 L_1 − log2 L_99) / (log2 L_99 − log2 L_1))``
    with ``L_1``/``L_99`` the 1st/99th percentiles and ``L̄`` the log-average of the pixels
    at or below ``L_99`` (0.18 when ``L_99 = L_1``);
    white (Eq. 5): ``L_white = 1.5 · 2^(log2 L_max − log2 L_min − 5)`` on the full range,
    except when ``log2(L_max / L_min) ≤ log2(s · L̄) + 4.415037``, with ``s = a / L̄_w``
    the world-to-scaled factor (Eq. 5's white would fall at or below the trimmed
    log-average in scaled units), where ``L_white = 1.5 · s · max(L)`` (hdritools' guard).
    ``L_white`` is in scaled units, like the paper's.

Departure from hdritools (edgarv/hdritools ``ImageIO/Reinhard02.cpp``, ``EstimateParams``):
its guard is ``log2(L_max/L_min) > log2(l_w) + 4.415037`` — in words (its comment), Eq. 5's
white ``1.5 · 2^(zones − 5)`` must exceed the log-average ``l_w``, as
``log2 1.5 − 5 = −4.415037``. But it compares a white in scaled units (its tone mapper uses
``L_white`` on ``(key / l_w) · Y``, ``ToneMapperSoA.cpp``) with ``l_w`` in image units, and
its fallback ``1.5 · L_max`` is in image units too. Multiplying the scene by ``k`` then moves
the guard by ``log2 k`` zones and can switch the white point, although the operator
promises scale invariance (key, ``L_white`` and ``L̄_w`` measured). hdrjax evaluates both
sides of the guard, and the fallback, in scaled units (the log-average becomes
``s · L̄``, about the key ``a``), which equals hdritools' test exactly where image and scaled
units coincide (``s = 1``) and is invariant under ``L → kL`` everywhere else.

GPU shader form (settings ``key=0.18, L_white="max", chroma="ycbcr", delta=1e-5``): shader
versions of the paper's global operator take the white point as the image's largest
luminance in scaled units, ``L_white = (a / L̄_w) · max(L_w)``, so the brightest pixel maps
to exactly 1, and replace the luma of YCbCr by ``L_d``, keeping Cb and Cr (which adds
``L_d − L_w`` to each channel); their log-average and maximum come from
repeated 4×4 reductions of the image, which equal the plain mean and maximum computed here
(up to rounding; exactly when the sides are powers of 4). Such versions use the BT.601 luma
weights (``weights=(0.299, 0.587, 0.114)``) and the offset ``δ = 1e-5``. With YCbCr the
chroma is not scaled with the luminance: the output is display-referred only for inputs of
modest range in relative units, and is not scale invariant.
"""

import math
from typing import Any, ClassVar, Literal

import jax.numpy as jnp
from jaxtyping import Array

from .._scale import ln_max, scale
from .._stats import DEFAULT_BINS, DEFAULT_DELTA, LuminanceStats, Statistics
from ._base import (
    AbstractLuminanceCurve,
    StatisticsSettings,
    bound_stats,
    chroma_field,
    estimated,
    fill,
    luminance_floor,
    max_luminance,
    param,
    parameter,
    register,
    weights_field,
)

KEY_DEFAULT = 0.18
WHITE_NAMES = ("max", "inf")
"""The names ``L_white`` also takes: the largest scaled luminance, or no white point."""
WHITE_METHODS = ("jgt", "max")
"""How ``L_white`` is measured when it is ``None``: JGT 2002 Eq. 5, or the largest scaled
luminance."""
REFERENCE = (
    "Reinhard, Stark, Shirley, Ferwerda 2002, Photographic tone reproduction for digital"
    " images, ACM TOG 21(3), https://doi.org/10.1145/566654.566575; Reinhard 2002, Parameter"
    " estimation for photographic tone reproduction, Journal of Graphics Tools 7(1),"
    " https://doi.org/10.1080/10867651.2002.10487554"
)


def key_parameter() -> Any:
    """The key ``a`` (JGT Eq. 4 when ``None``), shared by the Reinhard 2002 operators."""
    return estimated(
        "the key a (0.18 is the paper's default); None: JGT 2002 Eq. 4 estimate", pooling="log_mean"
    )


def white_parameter() -> Any:
    """``L_white`` in scaled units (JGT Eq. 5 when ``None``)."""
    return estimated(
        "smallest scaled luminance mapped to white (inf: L / (1 + L)); None: JGT 2002 Eq. 5",
        unit="scaled units",
        range="(0, inf]",
        pooling="log_mean",
    )


def _white_value(x: Any) -> Any:
    """``L_white``'s converter: its names pass (``Reinhard2002.__post_init__`` resolves
    them), numbers become parameters."""
    return x if isinstance(x, str) else param(x)


def named_white_parameter() -> Any:
    """``L_white`` in scaled units that also takes ``"max"`` and ``"inf"``."""
    return estimated(
        "smallest scaled luminance mapped to white; max: the largest scaled luminance (the"
        " brightest pixel maps to 1); inf: L / (1 + L); None: measured as white says",
        unit="scaled units",
        range="(0, inf]",
        pooling="log_mean",
        names=WHITE_NAMES,
        converter=_white_value,
    )


def log_average_parameter() -> Any:
    """The log-average ``L̄_w`` (measured with ``delta`` when ``None``)."""
    return estimated(
        "log-average luminance L̄_w; None: measured with delta",
        unit="image units",
        pooling="log_mean",
    )


def delta_setting() -> Any:
    """``delta``, the offset inside the log-average."""
    return parameter(
        DEFAULT_DELTA,
        help="offset inside the log-average (1e-6, HDR Toolbox)",
        unit="image units",
        range="[0, inf)",
        static=True,
    )


def percentile_method_setting() -> Any:
    """``percentile_method``: histogram or exact percentiles."""
    return parameter(
        "histogram",
        help="percentiles: histogram (fast, bounded error) or exact (sort)",
        static=True,
        choices=("histogram", "exact"),
    )


def bins_setting(default: int = DEFAULT_BINS) -> Any:
    """``bins``: the histogram resolution of the percentiles."""
    return parameter(
        default,
        help="histogram resolution of the percentiles (2^(ceil(log2 bins) - 3) bins per octave)",
        range="[1, inf)",
        static=True,
    )


def jgt_key(st: LuminanceStats) -> Array:
    """JGT 2002 Eq. 4 automatic key from P1, P99 and the trimmed log-average."""
    l1, l99 = jnp.log2(st.p01), jnp.log2(st.p99)
    lbar = jnp.log2(st.log_average_trimmed)
    span = l99 - l1
    ok = span > 0
    expo = (2 * lbar - l1 - l99) / jnp.where(ok, span, 1.0)
    return jnp.where(ok, KEY_DEFAULT * jnp.power(4.0, expo), KEY_DEFAULT)


def jgt_white_terms(st: LuminanceStats, scale: Array) -> tuple[Array, dict[str, Array]]:
    """:func:`jgt_white` and the intermediate terms it used: ``zones``
    (``log2 L_max − log2 L_min``) and ``guard`` (True where hdritools' guard, evaluated in
    scaled units, chose ``1.5 · max(L)`` in scaled units over Eq. 5; see the module
    docstring for why scaled units)."""
    any_pos = st.n_positive > 0
    L_max = jnp.where(any_pos & (st.max > 0), st.max, 1.0)  # safe for log and its gradient
    zones = jnp.log2(L_max) - jnp.log2(st.min_positive)  # no overflow of the ratio
    eq5 = 1.5 * jnp.exp2(jnp.minimum(zones - 5.0, 100.0))  # 2^100: finite in float32
    # log2 of the trimmed log-average in scaled units, as a sum of logs (no overflow of the
    # product); a boolean, so no gradient flows through it
    log2_avg_scaled = jnp.log2(scale) + jnp.log2(st.log_average_trimmed)
    guard = zones <= log2_avg_scaled + 4.415037
    # L_max · scale first: 1.5 · L_max overflows for L_max near the float maximum, and
    # its product with the zero cotangent of the branch not taken is NaN
    white = jnp.where(guard, 1.5 * (L_max * scale), eq5)
    white = jnp.where(any_pos, jnp.maximum(white, jnp.finfo(white.dtype).tiny), 1.0)
    return white, {"zones": zones, "guard": guard}


def jgt_white(st: LuminanceStats, scale: Array) -> Array:
    """JGT 2002 Eq. 5 white point (scaled units) from the full range, with hdritools' guard
    evaluated in scaled units (module docstring).

    ``scale`` is ``a / L̄_w``, the factor from world to scaled luminance.
    """
    return jgt_white_terms(st, scale)[0]


def jgt_settings(op: Any) -> StatisticsSettings | None:
    """The statistics the Reinhard operators bind from (their ``percentile_method``,
    ``bins`` and ``delta``); ``None`` once every parameter is set."""
    return StatisticsSettings(op.percentile_method, op.bins, op.delta) if op.unset() else None


def jgt_key_and_log_average(op: Any, stats: Statistics | None):
    """``(luminance statistics, key, log-average)`` of a Reinhard operator: the given
    values, else JGT Eq. 4's key and the measured log-average."""
    st = bound_stats(op, stats)
    key = jgt_key(st) if op.key is None else op.key
    lbar = st.log_average if op.log_average is None else op.log_average
    return st, key, lbar


def max_white(st: LuminanceStats, key: Array, log_average: Array) -> Array:
    """The largest finite luminance in scaled units, ``(key / L̄_w) · L_max`` (GPU shader
    versions' white point; ``key / L̄_w`` when no pixel is positive).

    Through logarithms clamped to the float range (a product that overflows would make
    the gradient NaN), and at least :func:`~hdrjax.operators._base.luminance_floor`
    (1.1e-19 in float32), whose square is a normal float: the compiled curve may evaluate
    ``L / L_white²``. Only images whose largest scaled luminance is below that floor (the
    offset ``delta`` dominates the log-average of an image dimmer than about 1e-24) reach
    it; their brightest pixel then no longer maps to white (but the output stays finite).
    """
    ln_white = jnp.log(key) - jnp.log(log_average) + jnp.log(max_luminance(st))
    dtype = ln_white.dtype
    lo, hi = math.log(luminance_floor(dtype)), ln_max(dtype)
    return jnp.exp(jnp.clip(ln_white, lo, hi))


def reinhard_curve(L: Array, L_white: Array) -> Array:
    """``L (1 + L / L_white²) / (1 + L)`` written to stay finite for L up to the float max."""
    return (L / (1.0 + L)) * (1.0 + (L / L_white) / L_white)


@register("reinhard2002")
class Reinhard2002(AbstractLuminanceCurve):
    """Reinhard et al. 2002 global photographic operator, JGT 2002 automatic key and white
    (module docstring).

    Input: linear RGB, relative or absolute (the operator is scale invariant when ``key``,
    ``L_white`` and ``log_average`` are measured). Output: display-referred linear RGB,
    ``L_d ∈ [0, 1]`` for ``L_w ≤ L_white``.

    Attributes:
        key: the key ``a``; ``None`` → JGT Eq. 4 estimate (0.18 is the paper's default).
        L_white: smallest scaled luminance mapped to white; ``None`` → measured as ``white``
            says (JGT Eq. 5 by default). ``"max"``: measured as the largest scaled luminance
            (sets ``white="max"``); ``"inf"`` or ``jnp.inf``: the simple operator
            ``L / (1 + L)``.
        log_average: ``L̄_w`` in image units; ``None`` → measured with ``delta``.
        delta: offset inside the log-average (1e-6, HDR Toolbox; GPU shader versions use 1e-5).
        percentile_method: ``"histogram"`` (fast, bounded error) or ``"exact"`` (sort).
        bins: histogram resolution for the percentiles (:func:`hdrjax.stats.percentile`:
            ``2^(ceil(log2 bins) − 3)`` bins per octave, 1024 by default).
        weights: luminance weights of the image's primaries (Rec.709 default); with
            ``chroma="ycbcr"`` also the luma weights of the YCbCr matrix.
        white: how ``L_white`` is measured when it is ``None``: ``"jgt"`` (JGT Eq. 5,
            the default) or ``"max"`` (the largest luminance in scaled units, GPU shader
            versions' choice; module docstring).
        chroma: ``"ratio"`` (default: RGB scaled by ``L_d / L_w``) or ``"ycbcr"`` (luma
            replaced by ``L_d``, Cb and Cr kept, as GPU shader versions do; not scale
            invariant, module docstring).

    >>> import hdrjax, numpy as np
    >>> rgb = np.array([[[0.5, 0.5, 0.5], [4.0, 4.0, 4.0]]], np.float32)
    >>> out = hdrjax.tonemap(rgb, "reinhard2002", key=0.18, L_white="max")
    >>> round(float(out[0, 1, 0]), 6)  # the brightest pixel maps to white
    1.0
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    """With ``chroma="ratio"`` (the default)."""
    default_fit_params: ClassVar[tuple[str, ...]] = ("key", "L_white")

    key: Array | None = key_parameter()
    L_white: Array | None = named_white_parameter()
    log_average: Array | None = log_average_parameter()
    delta: float = delta_setting()
    percentile_method: Literal["histogram", "exact"] = percentile_method_setting()
    bins: int = bins_setting()
    weights: tuple[float, float, float] = weights_field()
    white: Literal["jgt", "max"] = parameter(
        "jgt",
        help="how L_white is measured when None: jgt (JGT 2002 Eq. 5) or max (the largest"
        " scaled luminance, as GPU shader versions do)",
        static=True,
        choices=WHITE_METHODS,
    )
    chroma: Literal["ratio", "ycbcr"] = chroma_field()

    def __post_init__(self):
        # L_white's names: "max" is a way of measuring it, "inf" a value
        if isinstance(self.L_white, str):
            if self.L_white not in WHITE_NAMES:
                raise ValueError(
                    "L_white: expected a number in (0, inf], None or one of"
                    f" {' | '.join(WHITE_NAMES)}, got {self.L_white!r}"
                )
            if self.L_white == "max":
                self.white, self.L_white = "max", None
            else:
                self.L_white = param(math.inf)

    def statistics_settings(self) -> StatisticsSettings | None:
        return jgt_settings(self)

    def bind(self, stats: Statistics | None) -> "Reinhard2002":
        if not self.unset():
            return self
        st, key, lbar = jgt_key_and_log_average(self, stats)
        white = self.L_white
        if white is None:
            white = max_white(st, key, lbar) if self.white == "max" else jgt_white(st, key / lbar)
        return fill(self, key=key, L_white=white, log_average=lbar)

    def _curve(self, L: Array) -> Array:
        assert self.key is not None and self.L_white is not None
        assert self.log_average is not None
        return reinhard_curve(scale(L, self.key, self.log_average), self.L_white)


__all__ = [
    "KEY_DEFAULT",
    "WHITE_NAMES",
    "Reinhard2002",
    "jgt_key",
    "jgt_white",
    "jgt_white_terms",
    "max_white",
    "reinhard_curve",
]
