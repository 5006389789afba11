"""Threshold curves shared by the vision effects and the operators built on them: the
threshold-versus-intensity curves of Ferwerda, Pattanaik, Shirley & Greenberg (1996) and
Ward's (1994) contrast-based scale factor.

Numeric contract: adaptation luminance ``L_a`` in cd/m² (any shape, any float dtype);
returns the threshold luminance increment ``ΔL`` in cd/m², same shape. Non-positive ``L_a``
is treated as lying on the flat (absolute-threshold) branch.

Reference: J. A. Ferwerda, S. N. Pattanaik, P. Shirley, D. P. Greenberg, "A model of visual
adaptation for realistic image synthesis", SIGGRAPH 1996, pp. 249–258,
doi:10.1145/237170.237262. Transcribed from banterle/HDR_Toolbox ``TpFerwerda.m`` /
``TsFerwerda.m`` and NREL/Radiance ``pcond3.c`` (``htcontrs``).
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from . import _check
from ._photometry import log10_floor


def tvi_photopic(L_a: Float[ArrayLike, "*shape"]) -> Float[Array, "*shape"]:
    """Cone threshold ``ΔL = 10^t_p(log10 L_a)`` (Ferwerda et al. 1996).

    With ``x = log10 L_a``: ``t_p = -0.72`` for ``x <= -2.6``; ``x - 1.255`` for ``x >= 1.9``;
    ``(0.249 x + 0.65)^2.7 - 0.72`` between.

    Example:
        >>> float(tvi_photopic(100.0))  # Weber branch: 100 * 10**-1.255
        5.559...
    """
    _check.real(L_a, "L_a")
    L_a = _check.as_float(L_a)
    x = log10_floor(L_a, 10.0**-2.6)
    mid = (0.249 * jnp.clip(x, -2.6, 1.9) + 0.65) ** 2.7 - 0.72
    t = jnp.where(x <= -2.6, -0.72, jnp.where(x >= 1.9, x - 1.255, mid))
    return 10.0**t


def tvi_scotopic(L_a: Float[ArrayLike, "*shape"]) -> Float[Array, "*shape"]:
    """Rod threshold ``ΔL = 10^t_s(log10 L_a)`` (Ferwerda et al. 1996).

    With ``x = log10 L_a`` (scotopic cd/m²): ``t_s = -2.86`` for ``x <= -3.94``;
    ``x - 0.395`` for ``x >= -1.44``; ``(0.405 x + 1.6)^2.18 - 2.86`` between.
    """
    _check.real(L_a, "L_a")
    L_a = _check.as_float(L_a)
    x = log10_floor(L_a, 10.0**-3.94)
    mid = (0.405 * jnp.clip(x, -3.94, -1.44) + 1.6) ** 2.18 - 2.86
    t = jnp.where(x <= -3.94, -2.86, jnp.where(x >= -1.44, x - 0.395, mid))
    return 10.0**t


def ward1994_scale(
    L_wa: Float[ArrayLike, "*shape"], L_da: Float[ArrayLike, "*shape"]
) -> Float[Array, "*shape"]:
    """Ward 1994 scale factor ``m = [(1.219 + L_da^0.4)/(1.219 + L_wa^0.4)]^2.5``."""
    _check.real(L_wa, "L_wa")
    L_wa = jnp.maximum(_check.as_float(L_wa), 0.0)
    L_da = jnp.maximum(_check.as_float(L_da), 0.0)
    # x**0.4 has an infinite derivative at 0; evaluate it at a tiny positive value there.
    pw = jnp.where(L_wa > 0, jnp.where(L_wa > 0, L_wa, 1.0) ** 0.4, 0.0)
    pd = jnp.where(L_da > 0, jnp.where(L_da > 0, L_da, 1.0) ** 0.4, 0.0)
    return ((1.219 + pd) / (1.219 + pw)) ** 2.5


__all__ = ["tvi_photopic", "tvi_scotopic", "ward1994_scale"]
