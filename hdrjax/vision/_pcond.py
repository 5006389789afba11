"""Radiance ``pcond``'s human-vision formulas: contrast threshold, acuity, colour loss, veil.

Reference: G. Ward Larson, H. Rushmeier, C. Piatko, "A Visibility Matching Tone Reproduction
Operator for High Dynamic Range Scenes", IEEE TVCG 3(4), 1997, pp. 291–306,
doi:10.1109/2945.646233; code: NREL/Radiance ``src/px/pcond.h``, ``pcond.c`` (v3.30),
``pcond3.c``, ``pcond4.c``.

Numeric contract: linear RGB and luminances in cd/m²; outputs in cd/m².
"""

import functools
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._colour import luminance
from .._interp import lerp
from .._photometry import (
    LMIN,
    SWNORM,
    check_rgb,
    chroma_key,
    headroom,
    log10_floor,
    mesopic_weight,
    restore,
    sanitize,
    scotopic_unscaled,
    tvi,
    weights_of,
)
from .._scale import at_scale
from . import _fft
from ._fovea import block_mean, upsample
from ._view import ResolvedView, View, resolve_view

VADAPT = 0.08
"""Fraction of adaptation due to the veil (pcond4.c ``VADAPT``)."""
VEIL_RANGE = 4.5
"""pcond applies the veil only if the scene's ``ln`` range is at least this (about 90:1)."""


def acuity(L_a: Float[ArrayLike, "*shape"]) -> Float[Array, "*shape"]:
    """Highest resolvable spatial frequency, cycles/degree, at adaptation ``L_a`` (cd/m²).

    ``R(L_a) = 17.25 atan(1.4 log10 L_a + 0.35) + 25.72`` (pcond ``hacuity``, a fit to
    S. Shlaer, "The relation between visual acuity and illumination", J. Gen. Physiol.
    21(2), 1937, https://doi.org/10.1085/jgp.21.2.165). ``L_a`` is clamped to pcond's
    ``LMIN`` = 1e-7 cd/m², where ``R`` = 0.45 c/deg (the fit itself reaches 0 at ``L_a`` ≈ 6e-10).

    Example:
        >>> round(float(acuity(1.0)), 2)
        31.53
    """
    _check.real(L_a, "L_a")
    x = log10_floor(_check.as_float(L_a), LMIN)
    return 17.25 * jnp.arctan(1.4 * x + 0.35) + 25.72


def colour_loss(
    rgb: Float[ArrayLike, "*batch 3"], *, chromaticities: Sequence[float] | None = None
) -> Float[Array, "*batch 3"]:
    """Mesopic/scotopic loss of colour vision, per pixel (pcond3.c ``scotscan``).

    ``out = c·RGB + (1 - c)·(V / 2.26)·(1, 1, 1)`` with ``c`` = :func:`mesopic_weight` of the
    pixel's luminance and ``V`` its :func:`scotopic_luminance` (``SWNORM`` = 2.26 is the
    scotopic/photopic ratio of white). ``(1, 1, 1)`` is the image's white.

    Args:
        rgb: linear RGB in cd/m², channels last, any leading shape.
        chromaticities: the image's primaries (``None``: Rec.709/D65).

    Returns:
        RGB in cd/m²; non-finite pixels are returned unchanged.
    """
    ch = chroma_key(chromaticities)
    return _colour_loss(check_rgb(rgb), ch)


@functools.partial(jax.jit, static_argnums=1)
def _colour_loss(rgb: Array, chromaticities: tuple[float, ...] | None) -> Array:
    x, ok = sanitize(rgb)
    # linear in the pixel but for c: on the pixel × an exact power of two (1 below 2^64
    # cd/m², same bits), so that the derivative's c·x − c·V/2.26 terms cannot overflow
    # (NaN image gradients of pixels near the float maximum)
    out = at_scale(functools.partial(_colour_loss_scaled, chromaticities), x, headroom(x))
    return restore(out, rgb, ok)


def _colour_loss_scaled(chromaticities: tuple[float, ...] | None, x: Array, h: Array) -> Array:
    c = mesopic_weight(luminance(x, weights_of(chromaticities)) / h[..., 0])[..., None]
    V = scotopic_unscaled(x, chromaticities)[..., None]  # x is scaled already
    return c * x + (1.0 - c) * (V / SWNORM)


def veil_kernel(view: ResolvedView, fovea_shape: tuple[int, int]) -> np.ndarray:
    """pcond's veil weights ``0.5 cosθ/(1 - cosθ)`` on the foveal grid (centre 0, θ < 90°).

    θ is the angle between foveal sample centres, taken as the flat angular distance
    ``sqrt((Δy·by·py)² + (Δx·bx·px)²)`` (pcond uses the view's exact ray directions; the two
    agree at the centre of a perspective view). The kernel covers the whole foveal grid.
    """
    fy, fx = fovea_shape
    by, bx = view.fovea_block
    dy = np.arange(-(fy - 1), fy) * by * view.pixel_deg_y
    dx = np.arange(-(fx - 1), fx) * bx * view.pixel_deg_x
    theta = np.deg2rad(np.hypot(dy[:, None], dx[None, :]))
    cos = np.cos(theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where((cos > 1e-6) & (theta > 0), 0.5 * cos / (1.0 - cos), 0.0)
    return w


def veil(
    rgb: Float[ArrayLike, "H W 3"], view: "View | ResolvedView | float | None" = None
) -> Float[Array, "H W 3"]:
    """pcond's veiling luminance (pcond4.c ``compveil``/``addveil``).

    For every foveal sample ``i``: ``veil_i = 0.08 Σ_j w_ij L_j / Σ_j w_ij`` over the other
    foveal samples with ``w_ij = 0.5 cosθ_ij/(1 - cosθ_ij)`` (≈ cosθ/θ²); the veil image is
    bilinearly interpolated to full resolution and ``out = 0.92·RGB + veil`` (per channel),
    computed as one blend of RGB and the interpolated weighted mean, which stays between
    the two up to the float maximum.
    The convolution over the foveal grid is a zero-padded FFT (:func:`veil_kernel`).

    Args:
        rgb: linear RGB in cd/m², ``(H, W, 3)``.
        view: field of view (:class:`View`, horizontal degrees, resolved, or ``None``).

    Returns:
        RGB in cd/m²; non-finite pixels are returned unchanged and do not contribute.
    """
    rgb = check_rgb(rgb, image=True)
    return _veil(rgb, resolve_view(view, rgb.shape[0], rgb.shape[1]))


@functools.partial(jax.jit, static_argnums=1)
def _veil(rgb: Array, view: ResolvedView) -> Array:
    x, ok = sanitize(rgb)
    by, bx = view.fovea_block
    fov, cnt = block_mean(x, ok, by, bx)
    have = (cnt[..., :1] > 0).astype(x.dtype)
    fy, fx = fov.shape[:2]
    k = veil_kernel(view, (fy, fx))
    size = _fft.fft_size(fy, fx, fy - 1, fx - 1)
    spec = jnp.asarray(_fft.kernel_spectrum(k, size)).astype(
        jnp.result_type(x.dtype, jnp.complex64)
    )
    # the weighted sum num overflows near the float maximum although num / den does not:
    # it runs on fov × c (exact power of two, 1 below 2^64 cd/m²) and c is divided out
    c = headroom(fov, None)
    num = _fft.convolve(fov * (have * c), spec, size)
    den = _fft.convolve(have, spec, size)
    # den is a sum of positive weights or (no other sample: a 1-sample grid) FFT round-off;
    # without a surround the sample keeps its own light (pcond would divide by zero).
    okd = den > 1e-6 * float(k.max(initial=0.0))
    # the surround's weighted mean: FFT round-off can carry it a few ulps past the samples,
    # below 0 or (samples at the float maximum) past the maximum, where it saturates
    m = jnp.where(okd, num / jnp.where(okd, den, 1.0) / c, fov)
    m = jnp.where(jnp.min(fov) >= 0, jnp.maximum(m, 0.0), m)
    top = jnp.finfo(m.dtype).max
    m = jnp.where(jnp.abs(m) > top, jnp.sign(m) * top, m)
    # 0.92·RGB + 0.08·mean as one blend, which stays between its two values
    full = upsample(m, (by, bx), rgb.shape[:2])
    return restore(lerp(x, full, VADAPT), rgb, ok)


__all__ = ["VADAPT", "VEIL_RANGE", "acuity", "colour_loss", "mesopic_weight", "tvi", "veil"]
