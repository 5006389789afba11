"""Low-discrepancy point sets: van der Corput, Hammersley, Halton.

Formulas (J. G. van der Corput, "Verteilungsfunktionen", Proc. Akad. Wetensch. Amsterdam
38, 1935; J. M. Hammersley, D. C. Handscomb, "Monte Carlo Methods", Methuen 1964;
J. H. Halton, "On the efficiency of certain quasi-random sequences of points in evaluating
multi-dimensional integrals", Numerische Mathematik 2, 1960,
https://doi.org/10.1007/BF01386213; Loghin 2019 samples the sphere with the Hammersley set):

- van der Corput radical inverse in base 2 of a 32-bit index: reverse the bits (16-bit
  rotate, then swap bytes, nibbles, pairs, single bits) and multiply by ``2^-32``;
- Hammersley set of ``n`` points: ``(i / n, Φ₂(i))``, ``i = 0 … n − 1``;
- Halton sequence: ``(Φ₂(i), Φ₃(i), …)`` for ``i = 1 … n`` (the all-zero point ``i = 0`` is
  skipped, as most implementations do).

Each function works on NumPy (used at trace time, when the point set is a constant of a
compiled function) and returns a JAX array; the results are exact in float64 and rounded
once to the default float dtype.
"""

import math

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

_PRIMES = (2, 3, 5, 7, 11, 13, 17, 19, 23, 29)


def _radical_inverse_2(i: np.ndarray) -> np.ndarray:
    bits = i.astype(np.uint32)
    bits = (bits << np.uint32(16)) | (bits >> np.uint32(16))
    bits = ((bits & np.uint32(0x55555555)) << np.uint32(1)) | (
        (bits & np.uint32(0xAAAAAAAA)) >> np.uint32(1)
    )
    bits = ((bits & np.uint32(0x33333333)) << np.uint32(2)) | (
        (bits & np.uint32(0xCCCCCCCC)) >> np.uint32(2)
    )
    bits = ((bits & np.uint32(0x0F0F0F0F)) << np.uint32(4)) | (
        (bits & np.uint32(0xF0F0F0F0)) >> np.uint32(4)
    )
    bits = ((bits & np.uint32(0x00FF00FF)) << np.uint32(8)) | (
        (bits & np.uint32(0xFF00FF00)) >> np.uint32(8)
    )
    return bits.astype(np.float64) * 2.3283064365386963e-10


def _radical_inverse(i: np.ndarray, base: int) -> np.ndarray:
    if base == 2:
        return _radical_inverse_2(i)
    i = i.astype(np.int64)
    out = np.zeros(i.shape, np.float64)
    f = 1.0 / base
    while np.any(i > 0):
        out += f * (i % base)
        i //= base
        f /= base
    return out


def hammersley_np(n: int) -> np.ndarray:
    """Hammersley set as a float64 NumPy array ``(n, 2)`` (see :func:`hammersley`)."""
    i = np.arange(n, dtype=np.int64)
    return np.stack([i / max(n, 1), _radical_inverse_2(i)], axis=-1)


def halton_np(n: int, dims: int = 2) -> np.ndarray:
    """Halton sequence as a float64 NumPy array ``(n, dims)`` (see :func:`halton`)."""
    i = np.arange(1, n + 1, dtype=np.int64)
    return np.stack([_radical_inverse(i, b) for b in _PRIMES[:dims]], axis=-1)


def _count(n: int) -> int:
    if isinstance(n, bool) or int(n) != n or n < 0 or n >= 2**32:
        raise ValueError(f"n: expected an integer in [0, 2**32), got {n!r}")
    return int(n)


def van_der_corput(i: int | np.ndarray, base: int = 2) -> Float[Array, "*N"]:
    """Radical inverse ``Φ_b(i)`` of non-negative integer indices.

    >>> van_der_corput(np.arange(4)).tolist()
    [0.0, 0.5, 0.25, 0.75]
    """
    i = np.asarray(i)
    if not np.issubdtype(i.dtype, np.integer) or np.any(i < 0) or np.any(i >= 2**32):
        raise ValueError("i: expected integers in [0, 2**32)")
    if int(base) != base or base < 2:
        raise ValueError(f"base: expected an integer >= 2, got {base!r}")
    return jnp.asarray(_radical_inverse(i, int(base)), dtype=jnp.result_type(float))


def hammersley(n: int) -> Float[Array, "n 2"]:
    """The ``n``-point Hammersley set ``(i / n, Φ₂(i))`` in the unit square."""
    return jnp.asarray(hammersley_np(_count(n)), dtype=jnp.result_type(float))


def halton(n: int, dims: int = 2) -> Float[Array, "n dims"]:
    """The first ``n`` Halton points (bases 2, 3, 5, …; index 0 skipped) in ``[0, 1)^dims``."""
    if not 1 <= int(dims) <= len(_PRIMES):
        raise ValueError(f"dims: expected 1..{len(_PRIMES)}, got {dims!r}")
    return jnp.asarray(halton_np(_count(n), int(dims)), dtype=jnp.result_type(float))


def sphere_directions_np(n: int) -> np.ndarray:
    """Hammersley points mapped uniformly onto the unit sphere (Loghin 2019's ``sphereSample``).

    ``cos θ = 2 (i + ½) / n − 1`` (the half-index offset keeps the first and last points
    off the poles), ``φ = 2π Φ₂(i)``; returns float64 ``(sinθ cosφ, sinθ sinφ, cosθ)``,
    ``(n, 3)`` (Loghin's frame, z up).
    """
    i = np.arange(n, dtype=np.int64)
    z = 2.0 * (i + 0.5) / max(n, 1) - 1.0
    phi = 2.0 * math.pi * _radical_inverse_2(i)
    r = np.sqrt(np.maximum(1.0 - z * z, 0.0))
    return np.stack([np.cos(phi) * r, np.sin(phi) * r, z], axis=-1)


__all__ = ["halton", "hammersley", "van_der_corput"]
