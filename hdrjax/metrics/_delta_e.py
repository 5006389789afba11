"""ΔE_ITP, the colour difference of ITU-R BT.2124 for HDR display renditions.

ITU-R BT.2124-0, "Objective metric for the assessment of the potential visibility of colour
differences in television", 2019, https://www.itu.int/rec/R-REC-BT.2124; ICtCp as ITU-R
BT.2100-2 (2018) defines it with the PQ transfer function (SMPTE ST 2084).

Numeric contract: linear ITU-R BT.2020 RGB in absolute units (cd/m², as emitted by the
display), channels last ``(..., 3)``; one ΔE_ITP per pixel ``(...)``, where 1 is about one
just-noticeable difference.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike, Float

from .. import _check

RGB_TO_LMS = np.array([[1688, 2146, 262], [683, 2951, 462], [99, 309, 3688]]) / 4096
"""BT.2100's BT.2020 RGB → LMS matrix."""
LMS_TO_ICTCP = np.array([[2048, 2048, 0], [6610, -13613, 7003], [17933, -17390, -543]]) / 4096
"""BT.2100's PQ-encoded L'M'S' → ICtCp matrix."""
PQ_PEAK = 10000.0
"""Absolute luminance (cd/m²) of PQ's code value 1."""
M1, M2 = 2610 / 16384, 2523 / 4096 * 128
C1, C2, C3 = 3424 / 4096, 2413 / 4096 * 32, 2392 / 4096 * 32
"""The constants of SMPTE ST 2084's PQ curve."""


def _pq(Y: jax.Array) -> jax.Array:
    """PQ inverse EOTF of absolute values (cd/m²; negatives clamped to 0)."""
    y = jnp.maximum(Y / PQ_PEAK, 0.0)
    pos = y > 0
    yp = jnp.where(pos, jnp.where(pos, y, 1.0) ** M1, 0.0)  # finite gradient at 0
    return ((C1 + C2 * yp) / (1 + C3 * yp)) ** M2


def ictcp(rgb: jax.Array) -> jax.Array:
    """ICtCp (BT.2100, PQ) of linear BT.2020 RGB in cd/m²."""
    lms = rgb @ jnp.asarray(RGB_TO_LMS.T, rgb.dtype)
    return _pq(lms) @ jnp.asarray(LMS_TO_ICTCP.T, rgb.dtype)


@jax.jit
def _delta_e_itp(a: jax.Array, b: jax.Array) -> jax.Array:
    d = ictcp(a) - ictcp(b)
    sq = d[..., 0] ** 2 + (0.5 * d[..., 1]) ** 2 + d[..., 2] ** 2
    pos = sq > 0
    return 720.0 * jnp.where(pos, jnp.sqrt(jnp.where(pos, sq, 1.0)), 0.0)


def delta_e_itp(
    a: Float[ArrayLike, "*shape 3"], b: Float[ArrayLike, "*shape 3"]
) -> Float[jax.Array, "*shape"]:
    """ΔE_ITP (ITU-R BT.2124) between two HDR renditions, per pixel.

    .. math::

        \\Delta E_{ITP} = 720 \\sqrt{\\Delta I^2 + \\Delta T^2 + \\Delta P^2},
        \\qquad T = C_T / 2,\\ P = C_P

    with ``I, C_T, C_P`` the ICtCp (BT.2100, PQ) of each image: RGB → LMS, the PQ inverse
    EOTF of ``LMS / 10000 cd/m²``, → ICtCp. Equal to colour-science's
    ``colour.difference.delta_E_ITP(colour.RGB_to_ICtCp(a), colour.RGB_to_ICtCp(b))``
    (colour-science takes the RGB in cd/m² too).

    Args:
        a: linear ITU-R BT.2020 RGB in cd/m² (display light), channels last ``(..., 3)``;
            negative values count as 0.
        b: the other rendition, the shape of ``a``.

    Returns:
        ΔE_ITP of each pixel, shape ``a.shape[:-1]``; 0 for identical pixels (where its
        gradient is 0), NaN where a channel of either pixel is NaN. In float32 the result
        carries a rounding error of about 2e-3 ΔE_ITP (up to 0.03 near 10000 cd/m²: PQ's
        exponent 78.84 amplifies the rounding of ``L, M, S``), small against the threshold
        of 1; use float64 (x64) for reference values.

    Reference: ITU-R BT.2124-0 (2019), https://www.itu.int/rec/R-REC-BT.2124.
    """
    x = _check.rgb_pixels(a, "a")
    y = _check.rgb_pixels(b, "b")
    if x.shape != y.shape:
        raise ValueError(f"b: expected the shape of a {x.shape}, got shape {y.shape}")
    dt = jnp.result_type(x.dtype, y.dtype)
    return _delta_e_itp(x.astype(dt), y.astype(dt))
