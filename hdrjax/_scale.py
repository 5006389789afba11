"""Exact power-of-two scaling, for arithmetic that must stay finite up to the float maximum.

A sum, a mean or an FFT of values near the largest float overflows although its result
(after normalisation) is representable. Multiplying the operands by a power of two first,
and dividing it out of the result, is exact in binary floating point (only the exponent
changes), so the scaled computation returns the same bits as the unscaled one wherever the
latter does not overflow or reach subnormal numbers.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array


def positive_power(x: Array, p: float) -> Array:
    """``x ** p`` for ``x > 0`` as ``exp(p ln x)``: on XLA:CPU about 5× faster than
    ``jnp.power`` (which handles every sign and special case of the base), within a few
    float ulps of it. Callers mask ``x ≤ 0`` (``jnp.where(pos, x, 1.0)``)."""
    return jnp.exp(jnp.log(x) * p)


def ln_max(dtype) -> float:
    """The largest ``x`` of ``dtype`` whose ``exp`` is finite, with a few ulps of margin
    (``ln(max)`` rounded up gives +Inf; XLA's ``exp`` may round differently from NumPy's):
    clamp a mean of logarithms to it before ``exp``."""
    x = np.log(np.finfo(dtype).max).astype(dtype)
    with np.errstate(over="ignore"):
        while not np.isfinite(np.exp(x)):
            x = np.nextafter(x, np.zeros((), dtype))
    for _ in range(4):
        x = np.nextafter(x, np.zeros((), dtype))
    return float(x)


def saturate_finite(y: Array, x: Array) -> Array:
    """``y``, a linear map of the pixels ``x`` (channels last), with the pixels whose
    inputs are all finite clamped to the dtype's range: a colour matrix or spectral
    integration of values near the float maximum exceeds it, and finite in must stay
    finite out. Pixels with a NaN or Inf input keep their non-finite result."""
    top = jnp.finfo(y.dtype).max
    finite = jnp.all(jnp.isfinite(x), axis=-1, keepdims=True)
    return jnp.where(finite, jnp.clip(y, -top, top), y)


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


@jax.custom_jvp
def quotient(x: Array, d: Array) -> Array:
    """``x / d`` with the derivative ``(ẋ − (x / d) ḋ) / d``. JAX's own has ``x / d²``,
    which overflows or underflows (``d`` beyond ``2^64`` or below ``2^-64`` in float32)
    where the quotient and its derivative are representable: NaN gradients for very bright
    and very dim images."""
    return x / d


@quotient.defjvp
def _quotient_jvp(primals, tangents):
    (x, d), (tx, td) = primals, tangents
    r = x / d
    return r, (tx - r * td) / d


@jax.custom_jvp
def scale(x: Array, a: Array, d: Array) -> Array:
    """``(a / d) · x`` (one multiplication per element, as written) with a derivative that
    never forms ``x / d²`` or ``Σ ẋ x`` (both overflow for ``x`` near the float maximum):
    ``(a / d) ẋ + ȧ (x / d) − ḋ (a / d) x / d``."""
    return (a / d) * x


@scale.defjvp
def _scale_jvp(primals, tangents):
    (x, a, d), (tx, ta, td) = primals, tangents
    s = a / d
    out = s * x
    return out, s * tx + ta * quotient(x, d) - td * quotient(out, d)


def divide(x: Array, d: Array) -> Array:
    """``x / d`` for an array ``x`` and a scalar ``d > 0`` up to the largest float.

    XLA computes a division by a scalar as ``x · (1/d)``, and ``1/d`` is subnormal (flushed
    to 0 on CPU) once ``d > 1/tiny`` (8.5e37 in float32), which turned every pixel black;
    both are divided by 8 first (exact), which keeps ``1/d`` normal for every finite ``d``.
    """
    c = jnp.where(d > 1, 0.125, 1.0).astype(d.dtype)
    return quotient(x * c, d * c)


def at_scale(f, x: Array, c: Array) -> Array:
    """``f(x · c, c) / c`` for an exact power-of-two ``c`` (e.g. from ``headroom``), with
    the derivative ``∂f/∂x(x · c, c) ẋ`` (``c`` is a constant; ``f`` may read it, e.g. to
    evaluate a term on the unscaled values).

    That is the chain rule's value, but autodiff of the written form passes the cotangent
    ``1/c`` (up to ``2^64`` in float32) through ``f`` at values up to ``2^64``: the products
    overflow in the backward pass (NaN image gradients) although the gradient is
    representable. ``c = 1`` gives the unscaled values (multiplications by 1 are exact).

    A finite result whose unscaled value lies beyond the float range (an effect that
    brightens a pixel at the float maximum, or the round-off of a colour matrix and its
    inverse there) saturates at ``±finfo.max`` instead of becoming ``±Inf``, with
    derivative 0; non-finite results of ``f`` pass through.
    """
    return _at_scale(f, x, jax.lax.stop_gradient(c))


def _unscale(y: Array, c: Array) -> tuple[Array, Array]:
    """``(y / c`` saturated at ``±finfo.max`` where ``y`` is finite, the saturated mask)``."""
    out = y / c
    sat = jnp.isfinite(y) & jnp.isinf(out)
    return jnp.where(sat, jnp.sign(y) * jnp.finfo(y.dtype).max, out), sat


@functools.partial(jax.custom_jvp, nondiff_argnums=(0,))
def _at_scale(f, x, c):
    return _unscale(f(x * c, c), c)[0]


@_at_scale.defjvp
def _at_scale_jvp(f, primals, tangents):
    (x, c), (tx, _) = primals, tangents
    out, t = jax.jvp(lambda z: f(z, c), (x * c,), (tx,))
    out, sat = _unscale(out, c)
    return out, jnp.where(sat, 0.0, t)


__all__ = ["at_scale", "divide", "inverse_pow2", "quotient", "scale"]
