"""Camera response recovery from an exposure bracket, and response files.

Numeric contract: a bracket of integer code values ``(N, H, W, 3)`` (uint8 or uint16) with
exposure times in seconds goes in; the inverse camera response comes out as a ``(levels, 3)``
table ``g(z) = ln X``: the natural-log sensor exposure of each code value ``z`` (Debevec &
Malik's ``g``), per channel, normalised so that ``g`` at the top code is 0 (``X = 1`` is the
exposure that just saturates). Merged radiance is then ``ln E = g(z) − ln t``.

Three methods (``method=``):

- ``"debevec"`` — Debevec, P. E., & Malik, J. (1997). Recovering high dynamic range
  radiance maps from photographs. *SIGGRAPH 97*, 369–378. DOI 10.1145/258734.258884.
  Minimises ``Σ_i Σ_j [w(Z_ij)(g(Z_ij) − ln E_i − ln t_j)]² + λ Σ_z [w(z) g''(z)]²`` over
  ``g`` and the sample log-irradiances ``ln E_i``, with the triangle weights
  ``w(z) = 1 − |2z/(levels−1) − 1|`` and ``g''(z) = g(z−1) − 2g(z) + g(z+1)``; one gauge
  equation fixes the free offset. The paper solves the stacked system by SVD; here its normal
  equations are reduced to ``g`` alone (the ``ln E_i`` block is diagonal, so its Schur
  complement is exact and the system is ``nodes × nodes`` whatever the number of samples) and
  solved by Cholesky (lineax). Weights are scaled to [0, 1]: the same minimiser as the paper's
  code-unit weights for the same ``λ``, since both terms scale alike.
- ``"robertson"`` — Robertson, M. A., Borman, S., & Stevenson, R. L. (2003). Estimation-
  theoretic approach to dynamic range enhancement using multiple exposures. *Journal of
  Electronic Imaging*, 12(2), 219–228. DOI 10.1117/1.1557695. Alternates
  ``E_i = Σ_j w_ij t_j I(y_ij) / Σ_j w_ij t_j²`` and ``I(m) = mean_{(i,j): y_ij = m} t_j E_i``
  (``I = exp g``), normalised each round so that ``I`` at the middle code is 1, with the
  Gaussian-like weights ``w(y) = exp(−4 (y − c)² / c²)``, ``c = (levels − 1)/2``, from the
  paper's linear start, up to ``max_iter`` rounds or a relative change below ``tol``. Pixels
  seen in only one exposure are left out: any ``I`` explains them (their ``E`` is
  ``I(y)/t``), so they do not move the fixed point, only slow the alternation down. The
  alternation creeps: after 50 rounds it is still several per cent from its fixed point on
  noise-free brackets, as OpenCV's CalibrateRobertson (30 rounds) is.
- ``"mitsunaga1999"`` — Mitsunaga, T., & Nayar, S. K. (1999). Radiometric self calibration.
  *CVPR 1999*, 374–380. DOI 10.1109/CVPR.1999.786966. A polynomial inverse response
  ``X = f(M) = Σ_{n=0}^{K} c_n M^n`` of normalised code ``M`` with ``f(1) = 1``, fitted by
  linear least squares to ``f(M_q) = R_q f(M_{q+1})`` over pairs of consecutive exposures,
  alternating with the ratio refinement ``R_q = mean_p f(M_{p,q}) / f(M_{p,q+1})``, for each
  order ``K`` up to ``max_order``; the order with the smallest residual is kept (the paper's
  rule) among those whose curve rises over every code (a response does; on JPEG members the
  highest order followed the compression noise into a falling curve: 250 % largest error
  against 20 % with the rule on a 512 × 256 bracket; on smaller JPEG brackets the method stays
  unreliable, 160 % on 144 × 96, where ``"debevec"`` gives 8 %). The polynomial is written
  in the shifted Legendre basis ``P_n(2M − 1)`` — the same
  polynomials, but a float32 least squares of order 10 in monomials loses the darkest codes
  (measured: 27 % against 3 % error on a gamma-2.5 channel). The ratio refinement lets the
  curve drift along the exponential ambiguity ``f → f^γ`` that the paper discusses, so it is
  off by default (``refine_ratios``): exposure times given by the user or EXIF are trusted.

Codes 0 and the top code are censored (black or saturated: they bound the exposure, they do not
measure it): every method gives them weight 0, like Debevec & Malik's triangle. The value of
``g`` at codes no weighted sample reached: ``"debevec"`` — the smoothness term fills them
(linear extrapolation beyond the observed range, as the paper's solution); ``"robertson"`` —
linear interpolation of ``g`` between the nearest reached codes, and beyond the reached range
a straight line with the slope of its two outermost reached codes; ``"mitsunaga1999"`` — the
polynomial. All three then take a running maximum so that ``g`` never decreases, and ``g`` is
finite everywhere (also at code 0, whose true exposure is 0).

16-bit brackets: ``g`` is solved at ``nodes`` evenly spaced code values (1024 by default for
65536 levels; every code for 8-bit) with observations linearly interpolated between their two
nearest nodes, then interpolated back to all codes — no ``levels × levels`` system is formed.

Sample pixels. Debevec & Malik choose pixels "with a reasonably even distribution of pixel
values from Zmin to Zmax", "spatially well distributed", from "regions of the image with low
intensity variance", and need ``P (N − 1) > Zmax − Zmin``. Implemented: candidates are a
regular grid of about ``32 · samples`` pixels (spatially spread); per channel the middle
exposure's code range over the candidates is cut into ``samples`` equal bins, and in each bin
the candidate with the lowest 3 × 3 local variance of the middle exposure's codes is taken
(bins without a candidate leave their share to the lowest-variance candidates not yet
taken). The default ``samples`` is ``max(50, 2 · ceil((levels_used − 1) / (N − 1)))``, twice
the paper's minimum, with ``levels_used`` the node count. Robertson et al. use all pixels;
here a regular grid of at most ``samples`` pixels (default 2¹⁶) keeps large brackets fast.
Mitsunaga & Nayar sample pixels likewise (default 2¹⁴ on a regular grid).

JAX for the solves (jit, float32 by default, float64 under x64); ``"debevec"`` is
differentiable with respect to ``smoothness``. Sample selection is NumPy.
"""

import json
import math
import os
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..io import atomic_path
from ._bracket import as_codes, check_response

METHODS = ("debevec", "robertson", "mitsunaga1999")
"""Response recovery methods by paper name."""

_NODES_16BIT = 1024
_CANDIDATES_PER_SAMPLE = 32
_VARIANCE_RADIUS = 1


# ----------------------------------------------------------------------------- weights


def _triangle(u: jax.Array) -> jax.Array:
    """Debevec & Malik's hat on normalised codes ``u`` in [0, 1], scaled to peak 1."""
    return 1.0 - jnp.abs(2.0 * u - 1.0)


def _gaussian(u: jax.Array) -> jax.Array:
    """Robertson et al.'s weights ``exp(−4 (y − c)²/c²)`` on normalised codes ``u``."""
    return jnp.exp(-4.0 * jnp.square(2.0 * u - 1.0))


def _censor(z: jax.Array, w: jax.Array, levels: int) -> jax.Array:
    """Weight 0 for the black (0) and saturated (top) codes."""
    return jnp.where((z > 0) & (z < levels - 1), w, 0.0)


def _weights(z: jax.Array, levels: int, table: jax.Array | None, default: Callable) -> jax.Array:
    w = default(z / (levels - 1)) if table is None else table[z]
    return _censor(z, w, levels)


# ------------------------------------------------------------------------------- nodes


def _node_count(levels: int, nodes: int | None) -> int:
    if nodes is None:
        return levels if levels <= 256 else _NODES_16BIT
    if not isinstance(nodes, int | np.integer) or not 8 <= nodes <= levels:
        raise ValueError(f"nodes: expected an integer in [8, {levels}], got {nodes!r}")
    return int(nodes)


def _locate(z: jax.Array, levels: int, n: int) -> tuple[jax.Array, jax.Array]:
    """Node index ``b`` and fraction ``a``: code ``z`` sits at ``(1 − a)·node_b + a·node_{b+1}``."""
    u = z.astype(jnp.result_type(float)) * ((n - 1) / (levels - 1))
    b = jnp.clip(jnp.floor(u).astype(jnp.int32), 0, n - 2)
    return b, u - b


def _expand(g_nodes: jax.Array, levels: int) -> jax.Array:
    """Node values to every code value (linear interpolation)."""
    n = g_nodes.shape[0]
    if n == levels:
        return g_nodes
    b, a = _locate(jnp.arange(levels), levels, n)
    return g_nodes[b] * (1.0 - a) + g_nodes[b + 1] * a


def _finish(g_nodes: jax.Array, levels: int) -> jax.Array:
    """Non-decreasing, all codes, top code 0."""
    g = _expand(jax.lax.cummax(g_nodes), levels)
    return g - g[-1]


def _fill_unobserved(g: jax.Array, observed: jax.Array) -> jax.Array:
    """Linear interpolation of ``g`` between observed nodes; beyond them a straight line with
    the slope between the two outermost observed nodes at that end."""
    n = g.shape[0]
    k = jnp.arange(n)
    lo = jax.lax.cummax(jnp.where(observed, k, -1))
    hi = jnp.flip(jax.lax.cummin(jnp.flip(jnp.where(observed, k, n))))
    lo_c = jnp.clip(lo, 0, n - 1)
    hi_c = jnp.clip(hi, 0, n - 1)
    first = hi_c[0]
    last = lo_c[-1]
    second = hi_c[jnp.minimum(first + 1, n - 1)]
    before_last = lo_c[jnp.maximum(last - 1, 0)]
    slope_lo = jnp.maximum((g[second] - g[first]) / jnp.maximum(second - first, 1), 0.0)
    slope_hi = jnp.maximum((g[last] - g[before_last]) / jnp.maximum(last - before_last, 1), 0.0)
    gap = jnp.maximum(hi_c - lo_c, 1)
    inner = g[lo_c] + (g[hi_c] - g[lo_c]) * (k - lo_c) / gap
    below = g[first] - slope_lo * (first - k)
    above = g[last] + slope_hi * (k - last)
    out = jnp.where(lo < 0, below, jnp.where(hi >= n, above, inner))
    return jnp.where(observed, g, out)


# ----------------------------------------------------------------------------- debevec


@partial(jax.jit, static_argnames=("levels", "n"))
def _debevec_channel(
    z: jax.Array, log_t: jax.Array, smoothness: jax.Array, table: jax.Array | None, levels, n
):
    """Debevec & Malik's least squares for one channel: ``z`` ``(P, N)`` codes."""
    dtype = log_t.dtype
    p = z.shape[0]
    w = _weights(z, levels, table, _triangle).astype(dtype)
    w2 = jnp.square(w)
    b, a = _locate(z, levels, n)
    lt = jnp.broadcast_to(log_t[None, :], z.shape)
    rows = jnp.broadcast_to(jnp.arange(p)[:, None], z.shape)
    # normal equations of the data rows w·((1−a) g_b + a g_{b+1} − ln E_i − ln t_j)
    h = jnp.zeros((n, n), dtype)
    h = h.at[b, b].add(w2 * jnp.square(1.0 - a))
    h = h.at[b + 1, b + 1].add(w2 * jnp.square(a))
    h = h.at[b, b + 1].add(w2 * a * (1.0 - a))
    h = h.at[b + 1, b].add(w2 * a * (1.0 - a))
    v = jnp.zeros((n, p), dtype)
    v = v.at[b, rows].add(-w2 * (1.0 - a)).at[b + 1, rows].add(-w2 * a)
    r = jnp.zeros((n,), dtype).at[b].add(w2 * (1.0 - a) * lt).at[b + 1].add(w2 * a * lt)
    d = jnp.sum(w2, axis=1)
    r_e = -jnp.sum(w2 * lt, axis=1)
    # eliminate ln E (diagonal block): exact Schur complement
    d_safe = jnp.where(d > 0, d, 1.0)
    inv_d = jnp.where(d > 0, 1.0 / d_safe, 0.0)
    s = h - (v * inv_d[None, :]) @ v.T
    rhs = r - v @ (inv_d * r_e)
    # smoothness rows λ w(z_k) (g_{k−1} − 2 g_k + g_{k+1}), k = 1 … n−2
    u = jnp.arange(1, n - 1) / (n - 1)
    node_codes = jnp.rint(u * (levels - 1)).astype(jnp.int32)
    ws = (_triangle(u) if table is None else table[node_codes]).astype(dtype)
    second = jnp.zeros((n - 2, n), dtype)
    k = jnp.arange(n - 2)
    second = second.at[k, k].set(1.0).at[k, k + 1].set(-2.0).at[k, k + 2].set(1.0)
    ds = second * (smoothness * ws)[:, None]
    s = s + ds.T @ ds
    # gauge: g at the middle node = 0 (scaled to the system's size for conditioning)
    mid = (n - 1) // 2
    s = s.at[mid, mid].add(jnp.trace(s) / n)
    op = lx.MatrixLinearOperator(s, lx.positive_semidefinite_tag)
    g = lx.linear_solve(op, rhs, solver=lx.Cholesky()).value
    return _finish(g, levels)


def _debevec_samples(codes: np.ndarray, times: np.ndarray, samples: int, seed: int) -> np.ndarray:
    """Debevec & Malik's sample pixels, per channel: ``(3, P, N)`` codes (module docstring)."""
    n_exp, h, w, _ = codes.shape
    mid = codes[int(np.argsort(times)[(n_exp - 1) // 2])]
    want = _CANDIDATES_PER_SAMPLE * samples
    step = max(1, int(math.sqrt(h * w / want)))
    rng = np.random.default_rng(seed)
    oy, ox = rng.integers(0, step, 2) if step > 1 else (0, 0)
    ys = np.arange(oy, h, step)
    xs = np.arange(ox, w, step)
    yy, xx = (m.reshape(-1) for m in np.meshgrid(ys, xs, indexing="ij"))
    off = np.arange(-_VARIANCE_RADIUS, _VARIANCE_RADIUS + 1)
    wy = np.clip(yy[:, None, None] + off[None, :, None], 0, h - 1)
    wx = np.clip(xx[:, None, None] + off[None, None, :], 0, w - 1)
    patch = mid[wy, wx].reshape(len(yy), -1, 3).astype(np.float32)  # (K, 9, 3)
    mean = patch.mean(axis=1)
    var = np.square(patch).mean(axis=1) - np.square(mean)
    tie = rng.random(len(yy))
    out = np.empty((3, samples, n_exp), dtype=np.int32)
    k = len(yy)
    for c in range(3):
        zc = mid[yy, xx, c].astype(np.int64)
        lo, hi = zc.min(), zc.max()
        bins = ((zc - lo) * samples) // max(hi - lo + 1, 1)
        order = np.lexsort((tie, var[:, c], bins))
        sorted_bins = bins[order]
        starts = np.searchsorted(sorted_bins, sorted_bins, side="left")
        rank = np.arange(k) - starts  # 0 for each bin's lowest-variance candidate, then 1 …
        chosen = order[np.lexsort((tie[order], sorted_bins, rank))][:samples]
        idx = np.resize(chosen, samples)  # fewer candidates than samples: repeat (harmless)
        out[c] = codes[:, yy[idx], xx[idx], c].T
    return out


# --------------------------------------------------------------------------- robertson


@partial(jax.jit, static_argnames=("levels", "n", "max_iter"))
def _robertson_channel(
    z: jax.Array, t: jax.Array, table: jax.Array | None, tol: float, levels, n, max_iter
):
    """Robertson et al.'s alternation for one channel: ``z`` ``(P, N)`` codes."""
    dtype = t.dtype
    w = _weights(z, levels, table, _gaussian).astype(dtype)
    # a pixel seen in one exposure only confirms any I (its E is I(y)/t): drop it
    w = jnp.where(jnp.sum(w > 0, axis=1, keepdims=True) >= 2, w, 0.0)
    b, a = _locate(z, levels, n)
    tt = jnp.broadcast_to(t[None, :], z.shape)
    mid = (n - 1) // 2
    # I-step normal equations: Σ w (I((1−a)·b + a·(b+1)) − t E)², tridiagonal in the nodes
    diag = jnp.zeros((n,), dtype).at[b].add(w * jnp.square(1.0 - a)).at[b + 1].add(w * a * a)
    off = jnp.zeros((n - 1,), dtype).at[jnp.minimum(b, n - 2)].add(w * a * (1.0 - a))
    observed = diag > 0
    # a tiny pull towards the previous estimate keeps unobserved nodes defined
    ridge = 1e-6 * jnp.max(diag)
    op = lx.TridiagonalLinearOperator(diag + ridge, off, off)

    def interp(i_nodes):
        return i_nodes[b] * (1.0 - a) + i_nodes[b + 1] * a

    def step(i_nodes):
        e = jnp.sum(w * tt * interp(i_nodes), axis=1) / jnp.maximum(
            jnp.sum(w * tt * tt, axis=1), jnp.finfo(dtype).tiny
        )
        te = tt * e[:, None]
        rhs = jnp.zeros((n,), dtype).at[b].add(w * (1.0 - a) * te).at[b + 1].add(w * a * te)
        new = lx.linear_solve(op, rhs + ridge * i_nodes, solver=lx.Tridiagonal()).value
        new = jnp.where(observed, new, i_nodes)
        return new / new[mid]

    def cond(state):
        k, _, delta = state
        return (k < max_iter) & (delta > tol)

    def body(state):
        k, i_nodes, _ = state
        new = step(i_nodes)
        delta = jnp.max(jnp.abs(new - i_nodes) / jnp.maximum(new, jnp.finfo(dtype).tiny))
        return k + 1, new, delta

    i0 = jnp.linspace(1.0 / (n - 1), 1.0, n, dtype=dtype)
    i0 = i0 / i0[mid]
    _, i_nodes, _ = jax.lax.while_loop(cond, body, (0, i0, jnp.asarray(jnp.inf, dtype)))
    ok = observed & (i_nodes > 0)
    g = jnp.log(jnp.where(ok, i_nodes, 1.0))
    return _finish(_fill_unobserved(g, ok), levels)


def _grid_samples(codes: np.ndarray, samples: int) -> np.ndarray:
    """A regular grid of at most ``samples`` pixels: ``(3, P, N)`` codes."""
    n_exp, h, w, _ = codes.shape
    step = max(1, math.ceil(math.sqrt(h * w / samples)))
    sub = codes[:, ::step, ::step, :].reshape(n_exp, -1, 3)
    return np.ascontiguousarray(sub.transpose(2, 1, 0)).astype(np.int32)


# ----------------------------------------------------------------------- mitsunaga1999


@partial(jax.jit, static_argnames=("levels", "max_order", "iterations", "refine"))
def _mitsunaga_channel(z: jax.Array, t: jax.Array, levels, max_order, iterations, refine):
    """Mitsunaga & Nayar's polynomial fit for one channel: ``z`` ``(P, N)`` codes, exposures
    sorted by increasing time."""
    dtype = t.dtype
    m = z.astype(dtype) / (levels - 1)
    valid = (z > 0) & (z < levels - 1)
    m_q, m_q1 = m[:, :-1], m[:, 1:]  # (P, N−1) pairs of consecutive exposures
    ok = (valid[:, :-1] & valid[:, 1:]).astype(dtype)
    count = jnp.maximum(jnp.sum(ok, axis=0), 1.0)
    r0 = t[:-1] / t[1:]
    powers = jnp.arange(max_order + 1)

    def legendre(x):  # (…, max_order + 1): P_n(2x − 1), n = 0 … max_order
        s = 2.0 * x - 1.0
        out = [jnp.ones_like(s), s]
        for k in range(1, max_order):
            out.append(((2 * k + 1) * s * out[k] - k * out[k - 1]) / (k + 1))
        return jnp.stack(out[: max_order + 1], axis=-1)

    def last_axis(v, like):  # broadcast a (k,) vector along the last axis of ``like``
        return v.reshape((1,) * (like.ndim - 1) + (-1,))

    def fit(order):
        # unknowns c_0 … c_{order−1}; c_order = 1 − Σ c_n (f(1) = 1, as P_n(1) = 1);
        # higher ones 0
        active = (powers[:-1] < order).astype(dtype)
        pick = (powers == order).astype(dtype)

        def basis(x):  # (…, max_order): P_n − P_order for active n
            lp = legendre(x)[..., :-1]
            return (lp - top(x)[..., None]) * last_axis(active, lp)

        def top(x):
            lp = legendre(x)
            return jnp.sum(lp * last_axis(pick, lp), axis=-1)

        b_q, b_q1 = basis(m_q), basis(m_q1)
        f_top_q, f_top_q1 = top(m_q), top(m_q1)
        sw = jnp.sqrt(ok / count[None, :])

        def solve(r):
            a_mat = (b_q - r[None, :, None] * b_q1) * sw[..., None]
            rhs = -(f_top_q - r[None, :] * f_top_q1) * sw
            a_mat = a_mat.reshape(-1, max_order)
            pad = jnp.diag(1.0 - active)  # inactive coefficients pinned to 0
            a_mat = jnp.concatenate([a_mat, pad], axis=0)
            rhs = jnp.concatenate([rhs.reshape(-1), jnp.zeros((max_order,), dtype)])
            c = lx.linear_solve(lx.MatrixLinearOperator(a_mat), rhs, solver=lx.QR()).value
            resid = jnp.sum(jnp.square(a_mat @ c - rhs))
            return c, resid

        def f_of(c, x):
            bx = basis(x)
            return jnp.sum(bx * last_axis(c, bx), axis=-1) + top(x)

        def body(_, state):
            r, _, _ = state
            c, resid = solve(r)
            if refine:
                fq, fq1 = f_of(c, m_q), f_of(c, m_q1)
                fq1_safe = jnp.where(fq1 > 0, fq1, 1.0)
                ratio = jnp.where((fq1 > 0) & (ok > 0), fq / fq1_safe, 0.0)
                good = jnp.sum(ok * (fq1 > 0), axis=0)
                r_new = jnp.sum(ratio, axis=0) / jnp.maximum(good, 1.0)
                r = jnp.where((good > 0) & (r_new > 0) & (r_new < 1), r_new, r)
            return r, c, resid

        c0 = jnp.zeros((max_order,), dtype)
        _, c, resid = jax.lax.fori_loop(0, iterations, body, (r0, c0, jnp.zeros((), dtype)))
        grid = jnp.linspace(0.0, 1.0, levels, dtype=dtype)
        x = f_of(c, grid)
        return x, resid

    x_all, resid = jax.vmap(fit)(jnp.arange(1, max_order + 1))
    # the residual of nested least squares never grows with the order, so "the smallest
    # residual" alone always picks the highest order, which follows noise (JPEG members,
    # read noise) into a wavy, even decreasing curve: keep the orders whose curve rises
    # over the codes, and of those the one of smallest residual
    finite = jnp.isfinite(resid) & jnp.all(jnp.isfinite(x_all), axis=1)
    # (near black, below 2 % of the codes, a dip is floored below and does no harm)
    above = jnp.arange(1, levels) >= 0.02 * (levels - 1)
    rising = finite & jnp.all((jnp.diff(x_all, axis=1) >= 0) | ~above[None, :], axis=1)
    usable = jnp.where(jnp.any(rising), rising, finite)
    best = jnp.argmin(jnp.where(usable, resid, jnp.inf))
    x = x_all[best]
    # the polynomial may dip to ≤ 0 near black: floor at the smallest positive value
    pos = x > 0
    floor = jnp.min(jnp.where(pos, x, jnp.inf))
    floor = jnp.where(jnp.isfinite(floor), floor, jnp.finfo(dtype).tiny)
    g = jnp.log(jnp.where(pos, x, floor))
    return _finish(g, levels), best + 1


# --------------------------------------------------------------------------- public API


def _positive_int(value: Any, name: str, low: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
        raise ValueError(f"{name}: expected an integer ≥ {low}, got {value!r}")
    return int(value)


def recover_response(
    images: Any,
    exposure_times: ArrayLike | None = None,
    *,
    method: str = "debevec",
    samples: int | None = None,
    smoothness: float | ArrayLike | None = None,
    weights: ArrayLike | None = None,
    seed: int = 0,
    nodes: int | None = None,
    max_iter: int = 50,
    tol: float = 1e-4,
    max_order: int = 10,
    refine_ratios: bool = False,
) -> Float[Array, "levels 3"]:
    """Recover the inverse camera response ``g(z) = ln X`` from an exposure bracket.

    Args:
        images: ``(N, H, W, 3)`` uint8/uint16 codes, a list of ``(H, W, 3)`` arrays, or file
            paths (exposure times then come from EXIF unless given).
        exposure_times: ``(N,)`` seconds.
        method: ``"debevec"`` (Debevec & Malik 1997), ``"robertson"`` (Robertson et al.
            2003) or ``"mitsunaga1999"`` (Mitsunaga & Nayar 1999); case and separators
            ignored.
        samples: pixels used per channel. ``"debevec"``: selected as the paper proposes,
            default ``max(50, 2·ceil((nodes − 1)/(N − 1)))``; ``"robertson"``: a regular grid
            of at most this many (default 65536); ``"mitsunaga1999"``: likewise (default 16384).
        smoothness: Debevec & Malik's ``λ`` (default 10), weight of the second-difference
            term between adjacent nodes; differentiable.
        weights: optional ``(levels,)`` weighting table replacing the method's own (triangle
            for ``"debevec"``, Gaussian for ``"robertson"``); codes 0 and top get weight 0.
        seed: seeds the sample grid's offset and ties (``"debevec"``).
        nodes: code values at which ``g`` is solved (default every code for 8-bit, 1024 for
            16-bit), then interpolated to all codes.
        max_iter, tol: ``"robertson"``'s iteration limit and relative-change tolerance.
        max_order: ``"mitsunaga1999"``'s highest polynomial order tried.
        refine_ratios: ``"mitsunaga1999"`` re-estimates the exposure ratios (the paper);
            ``False`` keeps the given ones.

    Returns:
        ``(levels, 3)`` natural-log sensor exposure per code value, non-decreasing, finite,
        0 at the top code (float32, or float64 under x64).

    Raises:
        ValueError: one line naming the argument (bad bracket, times, method, options).
    """
    key = str(method).lower().replace("-", "").replace("_", "").replace(" ", "")
    if key not in METHODS:
        raise ValueError(f"method: expected one of {list(METHODS)}, got {method!r}")
    bracket = as_codes(images, exposure_times)
    codes, levels, times = bracket.codes, bracket.levels, bracket.exposure_times
    assert times is not None
    n_exp = codes.shape[0]
    n = _node_count(levels, nodes)
    dtype = jnp.result_type(float)
    table = None
    if weights is not None:
        tbl = np.asarray(weights, dtype=np.float64)
        if tbl.shape != (levels,) or not np.all(np.isfinite(tbl) & (tbl >= 0)):
            raise ValueError(
                f"weights: expected a ({levels},) table of non-negative finite weights, "
                f"got shape {tbl.shape}"
            )
        table = jnp.asarray(tbl, dtype)
    if key == "debevec":
        p = _positive_int(
            max(50, 2 * math.ceil((n - 1) / (n_exp - 1))) if samples is None else samples,
            "samples",
        )
        lam = 10.0 if smoothness is None else smoothness
        if not isinstance(lam, jax.Array) and not np.all(np.asarray(lam) >= 0):
            raise ValueError(f"smoothness: expected a non-negative number, got {lam!r}")
        z = jnp.asarray(_debevec_samples(codes, times, p, seed))
        log_t = jnp.log(jnp.asarray(times, dtype))
        lam = jnp.asarray(lam, dtype)
        g = jax.vmap(_debevec_channel, in_axes=(0, None, None, None, None, None))(
            z, log_t, lam, table, levels, n
        )
        return g.T
    if smoothness is not None:
        raise ValueError(f"smoothness: only method 'debevec' takes it, not {key!r}")
    if key == "robertson":
        p = _positive_int(65536 if samples is None else samples, "samples")
        z = jnp.asarray(_grid_samples(codes, p))
        t = jnp.asarray(times, dtype)
        max_iter = _positive_int(max_iter, "max_iter")
        g = jax.vmap(_robertson_channel, in_axes=(0, None, None, None, None, None, None))(
            z, t, table, float(tol), levels, n, max_iter
        )
        return g.T
    if weights is not None:
        raise ValueError("weights: method 'mitsunaga1999' uses no weighting table")
    p = _positive_int(16384 if samples is None else samples, "samples")
    max_order = _positive_int(max_order, "max_order")
    order = np.argsort(times)
    z = jnp.asarray(_grid_samples(codes[order], p))
    t = jnp.asarray(times[order], dtype)
    g, _ = jax.vmap(_mitsunaga_channel, in_axes=(0, None, None, None, None, None))(
        z, t, levels, max_order, 20, bool(refine_ratios)
    )
    return g.T


# ------------------------------------------------------------------------ response files

_CHANNEL_NAMES = ("IR", "IG", "IB")


def save_response(path: str | os.PathLike, response: ArrayLike, format: str | None = None) -> Path:
    """Write a response ``(levels, 3)`` (``ln X`` per code value) to ``path``, atomically.

    Formats (``format``, else from the suffix: ``.json`` → ``"json"``, anything else →
    ``"pfs"``):

    - ``"pfs"``: the text format ``pfshdrcalibrate -s`` writes and ``-f`` reads (pfstools;
      Octave-style matrices ``IR``, ``IG``, ``IB`` with columns ``log10(I) | code | I``, then
      a weighting matrix ``W``). pfstools stores the *linear* camera response ``I = X``, so
      ``I = exp(g)`` is written (``−inf`` codes as 0, as pfstools writes unexposed codes);
      ``W`` is Debevec & Malik's triangle, which ``pfshdrcalibrate`` does not read back.
    - ``"json"``: ``{"format": "hdrjax-response", "levels": L, "quantity": "ln exposure",
      "channels": ["R", "G", "B"], "g": [[…], [...], [...]]}`` (``null`` for ``−inf``).

    Returns the path written. Raises a one-line ``ValueError`` for a bad response or format.
    """
    g = check_response(response)
    p = Path(path)
    fmt = format or ("json" if p.suffix.lower() == ".json" else "pfs")
    if fmt not in ("pfs", "json"):
        raise ValueError(f"format: expected 'pfs' or 'json', got {format!r}")
    levels = g.shape[0]
    if fmt == "json":
        body = {
            "format": "hdrjax-response",
            "levels": levels,
            "quantity": "ln exposure",
            "channels": ["R", "G", "B"],
            "g": [[None if v == -np.inf else float(v) for v in g[:, c]] for c in range(3)],
        }
        text = json.dumps(body) + "\n"
    else:
        lines = []
        with np.errstate(over="ignore"):
            lin = np.exp(g)
        for c, name in enumerate(_CHANNEL_NAMES):
            lines += [
                f"# Camera response curve, channel {name}",
                "# data layout: log10(response) | camera output | response",
                f"# name: {name}",
                "# type: matrix",
                f"# rows: {levels}",
                "# columns: 3",
            ]
            for m in range(levels):
                i = float(lin[m, c])
                lg = math.log10(i) if i > 0 else -6.0
                lines.append(f" {lg:e} {m:4d} {i:e}")
            lines.append("")
        w = 1.0 - np.abs(2.0 * np.arange(levels) / (levels - 1) - 1.0)
        lines += [
            "# Weighting function",
            "# data layout: weight | camera output",
            "# name: W",
            "# type: matrix",
            f"# rows: {levels}",
            "# columns: 2",
        ]
        lines += [f" {w[m]:e} {m:4d}" for m in range(levels)]
        lines.append("")
        text = "\n".join(lines) + "\n"
    with atomic_path(p) as tmp:
        tmp.write_text(text)
    return p


def _read_pfs(p: Path, text: str) -> np.ndarray:
    blocks: dict[str, np.ndarray] = {}
    name = None
    rows: list[list[float]] = []
    for raw in text.splitlines() + [""]:
        line = raw.strip()
        if line.startswith("# name:"):
            name = line.split(":", 1)[1].strip()
            rows = []
        elif line.startswith("#"):
            continue
        elif line:
            rows.append([float(v) for v in line.split()])
        elif name is not None:
            blocks[name] = np.asarray(rows)
            name = None
    names = [n for n in ("IR", "IG", "IB") if n in blocks]
    if len(names) != 3:
        names = ["IY"] * 3 if "IY" in blocks else []
    if not names:
        raise ValueError(f"{p}: no response matrices IR, IG, IB (or IY) found")
    cols = []
    for n in names:
        m = blocks[n]
        if m.ndim != 2 or m.shape[1] != 3:
            raise ValueError(f"{p}: matrix {n} must have 3 columns (log10 I, code, I)")
        lin = np.zeros(int(m[:, 1].max()) + 1)
        lin[m[:, 1].astype(int)] = m[:, 2]
        cols.append(lin)
    if len({len(c) for c in cols}) != 1:
        raise ValueError(f"{p}: the channels have different numbers of codes")
    lin = np.stack(cols, axis=-1)
    if np.any(lin < 0) or not np.all(np.isfinite(lin)):
        raise ValueError(f"{p}: responses must be finite and non-negative")
    top = lin[-1]
    if np.any(top <= 0):
        raise ValueError(f"{p}: the response at the top code must be positive")
    with np.errstate(divide="ignore"):
        return np.log(lin / top[None, :])


def load_response(path: str | os.PathLike) -> Float[Array, "levels 3"]:
    """Read a response written by :func:`save_response` or by ``pfshdrcalibrate -s``.

    A pfstools file holds the linear response ``I`` per code (``IR``, ``IG``, ``IB``, or one
    ``IY`` for luminance, used for all three channels); it is returned as
    ``g = ln(I / I_top)`` per channel — the same convention as :func:`recover_response`
    (pfstools' own scale, arbitrary, is divided out; codes with ``I = 0`` become ``−inf``).

    Raises:
        ValueError: one line naming the file (missing, unreadable, not a response file).
    """
    p = Path(path)
    try:
        text = p.read_text()
    except (OSError, UnicodeDecodeError) as err:
        raise ValueError(f"{p}: cannot read a response file ({type(err).__name__})") from None
    try:
        if p.suffix.lower() == ".json" or text.lstrip().startswith("{"):
            body = json.loads(text)
            if not isinstance(body, dict) or body.get("format") != "hdrjax-response":
                raise ValueError(f"{p}: not an hdrjax response JSON file")
            g = np.asarray(
                [[-np.inf if v is None else v for v in ch] for ch in body["g"]], np.float64
            ).T
            g = check_response(g, name=str(p))
            if g.shape[0] != body.get("levels"):
                raise ValueError(f"{p}: 'levels' does not match the table")
        else:
            g = _read_pfs(p, text)
    except ValueError as err:
        msg = str(err)
        raise ValueError(msg if msg.startswith(str(p)) else f"{p}: {msg}") from None
    except (KeyError, TypeError, json.JSONDecodeError) as err:
        raise ValueError(f"{p}: not a response file ({type(err).__name__}: {err})") from None
    return jnp.asarray(g, jnp.result_type(float))
