"""The classic global operators of colour-hdri, so its users can switch.

Each class computes the same function as colour-hdri's ``tonemapping_operator_<Name>``
(``colour_hdri/tonemapping/global_operators/operators.py``; tests compare them to 1e-7 in
float64), with the image statistics it uses (``L_max``, the log-average, channel means)
exposed as optional parameters measured on the finite pixels when ``None``. Differences on
inputs colour-hdri cannot handle: negative channel values are clamped to 0 in the
per-channel operators (colour-hdri returns NaN or divides by zero), pixels with ``L ≤ 0``
are black, and NaN/Inf pixels follow :mod:`hdrjax.operators` rules instead of spreading
through the statistics.

References: Schlick 1994 (https://doi.org/10.1007/978-3-642-87825-1_2), Reinhard & Devlin
2005 (https://doi.org/10.1109/TVCG.2005.9), Hable 2010 (filmic, "Uncharted 2"), and the
colour-hdri documentation for the simple/normalisation/gamma/logarithmic/exponential
operators.
"""

from typing import Any, ClassVar

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._scale import divide, ln_max, quotient
from .._stats import Statistics
from ._base import (
    AbstractLuminanceCurve,
    AbstractOperator,
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
from ._reinhard2005 import (
    channel_average_field,
    fill_photoreceptor_statistics,
    luminance_range_fields,
    photoreceptor,
)

BANTERLE2011 = (
    "Banterle, Artusi, Debattista, Chalmers 2011, Advanced High Dynamic Range Imaging,"
    " A K Peters/CRC Press (ISBN 978-1-56881-719-4), as colour-hdri implements it"
)
SCHLICK1994 = (
    "Schlick 1994, Quantization techniques for visualization of high dynamic range"
    " pictures, Photorealistic Rendering Techniques, https://doi.org/10.1007/978-3-642-87825-1_2"
)


def _l_max(unit: str = "image units") -> Any:
    """The image's largest finite luminance, measured when ``None``."""
    return estimated(
        "luminance mapped to display white; None: the image's largest finite luminance",
        unit=unit,
        pooling="max",
    )


EPSILON = float(jnp.finfo(jnp.float64).eps)
"""colour-hdri's ``EPSILON`` (float64 machine epsilon) inside its log-average."""


def _log1p_product(a: Array, x: Array) -> Array:
    """``ln(1 + a x)`` for ``a ≥ 1``, ``x ≥ 0``, without overflow when ``a x`` exceeds the
    float range: ``ln x + ln(a + 1/x)`` for ``x ≥ 1`` (gradient-safe on both sides)."""
    big = x >= 1
    xs = jnp.where(big, 1.0, x)
    xb = jnp.where(big, x, 1.0)
    return jnp.where(big, jnp.log(xb) + jnp.log(a + 1 / xb), jnp.log1p(a * xs))


class _MaxNormalised(AbstractLuminanceCurve):
    """Operators whose only statistic is the largest luminance ``L_max``."""

    # L_max: a field of each subclass (the mixin declares no field, to keep their order)
    def statistics_settings(self) -> StatisticsSettings | None:
        return None if self.L_max is not None else StatisticsSettings()  # type: ignore[attr-defined]

    def bind(self, stats: Statistics | None):
        if self.L_max is not None:  # type: ignore[attr-defined]
            return self
        return fill(self, L_max=max_luminance(bound_stats(self, stats)))


@register("simple")
class Simple(AbstractOperator):
    """``RGB / (RGB + 1)`` per channel (colour-hdri ``tonemapping_operator_simple``)."""

    reference: ClassVar[str] = "colour-hdri's simple operator, RGB / (RGB + 1)"
    per_channel: ClassVar[bool] = True

    def _apply(self, p: Prepared) -> Array:
        c = jnp.maximum(p.rgb, 0.0)
        return c / (c + 1.0)


@register("normalisation")
class Normalisation(_MaxNormalised):
    """``RGB / L_max`` (colour-hdri ``tonemapping_operator_normalisation``)."""

    reference: ClassVar[str] = BANTERLE2011
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_max",)

    L_max: Array | None = _l_max()
    weights: tuple[float, float, float] = weights_field()

    def _curve(self, L: Array) -> Array:
        return divide(L, self.L_max)


@register("gamma")
class Gamma(AbstractOperator):
    """``(2^EV · RGB)^(1/gamma)`` per channel (colour-hdri ``tonemapping_operator_gamma``).

    Where ``2^EV · RGB`` overflows although the pixel is finite, the power is computed as
    ``exp((EV ln 2 + ln RGB) / gamma)``; results beyond the float range saturate at the
    largest float (image gradients stay finite). Other pixels: colour-hdri's formula."""

    reference: ClassVar[str] = BANTERLE2011
    per_channel: ClassVar[bool] = True

    gamma: Array = parameter(1.0, help="gamma: the exponent is 1 / gamma", range="(0, inf)")
    EV: Array = parameter(
        0.0, help="exposure adjustment: RGB is multiplied by 2^EV", unit="EV", range="(-inf, inf)"
    )

    def _apply(self, p: Prepared) -> Array:
        x = jnp.maximum(p.rgb, 0.0)
        c = jnp.exp2(self.EV) * x
        pos = c > 0
        over = jnp.isinf(c) & jnp.isfinite(x)  # (where-before-log: no 0·∞ derivative)
        ln = jnp.where(
            over,
            self.EV * np.log(2.0) + jnp.log(jnp.where(over, x, 1.0)),
            jnp.log(jnp.where(pos & ~over, c, 1.0)),
        )
        e = ln / self.gamma
        top = ln_max(e.dtype)
        sat = jnp.isfinite(e) & (e > top)
        out = jnp.where(sat, jnp.finfo(e.dtype).max, jnp.exp(jnp.where(sat, 0.0, e)))
        return jnp.where(pos, out, 0.0)


@register("logarithmic")
class Logarithmic(_MaxNormalised):
    """``log10(1 + q L) / log10(1 + k L_max)``, q, k ≥ 1 (colour-hdri ``..._logarithmic``).

    Computed as ``ln(1 + q L) / ln(1 + k L_max)`` with ``log1p``: finite for images at any
    scale of the float type (``1 + k L_max`` rounds to 1 in a dim image)."""

    reference: ClassVar[str] = BANTERLE2011
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_max",)

    q: Array = parameter(1.0, help="scale of L inside the logarithm (brightness)", range="[1, inf)")
    k: Array = parameter(
        1.0, help="scale of L_max inside the logarithm (contrast)", range="[1, inf)"
    )
    L_max: Array | None = _l_max()
    weights: tuple[float, float, float] = weights_field()

    def _curve(self, L: Array) -> Array:
        q, k = jnp.maximum(self.q, 1.0), jnp.maximum(self.k, 1.0)
        # the base cancels: ln(1 + qL) / ln(1 + k L_max); ``log1p`` keeps a dim image's
        # L_max (1 + k L_max == 1 below 6e-8 in float32: 0/0); ``quotient``'s derivative
        # has no 1 / ln(1 + k L_max)², which overflows for a dim image
        return quotient(_log1p_product(q, L), _log1p_product(k, self.L_max))


@register("exponential")
class Exponential(AbstractLuminanceCurve):
    """``1 − exp(−q L / (k L_a))``, ``L_a`` the log-average (colour-hdri ``..._exponential``)."""

    reference: ClassVar[str] = BANTERLE2011
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("log_average",)

    q: Array = parameter(1.0, help="multiplier of L (brightness)", range="[1, inf)")
    k: Array = parameter(1.0, help="multiplier of the log-average (darkens)", range="[1, inf)")
    log_average: Array | None = estimated(
        "log-average luminance L_a; None: measured (offset: float64 machine epsilon)",
        unit="image units",
        pooling="log_mean",
    )
    weights: tuple[float, float, float] = weights_field()

    def statistics_settings(self) -> StatisticsSettings | None:
        return None if self.log_average is not None else StatisticsSettings(delta=EPSILON)

    def bind(self, stats: Statistics | None) -> "Exponential":
        if self.log_average is not None:
            return self
        return fill(self, log_average=bound_stats(self, stats).log_average)

    def _curve(self, L: Array) -> Array:
        q, k = jnp.maximum(self.q, 1.0), jnp.maximum(self.k, 1.0)
        # beyond x = 200 the curve is 1 to double precision; the cap keeps gradients finite
        L = jnp.minimum(L, 200.0 * self.log_average * k / q)
        return 1 - jnp.exp(-(L * q) / (self.log_average * k))


@register("logarithmic_mapping")
class LogarithmicMapping(_MaxNormalised):
    """``(ln(1 + p L) / ln(1 + p L_max))^(1/q)`` (colour-hdri ``..._logarithmic_mapping``)."""

    reference: ClassVar[str] = SCHLICK1994
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_max",)

    p: Array = parameter(1.0, help="scale of L inside the logarithm", range="(0, inf)")
    q: Array = parameter(1.0, help="the result is raised to 1 / q", range="(0, inf)")
    L_max: Array | None = _l_max()
    weights: tuple[float, float, float] = weights_field()

    def _curve(self, L: Array) -> Array:
        r = quotient(jnp.log1p(self.p * L), jnp.log1p(self.p * self.L_max))
        pos = r > 0
        return jnp.where(pos, jnp.exp(jnp.log(jnp.where(pos, r, 1.0)) / self.q), 0.0)


@register("exponentiation_mapping")
class ExponentiationMapping(_MaxNormalised):
    """``(L / L_max)^(p/q)`` (colour-hdri ``..._exponentiation_mapping``)."""

    reference: ClassVar[str] = SCHLICK1994
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_max",)

    p: Array = parameter(1.0, help="numerator of the exponent p / q", range="(0, inf)")
    q: Array = parameter(1.0, help="denominator of the exponent p / q", range="(0, inf)")
    L_max: Array | None = _l_max()
    weights: tuple[float, float, float] = weights_field()

    def _curve(self, L: Array) -> Array:
        r = divide(L, self.L_max)
        pos = r > 0
        return jnp.where(pos, jnp.exp(jnp.log(jnp.where(pos, r, 1.0)) * self.p / self.q), 0.0)


@register("schlick1994")
class Schlick1994(_MaxNormalised):
    """``p L / (p L − L + L_max)`` (Schlick 1994; colour-hdri ``..._Schlick1994``).

    The curve depends on ``x = L / L_max`` alone (``p x / ((p − 1) x + 1)``), so it is
    evaluated on the image divided by ``L_max``: the same values as colour-hdri's, and
    finite for images at any scale of the float type. (Evaluated on ``L`` itself, the
    luminance floor that keeps gradients finite is absolute: below it, an image dimmer
    than 1e-19 in float32 got a wrong ratio for ``p ≠ 1``, and the ratio ``≈ 1 / L_max``
    overflowed to Inf in dim images and was flushed to 0 in bright ones.)
    """

    reference: ClassVar[str] = SCHLICK1994
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_max",)

    p: Array = parameter(
        1.0, help="slope of the curve at black (1: linear; Schlick's p >= 1)", range="[1, inf)"
    )
    L_max: Array | None = _l_max()
    weights: tuple[float, float, float] = weights_field()

    def _curve(self, L: Array) -> Array:
        return self._relative_curve(L / self.L_max)

    def _relative_curve(self, x: Array) -> Array:
        return (self.p * x) / ((self.p - 1) * x + 1)

    def _apply(self, p: Prepared) -> Array:
        # the one curve overriding the shared mapping: its floor must be relative to L_max
        # (see the class docstring); the rest of the mapping is the same
        return scale_by_luminance(
            divide(p.rgb, self.L_max), divide(p.L, self.L_max), self._relative_curve
        )


@register("reinhard2004")
class Reinhard2004(AbstractOperator):
    """Reinhard & Devlin 2005 photoreceptor operator, per channel, as colour-hdri computes it.

    ``RGB / (RGB + (e^−f I_a)^m)`` with ``I_a = a I_l + (1 − a) I_g``,
    ``I_l = (c RGB + (1 − c)) L``, ``I_g = c C_av + (1 − c) L_lav``; ``m ≤ 0`` selects the
    automatic contrast ``0.3 + 0.7 (ln L_max − L_lav) / (ln L_max − ln L_min)^1.4``. Both
    the ``I_l`` expression and the automatic ``m`` (which subtracts the linear log-average
    from a logarithm) reproduce colour-hdri exactly, including where they differ from the
    paper, so results match for users switching tools.

    ``reinhard2005`` (:class:`~hdrjax.operators.Reinhard2005`) is the same paper as pfstmo
    implements it, with the same response (:func:`photoreceptor`) and pfstmo's names and
    defaults: light adaptation ``l`` (0.75) for ``a`` (0 here), ``c`` 0.5 (0 here), ``m``
    automatic (0.3 here); the paper's ``I_l = c RGB + (1 − c) L``, the mean luminance (not
    the log-average) in ``I_g``, the paper's key ``0.3 + 0.7 k^1.4`` and pfstmo's stretch of
    the response to [0, 1], none of which colour-hdri has.

    Attributes:
        f: intensity (brightness) −8 … 8 (0). m: contrast 0.3 … 1 (0.3; ≤ 0 → automatic).
        a: light adaptation 0 … 1 (0). c: chromatic adaptation 0 … 1 (0).
        channel_average, log_average, L_min, L_max: statistics; ``None`` → measured.
    """

    reference: ClassVar[str] = (
        "Reinhard, Devlin 2005, Dynamic range reduction inspired by photoreceptor"
        " physiology, IEEE TVCG 11(1), https://doi.org/10.1109/TVCG.2005.9"
    )

    f: Array = parameter(0.0, help="intensity (brightness)", range="[-8, 8]")
    m: Array = parameter(0.3, help="contrast 0.3 … 1; <= 0: automatic", range="(-inf, 1]")
    a: Array = parameter(0.0, help="light adaptation (0: global, 1: per pixel)", range="[0, 1]")
    c: Array = parameter(
        0.0, help="chromatic adaptation (0: luminance, 1: per channel)", range="[0, 1]"
    )
    channel_average: Array | None = channel_average_field()
    log_average: Array | None = estimated(
        "log-average luminance; None: measured (offset: float64 machine epsilon)",
        unit="image units",
        pooling="log_mean",
    )
    L_min: Array | None = luminance_range_fields()[0]
    L_max: Array | None = luminance_range_fields()[1]
    weights: tuple[float, float, float] = weights_field()

    def statistics_settings(self) -> StatisticsSettings | None:
        if not self.unset():
            return None
        return StatisticsSettings(delta=EPSILON, channels=self.channel_average is None)

    def bind(self, stats: Statistics | None) -> "Reinhard2004":
        if not self.unset():
            return self
        return fill_photoreceptor_statistics(self, stats)

    def _apply(self, p: Prepared) -> Array:
        rgb = jnp.maximum(p.rgb, 0.0)
        L = jnp.maximum(p.L, 0.0)[..., None]
        ln_max = jnp.log(self.L_max)
        ln_min = jnp.log(jnp.maximum(self.L_min, jnp.finfo(L.dtype).tiny))
        # colour-hdri evaluates ``(ln L_max − L_lav) / (ln L_max − ln L_min) ** 1.4``: the
        # power binds to the denominator only (Python precedence); reproduced as is.
        span = jnp.where(ln_max > ln_min, ln_max - ln_min, 1.0)
        auto = 0.3 + 0.7 * (ln_max - self.log_average) / jnp.power(span, 1.4)
        m = jnp.where(self.m > 0, self.m, auto)
        I_l = (self.c * rgb + (1 - self.c)) * L
        C_av = self.channel_average.reshape((1,) * (rgb.ndim - 1) + (3,))
        I_g = self.c * C_av + (1 - self.c) * self.log_average
        return photoreceptor(rgb, I_l, I_g, self.a, self.f, m)


def hable(x: Array, A, B, C, D, E, F) -> Array:
    """Hable's filmic curve ``((x(Ax + CB) + DE) / (x(Ax + B) + DF)) − E/F``.

    For x > 1 numerator and denominator are divided by x² so huge inputs do not overflow.
    """
    x = jnp.asarray(x)
    big = x > 1
    inv = 1.0 / jnp.where(big, x, 1.0)
    r_big = (A + C * B * inv + D * E * inv * inv) / (A + B * inv + D * F * inv * inv)
    xs = jnp.where(big, 0.0, x)
    r_small = (xs * (A * xs + C * B) + D * E) / (xs * (A * xs + B) + D * F)
    return jnp.where(big, r_big, r_small) - E / F


_HABLE_PARAMETERS = {
    "shoulder_strength": ("shoulder strength A", "[0, inf)", ""),
    "linear_strength": ("linear strength B", "[0, inf)", ""),
    "linear_angle": ("linear angle C", "[0, inf)", ""),
    "toe_strength": ("toe strength D", "[0, inf)", ""),
    "toe_numerator": ("toe numerator E", "[0, inf)", ""),
    "toe_denominator": ("toe denominator F", "(0, inf)", ""),
    "exposure_bias": ("multiplier of RGB before the curve (Hable's ExposureBias)", "(0, inf)", ""),
    "linear_whitepoint": ("input value mapped to display white, W", "(0, inf)", "image units"),
}


def hable_parameter(name: str, default: float) -> Any:
    """The field of Hable's parameter ``name`` (help, range and unit shared by the
    operators built on :func:`hable`) with the operator's own ``default``."""
    help, range, unit = _HABLE_PARAMETERS[name]
    return parameter(default, help=help, unit=unit, range=range)


def hable_curve(op: Any, rgb: Array) -> Array:
    """``h(bias · max(RGB, 0)) / h(W)`` per channel with ``op``'s Hable parameters."""
    k = tuple(getattr(op, n) for n in tuple(_HABLE_PARAMETERS)[:6])
    return hable(jnp.maximum(rgb, 0.0) * op.exposure_bias, *k) / hable(op.linear_whitepoint, *k)


@register("filmic")
class Filmic(AbstractOperator):
    """Hable 2010 filmic curve per channel, normalised by its value at ``linear_whitepoint``
    (colour-hdri ``tonemapping_operator_filmic``; same parameter names and defaults).

    This is Hable's Uncharted 2 curve (:func:`hable`, shared with ``hable2010``,
    :class:`~hdrjax.operators.Hable2010`): the same formula, white 11.2 and exposure bias 2,
    but colour-hdri's constants A = 0.22, B = 0.30, E = 0.01 (it cites Hable's GDC 2010
    slides as well as his post) where ``hable2010`` has the 2010 blog post's A = 0.15,
    B = 0.50, E = 0.02; and unclamped (above the white it exceeds 1). ``hable2010`` with
    these three constants equals this operator clamped to [0, 1]."""

    reference: ClassVar[str] = (
        "Hable 2010, Uncharted 2: HDR Lighting (Game Developers Conference) and Filmic"
        " Tonemapping Operators, as colour-hdri implements it"
    )
    per_channel: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("exposure_bias",)

    shoulder_strength: Array = hable_parameter("shoulder_strength", 0.22)
    linear_strength: Array = hable_parameter("linear_strength", 0.3)
    linear_angle: Array = hable_parameter("linear_angle", 0.1)
    toe_strength: Array = hable_parameter("toe_strength", 0.2)
    toe_numerator: Array = hable_parameter("toe_numerator", 0.01)
    toe_denominator: Array = hable_parameter("toe_denominator", 0.3)
    exposure_bias: Array = hable_parameter("exposure_bias", 2.0)
    linear_whitepoint: Array = hable_parameter("linear_whitepoint", 11.2)

    def _apply(self, p: Prepared) -> Array:
        return hable_curve(self, p.rgb)


__all__ = [
    "ExponentiationMapping",
    "Exponential",
    "Filmic",
    "Gamma",
    "LogarithmicMapping",
    "Logarithmic",
    "Normalisation",
    "Reinhard2004",
    "Schlick1994",
    "Simple",
]
