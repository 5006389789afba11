"""Pattanaik, Tumblin, Yee, Greenberg 2000 time-dependent visual adaptation.

Reference:
    Pattanaik, Tumblin, Yee, Greenberg. "Time-dependent visual adaptation for fast
    realistic image display." Proceedings of ACM SIGGRAPH 2000.
    https://doi.org/10.1145/344779.344810

The model, as ``pfstmo_pattanaik00`` (pfstools 2.2.0) computes it, luminances in cd/m²:

- Receptor response of luminance ``L`` for a half-saturation ``σ`` (Naka–Rushton with
  ``n = 0.73``): ``R(L, σ) = L^n / (L^n + σ^n)``; cones and rods each respond, scaled by
  their bleaching terms: ``R_cone = B_cone R(L, σ_cone)``, ``R_rod = B_rod R(L, σ_rod)``,
  ``R = R_cone + R_rod``.
- Half-saturations from the adaptation luminances ``A`` (from Hunt's colour appearance
  model, as the paper takes them): ``σ_cone = 12.9223 A / (k⁴ A + 0.171 (1 − k⁴)²
  A^(1/3))``, ``k = 1 / (5A + 1)``; ``σ_rod = 2.5874 A / (19000 j² A + 0.2615 (1 − j²)⁴
  A^(1/6))``, ``j = 1 / (5·10⁴ A + 1)``.
- Bleaching in steady state: ``B_cone = 2·10⁶ / (2·10⁶ + A_cone)``,
  ``B_rod = 0.04 / (0.04 + A_rod)``.
- Appearance: the scene's white and black are ``5 A`` and ``A / 6.4``, the display's
  ``5 G_d`` and ``G_d / 6.4`` for the display adaptation ``G_d`` (25 cd/m²) whose cones
  respond with ``σ_d = σ_cone(G_d)``; the scene's response is shifted (and compressed when
  its white–black span exceeds the display's) so that its white (else its black) falls on
  the display's, clamped to ``[0, 1 − 2^−23]``, and inverted through the display's response:
  ``L_d = σ_d (R_a / (1 − R_a))^(1/n) / (5 G_d)`` (display-relative, 1 = display white).
- Colour: each channel ratio ``C / L`` is raised to ``s = B_cone n R(1 − R)(L, σ_cone)
  / S_d`` (the cones' colour saturation over the display's, ``S_d`` the display's
  white–black response span per decade), weighted by the cones' share of the response,
  the rods adding grey: ``C_d = L_d ((C / L)^s R_cone / R + R_rod / R)``.
- Time course: each adaptation luminance follows its goal ``G`` through an exponential
  of time constant 80 ms (cones) and 150 ms (rods); bleaching follows ``dB/dt =
  (1 − B) / τ − G B / I_0``, ``τ = 110 s, I_0 = 2.2·10⁸`` (cones), ``τ = 400 s,
  I_0 = 16`` (rods), whose steady state is the formula above
  (:func:`pattanaik2000_sequence`).
"""

import math
from collections.abc import Callable
from typing import ClassVar, Literal, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._stats import Statistics
from ._base import (
    Prepared,
    StatisticsSettings,
    bound_stats,
    dispatch,
    estimated,
    fill,
    parameter,
    register,
    rgb_statistics,
    safe_log,
    weights_field,
)
from ._time import AbstractTimeDependentOperator, scan_frames, sequence_arguments

REFERENCE = (
    "Pattanaik, Tumblin, Yee, Greenberg 2000, Time-dependent visual adaptation for fast"
    " realistic image display, SIGGRAPH 2000, https://doi.org/10.1145/344779.344810"
)
N = 0.73
"""Exponent of the receptors' response (the paper's n)."""
WHITE_FACTOR = 5.0
"""Scene and display white, in units of their adaptation luminance."""
DARK_FACTOR = 32.0 / 5.0
"""Scene and display black: adaptation luminance divided by this."""
KEY = 5.0
"""Adaptation luminance over the image's log-average (pfstmo's static mode)."""
PFSTMO_DELTA = 1e-4
"""pfstmo's offset inside the log-average (``exp(mean ln(Y + 1e-4)) − 1e-4``), cd/m²."""
RA_MAX = 1.0 - 2.0**-23
"""Largest appearance response inverted (pfstmo's ``0.9999999f``)."""
T0_CONE, T0_ROD = 0.080, 0.150
"""Time constants (s) of the cones' and rods' neural adaptation."""
TAU_CONE, TAU_ROD = 110.0, 400.0
"""Time constants (s) of pigment regeneration (bleaching recovery)."""
I0_CONE, I0_ROD = 2.2e8, 16.0
"""Bleaching half-luminances × time constant: ``dB/dt = (1 − B)/τ − G B / I_0`` (cd/m²·s)."""


def _clamp(x: Array, lo: float, hi: float) -> Array:
    """``x`` clamped to ``[lo, hi]`` with a zero gradient outside (``jnp.clip`` multiplies
    the outer gradient by 0, which is NaN where that gradient is infinite)."""
    return jnp.where(x < lo, lo, jnp.where(x > hi, hi, x))


LN_A_RANGE = (math.log(1e-12), math.log(1e12))
"""Adaptation luminances (cd/m², as logarithms) outside which the half-saturations follow
their asymptotes: constant below, ``A^(2/3)`` (cones) and ``A^(5/6)`` (rods) above (to
float64's precision there), so no term of the formulas overflows or underflows."""


def _asymptotic(log_sigma: Callable[[Array], Array], ln_A: Array, slope: float) -> Array:
    """``log_sigma`` inside :data:`LN_A_RANGE`, its asymptotes outside."""
    lo, hi = LN_A_RANGE
    inside = _clamp(ln_A, lo, hi)
    return log_sigma(inside) + jnp.where(ln_A > hi, slope * (ln_A - hi), 0.0)


def _log_sigma_cone(ln_A: Array) -> Array:
    """``ln σ_cone`` of the cones' adaptation ``A = e^ln_A``."""
    return _asymptotic(_log_sigma_cone_inside, ln_A, 2.0 / 3.0)


def _log_sigma_rod(ln_A: Array) -> Array:
    """``ln σ_rod`` of the rods' adaptation ``A = e^ln_A``."""
    return _asymptotic(_log_sigma_rod_inside, ln_A, 5.0 / 6.0)


def _log_sigma_cone_inside(ln_A: Array) -> Array:
    """``ln σ_cone`` of the cones' adaptation ``A = e^ln_A``: ``12.9223 / (k⁴ + 0.171
    (1 − k⁴)² A^(−2/3))``, ``1 − k⁴`` factored so it is exact for small ``A``."""
    u = 5.0 * jnp.exp(ln_A)
    k = 1.0 / (1.0 + u)
    one_minus_k = u * k
    k2 = k * k
    one_minus_k4 = one_minus_k * (1.0 + k) * (1.0 + k2)
    # (1 − k⁴)² A^(−2/3) without overflow: ln A is at least ln(tiny)
    rest = jnp.exp(2.0 * jnp.log(one_minus_k4) - (2.0 / 3.0) * ln_A)
    return math.log(12.9223) - jnp.log(k2 * k2 + 0.171 * rest)


def _log_sigma_rod_inside(ln_A: Array) -> Array:
    """``ln σ_rod``: ``2.5874 / (19000 j² + 0.2615 (1 − j²)⁴ A^(−5/6))``."""
    u = 5e4 * jnp.exp(ln_A)
    j = 1.0 / (1.0 + u)
    one_minus_j2 = u * j * (1.0 + j)
    rest = jnp.exp(4.0 * jnp.log(one_minus_j2) - (5.0 / 6.0) * ln_A)
    return math.log(2.5874) - jnp.log(19000.0 * j * j + 0.2615 * rest)


def _response(ln_L: Array, ln_sigma: Array) -> Array:
    """``L^n / (L^n + σ^n)`` from logarithms."""
    return jax.nn.sigmoid(N * (ln_L - ln_sigma))


class AdaptationState(NamedTuple):
    """The observer's state: adaptation luminances (cd/m²) and bleaching terms (0 … 1)."""

    A_cone: Array
    A_rod: Array
    B_cone: Array
    B_rod: Array


def steady_state(A_cone: ArrayLike, A_rod: ArrayLike) -> AdaptationState:
    """The state fully adapted to ``A_cone`` and ``A_rod`` (bleaching at equilibrium)."""
    A_cone, A_rod = jnp.asarray(A_cone), jnp.asarray(A_rod)
    return AdaptationState(A_cone, A_rod, 2e6 / (2e6 + A_cone), 0.04 / (0.04 + A_rod))


def _map(rgb: Array, L: Array, state: AdaptationState, display_adaptation: Array) -> Array:
    """Map one image for the observer ``state`` (module docstring)."""
    dt = rgb.dtype
    tiny = jnp.finfo(dt).tiny
    big = jnp.finfo(dt).max / 64.0
    A_cone = _clamp(state.A_cone, tiny, big)
    A_rod = _clamp(state.A_rod, tiny, big)
    B_cone, B_rod = state.B_cone, state.B_rod
    ln_white, ln_dark = math.log(WHITE_FACTOR), -math.log(DARK_FACTOR)

    ln_Gd = jnp.log(display_adaptation)
    ln_sd = _log_sigma_cone(ln_Gd)
    white_d = _response(ln_Gd + ln_white, ln_sd)
    black_d = _response(ln_Gd + ln_dark, ln_sd)
    S_d = (white_d - black_d) / math.log10(WHITE_FACTOR * DARK_FACTOR)

    ln_Ac, ln_Ar = jnp.log(A_cone), jnp.log(A_rod)
    ln_sc, ln_sr = _log_sigma_cone(ln_Ac), _log_sigma_rod(ln_Ar)

    def scene(ln_f):
        return B_cone * _response(ln_Ac + ln_f, ln_sc) + B_rod * _response(ln_Ar + ln_f, ln_sr)

    white_s, black_s = scene(ln_white), scene(ln_dark)
    span_s, span_d = white_s - black_s, white_d - black_d
    # pfstmo: the white shifted onto the display's when brighter, else the black when
    # darker, compressed by span_d / span_s only when the scene's span is the larger
    # (divided only there: a dim scene's span is tiny and its reciprocal's gradient
    # would overflow)
    compress = span_s > span_d
    to_white = white_s > white_d
    to_black = ~to_white & (black_s < black_d)
    shift = (to_white | to_black) & (span_s != span_d)
    x = jnp.where(to_white, white_s, black_s)
    z = jnp.where(to_white, white_d, black_d)
    y = jnp.where(shift & compress, span_d / jnp.where(compress, span_s, 1.0), 1.0)
    x, z = jnp.where(shift, x, 0.0), jnp.where(shift, z, 0.0)

    pos = L > 0
    ln_L = safe_log(L)
    r_cone = B_cone * jnp.where(pos, _response(ln_L, ln_sc), 0.0)
    r_rod = B_rod * jnp.where(pos, _response(ln_L, ln_sr), 0.0)
    r = r_cone + r_rod
    # the cones' and rods' shares of the response, from logarithms: r / r_cone would
    # overflow with its gradient for a dim pixel
    z_c, z_r = N * (ln_L - ln_sc), N * (ln_L - ln_sr)
    ln_B_cone = jnp.log(_clamp(B_cone, tiny, 1.0))
    ln_B_rod = jnp.log(_clamp(B_rod, tiny, 1.0))
    odds = ln_B_cone + jax.nn.log_sigmoid(z_c) - ln_B_rod - jax.nn.log_sigmoid(z_r)
    f_cone = jnp.where(pos, jax.nn.sigmoid(odds), 0.0)
    f_rod = jnp.where(pos, jax.nn.sigmoid(-odds), 0.0)
    s = B_cone * N * jax.nn.sigmoid(z_c) * jax.nn.sigmoid(-z_c) / S_d

    R_a = _clamp((r - x) * y + z, 0.0, RA_MAX)
    on = R_a > 0
    R_a_safe = jnp.where(on, R_a, 0.5)
    ln_Ld = (
        ln_sd
        - jnp.log(WHITE_FACTOR * display_adaptation)
        + (jnp.log(R_a_safe) - jnp.log1p(-R_a_safe)) / N
    )
    L_d = jnp.where(on & pos, jnp.exp(ln_Ld), 0.0)
    # the channel ratios: negative channels count as 0; the power's logarithm capped so
    # a huge ratio (a pixel whose luminance nearly cancels) stays finite
    ln_ratio = safe_log(rgb) - ln_L[..., None]
    cap = 0.25 * math.log(float(jnp.finfo(dt).max))
    tint = jnp.where(rgb > 0, jnp.exp(jnp.minimum(s[..., None] * ln_ratio, cap)), 0.0)
    return L_d[..., None] * (tint * f_cone[..., None] + f_rod[..., None])


@register("pattanaik2000")
class Pattanaik2000(AbstractTimeDependentOperator):
    """Pattanaik et al. 2000 cone and rod response model (module docstring), static mode,
    with pfstmo's defaults (``pfstmo_pattanaik00`` without ``--time-dependence``): the
    observer fully adapted to ``A = 5 (exp(mean ln(L + 10⁻⁴)) − 10⁻⁴)`` for cones and rods,
    bleaching in equilibrium. :func:`pattanaik2000_sequence` maps frames with the paper's
    time course.

    Input: linear RGB in cd/m² (the model is absolute: the same image at another level
    maps to another appearance, dim scenes going grey as rods take over). A relative image
    is read as if in cd/m², as pfstmo does; scale it first (pfstmo's ``--mul``) to place it.
    Output: display-referred linear RGB, 1 = the display's white (``5 G_d``); bright
    pixels exceed 1 and clip when encoded.

    Departures from pfstmo: channels are not clipped to [0, 1] here (the display encoding
    clips; unclipped values keep gradients); black pixels stay black (pfstmo's ``0 / 0``
    channel ratio makes them white); negative channels count as 0 in the ratio (NaN, so
    white, in pfstmo). pfstmo's local variant (``--local``) is not implemented. For
    finite values and gradients at every scale of the dtype: the adaptation luminances are
    kept between the smallest normal float and 1/64 of the largest (pfstmo's is 0 or
    negative for a black image, NaN beyond); the half-saturations follow their asymptotes
    outside 10⁻¹²–10¹² cd/m² (where the formulas already equal them to float64's
    precision); the power of the channel ratio is capped at ``e^(ln(max)/4)``, which only
    a pixel whose negative channels nearly cancel its luminance reaches.

    Attributes:
        display_adaptation: ``G_d``, the display's adaptation luminance (25 cd/m²).
        A_cone: cones' adaptation luminance; ``None`` → 5 × the log-average.
        A_rod: rods' adaptation luminance; ``None`` → ``A_cone``.
        delta: offset inside the log-average (pfstmo's 10⁻⁴ cd/m²).
        weights: luminance weights of the image's primaries.
    """

    reference: ClassVar[str] = REFERENCE
    default_fit_params: ClassVar[tuple[str, ...]] = ("A_cone", "display_adaptation")

    display_adaptation: Array = parameter(
        25.0,
        help="display adaptation luminance G_d: display white is 5 G_d",
        unit="cd/m²",
        range="(0, inf)",
    )
    A_cone: Array | None = estimated(
        "cones' adaptation luminance; None: 5 × the log-average", unit="cd/m²", pooling="log_mean"
    )
    A_rod: Array | None = estimated(
        "rods' adaptation luminance; None: A_cone", unit="cd/m²", pooling="log_mean"
    )
    delta: float = parameter(
        PFSTMO_DELTA,
        help="offset inside the log-average (pfstmo's 1e-4)",
        unit="cd/m²",
        range="[0, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings(delta=self.delta) if self.A_cone is None else None

    def bind(self, stats: Statistics | None) -> "Pattanaik2000":
        if not self.unset():
            return self
        A_cone = self.A_cone
        if A_cone is None:
            A_cone = adaptation_goal(bound_stats(self, stats).log_average, self.delta)
        A_rod = A_cone if self.A_rod is None else self.A_rod
        return fill(self, A_cone=A_cone, A_rod=A_rod)

    def state(self) -> AdaptationState:
        """The observer's state of the static mode (its adaptation luminances set)."""
        assert self.A_cone is not None and self.A_rod is not None
        return steady_state(self.A_cone, self.A_rod)

    def _apply(self, p: Prepared) -> Array:
        return _map(p.rgb, p.L, self.state(), self.display_adaptation)

    def sequence(
        self,
        frames: Float[ArrayLike, "T H W 3"],
        fps: float,
        *,
        initial: AdaptationState | None = None,
    ) -> tuple[Float[Array, "T H W 3"], AdaptationState]:
        """The paper's time course: :func:`pattanaik2000_sequence` with this operator."""
        return pattanaik2000_sequence(frames, fps, self, initial=initial)


def adaptation_goal(log_average: Array, delta: float, key: float = KEY) -> Array:
    """``key · (log_average − delta)``: the adaptation luminance of an image whose
    ``exp(mean ln(L + delta))`` is ``log_average``, at least the smallest normal float."""
    la = jnp.asarray(log_average)
    fi = jnp.finfo(la.dtype)
    return _clamp(key * (la - delta), fi.tiny, fi.max / 64.0)


def adapt(
    state: AdaptationState,
    G_cone: Array,
    G_rod: Array,
    dt: Array,
    *,
    compat: Literal["exact", "pfstmo"] = "exact",
) -> AdaptationState:
    """The state ``dt`` seconds later under goal luminances ``G`` (constant over the step).

    Adaptation luminances: ``A + (1 − e^(−dt/t₀)) (G − A)`` (exact for a constant goal).
    Bleaching, ``dB/dt = (1 − B)/τ − G B/I_0``: ``"exact"`` integrates it over the step,
    ``B_∞ + (B − B_∞) e^(−r dt)`` with ``r = 1/τ + G/I_0``, ``B_∞ = 1/(τ r)``; ``"pfstmo"``
    takes one Euler step, as pfstmo does (unstable for rods once ``G dt > 32`` cd/m²·s).
    """
    dt = jnp.asarray(dt)
    A_cone = state.A_cone + (-jnp.expm1(-dt / T0_CONE)) * (G_cone - state.A_cone)
    A_rod = state.A_rod + (-jnp.expm1(-dt / T0_ROD)) * (G_rod - state.A_rod)

    def bleach(B, G, tau, I0):
        if compat == "pfstmo":
            return B + dt * ((1.0 - B) / tau - G * B / I0)
        r = 1.0 / tau + G / I0
        B_inf = 1.0 / (tau * r)
        return B_inf + (B - B_inf) * jnp.exp(-r * dt)

    B_cone = bleach(state.B_cone, G_cone, TAU_CONE, I0_CONE)
    B_rod = bleach(state.B_rod, G_rod, TAU_ROD, I0_ROD)
    return AdaptationState(A_cone, A_rod, B_cone, B_rod)


def pattanaik2000_sequence(
    frames: Float[ArrayLike, "T H W 3"],
    fps: float | ArrayLike,
    op: Pattanaik2000 | None = None,
    *,
    initial: AdaptationState | None = None,
    compat: Literal["paper", "pfstmo"] = "paper",
) -> tuple[Float[Array, "T H W 3"], AdaptationState]:
    """Map a sequence with the paper's time course of adaptation (``jax.lax.scan``).

    The observer starts adapted to the first frame (``initial``: to a given state, e.g.
    :func:`steady_state`); before each later frame it adapts for ``1 / fps`` seconds
    towards that frame's goal (:func:`adapt`), and the frame is mapped with the state
    reached. The goal of a frame is the static mode's adaptation luminance,
    ``5 (exp(mean ln(L + δ)) − δ)``, so that a constant sequence maps every frame as the
    static mode does. pfstmo (``-t``) starts from that value but takes as the goal of
    later frames the log-average itself, without the factor 5, so that a still scene
    brightens over its first half second as the observer adapts to a fifth of the
    luminance; and it steps the bleaching with Euler's method: ``compat="pfstmo"``
    reproduces both.

    Args:
        frames: ``(T, H, W, 3)`` linear RGB in cd/m² (NaN/Inf pixels are left out of the
            goals; the frames are mapped as :class:`Pattanaik2000` maps them).
        fps: frames per second (pfstmo's default 16).
        op: the operator whose ``display_adaptation``, ``delta`` and ``weights`` are used
            (its ``A_cone``/``A_rod`` are ignored); ``None``: the defaults.
        initial: the observer's state before the first frame; ``None``: adapted to it.
        compat: ``"paper"`` or ``"pfstmo"`` (above).

    Returns:
        The mapped frames and the state after each frame (each field ``(T,)``).
    """
    if compat not in ("paper", "pfstmo"):
        raise ValueError(f"compat: expected 'paper' or 'pfstmo', got {compat!r}")
    frames, dt = sequence_arguments(frames, fps)
    op = Pattanaik2000() if op is None else op
    op = eqx.tree_at(lambda o: (o.A_cone, o.A_rod), op, (None, None), is_leaf=lambda x: x is None)
    if initial is not None:
        initial = AdaptationState(*(jnp.asarray(v, frames.dtype) for v in initial))
    return _sequence(frames, dt, op, initial, compat)


@eqx.filter_jit
def _sequence(
    frames: Array,
    dt: Array,
    op: Pattanaik2000,
    initial: AdaptationState | None,
    compat: str,
) -> tuple[Array, AdaptationState]:
    """:func:`pattanaik2000_sequence`, compiled."""

    def log_average(frame):
        return bound_stats(op, rgb_statistics(frame, op.weights_, settings)).log_average

    settings = op.statistics_settings()
    assert settings is not None
    la = jax.vmap(log_average)(frames)
    goals = adaptation_goal(la, op.delta, KEY if compat == "paper" else 1.0)
    adapted_to_first = initial is None
    if initial is None:
        first = adaptation_goal(la[0], op.delta)
        initial = steady_state(first, first)
    step = "exact" if compat == "paper" else "pfstmo"

    def move(state, x):
        return adapt(state, x[1], x[1], dt, compat=step)

    def render(state, x):
        return _apply_state(op, x[0], state)

    return scan_frames(move, render, initial, (frames, goals), adapted_to_first)


def _apply_state(op: Pattanaik2000, frame: Array, state: AdaptationState) -> Array:
    """One frame mapped for the observer ``state`` with ``op``'s display and weights."""

    def run(p):
        return _map(p.rgb, p.L, state, op.display_adaptation)

    return dispatch(frame, op.weights_, run, fix=True)


__all__ = [
    "AdaptationState",
    "Pattanaik2000",
    "adapt",
    "adaptation_goal",
    "pattanaik2000_sequence",
    "steady_state",
]
