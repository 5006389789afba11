"""Mantiuk, Myszkowski & Seidel 2006 contrast mapping and contrast equalisation, as
``pfstmo_mantiuk06`` computes them.

Reference:
    Mantiuk, Myszkowski, Seidel. "A perceptual framework for contrast processing of high
    dynamic range images." ACM Transactions on Applied Perception 3(3):286–308, 2006.
    https://doi.org/10.1145/1166087.1166095

The steps, with ``Y`` the luminance (Rec.709 weights; below ``10^-7 Y_max`` it and each
channel take ``10^-7 Y_max``) and ``x = log10 Y``:

1. Contrast pyramid: ``x_0 = x`` and ``x_{k+1} = D x_k`` (each output pixel the area-weighted
   mean of the input pixels it covers: a 2 × 2 mean for even sizes), down to the last
   level with both sides at least 3 pixels; at each level the forward differences
   ``G_k = ∇ x_k`` (log10 contrasts between horizontal and vertical neighbours, 0 past
   the last column and row).
2. Transducer (the paper's contrast-to-response function): each contrast goes to the response
   ``R = sign(G) T(10^(d |G|) − 1)`` and ``d`` the detail factor, with ``T`` the response of
   the Weber fraction ``W = 10^G − 1`` in just-noticeable differences, scaled to 1 at
   ``W_106``: the paper's JND-stepped integral of its contrast-discrimination function
   fitted to Whittle's data, ``W_0 = 0``, ``W_1 = 0.01`` (the detection threshold),
   ``W_{k+1} = W_k + ΔW(W_k)``, ``ΔW(W) = 0.0928 W^1.08 + 0.0046 W^−0.18``, at responses
   ``k / 106`` (:func:`weber_fractions`), cubic Hermite between the steps
   (:func:`weber_fraction`).
3. Contrast mapping ``R' = f R`` (``f = contrast_factor``) or contrast equalisation
   ``R' = f cdf(|R|) R / |R|`` (``|R|`` the length of the pixel's two responses,
   ``cdf`` its rank among those of every level, over their count); back to contrasts
   ``G'_k = sign(R') log10(1 + T⁻¹(|R'|)) / d``.
4. The luminance whose pyramid contrasts are closest to ``G'`` (the paper's
   reconstruction): minimise
   ``Σ_k Σ w_k (∇ D^k y − G'_k)²`` with weights ``w = 1 / ΔG(max(|G'|, 0.001))``, the
   discrimination threshold ``ΔG(G) = 0.038737 G^0.537756``. The normal equations
   ``A y = b``, ``A = Σ_k P_k ∇ᵀ W_k ∇ D^k``, ``b = Σ_k P_k ∇ᵀ W_k G'_k``, with the
   prolongation ``P_k`` the transpose of ``D^k`` times the area ratio (pixel
   replication for even sizes), are symmetric positive semi-definite (constants are their
   null space, which step 5 removes), solved by conjugate gradients from ``y = x``.
5. Output: ``Y' = 10^(2.3 (y − y_lo) / (y_hi − y_lo) − 2.3)`` with ``y_lo``, ``y_hi`` the
   0.1st and 99.9th percentiles of ``y`` (2.3 log10 units of display range), and each
   channel ``C' = (C / Y)^s Y'`` (``s = saturation``).

Deviations from ``pfstmo_mantiuk06`` (pfstools 2.2.0), each argued:

- Solver: pfstmo runs plain conjugate gradients to a relative residual of ``10^-3`` or
  200 iterations, restarting from its best iterate when the residual grows four times in a
  row; on some real images it stops at the cap, with residuals of 0.07–0.3 at 64 × 128
  (it warns "Not converged"). Here conjugate gradients are preconditioned by the
  diagonal of ``A`` (the weights ``w`` span three orders of magnitude) and run to ``tol``
  or ``max_iterations``: the paper's solution, not pfstmo's stopping point (the tests
  measure both). The default ``tol = 10^-4`` comes from the accuracy/time curve
  (``benchmarks/bench_accuracy.py``, ``mantiuk2006 tol``; against the float64 solution
  converged to ``10^-10`` at 512 × 1024, two images), each threefold tighter ``tol`` cuts
  the largest display error about threefold for a few more iterations: pfstmo's ``10^-3``
  leaves 0.071 (cornell_box; 0.020 on venice_sunset), ``10^-4`` 0.0066 (0.0029) for about a
  fifth more iterations (46 against 39 on venice_sunset), ``3·10^-5`` 0.0024 for another
  sixth. ``10^-4`` is the loosest setting whose largest error is below 0.01 on both.
  (A diagonal preconditioner over the pyramid's levels, each level's Galerkin diagonal,
  saved a tenth of the iterations for the cost of a pyramid a step: the levels of ``A``
  already make its coarse modes stiff; what is left is the weights' variation.)
- Prolongation: pfstmo's upsampling is bilinear-like and not the transpose of its
  downsampling for odd sizes (its matrix ``A`` is then not symmetric); here ``P_k`` is the
  transpose times the area ratio at every size, which equals pfstmo's for even sizes
  (every level of a 2^n-multiple image) and keeps ``A`` symmetric for the solver and its
  adjoint.
- Percentiles: linear interpolation between the order statistics (pfstmo weights the two
  the wrong way round, a difference below one order statistic).
- ``detail_factor`` (``d``, default 1: pfstmo's transducer) is not an option of pfstmo
  (Luminance HDR's version of the operator has one of that name); here it scales the
  contrasts before the transducer and back after it: ``d > 1`` moves contrasts into the
  transducer's compressive part, compressing large contrasts more against small ones.
- Transducer between the JND steps: pfstmo interpolates its table linearly, whose slope
  jumps by about a tenth at every step (a derivative that is piecewise constant, with
  central differences off by ``O(h)``); here ``W(R)`` is the cubic Hermite interpolant
  of the steps with centred-difference slopes (continuous derivatives; within 0.0018
  log10 units of the linear one), and the forward transducer its inverse sampled every
  :data:`STEP` log10 units and interpolated linearly (one gather, no search).
- Non-finite pixels (pfstmo has no rule): they count as copies of the first finite pixel
  (raster order) in the solve and the percentiles, so the finite pixels map as in that
  image, and are put back in the output (NaN stays NaN, +Inf white, −Inf black).
- An image without light (every luminance 0 or below) maps to black (pfstmo's floor would
  make it grey).
- The output's exponent is capped at :data:`MAX_LOG10_OUT` (a finite image gives a finite
  output), and a flat ``y`` (``y_hi = y_lo``) maps to ``10^-2.3``.

Differentiation: the solve is a ``lax.custom_linear_solve`` with a symmetric matrix, so
``jax.grad`` solves the adjoint system with the same solver (exact gradients of the
solution the solver converges to, not of its iterations). Contrast equalisation's ranks
are constants for ``jax.grad``. Batches: under ``vmap`` every frame stops at its own
tolerance (the loop runs until the last frame is done; a finished frame keeps its state),
so a batch equals a loop over its frames. Tiles: the solve couples every pixel with every
other, so the operator needs the whole image (:meth:`Mantiuk2006.halo` is infinite). A
level of odd size is resampled by dense area-weight matrices (a product per axis),
slower than the 2 × 2 means of even sizes.
"""

import math
from typing import ClassVar, Literal

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._interp import table_lerp, take
from .._scale import quotient
from .._stats import percentile_by_selection
from ._base import (
    AbstractOperator,
    Prepared,
    filled_with_first_valid,
    parameter,
    register,
    weights_field,
)
from ._cg import conjugate_gradients

REFERENCE = (
    "Mantiuk, Myszkowski, Seidel 2006, A perceptual framework for contrast processing of high"
    " dynamic range images, ACM Transactions on Applied Perception 3(3):286-308,"
    " https://doi.org/10.1145/1166087.1166095"
)
DETECTION_THRESHOLD = 0.01
"""The transducer's first step: a Weber fraction of 1 % is one just-noticeable difference."""
DISCRIMINATION = (0.0928, 1.08, 0.0046, -0.18)
"""``(a, b, c, d)`` of the paper's contrast-discrimination function ``ΔW(W) = a W^b + c W^d``
(Weber fractions, fitted to Whittle's data)."""
STEPS = 106
"""Just-noticeable differences from contrast 0 to the transducer's response 1."""


def discrimination(W: np.ndarray) -> np.ndarray:
    """``ΔW(W) = 0.0928 W^1.08 + 0.0046 W^−0.18``: the smallest noticeable increment of the
    Weber fraction ``W`` (the paper's fit to Whittle's data)."""
    a, b, c, d = DISCRIMINATION
    return a * W**b + c * W**d


def weber_fractions() -> np.ndarray:
    """The transducer as the paper builds it, one just-noticeable difference a step:
    ``W_0 = 0``, ``W_1 = 0.01`` (the detection threshold) and
    ``W_{k+1} = W_k + ΔW(W_k)`` (:func:`discrimination`), ``k = 1 … 105``; ``W_k`` is the
    Weber fraction ``10^G − 1`` whose response is ``k / 106``. Float64 NumPy, computed once
    at import; it reproduces the tabulated transducer of the reference implementation
    (pfstmo's) to its printed precision (six decimals; relative differences up to
    1.2·10⁻⁵)."""
    W = np.zeros(STEPS + 1)
    W[1] = DETECTION_THRESHOLD
    for k in range(1, STEPS):
        W[k + 1] = W[k] + discrimination(W[k])
    return W


W_TABLE = weber_fractions()
"""The transducer's Weber fractions ``W = 10^G − 1`` at responses ``k / 106``, ``k = 0 …
106`` (:func:`weber_fractions`)."""
THRESHOLD_A, THRESHOLD_B = 0.038737, 0.537756
"""The paper's discrimination threshold ``ΔG(G) = a G^b`` (log10 contrast units)."""
G_FLOOR = 0.001
"""Contrasts below this weigh as it (``1 / ΔG`` would grow without bound)."""
CLIP = 1e-7
"""Luminance and channels below ``CLIP Y_max`` take that value (pfstmo's)."""
CUT = 0.001
"""The output's range: the ``CUT`` and ``1 − CUT`` quantiles of the solution (pfstmo's)."""
DISPLAY_RANGE = 2.3
"""log10 units from the ``CUT`` to the ``1 − CUT`` quantile of the output (pfstmo's)."""
MIN_SIZE = 3
"""The pyramid's last level has both sides at least this many pixels (pfstmo's)."""
MAX_LOG10_OUT = 10.0
"""The output luminance's log10 is capped here (10^10: white many times over)."""
MIN_SPAN = 1e-6
"""Smallest ``y_hi − y_lo`` the normalisation divides by (a flat solution)."""


def pyramid_shapes(shape: tuple[int, int]) -> tuple[tuple[int, int], ...]:
    """The levels' ``(H, W)``: halved (rounding down) while both sides are at least
    :data:`MIN_SIZE`; at least the image's own level."""
    h, w = int(shape[0]), int(shape[1])
    out = [(h, w)]
    h, w = h // 2, w // 2
    while h >= MIN_SIZE and w >= MIN_SIZE:
        out.append((h, w))
        h, w = h // 2, w // 2
    return tuple(out)


def _area_matrix(n_in: int, n_out: int) -> np.ndarray:
    """``(n_out, n_in)``: the area-weighted mean of the input pixels each output covers."""
    dx = n_in / n_out
    lo = np.arange(n_out)[:, None] * dx
    j = np.arange(n_in)[None, :]
    overlap = np.clip(np.minimum(j + 1, lo + dx) - np.maximum(j, lo), 0.0, None)
    return overlap / dx


def _down_axis(x: Array, axis: int, n_out: int) -> Array:
    n = x.shape[axis]
    if n == 2 * n_out:
        shape = x.shape[:axis] + (n_out, 2) + x.shape[axis + 1 :]
        return jnp.mean(x.reshape(shape), axis=axis + 1)
    m = jnp.asarray(_area_matrix(n, n_out), x.dtype)
    hi = jax.lax.Precision.HIGHEST
    return jnp.moveaxis(jnp.tensordot(m, x, axes=([1], [axis]), precision=hi), 0, axis)


def _up_axis(x: Array, axis: int, n_out: int) -> Array:
    """The transpose of :func:`_down_axis` times ``n_out / n_in`` (replication for 2×)."""
    n = x.shape[axis]
    if n_out == 2 * n:
        return jnp.repeat(x, 2, axis=axis)
    m = jnp.asarray(_area_matrix(n_out, n).T * (n_out / n), x.dtype)
    hi = jax.lax.Precision.HIGHEST
    return jnp.moveaxis(jnp.tensordot(m, x, axes=([1], [axis]), precision=hi), 0, axis)


def downsample(x: Array, shape: tuple[int, int]) -> Array:
    """``D``: ``(H, W)`` to the next level's ``shape`` (area-weighted means)."""
    h, w = x.shape
    if (h, w) == (2 * shape[0], 2 * shape[1]):
        # the 2 × 2 blocks' four strided slices added: an elementwise loop that XLA:CPU
        # fuses with its consumers (a reduction over a reshape is a slower loop of its own)
        a, b, c, d = x[0::2, 0::2], x[1::2, 0::2], x[0::2, 1::2], x[1::2, 1::2]
        return 0.25 * ((a + b) + (c + d))
    return _down_axis(_down_axis(x, 0, shape[0]), 1, shape[1])


def prolong(x: Array, shape: tuple[int, int], *, fused: bool = False) -> Array:
    """``P``: a level to the finer ``shape``, the transpose of :func:`downsample` times the
    area ratio (each pixel repeated over its 2 × 2 block for even sizes).

    The 2 × 2 repetition is a windowed sum of the dilated level unless ``fused``: XLA:CPU
    computes a windowed sum into a buffer of its own, whereas it fuses a broadcast into its
    consumer, and a chain of broadcasts (:func:`collapse`) into one loop over the finest
    pixels that recomputes every coarser level's term at each of them (3× slower at 2048 ×
    1024; the finest level's, ``fused``, is computed once either way)."""
    h, w = x.shape
    if shape == (2 * h, 2 * w):
        if fused:
            return jnp.broadcast_to(x[:, None, :, None], (h, 2, w, 2)).reshape(shape)
        pad = ((1, 1), (1, 1))
        return jax.lax.reduce_window(x, 0.0, jax.lax.add, (2, 2), (1, 1), pad, base_dilation=(2, 2))
    return _up_axis(_up_axis(x, 0, shape[0]), 1, shape[1])


def gradients(x: Array) -> tuple[Array, Array]:
    """Forward differences ``(∂x, ∂y)`` along columns and rows, 0 past the last one."""
    gx = jnp.pad(x[:, 1:] - x[:, :-1], ((0, 0), (0, 1)))
    gy = jnp.pad(x[1:, :] - x[:-1, :], ((0, 1), (0, 0)))
    return gx, gy


def gradients_transpose(gx: Array, gy: Array) -> Array:
    """``∇ᵀ``: the adjoint of :func:`gradients` (minus the divergence; the last column of
    ``gx`` and row of ``gy`` are not read)."""
    dx, dy = gx[:, :-1], gy[:-1, :]
    return (
        jnp.pad(dx, ((0, 0), (1, 0)))
        - jnp.pad(dx, ((0, 0), (0, 1)))
        + jnp.pad(dy, ((1, 0), (0, 0)))
        - jnp.pad(dy, ((0, 1), (0, 0)))
    )


def pyramid(x: Array, shapes: tuple[tuple[int, int], ...]) -> list[Array]:
    """``[x, D x, D² x, …]`` at ``shapes``."""
    out = [x]
    for s in shapes[1:]:
        out.append(downsample(out[-1], s))
    return out


def collapse(levels: list[Array]) -> Array:
    """``Σ_k P_k levels[k]``: each level prolonged to the finest (coarsest first)."""
    acc = levels[-1]
    for k in range(len(levels) - 2, -1, -1):
        acc = prolong(acc, levels[k].shape, fused=k == 0) + levels[k]
    return acc


W_ODD = np.concatenate([-W_TABLE[:0:-1], W_TABLE])
"""``W`` at responses ``k / 106``, ``k = −106 … 106`` (odd)."""
W_SLOPE = np.gradient(W_ODD)
"""``dW/dk`` at the nodes of :data:`W_ODD` (centred differences; one-sided at the ends)."""


def _hermite(values: Array, slopes: Array, u: Array) -> Array:
    """The cubic Hermite interpolant of a uniform table (nodes ``0 … n − 1``) at ``u``
    (clipped to the nodes' range): continuous with its first derivative."""
    n = values.shape[0]
    u = jnp.clip(u, 0.0, float(n - 1))
    i = jnp.minimum(jnp.floor(u), float(n - 2))
    t = u - i
    k = i.astype(jnp.int32)
    p0, p1, m0, m1 = take(values, k), take(values, k + 1), take(slopes, k), take(slopes, k + 1)
    t2 = t * t
    return (
        p0 + t * m0 + t2 * (3.0 * (p1 - p0) - 2.0 * m0 - m1) + t2 * t * (2.0 * (p0 - p1) + m0 + m1)
    )


def weber_fraction(R: np.ndarray) -> np.ndarray:
    """``W(R)``, the inverse transducer between the JND steps: the cubic Hermite
    interpolant of :data:`W_ODD` at ``106 R`` (float64 NumPy)."""
    n = STEPS
    u = np.clip(np.asarray(R, np.float64) * n + n, 0.0, 2.0 * n)
    i = np.minimum(np.floor(u), 2 * n - 1).astype(int)
    t = u - i
    p0, p1, m0, m1 = W_ODD[i], W_ODD[i + 1], W_SLOPE[i], W_SLOPE[i + 1]
    return p0 + t * m0 + t * t * (3 * (p1 - p0) - 2 * m0 - m1) + t**3 * (2 * (p0 - p1) + m0 + m1)


STEP = 2.0**-10
"""The forward transducer is sampled every ``STEP`` log10 units of contrast (a uniform table
looks up in one gather; linear between samples)."""
SPAN = math.ceil(math.log10(1.0 + W_TABLE[-1]) / STEP)
"""Samples from 0 to the table's largest contrast (``log10(1 + W_max)``)."""


def _response_table() -> np.ndarray:
    """The response at log10 contrasts ``k STEP``, ``k = −SPAN … SPAN`` (odd): the inverse of
    :func:`weber_fraction` (monotone), by bisection to float64 precision."""
    W = np.minimum(np.expm1(np.arange(SPAN + 1) * STEP * math.log(10.0)), W_TABLE[-1])
    lo, hi = np.zeros_like(W), np.ones_like(W)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = weber_fraction(mid) < W
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    r = 0.5 * (lo + hi)
    return np.concatenate([-r[:0:-1], r])


RESPONSE_TABLE = _response_table()


def _signed_log1p(w: Array) -> Array:
    """``sign(w) ln(1 + |w|)``, differentiable at 0."""
    pos = w >= 0
    return jnp.where(pos, jnp.log1p(jnp.where(pos, w, 0.0)), -jnp.log1p(jnp.where(pos, 0.0, -w)))


def response(G: Array, detail_factor: Array) -> Array:
    """The transducer (module docstring, step 2): log10 contrasts to responses in [−1, 1]
    (the table's ends beyond them)."""
    table = jnp.asarray(RESPONSE_TABLE, G.dtype)
    return table_lerp(table, G * (detail_factor / STEP) + SPAN)


def contrast(R: Array, detail_factor: Array) -> Array:
    """The transducer's inverse: responses to log10 contrasts (:func:`weber_fraction`)."""
    n = STEPS
    dt = R.dtype
    W = _hermite(jnp.asarray(W_ODD, dt), jnp.asarray(W_SLOPE, dt), R * n + n)
    return _signed_log1p(W) / (detail_factor * math.log(10.0))


def _length(a: Array, b: Array) -> Array:
    """``sqrt(a² + b²)`` with finite gradients at 0."""
    ss = a * a + b * b
    ok = ss > 0
    return jnp.where(ok, jnp.sqrt(jnp.where(ok, ss, 1.0)), 0.0)


def equalised(Rs: list[tuple[Array, Array]], factor: Array) -> list[tuple[Array, Array]]:
    """Contrast equalisation (step 3): each pixel's two responses scaled to the length
    ``factor · cdf``, ``cdf`` the rank of their length among every level's, over their
    count (ranks are constants for ``jax.grad``)."""
    size = [_length(rx, ry) for rx, ry in Rs]
    flat = jnp.concatenate([s.reshape(-1) for s in size])
    order = jnp.argsort(jax.lax.stop_gradient(flat))
    rank = jnp.zeros(flat.shape, flat.dtype).at[order].set(jnp.arange(flat.size, dtype=flat.dtype))
    cdf = rank / flat.size
    out, start = [], 0
    for (rx, ry), s in zip(Rs, size, strict=True):
        c = cdf[start : start + s.size].reshape(s.shape)
        start += s.size
        ok = s > 0
        scale = jnp.where(ok, factor * c / jnp.where(ok, s, 1.0), 0.0)
        out.append((rx * scale, ry * scale))
    return out


def mapped_contrasts(
    x: Array,
    shapes: tuple[tuple[int, int], ...],
    contrast_factor: Array,
    detail_factor: Array,
    equalize: bool,
) -> list[tuple[Array, Array]]:
    """Steps 1–3: the pyramid's contrasts of ``x`` (log10 luminance), through the
    transducer, mapped or equalised, and back to contrasts."""
    Rs = [
        tuple(response(g, detail_factor) for g in gradients(level)) for level in pyramid(x, shapes)
    ]
    if equalize:
        Rs = equalised(Rs, contrast_factor)
    else:
        Rs = [(rx * contrast_factor, ry * contrast_factor) for rx, ry in Rs]
    return [(contrast(rx, detail_factor), contrast(ry, detail_factor)) for rx, ry in Rs]


def weights_of(G: tuple[Array, Array]) -> tuple[Array, Array]:
    """``w = 1 / ΔG(max(|G|, 0.001))`` for one level's two contrasts, 0 on the last column
    (``x``) and row (``y``), which have no neighbour."""

    def w(g):
        return 1.0 / (THRESHOLD_A * jnp.maximum(jnp.abs(g), G_FLOOR) ** THRESHOLD_B)

    wx = w(G[0]).at[:, -1].set(0.0)
    wy = w(G[1]).at[-1, :].set(0.0)
    return wx, wy


def system_matvec(
    y: Array, ws: list[tuple[Array, Array]], shapes: tuple[tuple[int, int], ...]
) -> Array:
    """``A y = Σ_k P_k ∇ᵀ W_k ∇ D^k y`` (step 4)."""
    terms = []
    for level, (wx, wy) in zip(pyramid(y, shapes), ws, strict=True):
        gx, gy = gradients(level)
        terms.append(gradients_transpose(wx * gx, wy * gy))
    return collapse(terms)


def system_rhs(G: list[tuple[Array, Array]], ws: list[tuple[Array, Array]]) -> Array:
    """``b = Σ_k P_k ∇ᵀ W_k G'_k`` (step 4)."""
    return collapse(
        [gradients_transpose(wx * gx, wy * gy) for (gx, gy), (wx, wy) in zip(G, ws, strict=True)]
    )


def system_diagonal(ws: list[tuple[Array, Array]]) -> Array:
    """The diagonal of ``A`` (exact for even sizes: level ``k`` adds its own diagonal over
    ``4^k``), the conjugate gradients' preconditioner."""
    terms = []
    for wx, wy in ws:
        d = wx + jnp.pad(wx[:, :-1], ((0, 0), (1, 0))) + wy + jnp.pad(wy[:-1, :], ((1, 0), (0, 0)))
        terms.append(d)
    acc = terms[-1]
    for fine in reversed(terms[:-1]):
        area = (fine.shape[0] / acc.shape[0]) * (fine.shape[1] / acc.shape[1])
        acc = prolong(acc, fine.shape) / area + fine
    return acc


def solve(
    x: Array,
    G: list[tuple[Array, Array]],
    shapes: tuple[tuple[int, int], ...],
    *,
    max_iterations: int,
    tol: float,
) -> Array:
    """Step 4: the luminance ``y`` whose pyramid contrasts best fit ``G`` (weighted least
    squares), by conjugate gradients from ``y = x``; differentiable through
    ``lax.custom_linear_solve``."""
    ws = [weights_of(g) for g in G]
    diag = jax.lax.stop_gradient(system_diagonal(ws))
    inv_diag = jnp.where(diag > 0, 1.0 / jnp.where(diag > 0, diag, 1.0), 0.0)

    def matvec(v):
        return system_matvec(v, ws, shapes)

    def cg(mv, rhs):
        # constants are A's null space: b's mean removed
        rhs = rhs - jnp.mean(rhs)
        return conjugate_gradients(mv, rhs, inv_diag, max_iterations=max_iterations, tol=tol)[0]

    x0 = jax.lax.stop_gradient(x)
    rhs = system_rhs(G, ws) - matvec(x0)
    return x0 + jax.lax.custom_linear_solve(matvec, rhs, cg, symmetric=True)


def quantiles(y: Array) -> tuple[Array, Array]:
    """The :data:`CUT` and ``1 − CUT`` quantiles of ``y``, linear between order statistics
    (by partial selection of the extreme values, no full sort)."""
    # the selection reads positive values: a shift that cancels, with no gradient
    shift = jax.lax.stop_gradient(1.0 - jnp.min(y))
    q = (100.0 * CUT, 100.0 * (1.0 - CUT))
    lo, hi = percentile_by_selection(y + shift, jnp.asarray(q, y.dtype), select=q) - shift
    return lo, hi


@register("mantiuk2006")
class Mantiuk2006(AbstractOperator):
    """Mantiuk, Myszkowski & Seidel 2006 contrast mapping (module docstring), with
    ``pfstmo_mantiuk06``'s defaults: contrast mapping with factor 0.1, saturation 0.8.

    Input: linear RGB, relative or absolute (the operator is scale invariant). Output:
    display-referred *linear* RGB (pfstmo tags its output ``LUMINANCE=RELATIVE``): the
    luminance's 0.1st to 99.9th percentiles span ``10^-2.3 … 1``, the brightest 0.1 %
    above 1 (clipped by the display).

    Attributes:
        contrast_factor: pfstmo's ``--factor`` (0.1; the responses' scale, smaller is
            more compression) or, in ``"equalisation"`` mode, its ``--equalize-contrast`` value
            (the equalised responses' largest length).
        saturation: pfstmo's ``--saturation`` (0.8): exponent of the colour ratios.
        detail_factor: scales contrasts before the transducer and back after it (1:
            pfstmo's; module docstring).
        mode: ``"mapping"`` (contrast mapping, pfstmo's default) or ``"equalisation"``
            (contrast equalisation, pfstmo's ``--equalize-contrast``).
        max_iterations: most conjugate-gradient iterations.
        tol: the solve stops at a residual of ``tol`` times the right-hand side's.
        weights: the luminance's weights (Rec.709's, as pfstmo's XYZ ``Y``).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("contrast_factor", "saturation")

    contrast_factor: Array = parameter(
        0.1,
        help="pfstmo's --factor: scale of the contrasts' responses (smaller compresses more);"
        " in equalisation mode, pfstmo's --equalize-contrast value",
        range="(0, inf)",
    )
    saturation: Array = parameter(
        0.8, help="pfstmo's --saturation: exponent of the colour ratios C/Y", range="[0, 2]"
    )
    detail_factor: Array = parameter(
        1.0,
        help="contrasts scaled by this before the transducer and back after it (1: pfstmo's)",
        range="(0, inf)",
    )
    mode: Literal["mapping", "equalisation"] = parameter(
        "mapping",
        help="mapping: contrast mapping (pfstmo's default); equalisation: contrast"
        " equalisation (pfstmo's --equalize-contrast)",
        static=True,
        choices=("mapping", "equalisation"),
    )
    max_iterations: int = parameter(
        200, help="most conjugate-gradient iterations", range="[1, inf)", static=True
    )
    tol: float = parameter(
        1e-4,
        help="the solve stops at this residual relative to the right-hand side's",
        range="[0, 1)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        super().__check_init__()
        if int(self.max_iterations) != self.max_iterations or self.max_iterations < 1:
            raise ValueError(
                f"max_iterations: expected an integer >= 1, got {self.max_iterations!r}"
            )
        if not 0 <= self.tol < 1:
            raise ValueError(f"tol: expected a value in [0, 1), got {self.tol!r}")

    def halo(self, shape: tuple[int, ...]) -> tuple[float, float]:
        """The whole image (infinite): the solve couples every pixel with every other."""
        del shape
        return (float("inf"), float("inf"))

    def log_luminance(self, p: Prepared) -> tuple[Array, Array]:
        """``x = log10 Y`` (at non-finite pixels the first finite pixel's, raster order)
        and the floor ``CLIP Y_max``."""
        dt = p.rgb.dtype
        tiny = jnp.asarray(np.finfo(dt).tiny, dt) * 16
        floor = jnp.maximum(jnp.max(p.L) * CLIP, tiny)
        x = jnp.log10(jnp.maximum(p.L, floor))
        if not p.clean:
            x = filled_with_first_valid(x, p.valid())
        return x, floor

    def solution(self, p: Prepared) -> Array:
        """Steps 1–4: the solved log10 luminance ``y``."""
        x, _ = self.log_luminance(p)
        dt = x.dtype
        shapes = pyramid_shapes(x.shape)
        G = mapped_contrasts(
            x,
            shapes,
            self.contrast_factor.astype(dt),
            self.detail_factor.astype(dt),
            self.mode == "equalisation",
        )
        return solve(x, G, shapes, max_iterations=self.max_iterations, tol=self.tol)

    def _apply(self, p: Prepared) -> Array:
        dt = p.rgb.dtype
        _, floor = self.log_luminance(p)
        y = self.solution(p)
        lo, hi = quantiles(y)
        span = hi - lo
        span = jnp.where(span > MIN_SPAN, span, 1.0)
        t = jnp.minimum((y - lo) / span * DISPLAY_RANGE - DISPLAY_RANGE, MAX_LOG10_OUT)
        Yd = jnp.power(jnp.asarray(10.0, dt), t)
        Y = jnp.maximum(p.L, floor)
        ratio = quotient(jnp.maximum(p.rgb, floor), Y[..., None])
        s = self.saturation.astype(dt)
        out = jnp.exp(s * jnp.log(ratio)) * Yd[..., None]
        # no light in (every luminance 0 or below), no light out
        return jnp.where(jnp.max(p.L) > 0, out, 0.0)


__all__ = [
    "Mantiuk2006",
    "discrimination",
    "weber_fraction",
    "weber_fractions",
    "mapped_contrasts",
    "pyramid_shapes",
    "response",
    "contrast",
    "solve",
]
