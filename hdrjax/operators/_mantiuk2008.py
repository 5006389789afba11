"""Mantiuk, Daly, Kerofsky 2008 display adaptive tone mapping, as ``pfstmo_mantiuk08``
(pfstools 2.2.0) computes it.

Reference:
    Mantiuk, Daly, Kerofsky. "Display adaptive tone mapping." ACM Transactions on Graphics
    27(3):68 (Proc. SIGGRAPH 2008). https://doi.org/10.1145/1360612.1360667

The tone curve is piecewise linear in ``l = log10 L`` (``L`` in cd/m²) with nodes
``l_i = −8 + δ i``, ``δ = 0.1``, ``i = 0 … 160``; its unknowns are the rises
``x_l = y_{l+1} − y_l ≥ 0`` of ``y = log10 L_d`` (display luminance) over each segment.

Image statistics (:func:`conditional_density`): the log-luminance ``l`` (below the image's
smallest positive luminance, at least ``10^-8``, it counts as that; above ``10^8`` as
``10^8``) is low-passed by four levels of an à-trous 5-tap kernel
``(0.05, 0.25, 0.4, 0.25, 0.05)`` (rows then columns, step ``2^f``, mirrored borders);
band ``f`` is ``g = l_f − l_{f+1}`` at frequency ``ρ_f = 15 / 2^f`` cycles per degree
(30 pixels per degree). The counts ``N(f, i, k)`` of pixels whose background ``l_{f+1}`` is
nearest node ``i`` and whose contrast ``g`` is nearest ``(k − 7) δ`` (``|g|`` between 0.0043,
the detection threshold, and ``δ/2`` counts as ``±δ``) are the paper's conditional
probabilities ``p(G | l)`` up to normalisation.

Objective (the visible contrast distortion, paper Eq. 9–10; :func:`contrast_distortion`):
    ``E = Σ_{f,i,k} N(f,i,k) [T(ΔY, S_f(y_i)) − T(e G, S_f(L_a))]²``
with ``G = |k − 7| δ`` the scene contrast between nodes ``i`` and ``j = i + k − 7``,
``ΔY = |y_j − y_i|`` its display contrast, ``e`` the contrast enhancement, ``S_f(L)`` Daly's
(1993) CSF at ``ρ_f`` and adaptation ``L`` (for the scene ``L_a = 1000`` cd/m²), and
``T(C, S) = sign C · 3.291 ((1 + (S W)³)^{1/3} − 1) / (0.2599 (3.433 + S W)^0.8)`` with
``W = 10^|C| − 1`` the transducer of contrast masking (paper Eq. 11). Minimised subject to
``x ≥ 0`` and ``Σ x ≤ log10(L_d(1) / L_d(0))`` (the display's dynamic range); the curve's
top is the display's peak, ``y_160 = log10 L_d(1)``.

Solution as pfstmo's: linearise ``T(ΔY) ≈ K ΔY`` with ``K = T(ΔY_n, S(y_n)) / ΔY_n`` at the
current curve, solve the quadratic program (a primal–dual interior-point method here,
GSL's ``mg_pdip`` there) and repeat from ``x = range / n`` until no rise changes by more
than ``δ / 10`` (at most 200 times). Rises no pixel pair spans are left out; a gap between
used ones (a "framework") is one unknown spread evenly over it and tied to its neighbours
with the weight ``0.1 Σ N`` (pfstmo's anchoring).

Display model (gamma–gain–offset, paper Eq. 2): ``L_d(v) = v^γ (L_max − L_black) + L_black
+ k E_amb / π`` for pixel values ``v ∈ [0, 1]``; the output is its inverse,
``v = ((L_d − L_off) / (L_max − L_black))^{1/γ}``, of each channel
``(C / L)^s L_d(L)`` with ``s`` the colour saturation from the curve's slope (Mantiuk et al.
2009, ``s = (1 + k_1) c^{k_2} / (1 + k_1 c^{k_2})``, ``k_1 = 1.48``, ``k_2 = 0.82``, times
the saturation factor).
"""

import functools
import math
from typing import Any, ClassVar, Literal

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._interp import table_lerp
from .._srgb import srgb_decode
from ._base import (
    AbstractOperator,
    Prepared,
    fill,
    parameter,
    register,
    weights_field,
)

REFERENCE = (
    "Mantiuk, Daly, Kerofsky 2008, Display adaptive tone mapping, ACM Transactions on Graphics"
    " 27(3):68 (SIGGRAPH 2008), https://doi.org/10.1145/1360612.1360667"
)
DELTA = float(np.float32(0.1))
"""Node spacing ``δ`` in ``log10`` cd/m² (pfstmo's float ``0.1f``)."""
LOG_MIN = -8.0
"""``log10`` of the first node (cd/m²)."""
NODES = 161
"""Nodes of the tone curve, ``log10 L = −8 + δ i``, ``i = 0 … 160``."""
SEGMENTS = NODES - 1
CONTRASTS = 15
"""Contrast bins ``(k − 7) δ``, ``k = 0 … 14``."""
NEIGHBOURS = 7
BANDS = 4
"""Frequency bands: ``15 / 2^f`` cycles per degree, ``f = 0 … 3`` (30 pixels per degree)."""
FREQUENCIES = tuple(15.0 / 2**f for f in range(BANDS))
THRESHOLD = float(np.float32(0.0043))
"""Contrast detection threshold, ``log10`` units (pfstmo's)."""
L_FLOOR = 1e-8
L_CEIL = 1e8
MAX_ITERATIONS = 200
ANCHOR = 0.1
"""Weight of the framework and reference-white rows, times the total count (pfstmo's)."""
KERNEL = (0.05, 0.25, 0.4, 0.25, 0.05)
DISPLAYS: dict[str, tuple[float, float, float, float, float]] = {
    # gamma, peak L_max (cd/m²), black L_black (cd/m²), ambient E_amb (lux), reflectivity k
    "lcd_office": (2.2, 100.0, 0.8, 400.0, 0.01),
    "lcd": (2.2, 200.0, 0.8, 60.0, 0.01),
    "lcd_bright": (2.6, 500.0, 0.5, 10.0, 0.01),
    "crt": (2.2, 80.0, 1.0, 60.0, 0.02),
    "gog": (2.2, 100.0, 1.0, 50.0, 0.01),
}
"""pfstmo's predefined displays (``-d pd=NAME``) and, as ``"gog"``, the values its explicit
gamma–gain–offset display (``-d g=…:l=…:b=…:k=…:a=…``) takes for those not given."""
VISUAL_MODEL = ("luminance_masking", "contrast_masking", "csf")
VISUAL_MODELS = (
    "full",
    "none",
    *VISUAL_MODEL,
    "luminance_masking,contrast_masking",
    "luminance_masking,csf",
    "contrast_masking,csf",
)
"""pfstmo's ``-m`` settings: all components, none, or the components named."""
SATURATION_K1 = 1.48
SATURATION_K2 = 0.82


# ----------------------------------------------------------------------- visual model


def csf_daly(rho, L_adapt, xp=jnp):
    """Daly's (1993) CSF at ``rho`` cycles per degree and adaptation ``L_adapt`` cd/m², as
    pfstmo evaluates it: orientation 0, image area 1 deg², viewing distance 0.5 m, no
    eccentricity, peak sensitivity 250; the smaller of the two evaluations at ``rho`` and
    ``rho / r_a``."""
    A = 0.801 * (1 + 0.7 / L_adapt) ** -0.2
    B = 0.3 * (1 + 100 / L_adapt) ** 0.15
    r_a = 0.856 * 0.5**0.14

    def s(r):
        B1 = B * 0.9 * r
        low = ((3.23 * (r * r) ** -0.3) ** 5 + 1.0) ** -0.2
        return low * A * 0.9 * r * xp.exp(-B1) * xp.sqrt(1 + 0.06 * xp.exp(B1))

    return xp.minimum(s(rho), s(rho / r_a)) * 250.0


def csf_model(rho: float, L_adapt, model: frozenset, xp=jnp):
    """pfstmo's ``csf_datmo``: without luminance masking the adaptation is 1000 cd/m²,
    without the CSF the frequency is 4 cycles per degree."""
    if "luminance_masking" not in model:
        L_adapt = 1000.0 * xp.ones_like(L_adapt)
    return csf_daly(rho if "csf" in model else 4.0, L_adapt, xp)


# CSF of each band at the nodes' luminances (pfstmo's lookup tables, interpolated in log10)
_NODE_L = 10.0 ** (LOG_MIN + DELTA * np.arange(NODES))


def _csf_tables(model: frozenset) -> np.ndarray:
    return np.stack([csf_model(r, _NODE_L, model, np) for r in FREQUENCIES])


def transducer(C: Array, S: Array, masking: bool) -> Array:
    """Response to the contrast ``C`` (``log10`` units) at sensitivity ``S`` (paper
    Eq. 11 with contrast masking, else ``S C``)."""
    if not masking:
        return C * S
    W = jnp.power(10.0, jnp.abs(C)) - 1.0
    SW = S * W
    pos = SW > 0
    SWs = jnp.where(pos, SW, 1.0)
    num = jnp.where(pos, jnp.cbrt(1.0 + SWs**3) - 1.0, 0.0)
    return jnp.sign(C) * 3.291 * num / (0.2599 * (3.433 + SW) ** 0.8)


# -------------------------------------------------------------------- image statistics


def _blur(x: Array, step: int) -> Array:
    """The 5-tap kernel at spacing ``step``: rows, then columns (mirrored borders)."""
    k = np.asarray(KERNEL, x.dtype)
    r = 2 * step

    def along(a, axis):
        pad = [(0, 0)] * a.ndim
        pad[axis] = (r, r)
        p = jnp.pad(a, pad, mode="reflect")
        n = a.shape[axis]
        out = 0.0
        for j in range(5):
            out = out + jax.lax.slice_in_dim(p, j * step, j * step + n, axis=axis) * k[j]
        return out

    return along(along(x, 1), 0)


def conditional_density(
    L: Float[ArrayLike, "H W"], valid: Array | None = None
) -> Float[Array, "4 15 161"]:
    """pfstmo's contrast statistics of a luminance image (cd/m²): ``N[f, k, i]``, the pixel
    counts of band ``f``, contrast bin ``k`` and background node ``i`` (module docstring),
    with pfstmo's extra count at ``k = 6`` and ``k = 8`` of every node whose flat bin
    (``k = 7``) is not empty. ``valid``: pixels to count (all by default); the others are
    filtered as black. Constants for ``jax.grad``."""
    L = jax.lax.stop_gradient(jnp.asarray(L))
    valid = jnp.ones(L.shape, bool) if valid is None else valid
    L = jnp.where(valid & jnp.isfinite(L), L, 0.0)
    lowest = jnp.min(jnp.where(L > 0, L, jnp.inf))
    floor = jnp.maximum(jnp.minimum(lowest, L_CEIL), L_FLOOR)
    high = jnp.log10(jnp.clip(L, floor, L_CEIL))
    hist = []
    for f in range(BANDS):
        low = _blur(high, 1 << f)
        g = high - low
        u = (low - LOG_MIN) / DELTA
        i = jnp.floor(u + 0.5).astype(jnp.int32)
        # (int)(x + 0.5) truncates towards zero: −1 < x + 0.5 < 0 is bin 0
        v = (g + DELTA * NEIGHBOURS) / DELTA + 0.5
        k = jnp.where(v > -1.0, jnp.floor(jnp.maximum(v, 0.0)), -1.0).astype(jnp.int32)
        k = jnp.where((g > THRESHOLD) & (g < DELTA / 2), NEIGHBOURS + 1, k)
        k = jnp.where((g < -THRESHOLD) & (g > -DELTA / 2), NEIGHBOURS - 1, k)
        ok = valid & (i >= 0) & (i < NODES) & (k >= 0) & (k < CONTRASTS)
        idx = jnp.where(ok, k * NODES + i, CONTRASTS * NODES)
        h = jnp.zeros(CONTRASTS * NODES + 1, jnp.int32).at[idx.reshape(-1)].add(1)
        hist.append(h[:-1].reshape(CONTRASTS, NODES))
        high = low
    N = jnp.stack(hist).astype(jnp.result_type(float))
    flat = (N[:, NEIGHBOURS] > 0).astype(N.dtype)
    return N.at[:, NEIGHBOURS - 1].add(flat).at[:, NEIGHBOURS + 1].add(flat)


# ---------------------------------------------------------------------- the problem

_I = np.arange(NODES, dtype=np.int32)[None, :]
_K = np.arange(CONTRASTS, dtype=np.int32)[:, None]
_J = _I + _K - NEIGHBOURS
# pfstmo's loop: j from max(0, i − 7) to min(159, i + 6), j ≠ i
_ROW_OK = (_J >= 0) & (_J < SEGMENTS) & (_K != NEIGHBOURS) & (_K < CONTRASTS - 1)
_FROM = np.where(_ROW_OK, np.minimum(_I, _J), 0).astype(np.int32)
_TO = np.where(_ROW_OK, np.maximum(_I, _J), 1).astype(np.int32)
_NODE_X = LOG_MIN + DELTA * np.arange(NODES)


class Display:
    """A gamma–gain–offset display: ``gamma``, ``peak`` and ``black`` (cd/m²),
    ``ambient`` illuminance (lux), screen ``reflectivity``."""

    def __init__(self, gamma, peak, black, ambient, reflectivity):
        self.gamma, self.peak, self.black = gamma, peak, black
        self.offset = black + reflectivity / math.pi * ambient

    def luminance_range(self) -> tuple[Array, Array]:
        """``L_d(0)`` and ``L_d(1)``, cd/m²."""
        return self.offset, self.peak - self.black + self.offset

    def inverse_above_black(self, e: Array) -> Array:
        """Pixel value ``v`` of the display luminance ``L = L_d(0) e^e`` (``e`` the natural
        log of its ratio to the display's black), without the cancellation of
        ``L − L_d(0)`` that the inverse gamma would magnify near black."""
        d = jnp.clip(self.offset * jnp.expm1(e), 0.0, self.peak)
        r = d / (self.peak - self.black)
        pos = r > 0
        return jnp.where(pos, jnp.power(jnp.where(pos, r, 1.0), 1.0 / self.gamma), 0.0)

    def inverse(self, L: Array) -> Array:
        """Pixel value ``v`` of display luminance ``L`` (clamped to the display's range)."""
        L = jnp.clip(L, self.offset, self.offset + self.peak)
        r = (L - self.offset) / (self.peak - self.black)
        pos = r > 0
        return jnp.where(pos, jnp.power(jnp.where(pos, r, 1.0), 1.0 / self.gamma), 0.0)


class _Problem:
    """The rows of the least-squares problem for one image's statistics (static structure
    from pfstmo's bookkeeping, computed with arrays so that it traces)."""

    def __init__(self, N, enhancement, scene_luminance, model, white_y, dtype):
        self.model = model
        masking = "contrast_masking" in model
        self.masking = masking
        N = N.astype(dtype)
        center = N[:, NEIGHBOURS] > 0
        off = jnp.sum(N, axis=1) - N[:, NEIGHBOURS]
        total = jnp.sum(jnp.where(center, off, 0.0))
        self.total = total
        rows = N * jnp.asarray(_ROW_OK[None], dtype)  # (F, K, X)
        seen = jnp.sum(rows, axis=0) > 0  # (K, X)
        start = jnp.zeros(NODES + 1, dtype).at[_FROM.reshape(-1)].add(seen.reshape(-1))
        stop = jnp.zeros(NODES + 1, dtype).at[_TO.reshape(-1)].add(seen.reshape(-1))
        used = (jnp.cumsum(start - stop)[:SEGMENTS]) > 0
        seg = jnp.arange(SEGMENTS, dtype=jnp.int32)
        lo = jnp.min(jnp.where(seen, _FROM, np.int32(SEGMENTS)))
        hi = jnp.max(jnp.where(seen, _TO - 1, np.int32(-1)))
        white_i = None
        if white_y is not None:
            wl = jnp.log10(jnp.maximum(white_y, L_FLOOR))
            white_i = jnp.sum(_NODE_X <= wl, dtype=jnp.int32) - 1
            white_i = jnp.clip(white_i, 0, SEGMENTS - 1)
            used = used | (seg == white_i)
            lo, hi = jnp.minimum(lo, white_i), jnp.maximum(hi, white_i)
        inside = (seg >= lo) & (seg <= hi)
        prev_used = jnp.concatenate([jnp.ones(1, bool), used[:-1]])
        kept = inside & (used | prev_used)
        frame = kept & ~used
        # next used segment after each (framework rows end there)
        nxt = jnp.where(used, seg, SEGMENTS)
        nxt = jax.lax.cummin(nxt[::-1])[::-1]
        next_used = jnp.concatenate([nxt[1:], jnp.array([SEGMENTS], jnp.int32)])
        # the kept unknown each segment takes its rise from, and how many segments share it
        owner = jax.lax.cummax(jnp.where(kept, seg, -1))
        nxt_k = jax.lax.cummin(jnp.where(kept, seg, SEGMENTS)[::-1])[::-1]
        next_kept = jnp.concatenate([nxt_k[1:], jnp.array([SEGMENTS], jnp.int32)])
        span = jnp.where((seg == hi) | ~frame, 1, next_kept - seg)
        self.kept, self.inside, self.owner, self.span = kept, inside, owner, span
        self.n = jnp.sum(kept)
        self.empty = self.n == 0
        # rows: the data rows (F·K·X), one framework row per segment, the white row
        F = BANDS
        fr_to = jnp.where(frame, next_used, seg + 1)
        w_frame = jnp.where(frame, ANCHOR * total, 0.0)
        self.row_from = jnp.concatenate(
            [jnp.asarray(np.broadcast_to(_FROM, (F, CONTRASTS, NODES)).reshape(-1)), seg]
        )
        self.row_band = np.concatenate(
            [np.repeat(np.arange(F), CONTRASTS * NODES), np.full(SEGMENTS, F - 1)]
        )
        self.row_back = jnp.concatenate(
            [jnp.asarray(np.broadcast_to(_I, (F, CONTRASTS, NODES)).reshape(-1)), fr_to]
        )
        self.row_N = jnp.concatenate([rows.reshape(-1), w_frame])
        # scene contrast of each row (its span times the enhancement) and its response
        g_data = np.abs(_NODE_X[_TO] - _NODE_X[_FROM])
        g_data = np.broadcast_to(g_data, (F, CONTRASTS, NODES)).reshape(-1)
        x = jnp.asarray(_NODE_X, dtype)
        g_frame = x[fr_to] - x[seg]
        G = jnp.concatenate([jnp.asarray(g_data, dtype), g_frame]) * enhancement
        if scene_luminance is None:  # "auto": the scene luminance at the row's start
            S_scene = jnp.asarray(_csf_tables(model), dtype)[self.row_band, self.row_from]
        else:
            S_bands = jnp.stack(
                [csf_model(r, jnp.asarray(scene_luminance, dtype), model) for r in FREQUENCIES]
            )
            S_scene = S_bands[self.row_band]
        self.row_B = transducer(G, S_scene, masking)
        self.row_to = jnp.concatenate(
            [jnp.asarray(np.broadcast_to(_TO, (F, CONTRASTS, NODES)).reshape(-1)), fr_to]
        )
        if white_i is not None:
            self.row_from = jnp.concatenate([self.row_from, white_i[None]])
            self.row_to = jnp.concatenate([self.row_to, jnp.array([SEGMENTS], jnp.int32)])
            self.row_band = np.concatenate([self.row_band, [0]])
            self.row_back = jnp.concatenate([self.row_back, white_i[None]])
            self.row_N = jnp.concatenate([self.row_N, ANCHOR * total[None]])
            self.row_B = jnp.concatenate([self.row_B, jnp.zeros(1, dtype)])
        self.csf = jnp.asarray(_csf_tables(model), dtype)
        self.dtype = dtype

    def curve(self, x: Array, top: Array) -> Array:
        """``y`` at the nodes for the unknowns ``x`` (zero where not kept): pfstmo's
        ``compute_y``, the curve's top at ``top = log10 L_d(1)``."""
        x = jnp.where(self.kept, x, 0.0)
        d = jnp.where(self.inside, x[jnp.maximum(self.owner, 0)] / self.span[self.owner], 0.0)
        d = jnp.where(self.owner >= 0, d, 0.0)
        y0 = top - jnp.sum(x)
        return y0 + jnp.concatenate([jnp.zeros(1, x.dtype), jnp.cumsum(d)])

    def contrasts(self, x: Array) -> Array:
        """Display contrast ``Σ_{from ≤ l < to} x_l`` of every row."""
        c = jnp.concatenate([jnp.zeros(1, x.dtype), jnp.cumsum(jnp.where(self.kept, x, 0.0))])
        return c[self.row_to] - c[self.row_from]

    def sensitivities(self, y: Array) -> Array:
        """``S_f(y_back)`` of every row: the band's CSF table interpolated at the curve."""
        S = jnp.stack([table_lerp(t, (y - LOG_MIN) / DELTA) for t in self.csf])
        return S[self.row_band, self.row_back]

    def responses(self, x: Array, top: Array) -> Array:
        return transducer(self.contrasts(x), self.sensitivities(self.curve(x, top)), self.masking)

    def quadratic(self, x: Array, top: Array) -> tuple[Array, Array]:
        """``H`` and ``q`` of ``½ x'Hx + q'x`` linearised at ``x`` (pfstmo's ``K``)."""
        Ax = self.contrasts(x)
        T = self.responses(x, top)
        small = jnp.abs(Ax) < 1e-4
        K = T / jnp.where(small, 1.0, Ax)
        scale = jnp.where(self.total > 0, self.total, 1.0)
        Nn = self.row_N / scale
        w, v = Nn * K * K, Nn * K * self.row_B
        H = _cover(w, self.row_from, self.row_to)
        q = -jnp.diagonal(_cover(v, self.row_from, self.row_to))
        return H, q


def _cover(w: Array, start: Array, stop: Array) -> Array:
    """``Σ_r w_r a_r a_r'`` for interval rows ``a_r = 1[start_r ≤ l < stop_r]``
    (``SEGMENTS × SEGMENTS``): a 2-D cumulative sum of the weights by (start, stop)."""
    W = jnp.zeros(SEGMENTS * NODES, w.dtype).at[start * NODES + stop].add(w)
    W = W.reshape(SEGMENTS, NODES)
    P = jnp.cumsum(W, axis=0)
    Q = jnp.flip(jnp.cumsum(jnp.flip(P, 1), axis=1), 1)[:, 1:]  # Σ_{stop > m}
    upper = jnp.triu(Q)
    return upper + jnp.triu(Q, 1).T


@functools.partial(jax.custom_jvp, nondiff_argnums=(4,))
def solve_qp(H: Array, q: Array, active: Array, budget: Array, steps: int = 40) -> Array:
    """``argmin ½ x'Hx + q'x`` subject to ``x ≥ 0`` and ``Σ x ≤ budget`` over the
    ``active`` unknowns (the others 0): a primal–dual interior-point method with a fixed
    number of Newton steps. Its derivative is that of the solution (the KKT conditions on
    the solution's active set, :func:`_solve_qp_jvp`), not of the iterations, whose
    barrier terms overflow when differentiated."""
    return _interior_point(H, q, active, budget, steps)[0]


def _interior_point(H, q, active, budget, steps):
    """``(x, z, s, λ)``: the solution, the multipliers of ``x ≥ 0``, the slack and the
    multiplier of the budget."""
    n = H.shape[0]
    a = active.astype(H.dtype)
    eye = jnp.eye(n, dtype=H.dtype)
    off = (1.0 - a)[:, None] * (1.0 - a)[None, :] * eye
    H = H * a[:, None] * a[None, :] + off
    q = q * a
    scale = jnp.maximum(jnp.max(jnp.abs(jnp.diagonal(H))), jnp.finfo(H.dtype).tiny)
    H, q = H / scale, q / scale
    m = jnp.maximum(jnp.sum(a), 1.0)
    # the complementarity reached (float32's must be small too: unknowns at their bound end
    # near floor / z, and with small multipliers z a larger floor leaves them visibly above 0)
    floor = 1e-14 if H.dtype == jnp.float64 else 1e-12
    x = jnp.full(n, 0.5, H.dtype) * budget / m
    z = jnp.ones(n, H.dtype)
    lam = jnp.ones((), H.dtype)

    def ratio(v, dv):
        return jnp.min(jnp.where(dv < 0, -v / jnp.where(dv < 0, dv, -1.0), jnp.inf))

    def step(_, c):
        x, z, lam = c
        s = budget - a @ x
        mu = (x @ z + lam * s) / (n + 1)
        t = jnp.maximum(0.1 * mu, floor)
        M = H + jnp.diag(z / x) + (lam / s) * jnp.outer(a, a)
        rhs = -(H @ x + q) + t / x - a * (t / s)
        # Jacobi scaling: the barrier terms z/x of the bound unknowns grow without limit
        # and would leave M too ill-conditioned for a float32 Cholesky factorisation
        d = jax.lax.rsqrt(jnp.diagonal(M))
        dx = d * jax.scipy.linalg.cho_solve(
            jax.scipy.linalg.cho_factor(M * d[:, None] * d[None, :]), rhs * d
        )
        dz = t / x - z - (z / x) * dx
        ds = -(a @ dx)
        dl = t / s - lam - (lam / s) * ds
        alpha = jnp.minimum(
            1.0,
            0.99
            * jnp.minimum(
                jnp.minimum(ratio(x, dx), ratio(z, dz)),
                jnp.minimum(ratio(s[None], ds[None]), ratio(lam[None], dl[None])),
            ),
        )
        ok = jnp.all(jnp.isfinite(dx)) & jnp.all(jnp.isfinite(dz)) & jnp.isfinite(dl)
        alpha = jnp.where(ok & jnp.isfinite(alpha), alpha, 0.0)
        dx, dz, dl = (jnp.where(ok, v, 0.0) for v in (dx, dz, dl))
        return x + alpha * dx, z + alpha * dz, lam + alpha * dl

    x, z, lam = jax.lax.fori_loop(0, steps, step, (x, z, lam))
    # unknowns at their bound (x below its multiplier: strict complementarity) are 0: the
    # barrier leaves them near floor / z, which the display's inverse gamma would make
    # visible at its black
    x = jnp.where(active & (x > z), x, 0.0)
    # and a budget whose slack is below its multiplier is spent exactly (the barrier leaves
    # a slack near floor / λ, which would lift the curve off the display's black)
    total = a @ x
    x = jnp.where(
        (budget - total < lam) & (total > 0), x * (budget / jnp.where(total > 0, total, 1.0)), x
    )
    return x, z, budget - a @ x, lam


@solve_qp.defjvp
def _solve_qp_jvp(steps, primals, tangents):
    """The solution's derivative: on its free set ``F`` (unknowns above their bound:
    ``x > z``, strict complementarity) and with the budget active when its slack is below
    its multiplier, the KKT conditions ``H_FF x_F + q_F + λ 1 = 0`` (and ``Σ x_F = budget``)
    differentiated: ``[H_FF 1; 1' 0] [dx_F; dλ] = [−dH_FF x_F − dq_F; d budget]``."""
    H, q, active, budget = primals
    dH, dq, _, d_budget = tangents
    H, q, budget = (jax.lax.stop_gradient(v) for v in (H, q, budget))
    x, z, s, lam = _interior_point(H, q, active, budget, steps)
    free = x > 0
    tight = (s < lam) & jnp.any(free)
    f = free.astype(H.dtype)
    n = H.shape[0]
    h = jnp.maximum(jnp.max(jnp.abs(jnp.diagonal(H))), 1.0)
    b = f * tight * h
    K = jnp.block(
        [
            [H * f[:, None] * f[None, :] + jnp.diag((1.0 - f) * h), b[:, None]],
            [b[None, :], jnp.where(tight, 0.0, h)[None, None]],
        ]
    )
    r = jnp.concatenate([-(dH @ x + dq) * f, jnp.where(tight, d_budget * h, 0.0)[None]])
    # the pseudo-inverse: unknowns that every row spans together (equal columns of H) are
    # a flat direction of the objective, along which the solution does not move
    dx = (jnp.linalg.pinv(K, hermitian=True) @ r)[:n] * f
    return x, dx


def _parse_model(visual_model: str) -> frozenset:
    parts = {p.strip() for p in visual_model.replace(":", ",").split(",") if p.strip()}
    if parts == {"full"}:
        return frozenset(VISUAL_MODEL)
    if parts == {"none"}:
        return frozenset()
    bad = parts - set(VISUAL_MODEL)
    if bad or not parts:
        raise ValueError(
            "visual_model: expected 'full', 'none' or a comma-separated subset of"
            f" {', '.join(VISUAL_MODEL)}, got {visual_model!r}"
        )
    return frozenset(parts)


def tone_curve(
    density: Float[ArrayLike, "4 15 161"],
    display: Display,
    *,
    enhancement: ArrayLike = 1.0,
    scene_luminance: ArrayLike | None = 1000.0,
    visual_model: str = "full",
    white_y: ArrayLike | None = None,
    tol: float = DELTA / 10,
    max_iterations: int = MAX_ITERATIONS,
) -> Float[Array, " 161"]:
    """The tone curve, ``y = log10 L_d`` at the 161 nodes, that minimises the visible
    contrast distortion of ``density`` (:func:`conditional_density`) on ``display``
    (module docstring). pfstmo stops when no rise changes by more than ``tol`` (``δ/10``);
    gradients (with respect to the display, the enhancement, the scene luminance) are
    those of the fixed point (implicit differentiation), exact as ``tol → 0``."""
    model = _parse_model(visual_model)
    dtype = jnp.result_type(float)
    N = jax.lax.stop_gradient(jnp.asarray(density, dtype))
    prob = _Problem(N, enhancement, scene_luminance, model, white_y, dtype)
    bottom, top_L = display.luminance_range()
    top = jnp.log10(jnp.asarray(top_L, dtype))
    budget = top - jnp.log10(jnp.asarray(bottom, dtype))
    x0 = jnp.where(prob.kept, budget / jnp.maximum(prob.n, 1), 0.0)

    def step(x, args):
        top, budget = args
        H, q = prob.quadratic(x, top)
        return solve_qp(H, q, prob.kept, budget)

    if "contrast_masking" in model and max_iterations > 1:

        def change(x):
            return step(x, (top, budget)) - x

        def iterate(change, x):  # pfstmo's iteration, to no rise changing by more than tol
            def more(c):
                i, _, d = c
                return (i < max_iterations) & (d > tol)

            def again(c):
                i, x, _ = c
                dx = change(x)
                return i + 1, x + dx, jnp.max(jnp.abs(dx))

            return jax.lax.while_loop(more, again, (0, x, jnp.asarray(jnp.inf, x.dtype)))[1]

        def linear(g, r):  # (J − I) v = r at the fixed point, J materialised (161 × 161)
            return jnp.linalg.pinv(jax.jacfwd(g)(r)) @ r

        # implicit differentiation without optimistix's adjoint, whose checked linear
        # solve calls back to Python and deadlocks XLA:CPU under vmap
        x = jax.lax.custom_root(change, x0, iterate, linear)
    else:  # pfstmo solves once (the linearisation is exact without masking)
        x = step(x0, (top, budget))
    y = prob.curve(x, top)
    # a curve that spends the display's whole range starts at its black exactly (top − Σx
    # would carry the rounding of top, which the display's inverse gamma magnifies)
    y_black = jnp.log10(jnp.asarray(bottom, dtype))
    spent = jnp.abs(y[0] - y_black) <= 8 * jnp.finfo(dtype).eps * jnp.maximum(jnp.abs(top), 1)
    y = jnp.where(spent, y_black + prob.curve(x, jnp.sum(jnp.where(prob.kept, x, 0.0))), y)
    return jnp.where(prob.empty, jnp.full_like(y, top), y)


def contrast_distortion(
    y: Float[ArrayLike, " 161"],
    density: Float[ArrayLike, "4 15 161"],
    *,
    enhancement: ArrayLike = 1.0,
    scene_luminance: ArrayLike | None = 1000.0,
    visual_model: str = "full",
) -> Float[Array, ""]:
    """The visible contrast distortion (paper Eq. 9–10) of the tone curve ``y``
    (``log10`` display luminance at the 161 nodes) for the statistics ``density``:
    ``Σ N (T(ΔY, S(y)) − T(e G, S(L_a)))² / Σ N`` over the statistics' contrast pairs
    (module docstring), in squared transducer units (JND²)."""
    model = _parse_model(visual_model)
    dtype = jnp.result_type(float)
    y = jnp.asarray(y, dtype)
    N = jax.lax.stop_gradient(jnp.asarray(density, dtype))
    prob = _Problem(N, enhancement, scene_luminance, model, None, dtype)
    n_data = BANDS * CONTRASTS * NODES
    dY = jnp.abs(y[prob.row_to] - y[prob.row_from])[:n_data]
    S = prob.sensitivities(y)[:n_data]
    T = transducer(dY, S, prob.masking)
    Nd = prob.row_N[:n_data]
    total = jnp.sum(Nd)
    return jnp.sum(Nd * (T - prob.row_B[:n_data]) ** 2) / jnp.where(total > 0, total, 1.0)


def rendition_curve(
    L: Float[ArrayLike, "H W"], L_d: Float[ArrayLike, "H W"], valid: Array
) -> Float[Array, " 161"]:
    """The tone curve a rendition shows: at each node ``i`` (``log10 L = −8 + δ i``), the
    ``log10`` display luminance ``L_d`` that a straight line fitted (least squares, in
    ``log10 L``) to the ``valid`` pixels nearest the node gives at the node — their mean
    when they do not spread around it; nodes without pixels are interpolated linearly
    between their nearest nodes with pixels (held flat beyond them). For a global operator
    this is its curve, sampled; for a local one, its average mapping."""
    L = jnp.asarray(L)
    u = (jnp.log10(jnp.clip(jnp.where(valid, L, 1.0), L_FLOOR, L_CEIL)) - LOG_MIN) / DELTA
    node = jnp.clip(jnp.floor(u + 0.5), 0, NODES - 1)
    d = jnp.where(valid, u - node, 0.0).reshape(-1)
    i = jnp.where(valid, node.astype(jnp.int32), NODES).reshape(-1)
    y = jnp.log10(jnp.where(valid, L_d, 1.0)).reshape(-1)

    def total(x):
        return jax.ops.segment_sum(x, i, NODES + 1)[:NODES]

    n, s1, s2 = total(jnp.ones_like(y)), total(d), total(d * d)
    t0, t1 = total(y), total(y * d)
    has = n > 0
    mean = t0 / jnp.where(has, n, 1.0)
    # the line's value at the node, where the pixels' spread in d determines it
    det = n * s2 - s1 * s1
    line = det > 1e-3 * jnp.square(n)
    at_node = (t0 * s2 - t1 * s1) / jnp.where(line, det, 1.0)
    value = jnp.where(line, at_node, mean)
    nodes = jnp.arange(NODES)
    before = jax.lax.cummax(jnp.where(has, nodes, -1))
    after = jax.lax.cummin(jnp.where(has, nodes, NODES), reverse=True)
    lo = jnp.where(before >= 0, before, after).clip(0, NODES - 1)
    hi = jnp.where(after < NODES, after, before).clip(0, NODES - 1)
    span = jnp.where(hi > lo, hi - lo, 1).astype(value.dtype)
    t = jnp.clip((nodes - lo) / span, 0.0, 1.0)
    return jnp.where(has, value, value[lo] + t * (value[hi] - value[lo]))


def _display_field(help: str, unit: str, range: str) -> Any:
    return parameter(None, help=f"{help}; None: the display's", unit=unit, range=range)


@register("mantiuk2008")
class Mantiuk2008(AbstractOperator):
    """Mantiuk, Daly, Kerofsky 2008 display adaptive tone mapping with pfstmo's statistics,
    solver and defaults (``pfstmo_mantiuk08``; module docstring for the equations).

    Input: linear RGB in cd/m² (absolute: the display model and the visual model are in
    cd/m²; pfstmo reads the file's values as such). Output: display-referred linear RGB,
    nominally [0, 1] (up to ``(L_max / (L_max − L_black))^{1/γ}`` at the display's peak).

    The tone curve's pixel values ``v`` are for the display model's own gamma (pfstmo
    writes them and tags its stream ``LUMINANCE=DISPLAY``: display-encoded values). As
    every hdrjax operator returns display-linear values, this one returns ``sRGB⁻¹(v)``, as
    ``mai2011`` does: encoding it for an sRGB display (:mod:`hdrjax.display`) shows ``v``,
    pfstmo's values. Colour: each channel's ratio to the luminance, raised to the
    saturation ``s`` of the curve's local slope, times the mapped luminance (pfstmo's
    colour correction).

    Display: ``display`` names one of pfstmo's predefined displays (``-d pd=NAME``:
    ``lcd_office`` γ 2.2, 100 cd/m², black 0.8 cd/m², 400 lx; ``lcd`` 2.2, 200, 0.8, 60 lx;
    ``lcd_bright`` 2.6, 500, 0.5, 10 lx; ``crt`` 2.2, 80, 1, 60 lx, reflectivity 0.02; the
    others 0.01) or ``"gog"``, pfstmo's explicit gamma–gain–offset display's defaults
    (2.2, 100, 1, 50 lx, 0.01: ``-d g=…:l=…:b=…:k=…:a=…``); ``gamma``, ``peak``, ``black``,
    ``ambient`` and ``reflectivity`` given override the named display's.

    The statistics are counts over a band-pass pyramid (:func:`conditional_density`),
    which neither merge across tiles nor come from the package's mergeable
    :class:`~hdrjax.Statistics`: with ``curve`` unset the operator measures the whole
    image (:meth:`halo` is infinite: no tiles or chunks); an operator from :meth:`measure`
    has its curve and maps tiles, chunks and frames pointwise. Gradients: with respect to
    the display, the enhancement and the scene luminance through the fixed point of the
    solver (implicit differentiation); the counts are constants; with respect to the image,
    those of each pixel's position on the curve.

    Departures from pfstmo: its ``--display-size`` has no effect in pfstools 2.2.0 (the
    statistics always use 30 pixels per degree), so there is no such parameter; its
    temporal filter of the curve (``--fps``) is for sequences, and for one frame scales
    the curve by its gain, 1 + 5e-8 (not reproduced); luminance weights are the file's
    (``weights``) instead of pfstools' sRGB matrix row; pixels of luminance 0 (or less) are
    black (pfstmo maps them to the curve at ``10^-8`` cd/m², which is black unless the
    curve does not reach the display's black, as for an all-black image).

    Attributes:
        curve: ``log10`` of the display luminance (cd/m²) at ``log10 L = −8 + 0.1 k``,
            ``k = 0 … 160``; ``None`` → solved for the image.
        display: the named display (see above).
        gamma, peak, black, ambient, reflectivity: the display model (γ; cd/m²; cd/m²;
            lux; fraction of the ambient light reflected); ``None``: the named display's.
        contrast_enhancement: factor on the scene contrasts to reproduce (pfstmo ``-e``).
        saturation: colour saturation factor (pfstmo ``-c``).
        white_y: luminance (cd/m²) of the reference white, pulled to the display's peak;
            ``None``: none (pfstmo's default for files without a ``WHITE_Y`` tag).
        scene_luminance: adaptation luminance of the scene (cd/m²); ``None``: each
            contrast's own background (pfstmo ``--scene-y-adapt auto``).
        visual_model: ``"full"``, ``"none"`` or a comma-separated subset of
            ``luminance_masking``, ``contrast_masking``, ``csf`` (pfstmo ``-m``).
        tol: the solver stops when no rise changes by more (``log10`` cd/m²; pfstmo's
            ``δ / 10``); gradients are those of the fixed point, exact as ``tol → 0``.
        weights: luminance weights of the image's primaries.
    """

    reference: ClassVar[str] = REFERENCE
    default_fit_params: ClassVar[tuple[str, ...]] = ("contrast_enhancement",)
    # pfstmo's iteration stops when the curve settles (up to 200 QP solves): frames differ
    frames_in_sequence: ClassVar[bool] = True

    curve: Array | None = parameter(
        None,
        help="log10 display luminance at log10 L = -8 + 0.1 k (k = 0..160); None: solved",
        unit="log10 cd/m2",
        range="(-inf, inf)",
        shape=(NODES,),
    )
    display: Literal["lcd", "lcd_office", "lcd_bright", "crt", "gog"] = parameter(
        "lcd",
        help="pfstmo's predefined display (gog: its explicit display's defaults)",
        static=True,
        choices=tuple(DISPLAYS),
    )
    gamma: Array | None = _display_field("display gamma", "", "(0, inf)")
    peak: Array | None = _display_field("display peak luminance L_max", "cd/m2", "(0, inf)")
    black: Array | None = _display_field("display black level", "cd/m2", "[0, inf)")
    ambient: Array | None = _display_field("ambient illuminance", "lx", "[0, inf)")
    reflectivity: Array | None = _display_field("screen reflectivity", "", "[0, 1]")
    contrast_enhancement: Array = parameter(
        1.0, help="factor on the scene contrasts to reproduce", range="(0, inf)"
    )
    saturation: Array = parameter(1.0, help="colour saturation factor", range="[0, 2]")
    white_y: Array | None = parameter(
        None,
        help="reference white pulled to the display's peak; None: none",
        unit="cd/m2",
        range="(0, inf)",
    )
    scene_luminance: Array | None = parameter(
        1000.0,
        help="adaptation luminance of the scene; None: each contrast's background",
        unit="cd/m2",
        range="(0, inf)",
    )
    visual_model: str = parameter(
        "full",
        help="full, none, or a comma list of luminance_masking, contrast_masking, csf",
        static=True,
        choices=VISUAL_MODELS,
    )
    tol: float = parameter(
        DELTA / 10,
        help="stop when no rise of the curve changes by more (pfstmo's 0.01)",
        unit="log10 cd/m2",
        range="(0, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        if self.curve is not None and self.curve.shape != (NODES,):
            raise ValueError(
                f"curve: expected {NODES} values (log10 L = -8 … 8 in steps of 0.1), got"
                f" shape {self.curve.shape}"
            )

    def display_model(self) -> Display:
        """The gamma–gain–offset display of the named display and the given values."""
        named = DISPLAYS[self.display]
        own = (self.gamma, self.peak, self.black, self.ambient, self.reflectivity)
        return Display(*(n if v is None else v for n, v in zip(named, own, strict=True)))

    def visible_distortion(
        self, hdr: Float[ArrayLike, "H W 3"], ldr: Float[ArrayLike, "H W 3"]
    ) -> Float[Array, ""]:
        """The visible contrast distortion (paper Eq. 9–10, the quantity this operator
        minimises) of any rendition ``ldr`` of the scene ``hdr`` on this operator's display.

        ``hdr``: linear RGB in cd/m²; ``ldr``: display-encoded values ``v`` in [0, 1] for the
        display model (what :mod:`hdrjax.display` writes for an sRGB display). The display
        luminance is ``L_d = Σ_c w_c v_c^γ (L_max − L_black) + L_black + k E_amb / π``; the
        rendition's curve is :func:`rendition_curve`; the statistics are the scene's
        (:func:`conditional_density`, constants); ``curve``, ``white_y`` and ``tol`` play no
        part. Squared transducer units (JND²), per counted contrast. Differentiable with
        respect to ``ldr`` and the display parameters.
        """
        rgb = jnp.asarray(hdr)
        v = jnp.clip(jnp.asarray(ldr, rgb.dtype), 0.0, 1.0)
        w = jnp.asarray(self.weights, rgb.dtype)
        finite = jnp.all(jnp.isfinite(rgb), axis=-1) & jnp.all(jnp.isfinite(v), axis=-1)
        rgb = jnp.where(finite[..., None], rgb, 0.0)
        v = jnp.where(finite[..., None], v, 0.0)
        L = rgb @ w
        disp = self.display_model()
        pos = v > 0
        lin = jnp.where(pos, jnp.power(jnp.where(pos, v, 1.0), disp.gamma), 0.0)
        L_d = (lin @ w) * (disp.peak - disp.black) + disp.offset
        valid = finite & (L > 0)
        density = conditional_density(L, valid)
        y = rendition_curve(L, L_d, valid)
        return contrast_distortion(
            y,
            density,
            enhancement=self.contrast_enhancement,
            scene_luminance=self.scene_luminance,
            visual_model=self.visual_model,
        )

    def halo(self, shape: tuple[int, ...]) -> tuple[float, float]:
        """0 once ``curve`` is set; else the whole image (infinite)."""
        del shape
        return (float("inf"), float("inf")) if self.curve is None else (0, 0)

    def _measure(self, p: Prepared) -> "Mantiuk2008":
        if self.curve is not None:
            return self
        density = conditional_density(p.L, None if p.clean else p.valid())
        y = tone_curve(
            density,
            self.display_model(),
            enhancement=self.contrast_enhancement,
            scene_luminance=self.scene_luminance,
            visual_model=self.visual_model,
            white_y=self.white_y,
            tol=self.tol,
        )
        # the display as solved for: a measured operator has every parameter set
        named = dict(
            zip(
                ("gamma", "peak", "black", "ambient", "reflectivity"),
                DISPLAYS[self.display],
                strict=True,
            )
        )
        values = {k: v for k, v in named.items() if getattr(self, k) is None}
        return fill(self, curve=y, **values)

    def _apply(self, p: Prepared) -> Array:
        assert self.curve is not None
        rgb = p.rgb
        dtype = rgb.dtype
        disp = self.display_model()
        bottom, top = disp.luminance_range()
        y_black = jnp.log10(jnp.asarray(bottom, dtype))
        y = jnp.clip(self.curve.astype(dtype), y_black, jnp.log10(top))
        slope = jnp.maximum(jnp.diff(y) / DELTA, 0.0)
        pos = slope > 0
        c = jnp.where(pos, jnp.power(jnp.where(pos, slope, 1.0), SATURATION_K2), 0.0)
        s = (1 + SATURATION_K1) * c / (1 + SATURATION_K1 * c) * self.saturation
        s = jnp.concatenate([s, jnp.ones(1, s.dtype)]).astype(dtype)
        L = jnp.maximum(p.L, L_FLOOR)
        u = (jnp.log10(L) - LOG_MIN) / DELTA
        # the curve's luminance over the display's black, L_out / L_d(0) − 1, interpolated
        # linearly in luminance as pfstmo does (exact 0 at the black: no cancellation)
        above = jnp.expm1((y - y_black) * math.log(10.0))
        e_out = jnp.log1p(table_lerp(above, u))[..., None]
        sat = table_lerp(s, u)[..., None]
        ratio = jnp.maximum(rgb / L[..., None], L_FLOOR)
        v = disp.inverse_above_black(sat * jnp.log(ratio) + e_out)
        # no light in, no light out: pfstmo maps black pixels to the curve at 1e-8, the
        # display's black (0) unless the whole curve is above it, as for an all-black image
        v = jnp.where((p.L > 0)[..., None], v, 0.0)
        return srgb_decode(v).astype(dtype)


__all__ = [
    "DISPLAYS",
    "Display",
    "Mantiuk2008",
    "conditional_density",
    "contrast_distortion",
    "rendition_curve",
    "tone_curve",
]
