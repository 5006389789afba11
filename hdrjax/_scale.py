"""Exact power-of-two scaling, for arithmetic that must stay finite up to the float maximum.

A sum, a mean or an FFT of values near the largest float overflows although its result
(after normalisation) is representable. Multiplying the operands by a power of two first,
and dividing it out of the result, is exact in binary floating point (only the exponent
changes), so the scaled computation returns the same bits as the unscaled one wherever the
latter does not overflow or reach subnormal numbers.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array


def inverse_pow2(x: Array) -> Array:
    """``2^-e`` with ``2^(e-1) ≤ |x| < 2^e``: ``|x| · inverse_pow2(x)`` lies in ``[0.5, 1)``.

    The exponent is clamped so that the factor itself is a normal float (``x`` near the
    float maximum then scales into ``[0.5, 4)``), and it is 1 for 0 and non-finite ``x``.
    A constant for ``jax.grad`` (the results it scales do not depend on it).
    """
    x = jax.lax.stop_gradient(jnp.asarray(x))
    _, e = jnp.frexp(jnp.where(jnp.isfinite(x) & (x != 0), x, 1.0))
    top = np.finfo(x.dtype).maxexp - 2  # 126 in float32: 2^-126 is the smallest normal
    return jnp.ldexp(jnp.ones((), x.dtype), -jnp.clip(e, -top, top))


__all__ = ["inverse_pow2"]
