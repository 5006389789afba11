"""Krawczyk, Myszkowski and Seidel 2005 lightness perception in tone reproduction: the image
decomposed into frameworks of similar luminance, each anchored to its own white (Gilchrist's
anchoring theory of lightness perception).

Reference:
    G. Krawczyk, K. Myszkowski, H.-P. Seidel. "Lightness perception in tone reproduction
    for high dynamic range images." Computer Graphics Forum 24(3):635–645 (Proceedings of
    Eurographics 2005). https://doi.org/10.1111/j.1467-8659.2005.00888.x

With ``Y = log10 L`` (``L`` the luminance, Rec. 709 weights, any units) the steps are
below. They depend on ``L`` only through differences of ``Y``, but the histograms that
carry them sit on the package's fixed grid of ``log2 L``: scaling an image by a factor other
than a power of two moves pixels across bin edges, and the clustering, which is
discontinuous, can then find other frameworks (on a 12 × 16 test image, scaling by 2^0.5
changes the result by up to 0.41). So the operator is not declared scale invariant.

1. Frameworks: K-means on the histogram of ``Y`` (256 bins from the
   image's smallest to its largest ``Y``), the centroids ``C_i`` starting one decade apart
   from the smallest ``Y``; clusters left empty are dropped and the iteration runs to its
   fixed point. Neighbouring centroids closer than ``merge_distance`` (1 decade) are
   merged (their pixel-weighted mean), the closest-to-the-bottom pair first, one pair at
   a time.
2. Probabilities: ``P_i = exp(−(C_i − Y)² / 2σ²)``, ``σ`` the largest distance between
   neighbouring centroids (the whole range of ``Y`` for one framework). A framework none
   of whose pixels (those nearest to its centroid) has a normalised probability
   ``P_i / Σ_j P_j`` above ``min_probability`` (0.6) is merged with the next one above it,
   and step 2 starts again (the last framework is never tested, as in HDR Toolbox).
3. Spatial processing: each ``P_i`` is smoothed by a bilateral filter whose range domain
   is ``P_i`` itself, spatial ``σ_s = min(H, W) / 2`` pixels and range ``σ_r =
   range_sigma`` (0.4), computed on a bilateral grid sampled at ``σ_s`` and ``σ_r``
   (Chen, Paris and Durand 2007, as HDR Toolbox's ``bilateralFilter``): every pixel added
   to the grid cell nearest to ``(y / σ_s, x / σ_s, P_i / σ_r)``, the data and the weights
   blurred by the 3 × 3 × 3 kernel ``exp(−r² / 2)``, divided, and read back by trilinear
   interpolation.
4. Articulation: ``A_i = 1 − exp(−(max Y_i − min Y_i)² / 2 σ_A²)`` with ``σ_A =
   articulation_sigma`` (0.33) over the framework's pixels; the probabilities become
   ``P_i ← A_i P̃_i / Σ_j A_j P̃_j``, so that a framework with little contrast anchors its
   pixels weakly (one with none anywhere: every ``A_i = 0``, the smoothed probabilities
   normalised as they are).
5. Anchoring: each framework's white ``W_i`` is the ``anchor_percentile`` (95th)
   percentile of ``Y`` over its pixels, and the net lightness is
   ``L(x, y) = Y − Σ_i P_i W_i``.
6. Display (HDR Toolbox's mapping of the lightness): ``L`` clamped to ``[−2, 0]`` and shown
   as ``L_d = 10^L`` (display-linear, 0.01 … 1), the colour kept: ``C_out = C L_d / L``.

Implementation. The clustering is discrete and runs on fixed-size histograms of ``Y``
(no data-dependent shapes: ``jit``, ``vmap``, each frame its own frameworks): at most
:data:`MAX_FRAMEWORKS` frameworks, unused ones masked. An image spanning more than
``MAX_FRAMEWORKS − 1`` decades starts with its centroids evenly spread over its range
instead of one decade apart. The histograms come from the package's mergeable statistics
(the fixed grid, 1024 bins per octave): the K-means histogram of step 1, the
``min_probability`` test of step 2 on one 8 times finer (the pixels at their bin's
centre), and the anchors of step 5 as histogram percentiles (a rank inside the
framework's pixels, no sort). Pixels are assigned to frameworks exactly (nearest
centroid, ties to the lower one), and the articulation uses the exact extrema.

Gradients: the centroids, ``σ``, the framework of each pixel and the histogram counts are
constants for ``jax.grad`` (a clustering has no derivative); the gradient flows through
the probabilities (``Y`` in ``P_i``, the bilateral grid's data and its trilinear read),
the articulation's extrema, the anchors (the derivative of an order statistic: that of the
pixels in the anchor's histogram bin, shared equally) and the display mapping.

Departures from HDR Toolbox's ``KrawczykTMO`` (commit 5375d05), following the paper:
``Y = log10 L`` where the toolbox takes ``log10(L + 10⁻⁶)`` in the image's units (which
ties the result to the absolute scale and puts black pixels at −6: here they take no part
and stay black); K-means runs to its fixed point, where the toolbox leaves its loop after
the first iteration that drops no cluster and does not lower the centroids' sum, often
the first one (``compat="hdrtoolbox"`` reproduces that stop); the probability test of
step 2 re-partitions the pixels after every merge. Percentiles take the nearest rank, the
``round(q n)``-th smallest value, as the toolbox does. With ``compat="hdrtoolbox"`` the
result matches the toolbox's on three real images (SSIM of the encoded luminance 1.0000);
the default finds the same frameworks on two of them and other ones on a sunset, whose
image then differs visibly (SSIM of the encoded luminance 0.93).

Pixels whose luminance is NaN, ±Inf, zero or negative take no part in the histograms, the
clustering or the bilateral grid; zero and negative ones come out black. The histograms
bin float64 luminance beyond float32's range at float32's extremes (the package's grid).
"""

import math
from typing import ClassVar, Literal

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._scale import quotient
from .._stats import Statistics, coarse_counts
from ._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    parameter,
    register,
    statistics_of,
    weights_field,
)

REFERENCE = (
    "Krawczyk, Myszkowski, Seidel 2005, Lightness perception in tone reproduction for high"
    " dynamic range images, Computer Graphics Forum 24(3):635-645 (Eurographics 2005),"
    " https://doi.org/10.1111/j.1467-8659.2005.00888.x"
)
MAX_FRAMEWORKS = 16
"""Most frameworks an image is decomposed into (the centroids' array size)."""
KMEANS_BINS = 256
"""Bins of the K-means histogram of ``log10 L`` (HDR Toolbox's)."""
KMEANS_ITERATIONS = 100
"""K-means iterations (a fixed point is reached well before on real images)."""
SUBBINS = 8
"""Bins of the finer histogram (of the ``min_probability`` test) per K-means bin."""
LIGHTNESS_RANGE = 2.0
"""Decades of lightness shown, ``[−2, 0]`` → ``[0.01, 1]`` (HDR Toolbox's)."""
GRID_PADDING = 3
"""Cells around the bilateral grid: ``floor(2 σ / sampling) + 1`` with sampling ``= σ``."""


def initial_centroids(lo: Array, hi: Array, distance: float) -> tuple[Array, Array]:
    """``(C, active)``: centroids ``distance`` apart from ``lo`` up to ``hi``, plus ``hi``
    where the last falls short (step 1); evenly spread when more than
    :data:`MAX_FRAMEWORKS` would be needed."""
    K = MAX_FRAMEWORKS
    span = hi - lo
    j = jnp.arange(K, dtype=lo.dtype)
    even = span > (K - 1) * distance  # more decades than centroids: spread evenly
    n = jnp.floor(span / distance) + 1  # centroids lo + j distance ≤ hi (≤ K when not even)
    C = jnp.where(even, lo + j * span / (K - 1), lo + j * distance)
    C = jnp.where(even & (j == K - 1), hi, C)
    extra = ~even & (j == n) & (lo + (n - 1) * distance < hi)  # hi, where the last falls short
    active = even | (j < n) | extra
    return jnp.where(active & ~extra, C, hi), active


def _nearest(C: Array, active: Array, v: Array) -> Array:
    """Index of the active centroid nearest to each ``v`` (ties: the lower one)."""
    d = jnp.abs(C[None, :] - v[:, None])
    return jnp.argmin(jnp.where(active[None, :], d, jnp.inf), axis=1)


def kmeans(
    values: Array, counts: Array, C: Array, active: Array, early_stop: bool = False
) -> tuple[Array, Array, Array]:
    """``(C, n, active)`` after :data:`KMEANS_ITERATIONS` iterations of K-means on the
    histogram (bins at ``values`` with ``counts``): each bin to its nearest centroid,
    each centroid to its bins' mean, empty clusters dropped; ``n`` the clusters' counts.

    ``early_stop``: HDR Toolbox's ``KrawczykKMeans`` stops after the first iteration that
    drops no cluster and does not lower the centroids' sum (``Σ (C_old − C_new) ≤ 0``),
    often the first one, far from the fixed point."""
    K = C.shape[0]

    def step(_, carry):
        C_old, n_old, active_old, done = carry
        near = _nearest(C_old, active_old, values)
        n = jax.ops.segment_sum(counts, near, K)
        s = jax.ops.segment_sum(counts * values, near, K)
        active = active_old & (n > 0)
        C = jnp.where(active, s / jnp.where(active, n, 1.0), C_old)
        stop = jnp.all(active == active_old) & (jnp.sum(jnp.where(active, C_old - C, 0.0)) <= 0)
        new = (C, n, active, done | (stop if early_stop else False))
        return jax.tree.map(lambda a, b: jnp.where(done, b, a), new, carry)

    init = (C, jnp.zeros_like(C), active, jnp.asarray(False))
    return jax.lax.fori_loop(0, KMEANS_ITERATIONS, step, init)[:3]


def compact(C: Array, n: Array, active: Array, top: Array) -> tuple[Array, Array, Array]:
    """The active centroids first, in their order (K-means keeps them ascending), the
    others at ``top`` with count 0, and their number ``k``."""
    K = C.shape[0]
    to = jnp.where(active, jnp.cumsum(active) - 1, K)
    C = jnp.full_like(C, top).at[to].set(C, mode="drop")
    n = jnp.zeros_like(n).at[to].set(n, mode="drop")
    return C, n, jnp.sum(active)


def _merge_at(C: Array, n: Array, k: Array, i: Array, top: Array):
    """Centroids ``i`` and ``i + 1`` merged into their count-weighted mean (compacted)."""
    K = C.shape[0]
    j = jnp.arange(K)
    nxt = jnp.minimum(i + 1, K - 1)
    tot = n[i] + n[nxt]
    merged = (C[i] * n[i] + C[nxt] * n[nxt]) / jnp.where(tot > 0, tot, 1.0)
    shifted_C = jnp.concatenate([C[1:], top[None]])
    shifted_n = jnp.concatenate([n[1:], jnp.zeros_like(n[:1])])
    C2 = jnp.where(j < i, C, jnp.where(j == i, merged, shifted_C))
    n2 = jnp.where(j < i, n, jnp.where(j == i, tot, shifted_n))
    return C2, n2, k - 1


def merge_close(C: Array, n: Array, k: Array, distance: float, top: Array):
    """Step 1's merging: while two neighbouring centroids are closer than ``distance``,
    the lowest such pair merged (compacted centroids, ``k`` active)."""
    K = C.shape[0]
    j = jnp.arange(K)

    def step(_, carry):
        C, n, k = carry
        close = (j + 1 < k) & (jnp.concatenate([C[1:], top[None]]) - C < distance)
        merged = _merge_at(C, n, k, jnp.argmax(close), top)
        return jax.tree.map(lambda a, b: jnp.where(jnp.any(close), a, b), merged, (C, n, k))

    return jax.lax.fori_loop(0, K - 1, step, (C, n, k))


def spread(C: Array, k: Array, span: Array) -> Array:
    """``σ`` of step 2: the largest gap between neighbouring active centroids, ``span``
    (the range of ``Y``) for one framework; 1 where that is 0."""
    j = jnp.arange(C.shape[0] - 1)
    gaps = jnp.where(j + 1 < k, jnp.diff(C), 0.0)
    s = jnp.where(k > 1, jnp.max(gaps), span)
    return jnp.where(s > 0, s, 1.0)


def _probabilities(C: Array, k: Array, sigma: Array, Y: Array) -> Array:
    """``exp(−(C_i − Y)² / 2σ²)`` for each ``Y`` (last axis: the frameworks), 0 for
    inactive ones."""
    lead = (1,) * Y.ndim
    on = (jnp.arange(C.shape[0]) < k).reshape(*lead, -1)
    d = C.reshape(*lead, -1) - Y[..., None]
    return jnp.where(on, jnp.exp(-jnp.square(d) / (2.0 * sigma * sigma)), 0.0)


def merge_weak(
    C: Array,
    n: Array,
    k: Array,
    values: Array,
    counts: Array,
    span: Array,
    threshold: float,
    top: Array,
):
    """Step 2's merging on the histogram (bins at ``values`` with ``counts``): while a
    framework below the last has no bin with a normalised probability above
    ``threshold``, the lowest such one merged with the next."""
    K = C.shape[0]
    j = jnp.arange(K)

    def step(_, carry):
        C, n, k = carry
        on = j < k
        P = _probabilities(C, k, spread(C, k, span), values)
        near = _nearest(C, on, values)
        own = jnp.take_along_axis(P, near[:, None], axis=1)[:, 0]
        own = own / jnp.maximum(jnp.sum(P, axis=1), jnp.finfo(P.dtype).tiny)
        mine = (near[:, None] == j[None, :]) & (counts > 0)[:, None]
        strong = jnp.any(mine & (own > threshold)[:, None], axis=0)
        weak = (j + 1 < k) & ~strong
        merged = _merge_at(C, n, k, jnp.argmax(weak), top)
        return jax.tree.map(lambda a, b: jnp.where(jnp.any(weak), a, b), merged, (C, n, k))

    return jax.lax.fori_loop(0, K - 1, step, (C, n, k))


def _blur3(x: Array, axis: int) -> Array:
    """``x`` convolved along ``axis`` with ``[e^-½, 1, e^-½]``, zeros outside."""
    e = math.exp(-0.5)
    pad = [(0, 0)] * x.ndim
    pad[axis] = (1, 1)
    p = jnp.pad(x, pad)
    n = x.shape[axis]
    take = lambda s: jax.lax.slice_in_dim(p, s, s + n, axis=axis)  # noqa: E731
    return take(1) + e * (take(0) + take(2))


def _grid_axis(size: int, sampling: float) -> tuple[np.ndarray, int, np.ndarray]:
    """For pixels ``0 … size − 1`` of one axis: the nearest cell, the number of cells and
    the (fractional) position on a grid sampled every ``sampling`` pixels and padded."""
    pos = np.arange(size) / sampling + GRID_PADDING
    cells = int(math.floor((size - 1) / sampling)) + 1 + 2 * GRID_PADDING
    return np.floor(pos + 0.5).astype(np.int32), cells, pos


def bilateral_grid(P: Array, valid: Array, sigma_s: float, sigma_r: float) -> Array:
    """Each map of ``P`` (``(H, W, K)``, values in [0, 1]) smoothed by the bilateral filter
    of step 3 (module docstring), its range domain itself; pixels not ``valid`` are left
    out of the grid."""
    H, W, K = P.shape
    dt = P.dtype
    ci, gh, yi = _grid_axis(H, sigma_s)
    cj, gw, xj = _grid_axis(W, sigma_s)
    gd = int(math.floor(1.0 / sigma_r)) + 1 + 2 * GRID_PADDING
    z = P / sigma_r + GRID_PADDING
    cz = jnp.clip(jnp.floor(jax.lax.stop_gradient(z) + 0.5), 0, gd - 1).astype(jnp.int32)
    cell = jnp.asarray((ci[:, None] * gw + cj[None, :]) * gd)[..., None]
    kk = (jnp.arange(K, dtype=jnp.int32) * (gh * gw * gd))[None, None, :]
    idx = (cell + cz + kk).reshape(-1)
    ok = jnp.broadcast_to(valid[..., None], P.shape).reshape(-1)
    size = K * gh * gw * gd
    data = jax.ops.segment_sum(jnp.where(ok, P.reshape(-1), 0.0), idx, size)
    weight = jax.ops.segment_sum(ok.astype(dt), idx, size)
    grid = jnp.stack([data, weight]).reshape(2, K, gh, gw, gd)
    for axis in (2, 3, 4):
        grid = _blur3(grid, axis)
    d, w = grid[0], grid[1]
    g = jnp.where(w > 0, d / jnp.where(w > 0, w, 1.0), 0.0).reshape(-1)
    # trilinear read at (y / σ_s, x / σ_s, P / σ_r), every position inside the padding
    i0 = np.minimum(np.floor(yi).astype(np.int32), gh - 2)
    j0 = np.minimum(np.floor(xj).astype(np.int32), gw - 2)
    fy = jnp.asarray(yi - i0, dt)[:, None, None]
    fx = jnp.asarray(xj - j0, dt)[None, :, None]
    z0 = jnp.clip(jnp.floor(jax.lax.stop_gradient(z)), 0, gd - 2).astype(jnp.int32)
    fz = z - z0.astype(dt)
    base = jnp.asarray((i0[:, None] * gw + j0[None, :]) * gd)[..., None] + kk + z0
    out = jnp.zeros_like(P)
    for a, wa in ((0, 1.0 - fy), (1, fy)):
        for b, wb in ((0, 1.0 - fx), (1, fx)):
            for c, wc in ((0, 1.0 - fz), (1, fz)):
                out = out + wa * wb * wc * g[base + (a * gw + b) * gd + c]
    return out


def _log_range(st: Statistics, dt) -> tuple[Array, Array, Array]:
    """``(lo, hi, any)``: ``log10`` of the smallest positive and the largest luminance
    (constants), and whether any pixel is positive."""
    any_pos = st.n_positive > 0
    lo = jnp.log10(jnp.where(any_pos, st.min_positive, 1.0)).astype(dt)
    hi = jnp.log10(jnp.where(any_pos, jnp.maximum(st.max, st.min_positive), 1.0)).astype(dt)
    return jax.lax.stop_gradient(lo), jax.lax.stop_gradient(hi), any_pos


def _histogram(st: Statistics, lo: Array, span: Array, n: int) -> Array:
    """Counts of the positive pixels in ``n`` equal bins of ``log10 L`` from ``lo`` over
    ``span`` (from the statistics' fixed grid)."""
    assert st.counts is not None and st.m is not None
    ln10 = math.log(10.0)
    width = jnp.where(span > 0, span, 1.0)
    return coarse_counts(st.counts, st.m, lo * ln10, width * ln10, n).astype(lo.dtype)


def frameworks(
    st: Statistics, dt, merge_distance: float, min_probability: float, early_stop: bool = False
) -> tuple[Array, Array, Array, Array]:
    """``(C, k, σ, span)``: the frameworks' centroids in ``log10`` units (ascending, the
    first ``k`` used), ``σ`` of step 2 and the range of ``log10 L``, from the statistics
    (steps 1 and 2 of the module docstring; ``early_stop``: :func:`kmeans`). Constants
    for ``jax.grad``."""
    lo, hi, _ = _log_range(st, dt)
    span = hi - lo
    top = hi
    # one histogram of SUBBINS bins per K-means bin, the last one at the maximum
    n_fine = (KMEANS_BINS - 1) * SUBBINS
    width = span / n_fine
    fine = _histogram(st, lo, width * (n_fine + 1), n_fine + 1)
    # step 1: K-means on 256 bins, each at its lower edge (bins 1/255 of the range wide)
    values = lo + span / (KMEANS_BINS - 1) * jnp.arange(KMEANS_BINS, dtype=dt)
    counts = jnp.concatenate(
        [jnp.sum(fine[:n_fine].reshape(KMEANS_BINS - 1, SUBBINS), axis=1), fine[n_fine:]]
    )
    C, active = initial_centroids(lo, hi, merge_distance)
    C, n, active = kmeans(values, counts, C, active, early_stop)
    C, n, k = compact(C, n, active, top)
    C, n, k = merge_close(C, n, k, merge_distance, top)
    # step 2 on the finer histogram, each bin at its centre
    centres = jnp.minimum(lo + width * (jnp.arange(n_fine + 1, dtype=dt) + 0.5), hi)
    C, n, k = merge_weak(C, n, k, centres, fine, span, min_probability, top)
    sigma = spread(C, k, span)
    return jax.lax.stop_gradient((C, k, sigma, span))


@register("krawczyk2005")
class Krawczyk2005(AbstractOperator):
    """Krawczyk, Myszkowski and Seidel 2005 lightness perception (module docstring), as
    HDR Toolbox's ``KrawczykTMO`` computes it where that follows the paper.

    Input: linear RGB, relative or absolute (scale invariant but for the histograms'
    binning: module docstring). Output: display-referred
    linear RGB, the luminance in ``[0.01, 1]`` (0 for black pixels); a saturated colour may
    have a channel above 1.

    Whole-image: the frameworks, their anchors and the bilateral filter's spatial scale
    (half the smaller image side) come from the whole image, so a tile needs all of it
    (:meth:`halo`).

    Attributes:
        articulation_sigma: ``σ_A`` of the articulation ``A = 1 − exp(−ΔY² / 2σ_A²)``,
            ``ΔY`` a framework's range in decades (0.33).
        range_sigma: range scale ``σ_r`` of the bilateral filter of the probability maps
            (0.4, in probability units); it sets the grid's size, so it is a setting.
        anchor_percentile: percentile of a framework's ``log10 L`` taken as its white (95).
        merge_distance: centroids closer than this (decades) are merged, and the initial
            centroids' spacing (1).
        min_probability: a framework none of whose pixels belongs to it with a higher
            probability is merged with the next (0.6).
        weights: the luminance weights (Rec. 709).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = False  # the fixed-grid histograms (module docstring)
    default_fit_params: ClassVar[tuple[str, ...]] = ("articulation_sigma",)

    articulation_sigma: Array = parameter(
        0.33,
        help="sigma of the articulation 1 - exp(-range^2 / 2 sigma^2) of a framework",
        unit="decades",
        range="(0, inf)",
    )
    range_sigma: float = parameter(
        0.4,
        help="range sigma of the bilateral filter of the probability maps",
        range="(0, 1]",
        static=True,
    )
    anchor_percentile: float = parameter(
        95.0,
        help="percentile of a framework's log luminance taken as its white",
        unit="%",
        range="[0, 100]",
        static=True,
    )
    merge_distance: float = parameter(
        1.0,
        help="centroids closer than this are merged (and the initial spacing)",
        unit="decades",
        range="(0, inf)",
        static=True,
    )
    min_probability: float = parameter(
        0.6,
        help="a framework with no pixel above this probability is merged with the next",
        range="[0, 1)",
        static=True,
    )
    compat: Literal["paper", "hdrtoolbox"] = parameter(
        "paper",
        help="paper: K-means to its fixed point; hdrtoolbox: KrawczykTMO's early stop",
        static=True,
        choices=("paper", "hdrtoolbox"),
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        if not 0 < self.range_sigma <= 1:
            raise ValueError(f"range_sigma: expected a value in (0, 1], got {self.range_sigma!r}")
        if not 0 <= self.anchor_percentile <= 100:
            raise ValueError(
                f"anchor_percentile: expected a value in [0, 100], got {self.anchor_percentile!r}"
            )
        if not self.merge_distance > 0:
            raise ValueError(
                f"merge_distance: expected a value in (0, inf), got {self.merge_distance!r}"
            )
        if not 0 <= self.min_probability < 1:
            raise ValueError(
                f"min_probability: expected a value in [0, 1), got {self.min_probability!r}"
            )

    def halo(self, shape: tuple[int, ...]) -> tuple[int, int]:
        """Half the image per axis: every window is the whole image (whole-image
        statistics and a spatial scale of half the smaller side)."""
        return -(-int(shape[0]) // 2), -(-int(shape[1]) // 2)

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings()

    def _apply(self, p: Prepared) -> Array:
        dt = p.rgb.dtype
        K = MAX_FRAMEWORKS
        st = statistics_of(p, self.statistics_settings())
        assert st is not None and st.counts is not None and st.m is not None
        C, k, sigma, _ = frameworks(
            st,
            dt,
            float(self.merge_distance),
            float(self.min_probability),
            early_stop=self.compat == "hdrtoolbox",
        )
        L = p.L
        pos = (L >= jnp.finfo(dt).tiny) & (L <= jnp.finfo(dt).max)
        if not p.clean:
            pos = pos & p.valid()
        Y = jnp.log10(jnp.where(pos, L, 1.0))
        # each pixel's framework: the nearest centroid (ties to the lower); others: K
        on = jnp.arange(K) < k
        bounds = jnp.where(jnp.arange(K) + 1 < k, 0.5 * (C + jnp.roll(C, -1)), jnp.inf)
        idx = jnp.sum(jax.lax.stop_gradient(Y)[..., None] > bounds[None, None, :], axis=-1)
        idx = jnp.where(pos, idx, K).reshape(-1)
        Yf = Y.reshape(-1)
        n_i = jax.ops.segment_sum(jnp.ones_like(Yf), idx, K + 1)[:K]
        present = on & (n_i > 0)
        # articulation from the exact extrema of each framework's Y
        y_max = jax.ops.segment_max(Yf, idx, K + 1)[:K]
        y_min = jax.ops.segment_min(Yf, idx, K + 1)[:K]
        dY = jnp.where(present, y_max - y_min, 0.0)
        s_A = self.articulation_sigma.astype(dt)
        A = jnp.where(present, -jnp.expm1(-jnp.square(dY) / (2.0 * s_A * s_A)), 0.0)
        A = jnp.where(jnp.any(A > 0), A, present.astype(dt))
        # anchors: the percentile of each framework's pixels, a rank among all of them
        W = self._anchors(st, Yf, idx, n_i, present)
        # probabilities, smoothed, weighted by articulation
        sigma_s = min(L.shape[-2:]) / 2.0
        P = _probabilities(C, k, sigma, Y)
        P = bilateral_grid(P, pos, sigma_s, float(self.range_sigma))
        w = P * A[None, None, :]
        total = jnp.sum(w, axis=-1, keepdims=True)
        ok = total > 0
        P = jnp.where(
            ok, w / jnp.where(ok, total, 1.0), jax.nn.one_hot(idx.reshape(L.shape), K, dtype=dt)
        )
        lightness = Y - jnp.sum(P * W[None, None, :], axis=-1)
        Ld = jnp.power(10.0, jnp.clip(lightness, -LIGHTNESS_RANGE, 0.0)).astype(dt)
        ratio = quotient(p.rgb, jnp.where(pos, L, 1.0)[..., None])
        return jnp.where(pos[..., None], ratio * Ld[..., None], 0.0)

    def _anchors(self, st: Statistics, Yf: Array, idx: Array, n_i: Array, present: Array):
        """Each framework's white ``W_i`` (``log10``): the ``anchor_percentile`` of its
        pixels, from the histogram, with the derivative shared by the pixels of its bin."""
        dt = Yf.dtype
        K = MAX_FRAMEWORKS
        q = self.anchor_percentile / 100.0
        below = jnp.cumsum(n_i) - n_i
        n_all = jnp.maximum(st.n_positive - 1, 1).astype(dt)
        # nearest rank (HDR Toolbox's): the round(q n)-th smallest, counting from 1
        rank = below + jnp.maximum(jnp.round(q * n_i), 1.0) - 1.0
        value, _ = st.quantile(jnp.clip(rank / n_all, 0.0, 1.0))
        W = jax.lax.stop_gradient(jnp.log10(jnp.where(present & (value > 0), value, 1.0)))
        W = W.astype(dt)
        # straight-through derivative of the order statistic
        width = float(np.log1p(2.0**-st.m) / math.log(10.0))  # a grid bin, decades
        Wp = jnp.concatenate([W, jnp.zeros((1,), dt)])[idx]
        hit = (idx < K) & (jnp.abs(jax.lax.stop_gradient(Yf) - Wp) <= width)
        cnt = jax.ops.segment_sum(hit.astype(dt), idx, K + 1)[:K]
        tang = jax.ops.segment_sum(jnp.where(hit, Yf - jax.lax.stop_gradient(Yf), 0.0), idx, K + 1)[
            :K
        ]
        return W + jnp.where(cnt > 0, tang / jnp.where(cnt > 0, cnt, 1.0), 0.0)


__all__ = ["Krawczyk2005", "bilateral_grid", "frameworks"]
