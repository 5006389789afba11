"""Order-preserving integer keys for floats, so comparator networks run on integer min/max.

``key(x) = bits(x) ^ ((bits(x) >> (n-1)) & (2^(n-1) - 1))`` maps IEEE-754 floats to signed
integers with the same order (−Inf < negatives < −0 < +0 < positives < +Inf), and every NaN
(after canonicalisation to the positive quiet NaN) above +Inf, as ``numpy.sort`` orders
them. The map is a bijection, so a network's output maps back to a bit-exact input value.
Integer min/max is one instruction on x86; float min/max with NaN propagation is three.
"""

import jax
import jax.numpy as jnp
from jax import Array

_INT = {jnp.dtype(jnp.float32): jnp.int32, jnp.dtype(jnp.float64): jnp.int64}


def key_dtype(dtype) -> jnp.dtype:
    """The integer key type for float32 (int32) or float64 (int64)."""
    return jnp.dtype(_INT[jnp.dtype(dtype)])


def to_key(x: Array) -> Array:
    """Float → order-preserving signed integer key (NaN above +Inf)."""
    it = _INT[x.dtype]
    x = jnp.where(jnp.isnan(x), jnp.array(jnp.nan, x.dtype), x)  # one NaN bit pattern
    b = jax.lax.bitcast_convert_type(x, it)
    nbits = jnp.iinfo(it).bits
    return b ^ ((b >> (nbits - 1)) & jnp.iinfo(it).max)


def from_key(k: Array, dtype) -> Array:
    """Inverse of :func:`to_key`."""
    nbits = jnp.iinfo(k.dtype).bits
    b = k ^ ((k >> (nbits - 1)) & jnp.iinfo(k.dtype).max)
    return jax.lax.bitcast_convert_type(b, jnp.dtype(dtype))
