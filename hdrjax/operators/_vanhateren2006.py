"""van Hateren 2006 cone model: the steady state of the human cone's response as a tone curve.

Reference:
    J. H. van Hateren. "Encoding of high dynamic range video with a model of human cones."
    ACM Transactions on Graphics 25(4), 2006, pp. 1380–1399.
    https://doi.org/10.1145/1183287.1183293

The paper drives a dynamic model of the human cone with the retinal illuminance of each
pixel and displays the model's response. For a still image (or a video frame held long
enough) the model is in its steady state; this module computes that state as HDR
Toolbox's ``VanHaterenTMO`` does, with retinal illuminance ``I = A L`` in trolands (``A``
the pupil area in mm², ``L`` in cd/m²):

    ``β = c_β + k_β I``  (the rate of the cGMP hydrolysis, 1/ms),
    ``a_C I_os^5 + I_os^4 = 1 / β``  (the outer-segment current, normalised),

and the displayed value is ``D = 1 − I_os / I_os,max`` with ``I_os,max`` the current in
the dark (``I = 0``). The equation has one positive root (its left side grows with
``I_os``); it is solved by Newton's method on ``ln I_os``, where the function is convex with
slope between 4 and 5, so a handful of steps from ``ln(1/β) / 4`` reach float64 precision.
"""

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array

from ._base import (
    AbstractOperator,
    Prepared,
    parameter,
    register,
    safe_log,
    scale_by_luminance,
    weights_field,
)

REFERENCE = (
    "van Hateren 2006, Encoding of high dynamic range video with a model of human cones,"
    " ACM Transactions on Graphics 25(4), pp. 1380-1399,"
    " https://doi.org/10.1145/1183287.1183293"
)
NEWTON_STEPS = 6
"""Newton steps on ``ln I_os`` (the error after the first guess is below 0.1; convergence
is quadratic, so 6 steps are far past float64 precision)."""


def outer_segment_log_current(ln_inv_beta: Array, a_C: Array) -> Array:
    """``ln I_os``: the positive root of ``a_C I_os^5 + I_os^4 = 1 / β`` given ``ln(1/β)``.

    With ``u = ln I_os``: ``h(u) = 4u + ln(1 + a_C e^u) − ln(1/β) = 0``, ``h' ∈ [4, 5]``,
    ``h'' > 0``; Newton's method from ``u₀ = ln(1/β) / 4`` (where ``h ≥ 0``) decreases
    monotonically to the root."""
    u = ln_inv_beta / 4.0
    for _ in range(NEWTON_STEPS):
        t = a_C * jnp.exp(u)
        u = u - (4.0 * u + jnp.log1p(t) - ln_inv_beta) / (4.0 + t / (1.0 + t))
    return u


def srgb_decode_extended(v: Array) -> Array:
    """The sRGB decoding (IEC 61966-2-1) of values outside [0, 1] too: linear through 0
    below the threshold, the power law above 1 (capped where it would overflow)."""
    hi = v > 0.04045
    top = float(jnp.finfo(v.dtype).max) ** (1.0 / 2.4) * 0.5
    base = (jnp.minimum(jnp.where(hi, v, 1.0), top) + 0.055) / 1.055
    return jnp.where(hi, jnp.exp(2.4 * jnp.log(base)), v / 12.92)


@register("vanhateren2006")
class VanHateren2006(AbstractOperator):
    """van Hateren 2006 cone model in its steady state (module docstring), as HDR Toolbox's
    ``VanHaterenTMO`` computes it (its constants and pupil area are the defaults).

    Input: absolute linear RGB in cd/m²; the model is absolute (its adaptation depends on
    the light level), so a relative image must first be multiplied by its cd/m² per unit;
    a relative image taken as cd/m² maps as a dim scene would. Luminance ``L`` with the
    image's weights; ``I = A L`` trolands.

    Output: display-referred linear RGB in [0, 1] for grey pixels. The model's response
    ``D`` is a display *signal*, not display light: HDR Toolbox returns ``C · D / L`` per
    channel to be shown as is (it warns that the image "does not require gamma correction":
    the cone's compressive response plays the part of the encoding). This operator returns
    the display light of that signal: each channel of ``C · D / L`` decoded with the sRGB
    transfer function, so that sRGB encoding (:mod:`hdrjax.display`) gives back exactly the
    Toolbox's values. Colour is therefore scaled in the encoded domain, as in the Toolbox:
    saturated colours come out more saturated than a ratio in linear light would make them.
    Channels above the signal's 1 stay above 1 (they clip when encoded).

    Departures: HDR Toolbox clamps ``D`` to [0, 1] (it is in [0, 1] already) and finds the
    root with ``roots`` of the fifth-degree polynomial per pixel; here Newton's method (same
    root to float rounding). Static images only: the dynamics of the cone model (its time
    constants, for video) are not modelled.

    Attributes:
        pupil_area: ``A``, mm² (10, HDR Toolbox's fixed pupil): trolands per cd/m².
        k_beta: ``k_β``, the light-driven part of the hydrolysis rate, 1/(ms·td) (1.6e-4).
        c_beta: ``c_β``, its dark rate, 1/ms (2.8e-3).
        a_C: ``a_C``, the strength of the calcium feedback (9e-2).
        weights: luminance weights of the image's primaries (Rec.709 default).
    """

    reference: ClassVar[str] = REFERENCE
    default_fit_params: ClassVar[tuple[str, ...]] = ("pupil_area",)

    pupil_area: Array = parameter(
        10.0,
        help="pupil area A: retinal illuminance I = A L trolands",
        unit="mm²",
        range="(0, inf)",
    )
    k_beta: Array = parameter(
        1.6e-4, help="light-driven hydrolysis rate k_beta", unit="1/(ms td)", range="(0, inf)"
    )
    c_beta: Array = parameter(
        2.8e-3, help="dark hydrolysis rate c_beta", unit="1/ms", range="(0, inf)"
    )
    a_C: Array = parameter(9e-2, help="calcium feedback strength a_C", range="[0, inf)")
    weights: tuple[float, float, float] = weights_field()

    def signal(self, L: Array) -> Array:
        """The model's display signal ``D = 1 − I_os / I_os,max`` of luminance ``L ≥ 0``
        (cd/m²), before any colour or decoding."""
        L = jnp.asarray(L)
        dtype = L.dtype
        c_beta = self.c_beta.astype(dtype)
        a_C = self.a_C.astype(dtype)
        ln_c = jnp.log(c_beta)
        # ln(1/β) = −ln(c_β + k_β A L), without overflow at the dtype's largest L
        ln_light = safe_log(L) + jnp.log(self.k_beta * self.pupil_area).astype(dtype)
        ln_beta = jnp.where(L > 0, jnp.logaddexp(ln_c, ln_light), ln_c)
        u = outer_segment_log_current(-ln_beta, a_C)
        u_max = outer_segment_log_current(-ln_c, a_C)
        return jnp.clip(-jnp.expm1(u - u_max), 0.0, 1.0)

    def _apply(self, p: Prepared) -> Array:
        encoded = scale_by_luminance(p.rgb, p.L, self.signal)
        return srgb_decode_extended(encoded)


__all__ = ["VanHateren2006", "outer_segment_log_current"]
