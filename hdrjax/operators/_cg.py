"""Jacobi-preconditioned conjugate gradients on image-shaped arrays, the solver of the
operators whose step is a sparse symmetric positive (semi-)definite system applied
matrix-free (``lischinski2006``, ``mantiuk2006``).

Reference: Hestenes, Stiefel. "Methods of conjugate gradients for solving linear systems."
Journal of Research of the National Bureau of Standards 49(6):409–436, 1952
(https://doi.org/10.6028/jres.049.044); the preconditioned form as in Saad, *Iterative
Methods for Sparse Linear Systems*, 2nd ed., SIAM 2003, Algorithm 9.1.

The operators wrap it in ``lax.custom_linear_solve`` (gradients by one more solve of the
same symmetric system, not through the iterations). lineax's ``CG`` does the same
iteration; this one adds what an image system needs: the right-hand side is scaled by a
power of two to a largest magnitude near 1 (exact), so that a cotangent of tiny values
(the gradient of a dim image's output) does not make ``r · M r`` subnormal and flushed to 0,
and it reports the iterations run and the final residual (the accuracy-versus-time
curves of ``benchmarks/bench_accuracy.py``).
"""

from collections.abc import Callable

import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._scale import inverse_pow2


def conjugate_gradients(
    matvec: Callable[[Array], Array],
    b: Array,
    inv_diag: Array,
    *,
    tol: float,
    max_iterations: int,
) -> tuple[Array, Array, Array]:
    """``x`` with ``matvec(x) = b`` from ``x = 0``, preconditioned with ``inv_diag`` (the
    inverse of the system's diagonal), until ``‖r‖ ≤ tol ‖b‖`` (``tol`` at least 100
    rounding errors: below that the recurrence loses orthogonality and diverges) or
    ``max_iterations``. Returns ``x``, the iterations run and ``‖r‖ / ‖b‖``.

    For a semidefinite system (``mantiuk2006``'s, whose null space is the constants) the
    caller removes that component from ``b`` first. Under ``vmap`` the loop runs until every
    frame is done and keeps the state of a frame done earlier (a select on its predicate),
    so each frame gets the result it gets alone."""
    c = inverse_pow2(jnp.max(jnp.abs(b)))
    b = b * c
    bb = jnp.vdot(b, b)
    floor = 100 * float(jnp.finfo(b.dtype).eps)
    stop = max(tol, floor) ** 2 * bb
    tiny = jnp.finfo(b.dtype).tiny

    def ratio(num: Array, den: Array) -> Array:
        return jnp.where(den > tiny, num / jnp.where(den > tiny, den, 1.0), 0.0)

    def cond(s):
        *_, rr, i = s
        return (i < max_iterations) & (rr > stop)

    def step(s):
        x, r, p, rz, _, i = s
        q = matvec(p)
        alpha = ratio(rz, jnp.vdot(p, q))
        x = x + alpha * p
        r = r - alpha * q
        z = r * inv_diag
        rz_new = jnp.vdot(r, z)
        return x, r, z + ratio(rz_new, rz) * p, rz_new, jnp.vdot(r, r), i + 1

    z = b * inv_diag
    init = (jnp.zeros_like(b), b, z, jnp.vdot(b, z), bb, jnp.asarray(0))
    x, _, _, _, rr, i = jax.lax.while_loop(cond, step, init)
    return x / c, i, jnp.sqrt(ratio(rr, bb))


__all__ = ["conjugate_gradients"]
