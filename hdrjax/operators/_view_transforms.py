"""The view transforms of real-time renderers: display curves applied per RGB pixel.

Seven published transforms, each as its authors' code computes it: Narkowicz's and Hill's
fits of ACES (2016), Sobotka's AgX with Blender 4.x's matrices (2023), Khronos PBR
Neutral (2024), Hable's Uncharted 2 curve (2010), Uchimura's Gran Turismo curve (2017) and
Lottes' curve (2016).

Numeric contract (all of them): the input is scene-linear RGB in relative units (1 is a
diffuse white; Rec.709/sRGB primaries for the transforms with colour matrices: ACES, AgX,
PBR Neutral), multiplied first by ``2^exposure`` (``exposure`` in EV stops, 0 by default);
the output is display-linear RGB in [0, 1], before any display encoding
(:mod:`hdrjax.display` encodes it). A display encoding in the published code is left out
(Hable's shader ends in ``x^(1/2.2)``); AgX's ``x^2.2``, which turns its sigmoid's
display-encoded output back into display-linear values, is kept. Where the published code
clamps to [0, 1] or leaves that to the display, hdrjax clamps. The curves take no image
statistics: ``exposure`` is the one setting a user fits (``hdrjax fit``).

Inputs the published code does not define, handled the same way in every transform:
negative channels are clamped to 0 before the curves (ACES Hill and AgX: after their input
matrices, as ACES' Reference Rendering Transform clamps its AP1 values and as AgX's
published code does); finite values whose exposure overflows are clamped to the largest
float; a rational curve ``(n₂x² + n₁x + n₀) / (d₂x² + d₁x + d₀)`` is evaluated in ``1/x``
beyond ``|x| = 1``, so huge values reach its limit ``n₂ / d₂`` instead of ``∞/∞``. NaN and
±Inf pixels follow :mod:`hdrjax.operators`' rules (NaN stays NaN, +Inf luminance is white,
−Inf black).

These operators have no luminance weights (``per_channel``): Narkowicz, Hable, Uchimura and
Lottes map each channel by itself; ACES Hill and AgX mix channels through fixed matrices,
and PBR Neutral through the pixel's smallest and largest channel, as published.
"""

import abc
from typing import Any, ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._colour import (
    REC709_CHROMATICITIES,
    REC709_WEIGHTS,
    apply_matrix,
    channel_max,
    channel_min,
    luminance,
    normalised_primary_matrix,
)
from .._scale import positive_power
from ._base import AbstractOperator, Prepared, parameter, register, traced
from ._classic import hable_curve, hable_parameter

REC2020_CHROMATICITIES = (0.708, 0.292, 0.170, 0.797, 0.131, 0.046, 0.3127, 0.3290)
"""ITU-R BT.2020 primaries with the D65 white (AgX's working space)."""


def _exposure(help: str = "exposure adjustment: RGB is multiplied by 2^exposure") -> Any:
    return parameter(0.0, help=help, unit="EV", range="[-64, 64]")


def _exposed(rgb: Array, exposure: Array) -> Array:
    """``rgb · 2^exposure``, clamped to the dtype's finite range."""
    top = jnp.finfo(rgb.dtype).max
    return jnp.clip(rgb * jnp.exp2(exposure).astype(rgb.dtype), -top, top)


def _rational(x: Array, num: tuple, den: tuple) -> Array:
    """``(n₂x² + n₁x + n₀) / (d₂x² + d₁x + d₀)`` with ``num = (n₂, n₁, n₀)`` and ``den``
    alike (the published ``x (a x + b) / (x (c x + d) + e)`` form), evaluated in ``t = 1/x``
    beyond ``|x| = 1`` (``(n₂ + t (n₁ + t n₀)) / (d₂ + t (d₁ + t d₀))``): huge ``x`` give the
    curve's limit ``n₂ / d₂``, where ``x²`` would overflow to ``∞/∞``. Gradient-safe on both
    sides (each branch sees only its own inputs)."""
    n2, n1, n0 = num
    d2, d1, d0 = den
    big = jnp.abs(x) > 1
    t = 1.0 / jnp.where(big, x, 1.0)
    xs = jnp.where(big, 0.0, x)
    small = (xs * (n2 * xs + n1) + n0) / (xs * (d2 * xs + d1) + d0)
    large = (n2 + t * (n1 + t * n0)) / (d2 + t * (d1 + t * d0))
    return jnp.where(big, large, small)


def _shown(v: Any) -> str:
    """A concrete parameter value for a message (float32 digits rounded off)."""
    v = np.asarray(v, np.float64)
    return f"{float(v):.6g}" if v.size == 1 else np.array2string(v, precision=6)


def _unit(x: Array) -> Array:
    return jnp.clip(x, 0.0, 1.0)


class _AbstractViewTransform(AbstractOperator):
    """A display transform of exposed scene-linear RGB (no image statistics)."""

    per_channel: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("exposure",)

    exposure: eqx.AbstractVar[Array]

    @abc.abstractmethod
    def _map(self, x: Array) -> Array:
        """Display-linear RGB in [0, 1] of exposed, finite scene-linear RGB ``x``."""

    def _apply(self, p: Prepared) -> Array:
        return self._map(_exposed(p.rgb, self.exposure))


# ----------------------------------------------------------------------------- ACES

NARKOWICZ2015 = ((2.51, 0.03, 0.0), (2.43, 0.59, 0.14))
"""Narkowicz's ``x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)``: (numerator, denominator)."""


@register("aces_narkowicz2015")
class AcesNarkowicz2015(_AbstractViewTransform):
    """Narkowicz's fit of the ACES filmic curve (RRT + Rec.709 ODT), per channel.

    ``f(x) = clamp(x (a x + b) / (x (c x + d) + e), 0, 1)`` with ``a = 2.51``, ``b = 0.03``,
    ``c = 2.43``, ``d = 0.59``, ``e = 0.14``, ``x = 2^exposure · RGB`` (relative scene
    units; output display-linear in [0, 1]). A luminance-only fit (largest error 0.0138,
    the post says), which over-saturates bright colours; :class:`AcesHill` fits the
    colour matrices too.

    Exposure: the fit was made on data "pre-exposed, so 1 on input maps to ~0.8 on output"
    (``f(1) = 0.804``); for the exposure of the original ACES curve the post says to
    multiply the input by 0.6, i.e. ``exposure = log2 0.6 = −0.737`` EV. The default is 0,
    the published function itself, which is what renderers that ship this curve apply
    (and the brightness it was made for); give ``exposure=-0.737`` for ACES' own.

    Reference: Narkowicz 2016, "ACES Filmic Tone Mapping Curve" (blog post dated 6 January
    2016, often cited as 2015, hence the name),
    https://knarkowicz.wordpress.com/2016/01/06/aces-filmic-tone-mapping-curve/

    Departures: negative channels are 0 (the published rational rises towards 1.03 as
    ``x → −∞``); the curve is evaluated in ``1/x`` above 1 (no ``∞/∞``).
    """

    reference: ClassVar[str] = (
        "Narkowicz 2016, ACES Filmic Tone Mapping Curve, blog post,"
        " https://knarkowicz.wordpress.com/2016/01/06/aces-filmic-tone-mapping-curve/"
    )

    exposure: Array = _exposure(
        "exposure adjustment: RGB is multiplied by 2^exposure (-0.737 = x 0.6: the original"
        " ACES exposure, per Narkowicz)"
    )

    def _map(self, x: Array) -> Array:
        return _unit(_rational(jnp.maximum(x, 0.0), *NARKOWICZ2015))


HILL_INPUT = np.array(
    [[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]]
)
"""Hill's ``ACESInputMat``: sRGB → XYZ → D65 to D60 → AP1 → RRT saturation (rows: outputs)."""
HILL_OUTPUT = np.array(
    [[1.60475, -0.53108, -0.07367], [-0.10208, 1.10813, -0.00605], [-0.00327, -0.07276, 1.07602]]
)
"""Hill's ``ACESOutputMat``: ODT saturation → XYZ → D60 to D65 → sRGB."""
HILL_FIT = ((1.0, 0.0245786, -0.000090537), (0.983729, 0.4329510, 0.238081))
"""Hill's ``RRTAndODTFit``: ``(v (v + 0.0245786) − 0.000090537) / (v (0.983729 v + 0.432951)
+ 0.238081)`` as (numerator, denominator)."""


@register("aces_hill")
class AcesHill(_AbstractViewTransform):
    """Hill's fit of ACES 1.0 RRT + sRGB ODT, with its colour matrices (BakingLab).

    ``out = clamp(M_out · fit(max(M_in · x, 0)), 0, 1)``, ``x = 2^exposure · RGB`` in linear
    sRGB/Rec.709 (relative units), where ``M_in`` takes sRGB to ACES AP1 with the RRT's
    saturation, ``fit(v) = (v (v + 0.0245786) − 0.000090537) / (v (0.983729 v + 0.432951) +
    0.238081)`` per channel, and ``M_out`` applies the ODT's saturation and returns to sRGB;
    the output is display-linear sRGB in [0, 1].

    Reference: Hill 2016, ACES fit in Pettineo's BakingLab (``BakingLab/ACES.hlsl``, MIT
    licence), https://github.com/TheRealMJP/BakingLab/blob/master/BakingLab/ACES.hlsl

    Departures: AP1 values are clamped at 0 before the fit, as ACES' own RRT clamps them
    (the published fit is not meant for negative values: it rises towards 1.017 as
    ``v → −∞``); the fit is evaluated in ``1/v`` above 1 (its limit 1/0.983729 at ``∞``).
    Three.js multiplies the input by 1/0.6 before this fit (a brighter look, its
    discussion #19621): ``exposure = 0.737`` reproduces it.
    """

    reference: ClassVar[str] = (
        "Hill 2016, ACES RRT + ODT fit, BakingLab ACES.hlsl (MIT licence),"
        " https://github.com/TheRealMJP/BakingLab/blob/master/BakingLab/ACES.hlsl"
    )

    exposure: Array = _exposure()

    def _map(self, x: Array) -> Array:
        v = jnp.maximum(apply_matrix(x, HILL_INPUT), 0.0)
        return _unit(apply_matrix(_rational(v, *HILL_FIT), HILL_OUTPUT))


# ----------------------------------------------------------------------------- AgX

REC709_TO_REC2020 = np.linalg.solve(
    normalised_primary_matrix(REC2020_CHROMATICITIES),
    normalised_primary_matrix(REC709_CHROMATICITIES),
)
"""Linear Rec.709 → Rec.2020 (both D65: no adaptation), from the primaries."""
REC2020_TO_REC709 = np.linalg.inv(REC709_TO_REC2020)
AGX_INSET = np.array(
    [
        [0.856627153315983, 0.0951212405381588, 0.0482516061458583],
        [0.137318972929847, 0.761241990602591, 0.101439036467562],
        [0.11189821299995, 0.0767994186031903, 0.811302368396859],
    ]
)
"""Blender 4.x's AgX inset (Sobotka's rotate (3, −1, −2), inset (0.4, 0.22, 0.13)), rows:
outputs, applied to Rec.2020."""
AGX_OUTSET = np.linalg.inv(
    np.array(
        [
            [0.899796955911611, 0.0871996192028351, 0.013003424885555],
            [0.11142098895748, 0.875575586156966, 0.0130034248855548],
            [0.11142098895748, 0.0871996192028349, 0.801379391839686],
        ]
    )
)
"""Blender 4.x's AgX outset: the inverse of Sobotka's inset (0.4, 0.22, 0.04), no rotation."""
AGX_MIN_EV, AGX_MAX_EV = -12.47393, 4.026069
"""The log2 encoding's range, ``log2(0.18 · 2^−10)`` and ``log2(0.18 · 2^6.5)``, rounded
as the published code rounds them (16.5 stops around middle grey)."""
AGX_SIGMOID = (15.5, -40.14, 31.96, -6.868, 0.4298, 0.1191, -0.00232)
"""Wrensch's 6th-degree fit of AgX's default-contrast sigmoid, x⁶ first."""
AGX_LOOKS: dict[str, tuple[tuple[float, float, float], float, float]] = {
    "punchy": ((1.0, 1.0, 1.0), 1.35, 1.4),
    "golden": ((1.0, 0.9, 0.5), 0.8, 1.3),
}
"""ASC CDL looks (slope per channel, power, saturation; offset 0), as Filament publishes
them."""


def _agx_sigmoid(x: Array) -> Array:
    x2 = x * x
    x4 = x2 * x2
    a6, a5, a4, a3, a2, a1, a0 = AGX_SIGMOID
    return a6 * x4 * x2 + a5 * x4 * x + a4 * x4 + a3 * x2 * x + a2 * x2 + a1 * x + a0


def _agx_look(v: Array, look: str) -> Array:
    """The published look: ``luma + sat · ((slope v)^power − luma)`` with the Rec.709 luma
    of ``v`` taken before the slope and power (so grey stays grey under a uniform slope)."""
    if look == "none":
        return v
    slope, power, sat = AGX_LOOKS[look]
    luma = luminance(v, REC709_WEIGHTS)[..., None]
    sv = v * jnp.asarray(slope, v.dtype).reshape((1,) * (v.ndim - 1) + (3,))
    pos = sv > 0  # (the published pow is undefined below 0: the sigmoid dips to -0.0023)
    cdl = jnp.where(pos, positive_power(jnp.where(pos, sv, 1.0), power), 0.0)
    return luma + sat * (cdl - luma)


@register("agx")
class AgX(_AbstractViewTransform):
    """Sobotka's AgX with Blender 4.x's matrices, the sigmoid as a published polynomial fit.

    With ``x = 2^exposure · RGB`` (linear Rec.709, relative units), per pixel:

    1. to Rec.2020 and clamp at 0, then Blender's inset matrix (towards the achromatic
       axis, with a rotation of the primaries);
    2. log2 encoding over 16.5 stops around middle grey:
       ``u = clamp((log2 max(v, 1e-10) − min_ev) / (max_ev − min_ev), 0, 1)``, ``min_ev =
       −12.47393``, ``max_ev = 4.026069`` (0.18 maps to ``u = 10/16.5``);
    3. the sigmoid, as Wrensch's polynomial ``15.5u⁶ − 40.14u⁵ + 31.96u⁴ − 6.868u³ +
       0.4298u² + 0.1191u − 0.00232``;
    4. the look (``look``), an ASC CDL on the sigmoid's output;
    5. Blender's outset matrix, ``max(·, 0)^2.2`` (the published display linearisation:
       the sigmoid's output is for a 2.2 display), back to Rec.709, clamp to [0, 1].

    Output: display-linear Rec.709 in [0, 1]. Greys stay grey (every matrix row sums to
    1) except with the ``golden`` look, whose slope (1, 0.9, 0.5) is a warm tint.

    How close to Blender 4.x: the matrices and log range are Blender's, but the polynomial
    fits Sobotka's original sigmoid (mean squared error 3.7e-6, Wrensch says), not
    Blender 4.x's (Chow 2023, after Sobotka and Smith's tunable sigmoid, for a 2.4
    display): on greys the two encoded curves differ by up to 0.030, the display-linear
    outputs by up to 0.05, and middle grey 0.18 comes out as 0.215 here where Blender
    gives 0.18. Blender also mixes 40 % of the pre-curve hue back and guards out-of-gamut
    values, which this published form does not; it is the form Filament and three.js
    ship.

    Looks (``look``): ``punchy`` (power 1.35, saturation 1.4) and ``golden`` (slope
    (1, 0.9, 0.5), power 0.8, saturation 1.3), Filament's figures after Wrensch; copies of
    Wrensch's post differ in the golden saturation and the punchy power. As published, the
    luma of the saturation step is that of the look's input (ASC CDL v1.2 takes it after
    the slope and power), and negative values before the power are 0 (the published pow is
    undefined there).

    References: Sobotka, AgX (https://github.com/sobotka/AgX); Blender 4.x's matrices,
    Chow 2023 (https://github.com/EaryChow/AgX_LUT_Gen, ``AgXBaseRec2020.py``); the
    polynomial and looks, Wrensch 2023, "Minimal AgX Implementation"
    (https://iolite-engine.com/blog_posts/minimal_agx_implementation) and Filament
    (https://github.com/google/filament, ``filament/src/ToneMapper.cpp``).
    """

    reference: ClassVar[str] = (
        "Sobotka, AgX, https://github.com/sobotka/AgX, with Blender 4.x's matrices"
        " (Chow 2023, https://github.com/EaryChow/AgX_LUT_Gen) and Wrensch's 2023 polynomial"
        " sigmoid and looks, https://iolite-engine.com/blog_posts/minimal_agx_implementation"
    )

    rounding: ClassVar[float] = 3e-5
    """float32: the log2 encoding and the cancelling matrices around the 2.2 power leave
    up to 3e-5 of display white between evaluation orders (measured against float64)."""

    exposure: Array = _exposure()
    look: str = parameter(
        "none",
        help="ASC CDL look after the sigmoid: none, punchy (more contrast and saturation),"
        " golden (warm tint)",
        static=True,
        choices=("none", "punchy", "golden"),
    )

    def _map(self, x: Array) -> Array:
        v = jnp.maximum(apply_matrix(x, REC709_TO_REC2020), 0.0)
        v = jnp.log2(jnp.maximum(apply_matrix(v, AGX_INSET), 1e-10))
        v = _agx_sigmoid(_unit((v - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV)))
        v = apply_matrix(_agx_look(v, self.look), AGX_OUTSET)
        pos = v > 0
        v = jnp.where(pos, positive_power(jnp.where(pos, v, 1.0), 2.2), 0.0)
        return _unit(apply_matrix(v, REC2020_TO_REC709))


# ----------------------------------------------------------------------------- PBR Neutral

PBR_F90 = 0.04
"""Fresnel reflectance at normal incidence of IoR 1.5 materials (PBR Neutral's offset)."""


@register("pbr_neutral")
class PbrNeutral(_AbstractViewTransform):
    """Khronos PBR Neutral tone mapper (2024), exactly as its specification.

    With ``c = max(2^exposure · RGB, 0)`` (linear Rec.709, relative units), ``x = min(c)``,
    ``f = x − x²/(4 F90)`` for ``x < 2 F90`` else ``F90`` (``F90 = 0.04``), ``p = max(c − f)``,
    ``K_s = start_compression`` (0.8 − 0.04), ``K_d = desaturation`` (0.15):

    - ``p < K_s``: ``out = c − f``;
    - else ``p_n = 1 − (1 − K_s)² / (p + 1 − 2 K_s)``, ``g = 1 / (K_d (p − p_n) + 1)``,
      ``out = (c − f) (p_n / p) g + p_n (1 − g)``.

    Output: display-linear Rec.709 in [0, 1] (no further clamp is needed). Base colours
    with every channel in [0.08, 0.8] come out as ``c − 0.04`` exactly, and hues (angles
    around the grey axis) never shift: the compression and desaturation happen in the plane
    of the colour and white.

    Reference: Khronos Group 2024, "Khronos PBR Neutral Tone Mapper", specification and
    sample code, https://github.com/KhronosGroup/ToneMapping/tree/main/PBR_Neutral
    (write-up: https://modelviewer.dev/examples/tone-mapping).

    Departure: negative channels are 0 (the specification requires non-negative input).
    """

    reference: ClassVar[str] = (
        "Khronos Group 2024, Khronos PBR Neutral Tone Mapper,"
        " https://github.com/KhronosGroup/ToneMapping/tree/main/PBR_Neutral"
    )

    exposure: Array = _exposure()
    start_compression: Array = parameter(
        0.8 - PBR_F90,
        help="largest channel (after the 0.04 offset) where highlight compression starts, K_s",
        range="[0, 1)",
    )
    desaturation: Array = parameter(
        0.15, help="speed of desaturation of compressed highlights, K_d", range="[0, inf)"
    )

    def _map(self, x: Array) -> Array:
        c = jnp.maximum(x, 0.0)
        low = channel_min(c, keepdims=True)
        offset = jnp.where(low < 2 * PBR_F90, low - low * low / (4 * PBR_F90), PBR_F90)
        c = c - offset
        peak = channel_max(c, keepdims=True)
        ks, kd = self.start_compression, self.desaturation
        compress = peak >= ks
        p = jnp.where(compress, peak, 1.0)  # the other branch must not divide by p + 1 - 2 K_s
        d = 1.0 - ks
        new_peak = 1.0 - d * d / (p + d - ks)
        g = 1.0 / (kd * (p - new_peak) + 1.0)
        return jnp.where(compress, c * (new_peak / p) * g + new_peak * (1.0 - g), c)


# ----------------------------------------------------------------------------- Hable


@register("hable2010")
class Hable2010(_AbstractViewTransform):
    """Hable's Uncharted 2 filmic curve with the constants of his 2010 blog post.

    ``out = clamp(h(bias · x) / h(W), 0, 1)``, ``x = 2^exposure · RGB`` per channel
    (relative units), with ``h(x) = (x (A x + C B) + D E) / (x (A x + B) + D F) − E / F``,
    ``A = 0.15`` (shoulder strength), ``B = 0.50`` (linear strength), ``C = 0.10`` (linear
    angle), ``D = 0.20`` (toe strength), ``E = 0.02`` (toe numerator), ``F = 0.30`` (toe
    denominator), white ``W = 11.2`` and exposure bias 2; output display-linear in [0, 1].

    The same curve as :class:`~hdrjax.operators.Filmic` (``filmic``, colour-hdri's operator,
    one shared function): ``filmic`` has the same formula, white and bias, but colour-hdri's
    constants ``A = 0.22``, ``B = 0.30``, ``E = 0.01`` (colour-hdri cites Hable's GDC 2010
    slides as well as this post), and no clamp (it exceeds 1 above ``W``). With those three
    constants, ``hable2010`` equals ``filmic`` clamped to [0, 1].

    Reference: Hable 2010, "Filmic Tonemapping Operators" (blog post),
    http://filmicworlds.com/blog/filmic-tonemapping-operators/ (first published at
    http://filmicgames.com/archives/75).

    Departures: negative channels are 0; the blog's shader also multiplies by a fixed 16
    for its test scene (``exposure = 4`` reproduces it) and encodes with ``x^(1/2.2)``,
    which hdrjax's display encoding replaces; the published curve is not clamped above
    ``W`` (a display clips it).
    """

    reference: ClassVar[str] = (
        "Hable 2010, Filmic Tonemapping Operators, blog post,"
        " http://filmicworlds.com/blog/filmic-tonemapping-operators/"
    )

    exposure: Array = _exposure()
    shoulder_strength: Array = hable_parameter("shoulder_strength", 0.15)
    linear_strength: Array = hable_parameter("linear_strength", 0.50)
    linear_angle: Array = hable_parameter("linear_angle", 0.10)
    toe_strength: Array = hable_parameter("toe_strength", 0.20)
    toe_numerator: Array = hable_parameter("toe_numerator", 0.02)
    toe_denominator: Array = hable_parameter("toe_denominator", 0.30)
    exposure_bias: Array = hable_parameter("exposure_bias", 2.0)
    linear_whitepoint: Array = hable_parameter("linear_whitepoint", 11.2)

    def _map(self, x: Array) -> Array:
        return _unit(hable_curve(self, x))


# ----------------------------------------------------------------------------- Uchimura


@register("uchimura2017")
class Uchimura2017(_AbstractViewTransform):
    """Uchimura's Gran Turismo curve (CEDEC 2017), per channel.

    A toe ``T(x) = m (x/m)^c + b``, a linear section ``L(x) = m + a (x − m)`` from ``m`` to
    ``S₀ = m + l₀``, ``l₀ = (P − m) l / a``, and a shoulder ``S(x) = P − (P − S₁)
    e^(−C x')`` with ``S₁ = m + a l₀``, ``C = a / (P − S₁)``, ``x' = x − S₀``; the toe
    blends into the line with ``w = 1 − smoothstep(0, m, x)``:
    ``out = T w + L (1 − w)`` below ``S₀``, ``S`` above. ``x = 2^exposure · RGB``
    (relative units); output display-linear in [0, P] (P = 1: [0, 1]).

    Parameters and defaults (P, a, m, l, c, b in the talk): ``max_display`` 1,
    ``contrast`` 1, ``linear_start`` 0.22, ``linear_length`` 0.4, ``black_tightness`` 1.33,
    ``pedestal`` 0; ``linear_start`` must be below ``max_display``.

    Reference: Uchimura 2017, "HDR theory and practice", CEDEC 2017 (Polyphony Digital),
    https://www.slideshare.net/nikuque/hdr-theory-and-practicce-jp; the formulas as
    transcribed by Romain Guy, https://www.desmos.com/calculator/gslcdxvipg

    Departure: negative channels are 0 (the published ``pow`` of a negative base is
    undefined).
    """

    reference: ClassVar[str] = (
        "Uchimura 2017, HDR theory and practice, CEDEC 2017,"
        " https://www.slideshare.net/nikuque/hdr-theory-and-practicce-jp"
    )

    exposure: Array = _exposure()
    max_display: Array = parameter(
        1.0, help="largest display value P (1: display white)", range="(0, 1]"
    )
    contrast: Array = parameter(1.0, help="slope a of the linear section", range="(0, inf)")
    linear_start: Array = parameter(
        0.22, help="start m of the linear section (below max_display)", range="(0, 1)"
    )
    linear_length: Array = parameter(
        0.4, help="length l of the linear section, a fraction of P - m", range="[0, 1)"
    )
    black_tightness: Array = parameter(
        1.33, help="toe exponent c (black tightness)", range="(0, inf)"
    )
    pedestal: Array = parameter(0.0, help="black level b added to the toe", range="[0, 1)")

    def __check_init__(self):
        if traced(self):
            return
        m, P = np.asarray(self.linear_start), np.asarray(self.max_display)
        if np.any(m >= P):
            raise ValueError(
                f"linear_start: expected a value below max_display ({_shown(P)})"
                f" (uchimura2017), got {_shown(m)}"
            )

    def _map(self, x: Array) -> Array:
        P, a, m = self.max_display, self.contrast, self.linear_start
        l, c, b = self.linear_length, self.black_tightness, self.pedestal  # noqa: E741
        l0 = (P - m) * l / a
        S0 = m + l0
        S1 = m + a * l0
        x = jnp.maximum(x, 0.0)
        toe = jnp.minimum(x, m) / m  # the toe only counts below m
        pos = toe > 0
        T = m * jnp.where(pos, positive_power(jnp.where(pos, toe, 1.0), c), 0.0) + b
        t = jnp.clip(x / m, 0.0, 1.0)
        w0 = 1.0 - t * t * (3.0 - 2.0 * t)
        L = m + a * (x - m)
        # the shoulder only counts from S0 on (its exponential grows below)
        S = P - (P - S1) * jnp.exp(-a / (P - S1) * (jnp.maximum(x, S0) - S0))
        return jnp.where(x >= S0, S, T * w0 + L * (1.0 - w0))


# ----------------------------------------------------------------------------- Lottes


@register("lottes2016")
class Lottes2016(_AbstractViewTransform):
    """Lottes' curve (GDC 2016), per channel.

    ``out = clamp(x^a / (x^(a d) b + c), 0, 1)``, ``x = 2^exposure · RGB`` (relative units),
    with contrast ``a``, shoulder ``d``, and ``b``, ``c`` derived so that ``mid_in`` maps
    to ``mid_out`` and ``hdr_max`` to 1:
    ``b = (−mid_in^a + hdr_max^a mid_out) / ((hdr_max^(ad) − mid_in^(ad)) mid_out)``,
    ``c = (hdr_max^(ad) mid_in^a − hdr_max^a mid_in^(ad) mid_out) / ((hdr_max^(ad) −
    mid_in^(ad)) mid_out)``. Output display-linear in [0, 1].

    Defaults ``a = 1.6``, ``d = 0.977``, ``hdr_max = 8``, ``mid_in = 0.18``,
    ``mid_out = 0.267``: those of the widely copied transcription (Romain Guy's, 2017;
    the talk gives the construction). The curve has no pole and is positive only while
    ``(mid_in/hdr_max)^a < mid_out < (mid_in/hdr_max)^(a (1 − d))`` (``b, c > 0``):
    concrete values outside are refused.

    Evaluated as ``exp(a ln x − ln(b e^(a d ln x) + c))`` (a log-sum-exp): no overflow of
    ``x^a`` for huge ``x`` (the published form gives ``∞/∞``).

    Reference: Lottes 2016, "Advanced Techniques and Optimization of HDR Color Pipelines",
    Game Developers Conference 2016 (AMD),
    https://gpuopen.com/wp-content/uploads/2016/03/GdcVdrLottes.pdf

    Departures: negative channels are 0; values above ``hdr_max`` (above 1 in the
    published curve, which rises as ``x^(a (1 − d))``) are clamped to 1.
    """

    reference: ClassVar[str] = (
        "Lottes 2016, Advanced Techniques and Optimization of HDR Color Pipelines, GDC 2016,"
        " https://gpuopen.com/wp-content/uploads/2016/03/GdcVdrLottes.pdf"
    )

    exposure: Array = _exposure()
    contrast: Array = parameter(1.6, help="contrast a (the toe's exponent)", range="(0, inf)")
    shoulder: Array = parameter(
        0.977, help="shoulder d: the highlights' exponent is a (1 - d)", range="(0, 1]"
    )
    hdr_max: Array = parameter(
        8.0, help="input value mapped to display white", unit="image units", range="(0, inf)"
    )
    mid_in: Array = parameter(
        0.18, help="input middle grey (mapped to mid_out)", unit="image units", range="(0, inf)"
    )
    mid_out: Array = parameter(0.267, help="display value of mid_in", range="(0, 1)")

    def __check_init__(self):
        if traced(self):
            return
        a, d = np.asarray(self.contrast), np.asarray(self.shoulder)
        mi, hm, mo = np.asarray(self.mid_in), np.asarray(self.hdr_max), np.asarray(self.mid_out)
        if np.any(mi >= hm):
            raise ValueError(
                f"mid_in: expected a value below hdr_max ({_shown(hm)}) (lottes2016), got"
                f" {_shown(mi)}"
            )
        r = mi / hm
        lo, hi = r**a, r ** (a * (1 - d))
        if np.any((mo <= lo) | (mo >= hi)):
            raise ValueError(
                f"mid_out: expected a value in ({_shown(np.round(lo, 4))},"
                f" {_shown(np.round(hi, 4))}) for"
                " these contrast, shoulder, mid_in and hdr_max (lottes2016: outside, the"
                f" curve has a pole or is negative), got {_shown(mo)}"
            )

    def _coefficients(self) -> tuple[Array, Array]:
        a, ad = self.contrast, self.contrast * self.shoulder
        mi, hm, mo = self.mid_in, self.hdr_max, self.mid_out
        den = (hm**ad - mi**ad) * mo
        b = (-(mi**a) + hm**a * mo) / den
        c = (hm**ad * mi**a - hm**a * mi**ad * mo) / den
        return b, c

    def _map(self, x: Array) -> Array:
        b, c = self._coefficients()
        a, ad = self.contrast, self.contrast * self.shoulder
        pos = x > 0
        lx = jnp.log(jnp.where(pos, x, 1.0))
        ln_out = a * lx - jnp.logaddexp(jnp.log(b) + ad * lx, jnp.log(c))
        return jnp.where(pos, jnp.exp(jnp.minimum(ln_out, 0.0)), 0.0)


__all__ = [
    "AcesHill",
    "AcesNarkowicz2015",
    "AgX",
    "Hable2010",
    "Lottes2016",
    "PbrNeutral",
    "Uchimura2017",
]
