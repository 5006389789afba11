"""Display encoding: the separate last step after tone mapping.

Numeric contract: input is display-referred *linear* RGB (an operator's output, nominally
[0, 1]); output is encoded values in [0, 1] (float) or integers (``quantize``). NaN pixels
encode as 0 (black) and +Inf as 1: an 8-bit file cannot hold them.

sRGB: IEC 61966-2-1 piecewise curve ``12.92 x`` for ``x ≤ 0.0031308``, else
``1.055 x^(1/2.4) − 0.055``. Plain gamma: ``x^(1/γ)``.
"""

from typing import Literal

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check

SRGB_THRESHOLD = 0.0031308


def _clip(x: Array) -> Array:
    x = jnp.nan_to_num(x, nan=0.0, posinf=1.0, neginf=0.0)
    return jnp.clip(x, 0.0, 1.0)


def srgb_encode(linear: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """sRGB transfer function (IEC 61966-2-1) after clipping to [0, 1]; differentiable."""
    _check.real(linear, "linear")
    x = _clip(jnp.asarray(linear, jnp.result_type(float)))
    hi = x > SRGB_THRESHOLD
    powed = 1.055 * jnp.power(jnp.where(hi, x, 1.0), 1.0 / 2.4) - 0.055
    return jnp.where(hi, powed, 12.92 * x)


def srgb_decode(encoded: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """Inverse of :func:`srgb_encode` on [0, 1]."""
    _check.real(encoded, "encoded")
    y = _clip(jnp.asarray(encoded, jnp.result_type(float)))
    hi = y > 12.92 * SRGB_THRESHOLD
    return jnp.where(hi, jnp.power((jnp.where(hi, y, 1.0) + 0.055) / 1.055, 2.4), y / 12.92)


def gamma_encode(linear: Float[ArrayLike, "..."], gamma: float = 2.2) -> Float[Array, "..."]:
    """Plain power law ``x^(1/gamma)`` after clipping to [0, 1]."""
    _check.real(linear, "linear")
    if not gamma > 0:
        raise ValueError(f"gamma: expected a number > 0, got {gamma!r}")
    x = _clip(jnp.asarray(linear, jnp.result_type(float)))
    pos = x > 0
    return jnp.where(pos, jnp.power(jnp.where(pos, x, 1.0), 1.0 / gamma), 0.0)


def quantize(encoded: ArrayLike, bits: Literal[8, 16] = 8) -> np.ndarray:
    """Round encoded [0, 1] values to ``uint8``/``uint16`` (NaN → 0), on the host."""
    _check.real(encoded, "encoded")
    if bits not in (8, 16):
        raise ValueError(f"bits: expected 8 or 16, got {bits!r}")
    top = (1 << bits) - 1
    x = np.nan_to_num(np.asarray(encoded, np.float64), nan=0.0, posinf=1.0, neginf=0.0)
    return np.rint(np.clip(x, 0.0, 1.0) * top).astype(np.uint8 if bits == 8 else np.uint16)


def encode(
    linear: Float[ArrayLike, "..."],
    transfer: Literal["srgb", "gamma", "linear"] = "srgb",
    *,
    gamma: float = 2.2,
) -> Float[Array, "..."]:
    """Clip display-referred linear values to [0, 1] and apply a transfer function."""
    _check.real(linear, "linear")
    if transfer == "srgb":
        return srgb_encode(linear)
    if transfer == "gamma":
        return gamma_encode(linear, gamma)
    if transfer == "linear":
        return _clip(jnp.asarray(linear, jnp.result_type(float)))
    raise ValueError(f"transfer: expected 'srgb', 'gamma' or 'linear', got {transfer!r}")


__all__ = ["encode", "gamma_encode", "quantize", "srgb_decode", "srgb_encode"]
