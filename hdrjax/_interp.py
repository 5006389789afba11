"""Linear interpolation shared by the resamplers (panoramas, the vision effects' upsampling)
and the tabulated tone curves (:func:`table_lerp`).

A blend ``a (1 - f) + b f`` with ``0 ≤ f ≤ 1`` lies between ``a`` and ``b``, but its
rounded terms can add up past the largest float when both neighbours are near it: a
float64 image at the float64 maximum, sampled at float32 coordinates, gave +Inf (``1 - f``
rounded in float32 made the two weights sum to ``1 + 2e-8``). :func:`lerp` forms the
weights in the samples' precision and keeps a blend that still rounds past the maximum at
the neighbour it cannot exceed.
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike


def lerp(a: Array, b: Array, f: ArrayLike) -> Array:
    """``a (1 - f) + b f`` for weights ``0 ≤ f ≤ 1``, elementwise (broadcasting).

    - ``f`` is promoted with ``a`` and ``b`` before ``1 - f`` (float32 weights of a float64
      blend: ``1 - f`` is then exact and the two weights sum to 1);
    - exactly ``a`` at ``f = 0`` and ``b`` at ``f = 1``: a NaN/Inf neighbour with zero
      weight does not reach the result (``0 · NaN`` would);
    - where the rounded blend is ±Inf it is replaced by ``max(a, b)`` (``min(a, b)`` for
      −Inf): a blend of finite neighbours can only have rounded past the float maximum
      (its true value is at most ``max(a, b)``), and an infinite neighbour still gives
      ±Inf; NaN (a NaN neighbour, or +Inf blended with −Inf) stays NaN.

    Finite blends are the formula's values, and their derivatives its derivatives. One
    fused elementwise step.
    """
    f = jnp.asarray(f, jnp.result_type(a, b, f))
    r = a * (1 - f) + b * f
    r = jnp.where(jnp.isinf(r), jnp.where(r > 0, jnp.maximum(a, b), jnp.minimum(a, b)), r)
    return jnp.where(f == 0, a, jnp.where(f == 1, b, r))


def take(table: Array, k: Array) -> Array:
    """``table[k]`` for integer indices ``k`` in range by construction: a gather without
    the out-of-range masking of JAX's default indexing (which costs about twice the rest of
    a tone curve on the CPU); an index out of range would be clamped by XLA's gather."""
    return table.at[k].get(mode="promise_in_bounds")


def table_lerp(table: Array, u: Array) -> Array:
    """Values of a uniform table at fractional positions ``u``: linear between nodes,
    ``table[i] + f (table[i + 1] − table[i])`` with ``i = ⌊u⌋``, ``f = u − i``; ``u`` is
    clipped to ``[0, n − 1]`` (``n = len(table) ≥ 2``), so the ends extend flat.

    The indices are in range by construction, and NaN positions convert to index 0 (XLA's
    float-to-integer conversion saturates, and its gather clamps), so the lookups use
    :func:`take`. The result at a NaN position is NaN (``f`` is).
    Gradients: with respect to ``table``, the interpolation weights; with respect to ``u``,
    the segment's slope (0 outside ``[0, n − 1]``).
    """
    n = table.shape[0]
    u = jnp.clip(u, 0.0, float(n - 1))
    i = jnp.minimum(jnp.floor(u), float(n - 2))
    f = u - i
    k = i.astype(jnp.int32)
    a, b = take(table, k), take(table, k + 1)
    return a + f * (b - a)


__all__ = ["lerp", "table_lerp", "take"]
