"""HDR signals: SMPTE ST 2084 (PQ), BT.2100 HLG and the BT.2390 EETF.

Numeric contract: the transfer functions map non-negative linear values to signals in
[0, 1] and back, per value, any shape; they are differentiable with finite gradients at 0
(where the power laws' slopes are infinite, the ``jnp.where(x > 0, x, 1)`` pattern keeps
the gradient finite).

- PQ, SMPTE ST 2084:2014 (ITU-R BT.2100-2, Table 4), with ``Y = L / 10000`` (``L`` in
  cd/m²): ``E' = ((c1 + c2 Y^m1) / (1 + c3 Y^m1))^m2``, ``m1 = 2610/16384``,
  ``m2 = 2523/4096 · 128``, ``c1 = 3424/4096``, ``c2 = 2413/4096 · 32``,
  ``c3 = 2392/4096 · 32``. Note ``E'(0) = c1^m2 ≈ 7.3e-7``, not 0, as the standard.
- HLG, ITU-R BT.2100-2, Table 5 (ARIB STD-B67): ``E' = √(3E)`` for ``E ≤ 1/12``, else
  ``a ln(12E − b) + c``, ``a = 0.17883277``, ``b = 1 − 4a``, ``c = 0.5 − a ln(4a)``,
  with ``E`` the relative scene-linear signal in [0, 1].
- EETF: the Hermite-spline roll-off of ITU-R BT.2390-4 (2018), section 5.4.1 (since
  moved to ITU-R BT.2408, Annex 5), mapping a mastering display's range
  ``[L_B, L_W]`` onto a target display's ``[L_min, L_max]`` in the PQ domain:
  ``E1 = (E' − PQ(L_B)) / (PQ(L_W) − PQ(L_B))``, ``minLum``, ``maxLum`` likewise;
  ``KS = 1.5 maxLum − 0.5``; ``E2 = E1`` below ``KS``, above it the spline
  ``P(T) = (2T³ − 3T² + 1) KS + (T³ − 2T² + T)(1 − KS) + (−2T³ + 3T²) maxLum`` with
  ``T = (E1 − KS) / (1 − KS)``; ``E3 = E2 + minLum (1 − E2)⁴``;
  ``E4 = E3 (PQ(L_W) − PQ(L_B)) + PQ(L_B)``.
"""

import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._scale import positive_power
from ._displays import DEFAULT_PEAK

PQ_PEAK = 10000.0
"""cd/m² of the PQ signal 1.0 (SMPTE ST 2084's range)."""
REFERENCE_WHITE = 203.0
"""cd/m² of HDR reference (diffuse) white, ITU-R BT.2408: PQ signal 0.58."""

_M1 = 2610.0 / 16384.0
_M2 = 2523.0 / 4096.0 * 128.0
_C1 = 3424.0 / 4096.0
_C2 = 2413.0 / 4096.0 * 32.0
_C3 = 2392.0 / 4096.0 * 32.0

_HLG_A = 0.17883277
_HLG_B = 1.0 - 4.0 * _HLG_A
_HLG_C = 0.5 - _HLG_A * math.log(4.0 * _HLG_A)
HLG_REFERENCE_SIGNAL = 0.75
"""HLG signal of reference white, ITU-R BT.2408 (203 cd/m² on a 1000 cd/m² display)."""
HLG_REFERENCE_WHITE = (math.exp((HLG_REFERENCE_SIGNAL - _HLG_C) / _HLG_A) + _HLG_B) / 12.0
"""Scene-linear ``E`` (≈ 0.2650) that the HLG OETF encodes as :data:`HLG_REFERENCE_SIGNAL`."""


def pq_inverse_eotf(y: Array) -> Array:
    """SMPTE ST 2084 inverse EOTF of ``y = L / 10000`` (``y ≥ 0``; float array)."""
    pos = y > 0
    ym = jnp.where(pos, positive_power(jnp.where(pos, y, 1.0), _M1), 0.0)
    return positive_power((_C1 + _C2 * ym) / (1.0 + _C3 * ym), _M2)


def pq_eotf(signal: Array) -> Array:
    """SMPTE ST 2084 EOTF: ``y = L / 10000`` of a signal in [0, 1] (float array)."""
    e = jnp.clip(signal, 0.0, 1.0)
    pos = e > 0
    ep = jnp.where(pos, positive_power(jnp.where(pos, e, 1.0), 1.0 / _M2), 0.0)
    num = ep - _C1
    lit = num > 0
    ratio = jnp.where(lit, num, 1.0) / (_C2 - _C3 * ep)
    return jnp.where(lit, positive_power(ratio, 1.0 / _M1), 0.0)


def hlg_oetf(e: Array) -> Array:
    """BT.2100 HLG OETF of the relative scene-linear ``e`` (clipped to [0, 1])."""
    e = jnp.clip(e, 0.0, 1.0)
    low = e <= 1.0 / 12.0
    root = jnp.sqrt(jnp.where(low & (e > 0), 3.0 * e, 1.0))
    log = _HLG_A * jnp.log(jnp.where(low, 1.0, 12.0 * e - _HLG_B)) + _HLG_C
    return jnp.where(low, jnp.where(e > 0, root, 0.0), log)


def pq_of(cd_m2: Any, like: Array) -> Any:
    """The PQ signal of a luminance in cd/m²: a NumPy float64 where the value is concrete
    (a constant folded before tracing: fewer operations to compile), else traced."""
    if isinstance(cd_m2, jax.core.Tracer):
        return pq_inverse_eotf(jnp.asarray(cd_m2, like.dtype) / PQ_PEAK)
    ym = np.maximum(np.asarray(cd_m2, np.float64) / PQ_PEAK, 0.0) ** _M1
    return ((_C1 + _C2 * ym) / (1.0 + _C3 * ym)) ** _M2


def eetf(e: Array, *, lb: Array, lw: Array, lmin: Array, lmax: Array) -> tuple[Array, Array]:
    """The EETF on PQ signals (all arguments signals); also returns where it departs from
    the identity (above the knee, or beyond the source range)."""
    span = lw - lb
    span = jnp.where(span > 0, span, 1.0)
    e1 = (e - lb) / span
    min_lum = (lmin - lb) / span
    max_lum = (lmax - lb) / span
    # A knee below 0 (a target under a third of the source in PQ) is held at 0 with the
    # start slope limited to 3 (maxLum − KS), the monotonicity bound of Fritsch & Carlson
    # (1980, doi:10.1137/0717021): BT.2390's own curve meets it with equality, so nothing
    # changes where KS ≥ 0
    ks = jnp.maximum(1.5 * max_lum - 0.5, 0.0)
    slope = jnp.minimum(1.0 - ks, 3.0 * (max_lum - ks))
    within = jnp.clip(e1, 0.0, 1.0)
    bend = (e1 > ks) & (ks < 1)
    t = jnp.where(bend, (within - ks) / jnp.where(bend, 1.0 - ks, 1.0), 0.0)
    t2, t3 = t * t, t * t * t
    p = (2 * t3 - 3 * t2 + 1) * ks + (t3 - 2 * t2 + t) * slope + (-2 * t3 + 3 * t2) * max_lum
    e2 = jnp.where(bend, jnp.minimum(p, max_lum), within)
    e3 = e2 + min_lum * (1.0 - e2) ** 4
    return e3 * span + lb, (e1 > jnp.minimum(ks, 1.0)) | (e1 < 0)


def bt2390_eetf(
    signal: Float[ArrayLike, "..."],
    *,
    source_peak: float,
    target_peak: float = DEFAULT_PEAK,
    source_black: float = 0.0,
    target_black: float = 0.0,
) -> Float[Array, "..."]:
    """ITU-R BT.2390 EETF: a PQ signal mastered on one display, for a smaller display.

    The Hermite-spline knee of ITU-R BT.2390-4 (2018), section 5.4.1 (equations in the
    module docstring): the identity up to the knee ``KS = 1.5 maxLum − 0.5`` (in the
    normalised PQ domain), then a spline with slope 1 at the knee and 0 at the source
    peak, which lands exactly on the target peak; the black lift ``minLum (1 − E2)⁴``
    maps the source black to the target's. A source no brighter than the target
    (``maxLum ≥ 1``) passes unchanged. Departures from the report: signals outside the
    source range are clipped to it first (above its peak: the target peak); for targets so
    dim that ``KS < 0`` (below a third of the source in PQ, where the report's spline is
    not monotone) the knee is held at 0 and the spline's start slope limited to keep it
    monotone (Fritsch & Carlson 1980, "Monotone piecewise cubic interpolation", SIAM J.
    Numer. Anal. 17(2), doi:10.1137/0717021).

    Args:
        signal: PQ (SMPTE ST 2084) signal values, any shape.
        source_peak: cd/m² of the mastering display's white ``L_W``.
        target_peak: cd/m² of the target display's white ``L_max`` (1000 by default).
        source_black: cd/m² of the mastering display's black ``L_B``.
        target_black: cd/m² of the target display's black ``L_min``.

    Returns:
        PQ signal values for the target display, same shape; in
        ``[PQ(target_black), PQ(target_peak)]``.

    Raises:
        ValueError: a complex signal; peaks not positive and finite, blacks negative,
            a black not below its peak (checked where the values are concrete).

    >>> import jax.numpy as jnp
    >>> out = bt2390_eetf(jnp.array([0.5, 0.9, 1.0]), source_peak=10000.0)
    >>> [round(v, 4) for v in out.tolist()]  # PQ(1000 cd/m²) = 0.7518
    [0.5, 0.7494, 0.7518]
    """
    _check.real(signal, "signal")
    for name, value, zero in (
        ("source_peak", source_peak, False),
        ("target_peak", target_peak, False),
        ("source_black", source_black, True),
        ("target_black", target_black, True),
    ):
        _check.positive(value, name, zero=zero)
    for black, peak, name in (
        (source_black, source_peak, "source_black"),
        (target_black, target_peak, "target_black"),
    ):
        traced = isinstance(black, jax.core.Tracer) or isinstance(peak, jax.core.Tracer)
        if not traced and not np.all(np.asarray(black) < np.asarray(peak)):
            raise ValueError(f"{name}: expected a value below the peak {peak!r}, got {black!r}")
    e = _check.as_float(signal)
    out, _ = eetf(
        e,
        lb=pq_of(source_black, e),
        lw=pq_of(source_peak, e),
        lmin=pq_of(target_black, e),
        lmax=pq_of(target_peak, e),
    )
    return out


__all__ = ["HLG_REFERENCE_WHITE", "PQ_PEAK", "REFERENCE_WHITE", "bt2390_eetf"]
