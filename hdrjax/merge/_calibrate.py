"""Absolute calibration of merged radiance: from sensor-exposure units to cd/m².

Numeric contract: linear RGB radiance ``(..., 3)`` as :func:`hdrjax.merge.merge` returns it
goes in — sensor exposure per second, ``E = X / t`` with ``X = 1`` the exposure that just
saturates the sensor (the response normalised to ``g`` = 0 at the top code) — and RGB whose
luminance (Rec. 709 weights) is in cd/m² comes out, float32 (float64 under x64).

- From the exposure settings (:func:`absolute_scale`, :func:`calibrate`): ISO 12232:2019's
  saturation-based speed. A scene luminance ``L`` gives the focal-plane exposure
  ``H = q L t / N²`` (lux·s; focus at infinity, no flare), which saturates the sensor at
  ``H_sat = 78 / S``: the luminance that just saturates at exposure time ``t`` is
  ``L_sat = 78 N² / (q S t)`` (:func:`hdrjax.operators.saturation_luminance`), with the lens
  factor ``q = (π/4) T v cos⁴θ`` (0.6516 for T = 0.9, v = 0.98, θ = 10°, colour-hdri's
  defaults). A pixel with ``X = E t`` therefore sees ``L = X · L_sat(t) = E · 78 N² / (q S)``:
  the scale ``78 N² / (q S)`` is the same for every member of the bracket (the f-number and ISO
  must be), which is why merged radiance calibrates with one factor.
- From a measured illuminance (:func:`calibrate_illuminance`): Lagarde, S., Lachambre, S., &
  Jover, C. (2016). An artist-friendly workflow for panoramic HDRI. *SIGGRAPH 2016 course
  "Physically Based Shading in Theory and Practice"*, as colour-hdri's
  ``absolute_luminance_calibration_Lagarde2016``: an equirectangular environment map (rows
  from the zenith, θ = 0, to the nadir, θ = π) is scaled so that its upper-hemisphere
  illuminance
  ``E_v = ∫∫ L(θ, φ) cos θ sin θ dθ dφ ≈ 2π² / (W H) Σ_{cos θ > 0} L cos θ sin θ``
  equals the illuminance measured at the camera (lux). The rows are sampled at
  ``θ_i = π i / (H − 1)`` as colour-hdri does.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._colour import luminance
from ..operators import Q_FACTOR, saturation_luminance


def absolute_scale(f_number: ArrayLike, iso: ArrayLike, *, q: float = Q_FACTOR) -> Array:
    """The factor ``78 N² / (q S)`` from merged radiance (``X / t``) to cd/m².

    Args:
        f_number: the aperture ``N`` of the bracket.
        iso: the ISO speed ``S`` (saturation-based, ISO 12232) of the bracket.
        q: ISO 12232 lens factor (default 0.6516).

    Returns:
        cd/m² per unit of merged radiance: the luminance that saturates the sensor in 1 s.

    >>> round(float(absolute_scale(8.0, 100)), 2)
    76.61
    """
    _check.positive(f_number, "f_number")
    _check.positive(iso, "iso")
    _check.positive(q, "q")
    return saturation_luminance(1.0, f_number, iso, q)


def _saturating_product(rgb: Array, factor: Array) -> Array:
    """``rgb · factor`` with a product of finite values that rounds past the largest float
    kept at ±that float (cd/m² beyond it are not representable; NaN/Inf pass through)."""
    out = rgb * factor
    top = jnp.finfo(rgb.dtype).max
    return jnp.where(jnp.isfinite(rgb) & jnp.isinf(out), jnp.sign(out) * top, out)


def calibrate(
    radiance: Float[ArrayLike, "*batch 3"],
    *,
    f_number: ArrayLike,
    iso: ArrayLike,
    q: float = Q_FACTOR,
) -> Float[Array, "*batch 3"]:
    """Merged radiance in cd/m² from the bracket's f-number and ISO (ISO 12232).

    Args:
        radiance: ``(..., 3)`` linear RGB from :func:`hdrjax.merge.merge` (``X / t``, with
            the response at 0 at the top code).
        f_number, iso, q: see :func:`absolute_scale`.

    Returns:
        RGB scaled by ``78 N² / (q S)``: its luminance is in cd/m². A finite value whose
        product exceeds the largest float of its dtype saturates at it; NaN and ±Inf pixels
        stay as they are.
    """
    rgb = _check.rgb_pixels(radiance, "radiance")
    return _saturating_product(rgb, absolute_scale(f_number, iso, q=q).astype(rgb.dtype))


def _map(radiance: ArrayLike) -> Array:
    rgb = _check.rgb_pixels(radiance, "radiance")
    if rgb.ndim != 3 or rgb.shape[0] < 2 or rgb.shape[1] < 1:
        raise ValueError(
            f"radiance: expected an (H, W, 3) equirectangular map with at least 2 rows and 1 "
            f"column, got shape {rgb.shape}"
        )
    return rgb


def _hemisphere(rgb: Array) -> tuple[Array, Array]:
    """``(m, e)`` with the upper-hemisphere illuminance ``E_v = m · e``: ``m`` the largest
    finite luminance magnitude (1 for a black map), ``e`` the sum over the map divided by
    ``m`` first, so that neither overflows nor underflows; non-finite pixels are left out."""
    h, w = rgb.shape[:2]
    L = luminance(jnp.where(jnp.isfinite(rgb), rgb, 0.0))
    L = jnp.where(jnp.isfinite(L), L, 0.0)
    # m cancels in the calibrated map ((rgb / m) · E_lux / e, e ∝ 1 / m): a constant for grad
    m = jax.lax.stop_gradient(jnp.max(jnp.abs(L)))
    m = jnp.where(m > 0, m, 1.0)
    theta = jnp.linspace(0.0, math.pi, h, dtype=rgb.dtype)
    c = jnp.cos(theta)
    row = jnp.where(c > 0, c * jnp.sin(theta), 0.0)
    return m, jnp.sum((L / m) * row[:, None]) * (2.0 * math.pi**2 / (w * h))


def upper_hemisphere_illuminance(radiance: Float[ArrayLike, "H W 3"]) -> Array:
    """Illuminance (lux if ``radiance`` is in cd/m²) on an upward-facing plane from an
    equirectangular environment map (Lagarde et al. 2016; rows as colour-hdri samples them);
    non-finite pixels are left out."""
    m, e = _hemisphere(_map(radiance))
    return m * e


def calibrate_illuminance(
    radiance: Float[ArrayLike, "H W 3"], illuminance_lux: ArrayLike
) -> Float[Array, "H W 3"]:
    """Scale an equirectangular map so its upper-hemisphere illuminance is
    ``illuminance_lux`` (Lagarde et al. 2016, as colour-hdri).

    Args:
        radiance: ``(H, W, 3)`` linear RGB, latitude-longitude, zenith in the first row.
        illuminance_lux: the illuminance measured at the camera, facing up (lux).

    Returns:
        The map in cd/m² (its luminance). NaN and ±Inf pixels stay as they are and take no
        part in the illuminance; a finite value scaled past the largest float saturates at
        it. A map whose upper hemisphere is black (or below ~1e-14 of the brightest pixel in
        float32, ~1e-150 in float64, where the scale's derivative is not a float) is
        returned unchanged under ``jit`` (there is nothing to scale) and refused with a
        ``ValueError`` otherwise.

    Raises:
        ValueError: a map with no light in its upper hemisphere, a non-positive
            illuminance, or a map that is not ``(H, W, 3)`` with at least 2 rows.
    """
    _check.positive(illuminance_lux, "illuminance_lux")
    rgb = _map(radiance)
    m, e = _hemisphere(rgb)
    if not isinstance(e, jax.core.Tracer) and not np.asarray(e) > 0:
        raise ValueError("radiance: its upper hemisphere is black; it cannot be calibrated")
    lux = jnp.asarray(illuminance_lux, rgb.dtype)
    # e is the hemisphere's illuminance relative to the brightest pixel; one so small that
    # the factor's derivative, lux / e², would not be a float (below ~1e-14 in float32, a
    # map lit only below the horizon) is treated as black
    lit = jnp.square(e) > lux * 1e6 / jnp.finfo(rgb.dtype).max
    factor = lux / jnp.where(lit, e, 1.0)
    # (rgb / m) · (E_lux / e): each factor stays in range where m · e would not; NaN/Inf
    # pixels are put back afterwards, so that no NaN reaches the shared factor's gradient
    finite = jnp.isfinite(rgb)
    scaled = _saturating_product(jnp.where(finite, rgb, 0.0) / m, factor)
    return jnp.where(lit & finite, scaled, rgb)


__all__ = ["absolute_scale", "calibrate", "calibrate_illuminance", "upper_hemisphere_illuminance"]
