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

For video, :func:`vanhateren2006_sequence` integrates the model's dynamics (its low-pass
stages and divisive feedback loops) over the frames, each pixel its own cone, carrying
the state from frame to frame with ``jax.lax.scan``.
"""

import math
from typing import ClassVar, Literal, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._colour import luminance
from ._base import (
    Prepared,
    dispatch,
    parameter,
    register,
    safe_log,
    scale_by_luminance,
    weights_field,
)
from ._time import AbstractTimeDependentOperator, scan_frames, sequence_arguments

REFERENCE = (
    "van Hateren 2006, Encoding of high dynamic range video with a model of human cones,"
    " ACM Transactions on Graphics 25(4), pp. 1380-1399,"
    " https://doi.org/10.1145/1183287.1183293"
)
NEWTON_STEPS = 6
"""Newton steps on ``ln I_os`` (the error after the first guess is below 0.1; convergence
is quadratic, so 6 steps are far past float64 precision)."""


def outer_segment_log_current(
    ln_inv_beta: Array,
    a_C: Array,
    exponents: tuple[float, float] = (0.25, 1.0),
    steps: int = NEWTON_STEPS,
) -> Array:
    """``ln I_os``: the positive root of ``a_C I_os^5 + I_os^4 = 1 / β`` given ``ln(1/β)``.

    With ``u = ln I_os``: ``h(u) = 4u + ln(1 + a_C e^u) − ln(1/β) = 0``, ``h' ∈ [4, 5]``,
    ``h'' > 0``; Newton's method from ``u₀ = ln(1/β) / 4`` (where ``h ≥ 0``) decreases
    monotonically to the root.

    ``exponents = (n_X, n_C)`` solves the cone model's steady state in general,
    ``I_os^(1/n_X) (1 + (a_C I_os)^n_C) = 1/β`` (:func:`vanhateren2006_sequence`; the
    default ``(1/4, 1)`` is the equation above): ``h(u) = u / n_X + ln(1 + t) − ln(1/β)``,
    ``t = (a_C e^u)^n_C``, convex with slope between ``1/n_X`` and ``1/n_X + n_C``, from
    ``u₀ = n_X ln(1/β)``; ``steps`` Newton steps."""
    n_X, n_C = exponents
    u = n_X * ln_inv_beta
    for _ in range(steps):
        t = a_C * jnp.exp(u) if n_C == 1.0 else jnp.power(a_C * jnp.exp(u), n_C)
        u = u - (u / n_X + jnp.log1p(t) - ln_inv_beta) / (1.0 / n_X + n_C * t / (1.0 + t))
    return u


def srgb_decode_extended(v: Array) -> Array:
    """The sRGB decoding (IEC 61966-2-1) of values outside [0, 1] too: linear through 0
    below the threshold, the power law above 1 (capped where it would overflow)."""
    hi = v > 0.04045
    top = float(jnp.finfo(v.dtype).max) ** (1.0 / 2.4) * 0.5
    base = (jnp.minimum(jnp.where(hi, v, 1.0), top) + 0.055) / 1.055
    return jnp.where(hi, jnp.exp(2.4 * jnp.log(base)), v / 12.92)


@register("vanhateren2006")
class VanHateren2006(AbstractTimeDependentOperator):
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
    root to float rounding). This is the steady state; :func:`vanhateren2006_sequence`
    (or :meth:`sequence`) maps video with the model's dynamics.

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
        return _display(p, self.signal(p.L))

    def sequence(
        self,
        frames: Float[ArrayLike, "T H W 3"],
        fps: float,
        *,
        initial: "ConeState | None" = None,
    ) -> tuple[Float[Array, "T H W 3"], "ConeState"]:
        """The cone model's dynamics: :func:`vanhateren2006_sequence` with this operator."""
        return vanhateren2006_sequence(frames, fps, self, initial=initial)


def _display(p: Prepared, D: Array) -> Array:
    """Display light of the signal ``D`` (per pixel) with the pixel's colour ratios,
    scaled in the encoded domain (class docstring)."""
    encoded = scale_by_luminance(p.rgb, p.L, lambda Lc: jnp.broadcast_to(D[..., None], Lc.shape))
    return srgb_decode_extended(encoded)


# ---------------------------------------------------------------------------- dynamics

TAU_R = 0.49
"""Time constant (ms) of the activated visual pigment ``R*`` (van Hateren 2005)."""
TAU_E = 16.8
"""Time constant (ms) of the activated phosphodiesterase ``E*`` (van Hateren 2005)."""
TAU_C = 2.89
"""Time constant (ms) of the calcium concentration ``C`` (van Hateren 2005)."""
MAX_STEP = 0.5
"""Longest integration step (ms) within a frame interval (:func:`vanhateren2006_sequence`)."""
EXPONENTS = {"hdrtoolbox": (0.25, 1.0), "paper": (1.0, 4.0)}
"""``(n_X, n_C)``, the exponents of the outer segment's current ``I_os = X^n_X`` and of the
calcium feedback ``α = 1 / (1 + (a_C C)^n_C)``, of each ``compat`` mode."""
PAPER_NEWTON_STEPS = 12
"""Newton steps of the steady state with the paper's exponents (slope between 1 and 5)."""


class ConeState(NamedTuple):
    """The cone model's state per pixel: ``R`` and ``E``, the low-passed illuminance after
    the pigment (``R*``) and phosphodiesterase (``E*``) stages, in cd/m² (trolands over
    the pupil area); ``X``, the cGMP concentration; ``C``, the calcium concentration
    (normalised, dimensionless)."""

    R: Array
    E: Array
    X: Array
    C: Array


def _input_luminance(frames: Array, weights) -> Array:
    """The luminance driving the cones: NaN/Inf pixels and negative luminance count as 0
    (the output puts NaN and Inf pixels back)."""
    L = luminance(frames, weights)
    return jnp.where(jnp.isfinite(L) & (L > 0), L, 0.0)


def _rate(op: VanHateren2006, E: Array) -> Array:
    """``β = c_β + k_β A E`` (1/ms) of ``E`` in cd/m²."""
    dt = E.dtype
    return op.c_beta.astype(dt) + (op.k_beta * op.pupil_area).astype(dt) * E


def _log_current(op: VanHateren2006, ln_inv_beta: Array, exponents: tuple[float, float]) -> Array:
    """``ln I_os`` in the steady state for ``ln(1/β)`` (:func:`outer_segment_log_current`)."""
    steps = NEWTON_STEPS if exponents == EXPONENTS["hdrtoolbox"] else PAPER_NEWTON_STEPS
    a_C = op.a_C.astype(ln_inv_beta.dtype)
    return outer_segment_log_current(ln_inv_beta, a_C, exponents, steps)


def cone_steady_state(
    op: VanHateren2006, L: Array, compat: Literal["hdrtoolbox", "paper"] = "hdrtoolbox"
) -> ConeState:
    """The state adapted to luminance ``L`` (cd/m², per pixel) held constant: ``R = E = L``,
    ``C = I_os`` (the steady-state root, :func:`outer_segment_log_current`),
    ``X = I_os^(1/n_X)``."""
    n_X, _ = exponents = EXPONENTS[compat]
    u = _log_current(op, -jnp.log(_rate(op, L)), exponents)
    return ConeState(L, L, jnp.exp(u / n_X), jnp.exp(u))


def _cone_step(
    op: VanHateren2006, s: ConeState, L: Array, h: float, exponents: tuple[float, float]
) -> ConeState:
    """The state ``h`` ms later under luminance ``L`` (:func:`vanhateren2006_sequence`).

    ``R`` and ``E`` exactly (a constant input through two first-order low-pass filters);
    ``X`` and ``C`` by an exponential step: each relaxes towards its instantaneous goal at
    its own rate, ``X → α/β`` at rate ``β``, ``C → I_os`` at rate ``1/τ_C``, which is
    stable at any step and leaves the steady state exactly where it is."""
    n_X, n_C = exponents
    dt = L.dtype
    tiny = jnp.finfo(dt).tiny
    e_R, e_E = math.exp(-h / TAU_R), math.exp(-h / TAU_E)
    r, e = s.R - L, s.E - L
    a = r * (TAU_R / (TAU_R - TAU_E))
    R = L + r * e_R
    E = L + a * e_R + (e - a) * e_E
    beta = _rate(op, 0.5 * (s.E + E))  # the rate over the step at its midpoint
    a_C = op.a_C.astype(dt)
    feedback = a_C * s.C if n_C == 1.0 else jnp.power(a_C * s.C, n_C)
    goal = 1.0 / (beta * (1.0 + feedback))
    X = goal + (s.X - goal) * jnp.exp(-beta * h)
    I_os = jnp.exp(n_X * jnp.log(jnp.maximum(X, tiny)))
    C = I_os + (s.C - I_os) * math.exp(-h / TAU_C)
    return ConeState(R, E, X, C)


def vanhateren2006_sequence(
    frames: Float[ArrayLike, "T H W 3"],
    fps: float,
    op: VanHateren2006 | None = None,
    *,
    initial: ConeState | None = None,
    compat: Literal["hdrtoolbox", "paper"] = "hdrtoolbox",
    max_step: float = MAX_STEP,
) -> tuple[Float[Array, "T H W 3"], ConeState]:
    """Map video with the dynamics of van Hateren's (2006) cone model, pixel by pixel.

    Each pixel drives its own model cone with its retinal illuminance ``I = A L`` (td), held
    for the frame interval ``1 / fps`` (a sample-and-hold display). The stages of the
    model (van Hateren 2005, Journal of Vision 5(4):331–347,
    https://doi.org/10.1167/5.4.5, whose constants the 2006 paper uses), times in ms:

    - two first-order low-pass filters, the activated pigment and phosphodiesterase:
      ``τ_R dR/dt = I − R``, ``τ_E dE/dt = R − E`` (``τ_R = 0.49``, ``τ_E = 16.8``);
    - the hydrolysis of cGMP, a divisive feedback loop whose gain and time constant are
      both ``1/β``: ``dX/dt = α − β X``, ``β = c_β + k_β E``;
    - the outer segment's current ``I_os = X^n_X`` and the calcium feedback on the
      synthesis of cGMP, a second divisive loop: ``α = 1 / (1 + (a_C C)^n_C)``,
      ``τ_C dC/dt = I_os − C`` (``τ_C = 2.89``);
    - the display signal, as the static operator: ``D = 1 − I_os / I_os,max``, colour as
      :class:`VanHateren2006` puts it back.

    The steady state is ``I_os^(1/n_X) (1 + (a_C I_os)^n_C) = 1/β``. The model's exponents
    are ``n_X = 1``, ``n_C = 4`` (``compat="paper"``): ``a_C⁴ I_os⁵ + I_os = 1/β``. HDR
    Toolbox's ``VanHaterenTMO``, which :class:`VanHateren2006` reproduces, solves
    ``a_C I_os⁵ + I_os⁴ = 1/β`` instead: the same structure with ``n_X = 1/4``,
    ``n_C = 1``, which ``compat="hdrtoolbox"`` (the default) uses so that a still scene
    maps exactly as the static operator maps it (and ``hdrjax batch --fps`` agrees with
    ``hdrjax batch`` on still scenes). The membrane stages after the outer segment are not
    modelled (the display signal is the outer segment's, as in the static operator). The
    slowest part of the adaptation is the cGMP loop in dim light (``1/c_β = 357`` ms): the
    cones adapt to a brighter scene within a frame and to a darker one over several.

    Integration: ``R`` and ``E`` exactly over each step, ``X`` and ``C`` with exponential
    steps (:func:`_cone_step`) of at most ``max_step`` ms, ``⌈1000 / (fps · max_step)⌉``
    per frame; the error against an ODE solver is in the tests.

    Args:
        frames: ``(T, H, W, 3)`` linear RGB in cd/m²; NaN/Inf pixels drive their cone as
            black and come out as the static operator puts them (NaN, or white for +Inf).
        fps: frames per second, a number (it sets the steps per frame).
        op: the operator whose ``pupil_area``, ``k_beta``, ``c_beta``, ``a_C`` and
            ``weights`` are used; ``None``: the defaults.
        initial: the state before the first frame (e.g. the last state of a previous chunk
            of frames); ``None``: adapted to the first frame.
        compat: the exponents, ``"hdrtoolbox"`` or ``"paper"`` (above).
        max_step: longest integration step, ms.

    Returns:
        The mapped frames and the state after each frame (each field ``(T, H, W)``).
    """
    if compat not in EXPONENTS:
        raise ValueError(f"compat: expected 'hdrtoolbox' or 'paper', got {compat!r}")
    frames, _ = sequence_arguments(frames, fps)
    if not max_step > 0:
        raise ValueError(f"max_step: expected a number of ms > 0, got {max_step!r}")
    try:
        interval = 1000.0 / float(fps)
    except TypeError:  # a traced fps: the steps per frame must be known
        raise ValueError("fps: expected a number (it sets the steps per frame)") from None
    steps = max(1, math.ceil(interval / max_step - 1e-9))
    op = VanHateren2006() if op is None else op
    if initial is not None:
        initial = ConeState(*(jnp.asarray(v, frames.dtype) for v in initial))
    return _sequence(frames, op, initial, steps, interval / steps, compat)


@eqx.filter_jit
def _sequence(
    frames: Array,
    op: VanHateren2006,
    initial: ConeState | None,
    steps: int,
    h: float,
    compat: Literal["hdrtoolbox", "paper"],
) -> tuple[Array, ConeState]:
    """:func:`vanhateren2006_sequence`, compiled."""
    exponents = EXPONENTS[compat]
    lum = _input_luminance(frames, op.weights_)
    adapted_to_first = initial is None
    if initial is None:
        initial = cone_steady_state(op, lum[0], compat)
    dt = frames.dtype
    u_max = _log_current(op, -jnp.log(op.c_beta.astype(dt)), exponents)

    def adapt(state, x):
        return jax.lax.fori_loop(
            0, steps, lambda _, s: _cone_step(op, s, x[1], h, exponents), state
        )

    def render(state, x):
        frame = x[0]
        ln_I_os = exponents[0] * jnp.log(jnp.maximum(state.X, jnp.finfo(dt).tiny))
        D = jnp.clip(-jnp.expm1(ln_I_os - u_max), 0.0, 1.0)
        return dispatch(frame, op.weights_, lambda p: _display(p, D), fix=True)

    return scan_frames(adapt, render, initial, (frames, lum), adapted_to_first)


__all__ = [
    "ConeState",
    "VanHateren2006",
    "cone_steady_state",
    "outer_segment_log_current",
    "vanhateren2006_sequence",
]
