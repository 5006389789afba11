"""Photometric constants, the threshold-versus-intensity curve and colour conversions
shared by the vision effects and the Budak 2005 operator.

Numeric contract: linear RGB in absolute units (cd/m²), channels last, any primaries given
as an OpenEXR-style ``chromaticities`` 8-tuple (Rec.709/sRGB with D65 when ``None``).
Luminance ``Y`` always comes from :func:`hdrjax.luminance` with the image's weights, so the
RGB→XYZ matrix used here has exactly those weights as its Y row (its X and Z rows are
colour-science's ``normalised_primary_matrix``); RGB→XYZ→RGB is an exact round trip.

Constants are Radiance ``pcond``'s (G. Ward Larson, NREL/Radiance ``src/px/pcond.h``).
"""

import functools
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from . import _check
from ._colour import REC709_CHROMATICITIES, luminance, luminance_weights
from ._scale import at_scale, inverse_pow2

LMIN = 1e-7
"""Smallest visible world luminance, cd/m² (pcond.h ``LMIN``)."""
LMAX = 1e5
"""Largest visible world luminance, cd/m² (pcond.h ``LMAX``)."""
BOT_MESOPIC = 5.62e-3
"""Top of the scotopic range / bottom of the mesopic range, cd/m² (pcond.h ``BotMesopic``)."""
TOP_MESOPIC = 5.62
"""Top of the mesopic range / bottom of the photopic range, cd/m² (pcond.h ``TopMesopic``)."""
SWNORM = 2.26
"""Scotopic/photopic luminance ratio of white (pcond.h ``SWNORM``)."""


def check_rgb(
    rgb: ArrayLike, name: str = "rgb", *, image: bool = False, pooled: bool = False
) -> Array:
    """``rgb`` as a float array with 3 channels last (and 3 dims when ``image``). An image
    (``image``), or pixels a function pools statistics over (``pooled``), needs H, W >= 1;
    per-pixel functions take empty arrays (an empty result)."""
    _check.real(rgb, name)
    rgb = _check.as_float(rgb)
    if rgb.ndim < 1 or rgb.shape[-1] != 3:
        raise ValueError(f"{name}: expected channels-last RGB (..., 3), got shape {rgb.shape}")
    if image and rgb.ndim != 3:
        raise ValueError(
            f"{name}: expected one image of shape (H, W, 3), got shape {rgb.shape}; "
            "use jax.vmap for batches"
        )
    if image or pooled:
        _check.nonempty(rgb.shape, name, "(H, W, 3)")
    return rgb


def log10_floor(L: Array, floor: float) -> Array:
    """``log10(max(L, floor))`` with a finite gradient everywhere (0 below ``floor``): the
    log luminance of the threshold-versus-intensity curves, floored at their lowest
    luminance (Ferwerda et al. 1996; pcond's ``LMIN``)."""
    ok = L > floor
    return jnp.where(ok, jnp.log10(jnp.where(ok, L, 1.0)), jnp.log10(floor))


def tvi(L_a: Float[ArrayLike, "*shape"]) -> Float[Array, "*shape"]:
    """Combined rod/cone threshold ``ΔL(L_a)`` in cd/m² (pcond3.c ``htcontrs``).

    From Ferwerda et al. 1996: ``1.38e-3`` below ``L_a = 1.148e-4``; otherwise
    ``10^y`` with ``x = log10 L_a`` and ``y = (0.405x + 1.6)^2.18 - 2.86`` for
    ``x < -1.44``, ``x - 0.395`` for ``x < -0.0184``, ``(0.249x + 0.65)^2.7 - 0.72`` for
    ``x < 1.9`` and ``x - 1.255`` above.

    Example:
        >>> round(float(tvi(1.0)), 4)  # cone branch at x = 0: 10**(0.65**2.7 - 0.72)
        0.3913
    """
    _check.real(L_a, "L_a")
    L_a = _check.as_float(L_a)
    x = log10_floor(L_a, 1.148e-4)
    rod = (0.405 * jnp.clip(x, -3.94, -1.44) + 1.6) ** 2.18 - 2.86
    cone = (0.249 * jnp.clip(x, -0.0184, 1.9) + 0.65) ** 2.7 - 0.72
    y = jnp.where(x < -1.44, rod, jnp.where(x < -0.0184, x - 0.395, cone))
    y = jnp.where(x < 1.9, y, x - 1.255)
    return jnp.where(L_a < 1.148e-4, 1.38e-3, 10.0**y)


def mesopic_weight(L: Float[ArrayLike, "*shape"]) -> Float[Array, "*shape"]:
    """Share of colour vision at luminance ``L``: pcond3.c ``scotscan``'s ``incolor``.

    ``c = (L - 5.62e-3)/(5.62 - 5.62e-3)`` clamped to [0, 1]: 0 (rods only) at or below
    5.62e-3 cd/m², 1 (cones only) at or above 5.62 cd/m², linear in ``L`` between.
    """
    _check.real(L, "L")
    L = _check.as_float(L)
    return jnp.clip((L - BOT_MESOPIC) / (TOP_MESOPIC - BOT_MESOPIC), 0.0, 1.0)


def chroma_key(chromaticities: Sequence[float] | None) -> tuple[float, ...] | None:
    """Hashable, validated primaries: ``None`` for Rec.709/D65, else the 8 floats.

    Raises:
        ValueError: not 8 finite numbers, or degenerate primaries.
    """
    if chromaticities is None:
        return None
    c = np.asarray(chromaticities, dtype=np.float64).reshape(-1)
    if c.shape == (8,) and np.allclose(c, REC709_CHROMATICITIES, atol=1e-4):
        return None
    key = tuple(float(v) for v in c)
    xyz_matrices(key)  # validates (luminance_weights raises ValueError)
    return key


def weights_of(key: tuple[float, ...] | None) -> tuple[float, float, float]:
    """Luminance weights (the Y row of :func:`rgb_to_xyz_matrix`) of validated primaries."""
    return tuple(float(w) for w in xyz_matrices(key)[0][1])  # type: ignore[return-value]


@functools.lru_cache(maxsize=16)
def xyz_matrices(key: tuple[float, ...] | None) -> tuple[np.ndarray, np.ndarray]:
    weights = luminance_weights(key)  # validates the chromaticities
    c = np.asarray(REC709_CHROMATICITIES if key is None else key, dtype=np.float64)
    import colour  # slow import, only when a colour effect runs

    npm = np.array(colour.normalised_primary_matrix(c[:6].reshape(3, 2), c[6:]), np.float64)
    npm[1] = weights  # Y row = hdrjax's luminance weights (the standard's rounding for 709)
    return npm, np.linalg.inv(npm)


def rgb_to_xyz_matrix(chromaticities: Sequence[float] | None = None) -> np.ndarray:
    """RGB→XYZ matrix (float64, 3×3) whose Y row is :func:`hdrjax.luminance_weights`."""
    return xyz_matrices(chroma_key(chromaticities))[0].copy()


def _apply3(m: np.ndarray, a: Array, b: Array, c: Array) -> tuple[Array, Array, Array]:
    return tuple(  # type: ignore[return-value]
        a * float(m[i, 0]) + b * float(m[i, 1]) + c * float(m[i, 2]) for i in range(3)
    )


def rgb_to_xyz(
    rgb: Float[ArrayLike, "*batch 3"], chromaticities: Sequence[float] | None = None
) -> tuple[Array, Array, Array]:
    """CIE XYZ (cd/m² for Y) of linear RGB, as three arrays of shape ``rgb.shape[:-1]``."""
    rgb = check_rgb(rgb)
    m = xyz_matrices(chroma_key(chromaticities))[0]
    X, _, Z = _apply3(m, rgb[..., 0], rgb[..., 1], rgb[..., 2])
    Y = luminance(rgb, tuple(m[1]))
    return X, Y, Z


def xyz_to_rgb(
    X: ArrayLike, Y: ArrayLike, Z: ArrayLike, chromaticities: Sequence[float] | None = None
) -> Float[Array, "*batch 3"]:
    """Inverse of :func:`rgb_to_xyz`: linear RGB, channels last."""
    minv = xyz_matrices(chroma_key(chromaticities))[1]
    r, g, b = _apply3(minv, jnp.asarray(X), jnp.asarray(Y), jnp.asarray(Z))
    return jnp.stack([r, g, b], axis=-1)


SCOTOPIC_RATIO_MAX = 300.0
"""Cap on ``(Y + Z)/X`` in :func:`scotopic_luminance`. Every real colour has
``(Y + Z)/X = (1 - x)/x <= 274`` (CIE 1931 2° spectral locus, smallest chromaticity
``x = 0.00364`` at 504 nm; the purples and the inside of the locus have larger ``x``), so the
cap changes only XYZ that no light produces (negative-channel noise, primaries outside the
locus)."""


def largest_component_reciprocal(X: Array, Y: Array, Z: Array) -> Array:
    """``1 / max(|X|, |Y|, |Z|)`` per pixel, held constant under differentiation (1 where
    that maximum is 0 or not finite).

    Ratios of X, Y, Z formed after multiplying by it have the same value, but their
    derivatives no longer square a component: ``d(a/b)/db = -a/b²`` over- or underflows
    ``b²`` in float32 for ``|b|`` beyond 1e±19. It is a factor rather than a divisor
    because dividing by the maximum instead gave a non-finite compiled (jit) gradient of
    :func:`~hdrjax.vision.blue_shift` near 1e-37 cd/m² on XLA:CPU (eager was finite).
    """
    m = jnp.maximum(jnp.maximum(jnp.abs(X), jnp.abs(Y)), jnp.abs(Z))
    m = jnp.where((m > 0) & jnp.isfinite(m), m, 1.0)
    return jax.lax.stop_gradient(1.0 / m)


def scotopic_luminance(
    rgb: Float[ArrayLike, "*batch 3"], *, chromaticities: Sequence[float] | None = None
) -> Float[Array, "*batch"]:
    """Scotopic luminance ``V`` (scotopic cd/m²) of linear RGB in cd/m².

    ``V = Y (1.33 (1 + (Y + Z)/X) - 1.68)`` (Radiance ``cielum``, NREL/Radiance
    ``src/px/pcond2.c``; HDR Toolbox ``lumScotopic.m``), evaluated on XYZ from the image's
    primaries. Pixels with ``X <= 0`` (black, or out of gamut) and negative results give 0.
    For an equal-energy white ``V/Y = 2.31``, close to pcond's ``SWNORM = 2.26``.

    Domain: real colours, for which ``(Y + Z)/X <= 274`` (:data:`SCOTOPIC_RATIO_MAX`).
    Out-of-gamut XYZ with ``X > 0`` but ``|Y| + |Z| > 300 X`` use
    ``X_eff = (|Y| + |Z|)/300`` in place of ``X`` (the formula's value is continuous there);
    ``cielum`` itself would return up to ``±∞`` as ``X → 0⁺``. Numerics: the ratio is formed
    from X, Y, Z scaled by :func:`largest_component_reciprocal`, so value and gradient stay
    finite from 1e-38 cd/m² to the float maximum (a ``V`` beyond the float range saturates at
    the largest float) (``d/dX (Y + Z)/X = -(Y + Z)/X²`` of the
    unscaled formula over- or underflows ``X²`` beyond 1e±19).

    Args:
        rgb: linear RGB, cd/m², channels last.
        chromaticities: the image's primaries (``None``: Rec.709/D65).

    Returns:
        ``V`` with shape ``rgb.shape[:-1]``.
    """
    rgb = check_rgb(rgb)
    # homogeneous of degree 1: evaluated on RGB × an exact power of two (1 below 2^64
    # cd/m², same bits), whose XYZ cannot overflow (Z of a white is 1.09 RGB)
    f = lambda x, _: scotopic_unscaled(x, chromaticities)[..., None]  # noqa: E731
    V = at_scale(f, rgb, headroom(rgb))[..., 0]
    return jnp.minimum(V, jnp.finfo(V.dtype).max)  # V/Y reaches 4.4: saturate


def scotopic_unscaled(rgb: Array, chromaticities: Sequence[float] | None) -> Array:
    X, Y, Z = rgb_to_xyz(rgb, chromaticities)
    r = largest_component_reciprocal(X, Y, Z)
    x, y, z = X * r, Y * r, Z * r  # the largest of |x|, |y|, |z| is 1
    ok = x > 0
    # x > 0 and max(|x|, |y|, |z|) = 1 give x_eff >= 1/300, so d ratio/dx <= 2·300²
    x_eff = jnp.maximum(x, (jnp.abs(y) + jnp.abs(z)) / SCOTOPIC_RATIO_MAX)
    ratio = (y + z) / jnp.where(ok, x_eff, 1.0)
    V = Y * (1.33 * (1.0 + ratio) - 1.68)
    return jnp.where(ok, jnp.maximum(V, 0.0), 0.0)


def headroom(x: Array, axis: int | None = -1) -> Array:
    """Exact power-of-two factor ``c ≤ 1`` that brings ``max |x|`` (per pixel along ``axis``,
    or over all of ``x`` for ``None``) down to at most ``2^(maxexp/2)`` (2^64 in float32).

    Colour matrices (``Z`` of a white reaches 1.09·RGB), FFT sums and the like overflow near
    the float maximum although their normalised results are representable: computing on
    ``x · c`` and dividing ``c`` out of the result is exact (only exponents change), and
    ``c = 1`` for all values below 2^64, so ordinary images give the same bits. A constant
    for ``jax.grad``; non-finite values give 1.
    """
    top = 2.0 ** (jnp.finfo(x.dtype).maxexp // 2)
    m = jax.lax.stop_gradient(jnp.max(jnp.abs(x), axis=axis, keepdims=axis is not None))
    big = jnp.isfinite(m) & (m > top)
    return jnp.where(big, inverse_pow2(m) * top, 1.0).astype(x.dtype)


def finite_pixels(rgb: Array) -> Array:
    """Boolean ``(..., )`` mask of pixels whose three channels are all finite."""
    return jnp.all(jnp.isfinite(rgb), axis=-1)


def sanitize(rgb: Array) -> tuple[Array, Array]:
    """``(rgb with non-finite pixels set to 0, mask of finite pixels)``.

    Effects compute on the sanitised image and :func:`restore` puts the original values back
    in the non-finite pixels, so NaN/Inf never spread and their gradients are not NaN.
    """
    ok = finite_pixels(rgb)
    return jnp.where(ok[..., None], rgb, 0.0), ok


def restore(out: Array, rgb: Array, ok: Array) -> Array:
    """Original values in the non-finite pixels (see :func:`sanitize`)."""
    return jnp.where(ok[..., None], out, rgb)


__all__ = [
    "BOT_MESOPIC",
    "LMAX",
    "LMIN",
    "SCOTOPIC_RATIO_MAX",
    "SWNORM",
    "TOP_MESOPIC",
    "check_rgb",
    "finite_pixels",
    "headroom",
    "largest_component_reciprocal",
    "mesopic_weight",
    "restore",
    "rgb_to_xyz",
    "rgb_to_xyz_matrix",
    "sanitize",
    "scotopic_luminance",
    "tvi",
    "xyz_to_rgb",
]
