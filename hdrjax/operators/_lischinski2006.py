"""Lischinski, Farbman, Uyttendaele & Szeliski 2006 interactive local adjustment of tonal
values, its automatic mode (Section 5), with HDR Toolbox's settings (``LischinskiTMO``).

Reference:
    Lischinski, Farbman, Uyttendaele, Szeliski. "Interactive local adjustment of tonal
    values." ACM Transactions on Graphics 25(3):646–653, 2006 (Proc. SIGGRAPH).
    https://doi.org/10.1145/1141911.1141936

The steps, with ``Y`` the luminance (the image's units; ``ε_Y`` = ``offset``):

1. Zones (Section 5): one f-stop each, the first from ``Y_0 = max(Y_min, 0) + ε_Y``
   (HDR Toolbox's origin): zone ``z = 1, 2, …`` holds the pixels with
   ``2^(z−1) Y_0 ≤ Y < 2^z Y_0``; pixels below ``Y_0`` belong to no zone.
2. Targets: each zone's representative luminance ``R_z`` (its ``zone_quantile`` quantile,
   0.75 as HDR Toolbox's) mapped by Reinhard et al.'s global operator (2002,
   https://doi.org/10.1145/566654.566575), ``R_s = a R_z / L̄_w`` to ``R_s / (1 + R_s)``;
   the zone's target exposure in stops is ``g_z = log2(R_s / (1 + R_s) / R_z)``. ``a`` is
   the key (Reinhard 2002, JGT Eq. 4, from the 1st and 99th percentiles and the
   log-average, as HDR Toolbox's ``ReinhardAlpha``), ``L̄_w`` the log-average (Reinhard
   2002's Eq. 1, offset ``delta``). Pixels in no zone have the target 0 (exposure 1).
3. Propagation (the paper's weighted least-squares functional): the exposure map ``f``
   (stops) minimising
   ``Σ_x w (f(x) − g(x))² + λ Σ_x [f_x² / (|ℓ_x|^α + ε) + f_y² / (|ℓ_y|^α + ε)]``, with
   ``ℓ = log2(Y + ε_Y)`` and forward differences on the pixel grid (no term across the
   border), i.e. the sparse symmetric positive definite system
   ``(I + (λ / w) L_h) f = g`` with ``L_h`` the 5-point graph Laplacian whose edge weights
   are ``1 / (|Δℓ|^α + ε)``.
4. Output ``C 2^f`` per channel (display-referred linear; the colour ratios kept).

Solver: conjugate gradients with the Jacobi preconditioner (the operators' shared
``conjugate_gradients``), the operator applied matrix-free on the pixel grid, inside
``lax.custom_linear_solve``, so that
``jax.grad`` differentiates the solution implicitly, exactly for the solved system (the
image and ``α``, ``λ``, ``ε``, ``w`` included); stopped when the residual is below ``tol``
times the targets' norm or after ``max_iterations``. The system's smallest eigenvalue is
at least 1, so the error of ``f`` is at most the residual: ``‖f − f*‖ ≤ tol · ‖g‖`` (in
stops).

Deviations from HDR Toolbox's ``LischinskiTMO`` (commit 5375d05), each argued:

- Statistics: the zone representatives ``R_z`` and the key's percentiles come from the
  package's fixed-grid histogram (1024 bins per octave, a relative error ≤ 0.1 %), so that
  the statistics of tiles, chunks and frames merge; a pixel within one histogram bin of a
  zone's edge may count in the neighbouring zone there. The percentiles are of the
  positive pixels (HDR Toolbox's of every pixel, zeros included). Ranks as HDR Toolbox's
  (``max(round(q n), 1)``-th of the zone's ``n``).
- Solver: conjugate gradients to ``tol`` instead of a direct sparse factorisation.
- Zones: at most :data:`ZONES` (float32's whole range above ``ε_Y = 10⁻⁴``); brighter
  pixels take the last zone's target.
- Non-finite pixels: for the zones' assignment, ``ℓ`` and the solve they take the
  luminance of the image's first finite pixel (raster order), so that the finite pixels
  map exactly as in the image with that copy in place (a rule of the package for
  whole-image operators); they are put back in the output (NaN stays NaN, +Inf is white).

Not scale invariant: ``ε_Y`` is in the image's units (HDR Toolbox's 10⁻⁴, meant for
cd/m²), so images far below it (all of ``Y < ε_Y``) keep their values (exposure 1).

Tiles: the solve couples every pixel with every other, so the operator declares an
infinite halo (:meth:`Lischinski2006.halo`) and runs on the whole image only.
"""

import math
from typing import ClassVar

import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._scale import inverse_pow2, saturate_finite
from .._stats import DEFAULT_DELTA, Statistics, grid_size
from ._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    checked_statistics,
    estimated,
    fill,
    filled_with_first_valid,
    parameter,
    register,
    weights_field,
)
from ._cg import conjugate_gradients

REFERENCE = (
    "Lischinski, Farbman, Uyttendaele, Szeliski 2006, Interactive local adjustment of tonal"
    " values, ACM Transactions on Graphics 25(3):646-653,"
    " https://doi.org/10.1145/1141911.1141936"
)
ZONES = 144
"""Zones of one f-stop (float32's range above ``ε_Y = 10⁻⁴``: ``⌈128 + log2 10⁴⌉ = 142``)."""
KEY_DEFAULT = 0.18
"""The key where the image has no range (Reinhard 2002)."""


def reinhard_alpha(p01: Array, p99: Array, log_average: Array, delta: float) -> Array:
    """The key ``a = 0.18 · 4^((2 log2 L̄ − log2 P1 − log2 P99) / (log2 P99 − log2 P1))``
    (Reinhard 2002, JGT Eq. 4; HDR Toolbox's ``ReinhardAlpha``, each term offset by
    ``delta``); 0.18 where ``P99 = P1``."""
    l1, l99 = jnp.log2(p01 + delta), jnp.log2(p99 + delta)
    lbar = jnp.log2(log_average + delta)
    span = l99 - l1
    ok = span > 0
    return jnp.where(
        ok,
        KEY_DEFAULT * jnp.exp2(2.0 * (2 * lbar - l1 - l99) / jnp.where(ok, span, 1.0)),
        KEY_DEFAULT,
    )


def _grid_edge(b: Array, m: int) -> Array:
    """The lower edge of grid bin ``b`` (float32: the bit pattern ``b << (23 − m)``)."""
    bits = jnp.minimum(b, grid_size(m)).astype(jnp.uint32) << (23 - m)
    return jnp.minimum(jax.lax.bitcast_convert_type(bits, jnp.float32), jnp.finfo(jnp.float32).max)


def zone_exposures(
    stats: Statistics, origin: Array, key: Array, log_average: Array, quantile: float
) -> Array:
    """``g_z`` (module docstring, step 2) for zones ``z = 1 … ZONES`` from ``origin``
    (``Y_0``, image units), 0 for zones with no pixel. From the histogram: constants for
    ``jax.grad`` except through ``key`` and ``log_average``.

    On the fixed grid directly (the package's one histogram, :mod:`hdrjax._stats`): a zone
    holds the grid bins from the one that contains its lower edge up to the one before
    the bin of its upper edge (each edge placed within one bin, a factor ``1 + 2^-m``);
    its representative is interpolated in ``ln Y`` inside the bin of its rank, as the
    package's percentiles are. (The grid's bins are found from their bit patterns, with
    no table of their edges: that table, 261 120 values, is what makes the compiled
    program slow to build.)"""
    m = stats.m
    assert stats.counts is not None and m is not None
    dt = jnp.result_type(key, log_average)
    c = jax.lax.stop_gradient(stats.counts).at[: 1 << m].set(0)  # zero and subnormals
    cum = jnp.cumsum(c)
    # the zones' edges Y_0 2^k, k = 0 … ZONES, and the bins that hold them
    o32 = jax.lax.stop_gradient(origin).astype(jnp.float32)
    k = jnp.arange(ZONES + 1, dtype=jnp.int32)
    edges = jnp.minimum(jnp.ldexp(o32, k), jnp.finfo(jnp.float32).max)
    eb = jnp.minimum(
        jax.lax.bitcast_convert_type(edges, jnp.uint32) >> (23 - m), grid_size(m)
    ).astype(jnp.int32)
    below = jnp.where(eb > 0, cum[jnp.maximum(eb - 1, 0)], 0)  # pixels below each edge
    count = below[1:] - below[:-1]
    rank = (
        below[:-1]
        + jnp.maximum(jnp.floor(quantile * count.astype(jnp.float32) + 0.5).astype(cum.dtype), 1)
        - 1
    )
    b = jnp.clip(jnp.searchsorted(cum, rank, side="right"), 0, c.shape[0] - 1)
    before = jnp.where(b > 0, cum[jnp.maximum(b - 1, 0)], 0)
    frac = jnp.clip((rank - before).astype(dt) + 0.5, 0.0, None) / jnp.maximum(c[b], 1).astype(dt)
    lo = jnp.log(jnp.maximum(_grid_edge(b, m), jnp.finfo(jnp.float32).tiny).astype(dt))
    hi = jnp.log(_grid_edge(b + 1, m).astype(dt))
    log2_R = (lo + jnp.clip(frac, 0.0, 1.0) * (hi - lo)) / math.log(2.0)
    ok = count > 0
    s = jnp.log2(key) - jnp.log2(log_average)  # log2(a / L̄)
    # log2(R_s / (1 + R_s) / R) = log2(a / L̄) − log2(1 + a R / L̄)
    return jnp.where(ok, s - jnp.logaddexp2(0.0, s + jnp.where(ok, log2_R, 0.0)), 0.0)


def edge_weights(ell: Array, alpha: Array, epsilon: Array) -> tuple[Array, Array]:
    """``1 / (|Δℓ|^α + ε)`` across the horizontal (``(H, W − 1)``) and vertical
    (``(H − 1, W)``) edges of the grid."""

    def weight(d: Array) -> Array:
        a = jnp.abs(d)
        pos = a > 0
        p = jnp.where(pos, jnp.exp(alpha * jnp.log(jnp.where(pos, a, 1.0))), 0.0)
        return 1.0 / (p + epsilon)

    return weight(ell[:, 1:] - ell[:, :-1]), weight(ell[1:] - ell[:-1])


def laplacian(f: Array, wx: Array, wy: Array) -> Array:
    """``L_h f``: ``Σ_neighbours w (f − f_neighbour)`` on the 5-point grid (no neighbour
    across the border)."""
    fx = wx * (f[:, 1:] - f[:, :-1])
    fy = wy * (f[1:] - f[:-1])
    return (
        jnp.pad(fx, ((0, 0), (1, 0)))
        - jnp.pad(fx, ((0, 0), (0, 1)))
        + jnp.pad(fy, ((1, 0), (0, 0)))
        - jnp.pad(fy, ((0, 1), (0, 0)))
    )


def degree(wx: Array, wy: Array) -> Array:
    """The diagonal of :func:`laplacian`: each pixel's summed edge weights."""
    return (
        jnp.pad(wx, ((0, 0), (1, 0)))
        + jnp.pad(wx, ((0, 0), (0, 1)))
        + jnp.pad(wy, ((1, 0), (0, 0)))
        + jnp.pad(wy, ((0, 1), (0, 0)))
    )


def propagate(
    g: Array,
    ell: Array,
    *,
    alpha: Array,
    smoothness: Array,
    epsilon: Array,
    tolerance: float,
    max_iterations: int,
) -> Array:
    """``f`` with ``(I + smoothness · L_h) f = g`` (module docstring, step 3;
    ``smoothness = λ / w``) by Jacobi-preconditioned conjugate gradients inside
    ``lax.custom_linear_solve``, so that
    ``jax.grad`` differentiates the solution implicitly (one more solve of the same
    symmetric system), not through the iterations."""
    wx, wy = edge_weights(ell, alpha, epsilon)
    wx, wy = smoothness * wx, smoothness * wy
    inv_diag = jax.lax.stop_gradient(1.0 / (1.0 + degree(wx, wy)))

    def matvec(f):
        return f + laplacian(f, wx, wy)

    def solve(mv, rhs):
        f, _, _ = conjugate_gradients(
            mv, rhs, inv_diag, tol=tolerance, max_iterations=max_iterations
        )
        return f

    return jax.lax.custom_linear_solve(matvec, g, solve, symmetric=True)


@register("lischinski2006")
class Lischinski2006(AbstractOperator):
    """Lischinski et al. 2006 automatic local tonal adjustment (Section 5) with HDR
    Toolbox's settings (``LischinskiTMO``); the steps and the departures are in the module
    docstring.

    Input: linear RGB in cd/m² (or units where ``offset`` is small: not scale invariant).
    Output: display-referred linear RGB ``C 2^f``; a zone's representative maps near the
    global Reinhard curve's value, brighter pixels of a zone above it (some above 1).

    Attributes:
        alpha: the paper's ``α`` (1): sensitivity of the smoothness term to the
            log-luminance gradient (the paper uses 1 to 2; larger keeps edges sharper).
        lambda_: the paper's ``λ`` (0.4, HDR Toolbox's): weight of the smoothness term.
        epsilon: the paper's ``ε`` (10⁻⁴), in stops: keeps the smoothness weights finite
            in flat regions.
        constraint_weight: the paper's ``w`` of every pixel's target (0.07, HDR
            Toolbox's); only ``λ / w`` matters.
        key: the key ``a`` of the zones' Reinhard mapping; ``None`` → JGT 2002 Eq. 4
            (HDR Toolbox's ``ReinhardAlpha``).
        log_average: ``L̄_w`` in image units; ``None`` → measured with ``delta``.
        zone_origin: ``Y_0``, the first zone's lower edge in image units; ``None`` →
            ``max(Y_min, 0) + offset``.
        zone_exposures: the targets ``g_z`` in stops of the :data:`ZONES` zones; ``None`` →
            from the image (step 2).
        offset: ``ε_Y`` (10⁻⁴ image units, HDR Toolbox's): added to ``Y`` for the zones'
            origin and the log luminance ``ℓ``.
        zone_quantile: the quantile of each zone taken as its representative (0.75, HDR
            Toolbox's).
        delta: offset inside the log-average (10⁻⁶, HDR Toolbox's).
        tol: the solve's stopping residual, relative to ``‖g‖`` (10⁻⁴: display values
            within 10⁻⁴ of the converged solve's on real images, a few times float32's own
            rounding).
        max_iterations: the solve's iteration cap.
        weights: the luminance weights of the image's primaries (Rec. 709).
    """

    reference: ClassVar[str] = REFERENCE
    default_fit_params: ClassVar[tuple[str, ...]] = ("alpha", "lambda_")
    only_feeds: ClassVar[dict[str, str]] = {
        "key": "zone_exposures",
        "log_average": "zone_exposures",
    }

    alpha: Array = parameter(
        1.0,
        help="the paper's alpha: sensitivity of smoothing to log-luminance gradients",
        range="(0, inf)",
    )
    lambda_: Array = parameter(
        0.4,
        help="the paper's lambda: weight of the smoothness term (HDR Toolbox 0.4)",
        range="(0, inf)",
    )
    epsilon: Array = parameter(
        1e-4,
        help="the paper's epsilon: added to |grad log2 Y|^alpha in the smoothness weights",
        unit="stops",
        range="(0, inf)",
    )
    constraint_weight: Array = parameter(
        0.07,
        help="the paper's w: weight of each pixel's zone target (HDR Toolbox 0.07)",
        range="(0, inf)",
    )
    key: Array | None = estimated(
        "key a of the zones' Reinhard mapping; None: JGT 2002 Eq. 4 (HDR Toolbox)",
        pooling="log_mean",
    )
    log_average: Array | None = estimated(
        "log-average luminance; None: measured with delta",
        unit="image units",
        pooling="log_mean",
    )
    zone_origin: Array | None = estimated(
        "lower edge of the first one-stop zone; None: min(Y) + offset",
        unit="image units",
        pooling="min",
    )
    zone_exposures: Array | None = estimated(
        "target exposure of each one-stop zone; None: from the image's zones",
        unit="stops",
        range="[-inf, inf]",
        pooling="mean",
        shape=(ZONES,),
    )
    offset: float = parameter(
        1e-4,
        help="added to Y for the zones' origin and the log luminance (HDR Toolbox)",
        unit="image units",
        range="(0, inf)",
        static=True,
    )
    zone_quantile: float = parameter(
        0.75,
        help="quantile of each zone taken as its representative (HDR Toolbox 0.75)",
        range="[0, 1]",
        static=True,
    )
    delta: float = parameter(
        DEFAULT_DELTA,
        help="offset inside the log-average (1e-6, HDR Toolbox)",
        unit="image units",
        range="[0, inf)",
        static=True,
    )
    tol: float = parameter(
        1e-4,
        help="conjugate gradients stop at this residual relative to the targets' norm",
        range="(0, 1)",
        static=True,
    )
    max_iterations: int = parameter(
        2000,
        help="conjugate gradients' iteration cap",
        range="[1, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        super().__check_init__()
        if self.zone_exposures is not None and self.zone_exposures.shape != (ZONES,):
            raise ValueError(
                f"zone_exposures: expected {ZONES} values, got shape {self.zone_exposures.shape}"
            )
        if int(self.max_iterations) != self.max_iterations or self.max_iterations < 1:
            raise ValueError(
                f"max_iterations: expected an integer >= 1, got {self.max_iterations!r}"
            )

    def halo(self, shape: tuple[int, ...]) -> tuple[float, float]:
        """The whole image (infinite): the solve couples every pixel."""
        del shape
        return (math.inf, math.inf)

    def statistics_settings(self) -> StatisticsSettings | None:
        if self.zone_origin is not None and self.zone_exposures is not None:
            return None
        return StatisticsSettings(delta=float(self.delta))

    def bind(self, stats: Statistics | None) -> "Lischinski2006":
        if self.zone_origin is not None and self.zone_exposures is not None:
            return self
        st = checked_statistics(self, stats)
        key, lbar, origin = self.key, self.log_average, self.zone_origin
        if key is None or lbar is None or origin is None:  # (percentiles: only if needed)
            ls = st.luminance_stats()
            lbar = ls.log_average if lbar is None else lbar
            if key is None:
                key = reinhard_alpha(ls.p01, ls.p99, lbar, float(self.delta))
            if origin is None:
                origin = jnp.maximum(ls.min, 0.0) + self.offset
        exposures = self.zone_exposures
        if exposures is None:
            exposures = zone_exposures(st, origin, key, lbar, float(self.zone_quantile))
        return fill(self, key=key, log_average=lbar, zone_origin=origin, zone_exposures=exposures)

    def _apply(self, p: Prepared) -> Array:
        assert self.zone_origin is not None and self.zone_exposures is not None
        dt = p.rgb.dtype
        # (a luminance of channels at the float maximum may round to +Inf)
        Y = jnp.clip(
            p.L if p.clean else filled_with_first_valid(p.L, p.valid()), 0.0, jnp.finfo(dt).max
        )
        # zone of each pixel (0: below the first), a constant for jax.grad
        Yc = jax.lax.stop_gradient(Y)
        pos = Yc > 0
        log2_Y = jnp.log2(jnp.where(pos, Yc, 1.0))
        origin = jax.lax.stop_gradient(self.zone_origin).astype(dt)
        z = jnp.floor(log2_Y - jnp.log2(origin)) + 1.0
        z = jnp.where(pos, jnp.clip(z, 0.0, ZONES), 0.0).astype(jnp.int32)
        table = jnp.concatenate([jnp.zeros((1,), dt), self.zone_exposures.astype(dt)])
        g = jnp.take(table, z)
        ell = jnp.log2(Y + jnp.asarray(self.offset, dt))
        f = propagate(
            g,
            ell,
            alpha=self.alpha.astype(dt),
            smoothness=(self.lambda_ / self.constraint_weight).astype(dt),
            epsilon=self.epsilon.astype(dt),
            tolerance=float(self.tol),
            max_iterations=int(self.max_iterations),
        )
        # C 2^f with C scaled near 1 first (2^f alone leaves the float range for images
        # near the float maximum or minimum)
        c = inverse_pow2(jnp.max(jnp.abs(p.rgb)))
        return saturate_finite((p.rgb * c) * jnp.exp2(f - jnp.log2(c))[..., None], p.rgb)


__all__ = [
    "ZONES",
    "Lischinski2006",
    "edge_weights",
    "laplacian",
    "propagate",
    "reinhard_alpha",
    "zone_exposures",
]
