"""Light-source detection in environment maps after Loghin (2019), vectorised in JAX.

Reference:
    D.-A. Loghin, "Detection of light sources from environment maps", 2019,
    http://alinloghin.com/articles/env_lights.html (with Python listings).

Numeric contract: input is linear RGB (relative or absolute; LDR maps in [0, 1] are
treated as linear), channels last, any float dtype (float16 is computed in float32).
Pixels with a NaN/±Inf channel are excluded (zero), negative values are clamped to zero.
Outputs are float32, or float64 for float64 input under x64; none is NaN.

Pipeline (the paper's steps 1–9; every step a fixed-shape array operation: no Python loop over
samples or pixels, three compiled calls — see ``_run`` for why three):

1. **Reduce** the map to at most ``width`` columns: box average by the smallest integer
   factor (keeps each light's energy; the largest input luminance of each block is kept
   too, for the peak), bilinear when the size is not a multiple.
2. **Luminance** (:func:`hdrjax.luminance`), optionally a separable Gaussian **blur** of
   ``blur`` pixels (wrapping across the seam; off by default, see below).
3–4. **Hammersley** samples: ``n_samples`` points uniform on the sphere (the paper's
   ``sphereSample``; Halton points on a plain image), mapped to pixels.
5. **Neighbourhood maximum**: each sample searches a window (radius 0.75 × the sample
   spacing, so the windows cover the sphere; on the sphere its columns span the same
   angle at every latitude, and it wraps across the seam and the poles) on a 2×2
   max-pooled image. A sample is a candidate when the window's maximum exceeds the
   threshold ``T``; the candidate moves to that local maximum.
6. **Sort** candidates by luminance (``lax.top_k``, at most ``max_candidates``).
7. **Euclidean filter**: the paper's greedy pass (a candidate joins the first brighter kept
   one within the window radius) as a fixed-point iteration on the candidate distance
   matrix; distances are angles on the sphere, so the seam is no border.
8. **Bresenham merge**: between every pair of kept candidates a fixed number of pixels
   along the (seam-wrapped) line is read and the listing's running-mean test applied:
   on an HDR map the listing's ``|mean − lum(start)| > 0.15 and mean < 1`` reduces to
   "the running mean of ``min(lum, 1.25)`` drops below 1"; here the same with luminance in
   units of ``T``. The greedy merge (a candidate joins the first brighter light whose seed
   passes the test) is again a fixed-point iteration, and only merges within
   ``max_radius`` degrees (the paper's suggested distance limit).
9. **Light position and area** (the paper's suggested extension): each light grows from
   its merged local maxima over the 8-connected pixels above ``T``, in a window of
   ``±max_radius`` rows and twice that many columns (so ``max_radius`` in angle up to 60°
   elevation) around the mean of its samples' local maxima, across the seam and poles;
   where two lights reach the same pixel the geodesically nearer (then brighter) keeps it.
   The pixels give the label image, energy, solid angle, colour, the direction (the
   energy-weighted mean of the pixels' unit vectors: the paper's luminance-weighted
   position, on the sphere) and the pixel position (the same mean in image coordinates).

Deviations from the listing, and why: its fixed threshold 0.8 is for LDR maps; here it is
relative to the map (below). The listing keeps each sample at its own pixel; here it moves
to its window's maximum, so a light smaller than the sample spacing is placed on its peak,
not on whichever sample saw it. The incremental position blend of the listing becomes the
energy centroid of the light's pixels. Its undefined helpers (``computeNeighborLuminance``,
``euclideanThresholdPixel``) get the window meaning above. The blur defaults to 0: after a
box reduction there is no aliasing to remove, a blurred mask spreads beyond the light
(into sky around the sun), and on the real maps blur 1 missed more lamps and cost ~1.5 ms
(``benchmarks/bench_lights.py``).

Automatic threshold (``threshold=None``), from the samples' median luminance ``m`` (the
samples are uniform on the sphere: a solid-angle median) and the largest input luminance
``M``: ``T = min(max(50 m, 0.02 M), 0.8 M)``. The first term is hdrjax's own definition
of a bright blob (50 times the median, or 2 % of the maximum where that is higher); the cap
reproduces the 0.8 of Loghin's listing on LDR maps whose maximum is 1. A map with
``T < 2 m`` (black, constant, no contrast) has no light (``T = inf``).

Known limits: within about ``max_radius`` of a pole a light spans more columns than its
mask window, so its mask, energy and size are cut (its direction stays within a few
degrees; ``tests/lights/test_detect.py``); a light larger than ``max_radius`` (or a
flat-topped one whose brightest local maximum is on its rim) becomes several lights; at
most ``max_lights`` lights, ``max_candidates`` candidates and ``4 max_lights`` kept
candidates (``truncated`` says when a cap was hit).

Speed (XLA:CPU; every choice keeps the results of the plain formulation: counts, labels
and samples bit for bit on the test and benchmark maps, the light statistics up to float
rounding of reordered sums): the window maximum of step 5 is separable (a column-wise
maximum over the window's rows, computed once per map, then one value per window column
and sample); step 8 tests only the pairs ``i < j`` the greedy merge reads; step 9 reads
each light-window row as one slice (rows across the seam from a strip of the columns
around it, no padded copy of the map), grows the masks bit-packed (32 rows to a word;
a single map stores each step's mask instead of counting steps: :func:`_grow`),
resolves pixels two lights reach by a scatter-min of window rows (the seam columns
folded in place), sums each light's
statistics along the window rows by one matrix product (per-column weights: 1, the
column offset, cos/sin of the azimuth offset) and then over the rows, and writes the
label image by a scatter of each light's owned pixels; the median of the automatic
threshold sorts the luminances' bit patterns as integers. A single map (no batch axis)
is not vmapped, so that steps 8 and 9 branch on the data: with at most ``SMALL_REPS``
kept candidates or ``SMALL_LIGHTS`` lights (most maps) they run on those sizes only.
"""

import dataclasses
import functools
import math
from collections.abc import Callable, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._colour import luminance
from .._scale import inverse_pow2
from .._stats import accurate_sum
from ._result import Lights
from ._sequences import halton_np, sphere_directions_np
from ._working_map import (
    flatten_batch,
    flatten_batch_float,
    image_shape,
    weights_key,
    working_rgb,
    working_size,
)

DEFAULT_WIDTH = 512
"""Working width (pixels): see the accuracy/time table in the README (``benchmarks/``)."""
DEFAULT_SAMPLES_PER_PIXEL = 0.006
"""The listing's ``samplesMultiplier``: samples per working-resolution pixel."""
DEFAULT_BLUR = 0.0
"""Gaussian blur sigma in working-resolution pixels (the paper suggests 1–2 px at 1024)."""
DEFAULT_MAX_RADIUS = 10.0
"""Largest light radius in degrees: merge distance limit and mask window."""
DEFAULT_MAX_LIGHTS = 32

LINE_TOLERANCE = 0.0
"""How far below ``T`` the line test's running mean may drop. The listing's 0.15 only acts
when the start pixel is below 1.15 (LDR); on HDR maps its test is "mean ≥ 1", i.e. 0."""
LINE_CLAMP = 1.25
"""The listing's ``min(lum, 1.25)``, in units of ``T``."""
AUTO_MEDIAN_FACTOR = 50.0
AUTO_PEAK_FACTOR = 0.02
LDR_FACTOR = 0.8
"""The listing's fixed threshold, as a fraction of the maximum (cap of the automatic one)."""
MIN_CONTRAST = 2.0
SMALL_REPS = 32
"""Kept candidates up to which a single map's line test reads only the first ones."""
SMALL_LIGHTS = 8
"""Lights up to which a single map's step 9 looks at only the first ones."""


@dataclasses.dataclass(frozen=True)
class _Plan:
    """Everything static about one detection: shapes, counts, radii (hashable)."""

    sphere: bool
    in_h: int
    in_w: int
    factor: int  # integer box factor; 0 means resize to (h, w)
    h: int
    w: int
    n_samples: int
    window: int  # sample window radius in pixels (rows; columns scale with 1/cos(el))
    blur: float
    nms_cos: float  # sphere: cos of the Euclidean-filter angle; plane: squared pixels
    merge_cos: float  # sphere: cos of max_radius; plane: squared pixels
    radius: int  # mask window radius (rows), pixels
    radius_x: int  # mask window radius (columns), pixels
    line_points: int
    max_candidates: int
    max_reps: int
    max_lights: int
    weights: tuple[float, float, float] | None


def _plan(
    sphere: bool,
    in_h: int,
    in_w: int,
    *,
    width: int,
    n_samples: int | None,
    blur: float,
    max_radius: float,
    max_lights: int,
    max_candidates: int | None,
    weights: Sequence[float] | None,
) -> _Plan:
    if not (math.isfinite(blur) and blur >= 0):
        raise ValueError(f"blur: expected a finite number >= 0, got {blur!r}")
    if not (math.isfinite(max_radius) and max_radius > 0):
        raise ValueError(f"max_radius: expected a finite number > 0, got {max_radius!r}")
    if int(max_lights) != max_lights or max_lights < 1:
        raise ValueError(f"max_lights: expected an integer >= 1, got {max_lights!r}")
    factor, h, w = working_size(in_h, in_w, width)
    if n_samples is None:
        n = max(64, round(DEFAULT_SAMPLES_PER_PIXEL * w * h))
    else:
        if int(n_samples) != n_samples or n_samples < 1:
            raise ValueError(f"n_samples: expected an integer >= 1, got {n_samples!r}")
        n = int(n_samples)
    if sphere:
        spacing = math.sqrt(4 * math.pi / n) * w / (2 * math.pi)
        radius = math.ceil(math.radians(max_radius) * w / (2 * math.pi))
        radius = max(1, min(radius, (w // 2 - 2) // 2, h - 1))
    else:
        spacing = math.sqrt(w * h / n)
        radius = max(1, min(math.ceil(max_radius), (min(w, h) - 1) // 2))
    window = max(1, min(math.ceil(0.75 * spacing), (min(w // 2, h) - 1) // 2))
    if sphere:
        nms = math.cos(window * 2 * math.pi / w)
        merge = math.cos(math.radians(min(max_radius, 180.0)))
    else:
        nms, merge = float(window * window), float(radius * radius)
    if max_candidates is not None and (int(max_candidates) != max_candidates or max_candidates < 1):
        raise ValueError(f"max_candidates: expected an integer >= 1, got {max_candidates!r}")
    c = min(n, int(max_candidates) if max_candidates else max(256, 8 * int(max_lights)))
    return _Plan(
        sphere=sphere,
        in_h=in_h,
        in_w=in_w,
        factor=factor,
        h=h,
        w=w,
        n_samples=n,
        window=window,
        blur=float(blur),
        nms_cos=nms,
        merge_cos=merge,
        radius=radius,
        radius_x=max(1, min(2 * radius, (w // 2 - 2) // 2)) if sphere else radius,
        line_points=max(4, radius + 1),
        max_candidates=c,
        max_reps=min(c, 4 * int(max_lights)),
        max_lights=int(max_lights),
        weights=weights_key(weights),
    )


_cached_plan = functools.lru_cache(maxsize=64)(_plan)


# ----------------------------------------------------------------------------- geometry


def _row_geometry(h: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """cos(el), sin(el) at row centres and each row's solid angle per pixel column (×W)."""
    el = np.pi * (0.5 - (np.arange(h) + 0.5) / h)
    theta = np.pi * np.arange(h + 1) / h
    band = np.cos(theta[:-1]) - np.cos(theta[1:])  # exact band area / (2π)
    return np.cos(el), np.sin(el), band * 2 * np.pi


def _col_geometry(w: int) -> tuple[np.ndarray, np.ndarray]:
    az = 2 * np.pi * ((np.arange(w) + 0.5) / w - 0.5)
    return np.cos(az), np.sin(az)


def _sample_pixels(plan: _Plan) -> tuple[np.ndarray, np.ndarray]:
    if plan.sphere:
        d = sphere_directions_np(plan.n_samples)  # z = cos θ is up
        u = np.arctan2(d[:, 1], d[:, 0]) / (2 * np.pi) + 0.5
        v = 0.5 - np.arcsin(np.clip(d[:, 2], -1, 1)) / np.pi
    else:
        u, v = halton_np(plan.n_samples, 2).T
    sx = np.clip(np.floor(u * plan.w), 0, plan.w - 1).astype(np.int64)
    sy = np.clip(np.floor(v * plan.h), 0, plan.h - 1).astype(np.int64)
    return sx, sy


def _wrap_np(x: np.ndarray, y: np.ndarray, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
    """Equirectangular neighbours: rows past a pole come back on the opposite meridian."""
    top, bottom = y < 0, y >= h
    y = np.where(top, -y - 1, np.where(bottom, 2 * h - 1 - y, y))
    x = np.where(top | bottom, x + w // 2, x)
    return np.mod(x, w), y


def _pool_factor(plan: _Plan) -> int:
    """The neighbourhood search runs on a 2×2 max-pooled image when the shape allows."""
    ok = plan.h % 2 == 0 and plan.w % (4 if plan.sphere else 2) == 0 and plan.window >= 4
    return 2 if ok else 1


def _search_columns(plan: _Plan) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Every sample's window columns in the pooled image ``(N, 2 kmax + 1)``, the samples'
    pixels, and the window's half-height ``rr`` in pooled rows.

    A window spans ``±window`` pixels in rows. On the sphere its columns span
    ``±window / cos(el)`` pixels (the same angle as at the equator; at most half the
    row), read every ``1 / cos(el)`` pixels — one equator pixel in angle — or sparser
    where more than ``2 × ceil(window / 2)`` steps per side would be needed (within ~15°
    of the poles). The search runs on the 2×2 max-pooled image: offsets are in cells of
    2 pixels. Rows past a pole continue on the opposite meridian (:func:`_search_image`
    builds them); the columns here are those of the sample's own row.
    """
    sx, sy = _sample_pixels(plan)
    q = _pool_factor(plan)
    w = plan.w // q
    rr = -(-plan.window // q)  # window radius in cells (rows)
    kmax = 2 * rr if plan.sphere else rr  # column steps per side
    if plan.sphere:
        ce = np.maximum(np.cos(np.pi * (0.5 - (sy + 0.5) / plan.h)), 1e-6)
        ext = np.minimum(np.ceil(plan.window / ce / q), (w - 1) // 2).astype(np.int64)
        step = np.maximum(1, np.round(1.0 / (q * ce))).astype(np.int64)
        step = np.maximum(step, -(-ext // kmax))
        k = -(-ext // step)  # this sample's steps per side
    else:
        step = np.ones_like(sx)
        k = np.full_like(sx, rr)
    cols = np.arange(-kmax, kmax + 1)[None, :]
    cx = (sx // q)[:, None] + np.clip(cols, -k[:, None], k[:, None]) * step[:, None]
    cx = np.mod(cx, w) if plan.sphere else np.clip(cx, 0, w - 1)
    return cx.astype(np.int32), sx, sy, rr


def _window_indices(plan: _Plan) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Flat indices into the pooled image of every sample's whole window ``(N, k)``, in
    the order the search's first maximum refers to (columns, then rows), and the samples'
    pixels: the cells :func:`_search_columns` and :func:`_search_image` cover (tests)."""
    cols, sx, sy, rr = _search_columns(plan)
    q = _pool_factor(plan)
    h, w = plan.h // q, plan.w // q
    rows = np.arange(-rr, rr + 1)
    cx = np.repeat(cols, rows.size, axis=1)
    cy = (sy // q)[:, None] + np.tile(rows, cols.shape[1])[None, :]
    if plan.sphere:
        cx, cy = _wrap_np(cx, cy, w, h)
    else:
        cy = np.clip(cy, 0, h - 1)
    return (cy * w + cx).astype(np.int32), sx, sy


def _search_image(pooled: Array, rr: int, sphere: bool) -> tuple[Array, Array]:
    """Column-wise maximum over each window's ``2 rr + 1`` rows, and the first row offset
    that holds it.

    ``E`` is the pooled image extended by ``rr`` rows past each pole (on the sphere: the
    rows next to the pole on the opposite meridian, as :func:`_wrap_np`; on a plane: the
    edge rows); ``V[y, x] = max_i E[y + i, x]`` for ``i = 0 … 2 rr``, ``I`` the smallest
    such ``i``. The window search then reads one value per window column instead of the
    whole window (the window maximum and its first position in column-major order are
    unchanged).
    """
    h, w = pooled.shape
    if sphere:
        flip = jnp.roll(pooled, -(w // 2), axis=1)  # flip[y, x] = pooled[y, (x + w/2) mod w]
        E = jnp.concatenate([flip[:rr][::-1], pooled, flip[h - rr :][::-1]], axis=0)
    else:
        E = jnp.concatenate(
            [jnp.repeat(pooled[:1], rr, 0), pooled, jnp.repeat(pooled[-1:], rr, 0)], axis=0
        )
    V, I = E[:h], jnp.zeros((h, w), jnp.int32)
    for i in range(1, 2 * rr + 1):
        up = E[i : i + h] > V
        V, I = jnp.where(up, E[i : i + h], V), jnp.where(up, jnp.int32(i), I)
    return V, I


# ----------------------------------------------------------------------------- image ops


def _blur(L: Array, sigma: float, wrap: bool) -> Array:
    """Separable Gaussian (truncated at 2σ, renormalised over the taps inside the image);
    columns wrap on the sphere.

    The horizontal pass runs on the transpose: XLA:CPU does shifted row slices much
    faster than shifted column slices (1.3 ms vs 2.1 ms at 1024×512).
    """
    if sigma <= 0:
        return L
    r = max(1, math.ceil(2 * sigma))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k = k / k.sum()

    def along_rows(x: Array, wrap_rows: bool) -> Array:
        n = x.shape[0]
        if wrap_rows:
            p = jnp.concatenate([x[n - r :], x, x[:r]], axis=0)
            return sum(float(k[i]) * p[i : i + n] for i in range(2 * r + 1))
        p = jnp.pad(x, ((r, r), (0, 0)))
        inside = np.convolve(np.ones(n), k, mode="same")  # tap weight inside the image
        out = sum(float(k[i]) * p[i : i + n] for i in range(2 * r + 1))
        return out * jnp.asarray(1.0 / inside, x.dtype)[:, None]

    return along_rows(along_rows(L, False).T, wrap).T


def _grow(filled: Array, above: Array, limit: int, history: bool = False) -> tuple[Array, Array]:
    """Grow ``filled`` over the 8-connected pixels of ``above`` (both ``(..., Y, X)``
    bool), one ring per step, for at most ``limit`` steps; also each filled pixel's step
    (its geodesic distance from the start, in pixels).

    The masks are bit-packed, 32 rows to a ``uint32`` word, so a step is a few word
    operations on ``(..., ceil(Y / 32), X)`` arrays (on booleans each step cost ~100 µs
    on XLA:CPU and large lights take 25+ steps). The distance is
    ``dist(p) = #{steps whose start had p unfilled}``, kept as a bit-sliced counter (one
    word array per bit); the first up to 31 steps (most lights stop there) count with 5
    planes, the rest with all ``bit_length(limit)``.

    ``history`` (not under ``vmap``: the step index would be batched): the first 31 steps
    store their start masks ``S_i`` in a stack instead of counting (one in-place update per
    step instead of the counter's 5 planes and their copies). The masks grow, so
    ``count(p) ≥ m ⟺ p ∉ S_{m−1}``, and the 5 counter planes follow after the loop by a
    binary search, most significant bit first (``S_15``, then ``S_7``/``S_23``, …; slots of
    steps not run are all ones). Same results.
    """
    ny = above.shape[-2]
    nw = -(-ny // 32)
    bits = max(1, int(limit).bit_length())
    pad = [(0, 0)] * (above.ndim - 2) + [(0, nw * 32 - ny), (0, 0)]
    lead = (1,) * (above.ndim - 2)

    def pack(x: Array) -> Array:
        # an unrolled OR of shifted rows (a sum over the bit axis ran ~5x slower)
        x = jnp.pad(x, pad).astype(jnp.uint32)
        words = [
            functools.reduce(
                jnp.bitwise_or, [x[..., 32 * w + i, :] << jnp.uint32(i) for i in range(32)]
            )
            for w in range(nw)
        ]
        return jnp.stack(words, axis=-2)

    def dilate(m: Array) -> Array:
        zero = jnp.zeros_like(m[..., :1, :])
        up = (m << 1) | jnp.concatenate([zero, m[..., :-1, :] >> 31], axis=-2)
        down = (m >> 1) | (jnp.concatenate([m[..., 1:, :], zero], axis=-2) << 31)
        v = m | up | down
        zcol = jnp.zeros_like(v[..., :1])
        return (
            v
            | jnp.concatenate([zcol, v[..., :-1]], axis=-1)
            | jnp.concatenate([v[..., 1:], zcol], axis=-1)
        )

    def ring(fill: Array) -> tuple[Array, Array]:
        new = above_p & dilate(fill) & ~fill
        return fill | new, jnp.max(new) != 0

    def step(state: tuple[Array, tuple[Array, ...], Array, Array]) -> Any:
        fill, count, i, _ = state
        carry, planes = ~fill, []
        for c in count:
            planes.append(c ^ carry)
            carry = c & carry
        fill, more = ring(fill)
        return fill, tuple(planes), i + 1, more

    above_p = pack(above)
    zeros = jnp.zeros_like(above_p)
    b1 = min(bits, 5)
    n1 = min(limit, 2**b1 - 1)  # steps of the first loop
    if history:

        def store(state: tuple[Array, Array, Array, Array]) -> Any:
            fill, hist, i, _ = state
            hist = jax.lax.dynamic_update_index_in_dim(hist, fill, i, 0)
            fill, more = ring(fill)
            return fill, hist, i + 1, more

        ones = jnp.full((2**b1 - 1,) + above_p.shape, 0xFFFFFFFF, jnp.uint32)
        state = (pack(filled), ones, jnp.int32(0), jnp.bool_(True))
        fill, hist, i, more = jax.lax.while_loop(lambda s: s[3] & (s[2] < n1), store, state)
        # binary search: bit b of the count from S[base + 2^b − 1], base = the higher bits
        count: list[Array] = []
        for b in range(b1 - 1, -1, -1):
            opts = [~hist[j + 2**b - 1] for j in range(0, 2**b1 - 1, 2 ** (b + 1))]
            for sel in count:  # count[0]: the least significant known bit, picks first
                opts = [
                    (sel & hi) | (~sel & lo) for lo, hi in zip(opts[0::2], opts[1::2], strict=True)
                ]
            count.insert(0, opts[0])
        state = (fill, tuple(count), i, more)
    else:
        state = (pack(filled), (zeros,) * b1, jnp.int32(0), jnp.bool_(True))
        state = jax.lax.while_loop(lambda s: s[3] & (s[2] < n1), step, state)
    if b1 < bits:  # more steps, with all planes
        fill, counted, i, more = state
        state = (fill, counted + (zeros,) * (bits - b1), i, more)
        state = jax.lax.while_loop(lambda s: s[3] & (s[2] < limit), step, state)
    fill, counted, _, _ = state
    # unpack: row y is bit y % 32 of word y // 32
    rows = np.arange(ny)
    word = jnp.asarray(rows // 32)
    bit = jnp.asarray(rows % 32, jnp.uint32).reshape(lead + (ny, 1))

    def unpack(m: Array) -> Array:
        return (m[..., word, :] >> bit) & 1

    dist = sum(unpack(c).astype(jnp.int32) << b for b, c in enumerate(counted))
    return unpack(fill).astype(bool), dist


# ----------------------------------------------------------------------------- clustering


def _leaders(adj: Array, valid: Array) -> Array:
    """Greedy leader clustering in index order, as a fixed point.

    ``adj[i, j]`` (only used for ``i < j``) says ``j`` may join ``i``. Item ``j`` leads
    when it is valid and no earlier leader may take it: the paper's sequential loops. The
    iteration ``lead ← valid ∧ ¬(adjᵀ lead)`` fixes one more prefix item per step and stops
    at the unique fixed point (usually after a few steps).
    """
    n = valid.shape[0]
    upper = jnp.triu(jnp.ones((n, n), bool), 1)
    adj = adj & upper

    def step(state: tuple[Array, Array]) -> tuple[Array, Array]:
        lead, _ = state
        return valid & ~jnp.any(adj & lead[:, None], axis=0), lead

    lead, _ = jax.lax.while_loop(lambda s: jnp.any(s[0] != s[1]), step, (valid, ~valid))
    return lead


def _owner(adj: Array, lead: Array, valid: Array) -> Array:
    """Index of the first leader that takes each item (itself for a leader; −1 if invalid).

    The first index as a min-reduction (an argmax over booleans is a two-value reduction
    that XLA:CPU runs several times slower)."""
    n = valid.shape[0]
    idx = jnp.arange(n, dtype=jnp.int32)
    takes = lead[:, None] & ((adj & (idx[:, None] < idx[None, :])) | jnp.eye(n, dtype=bool))
    first = jnp.min(jnp.where(takes, idx[:, None], n), axis=0)
    return jnp.where(valid & (first < n), first, -1)


def _compact(mask: Array, size: int) -> tuple[Array, Array, Array]:
    """Positions of the first ``size`` True entries, a validity mask, and each entry's rank."""
    rank = jnp.cumsum(mask) - 1
    slot = jnp.where(mask & (rank < size), rank, size)
    pos = (
        jnp.zeros(size, jnp.int32)
        .at[slot]
        .set(jnp.arange(mask.shape[0], dtype=jnp.int32), mode="drop")
    )
    return pos, jnp.arange(size) < jnp.sum(mask), jnp.where(mask, rank, -1)


# ----------------------------------------------------------------------------- the pipeline


def _median(x: Array) -> Array:
    """``jnp.median`` of a 1-D array of luminances (≥ 0, no NaN): the mean of the order
    statistics ``⌊(n−1)/2⌋`` and ``⌈(n−1)/2⌉``.

    Sorted as integers: the bit patterns of floats ≥ 0 are ordered as their values (−0
    is mapped to +0), and XLA:CPU sorts integers ~3x faster than floats (its float sort
    and ``lax.top_k`` use a NaN-aware comparator)."""
    n = x.shape[0]
    it = {4: jnp.int32, 8: jnp.int64}[x.dtype.itemsize]
    keys = jnp.sort(jnp.maximum(jax.lax.bitcast_convert_type(x, it), 0))
    lo, hi = (jax.lax.bitcast_convert_type(keys[i], x.dtype) for i in ((n - 1) // 2, n // 2))
    return (lo + hi) * 0.5


def _threshold(top: Array, sample_vals: Array, thr: Array) -> Array:
    """The user's threshold, or the automatic one (module docstring); ``inf`` = no light.
    ``top`` is the largest input luminance ``M``."""
    med = _median(sample_vals)
    auto = jnp.maximum(AUTO_MEDIAN_FACTOR * med, AUTO_PEAK_FACTOR * top)
    auto = jnp.minimum(auto, LDR_FACTOR * top)
    auto = jnp.where((top > 0) & (auto > 0) & (auto >= MIN_CONTRAST * med), auto, jnp.inf)
    user = jnp.where(thr > 0, thr, jnp.inf)
    return jnp.where(jnp.isnan(thr), auto, user).astype(top.dtype)


def _prepare(rgb: Array, plan: _Plan) -> tuple[Array, Array]:
    return working_rgb(rgb, plan.factor, (plan.h, plan.w), plan.weights)


def _domega(plan: _Plan) -> np.ndarray:
    """Solid angle of one pixel of each working row (sr; 1 on a plane: energy = ∑ L)."""
    return _row_geometry(plan.h)[2] / plan.w if plan.sphere else np.ones(plan.h)


def _total_exp(plan: _Plan) -> int:
    """``k`` with ``2^k`` ≥ the map's ∑ dω (4π on the sphere, the pixel count on a plane)."""
    return max(int(np.ceil(np.log2(plan.w * _domega(plan).sum()))), 0)


def _smooth(rgb_w: Array, L_peak: Array, plan: _Plan) -> dict[str, Array]:
    """Step 2 and the per-pixel passes over the map that need no threshold, materialised
    once (a call boundary: fused into their consumers they were recomputed per read):

    - ``L``, ``Lb``: the luminance and its blur (samples, 2×2 blocks, line test); ``Lb``
      only when blurred (else it is ``L``: a second output of one image is a copy);
    - ``V``, ``I``: the column-wise window maximum of the 2×2 max-pooled ``Lb``
      (:func:`_search_image`);
    - ``strips``: each channel step 9 reads (``L``, RGB, the peak luminance, ``Lb`` when
      blurred) at the ``2n`` columns around the seam (:func:`_windows`);
    - ``total``: ∑ L dω of the map, ``top``: its largest input luminance.
    """
    L = jnp.maximum(luminance(rgb_w, plan.weights), 0)
    Lb = _blur(L, plan.blur, plan.sphere)
    if _pool_factor(plan) == 2:
        rows = jnp.maximum(Lb[0::2], Lb[1::2])
        pooled = jnp.maximum(rows[:, 0::2], rows[:, 1::2])
    else:
        pooled = Lb
    V, I = _search_image(pooled, _search_columns(plan)[3], plan.sphere)
    n = 2 * plan.radius_x + 1
    chans = dict(L=L, rgb=rgb_w, peak=L_peak) | (dict(Lb=Lb) if plan.blur > 0 else {})
    strips = {
        k: jnp.concatenate([v[:, v.shape[1] - n :], v[:, :n]], axis=1) for k, v in chans.items()
    }
    # the map's energy times 2^-k (exact), 2^k ≥ the map's ∑ dω (4π on the sphere, the pixel
    # count on a plane): no overflow for pixels near the float maximum
    dw = np.ldexp(_domega(plan), -_total_exp(plan))
    total = accurate_sum(L * jnp.asarray(dw, L.dtype)[:, None])
    # Lb is L when unblurred: returned once (a second output of the same image is a copy)
    blurred = dict(Lb=Lb) if plan.blur > 0 else {}
    return dict(L=L, V=V, I=I, strips=strips, total=total, top=jnp.max(L_peak)) | blurred


def _row_slices(x: Array, y: Array, x0: Array, n: int) -> Array:
    """``x[y, x0 : x0 + n]`` for every pair of ``y``, ``x0`` (same shape ``S``): ``S + (n,) +
    x.shape[2:]`` (one slice gather: far cheaper on XLA:CPU than a gather per pixel)."""
    tail = x.shape[2:]

    def one(yy: Array, xx: Array) -> Array:
        start = (yy, xx) + (jnp.zeros((), yy.dtype),) * len(tail)
        return jax.lax.dynamic_slice(x, start, (1, n) + tail)[0]

    out = jax.vmap(one)(y.reshape(-1), x0.reshape(-1))
    return out.reshape(y.shape + (n,) + tail)


def _windows(x: Array, strip: Array, y: Array, x0: Array, r: int) -> Array:
    """Window rows ``x[y, x0 − r … x0 + r]``, columns wrapped: ``y.shape + (2r + 1,) +
    x.shape[2:]``.

    A row inside the image is one slice of ``x``; a row across the seam (or, on a plane,
    past an edge, where the values are masked) one slice of ``strip``: the columns
    ``W − n … W − 1, 0 … n − 1`` (``n = 2r + 1``; :func:`_smooth`). No padded copy of
    the map is made (copying the map's channels cost more than all of step 9).
    """
    n, w = 2 * r + 1, x.shape[1]
    s = x0 - r
    cross = (s < 0) | (s > w - n)
    inner = _row_slices(x, y, jnp.clip(s, 0, w - n), n)
    seam = _row_slices(strip, y, jnp.clip(jnp.mod(s + n, w), 0, n), n)
    # the barrier keeps both as slice gathers (fused into the select, XLA:CPU gathered
    # pixel by pixel, several times slower) and materialises the row flags (else the
    # select recomputed their index arithmetic for every pixel)
    inner, seam, cross = jax.lax.optimization_barrier((inner, seam, cross))
    return jnp.where(cross.reshape(cross.shape + (1,) * (inner.ndim - cross.ndim)), seam, inner)


def _find(
    rgb_w: Array,
    L_peak: Array,
    smooth: dict[str, Any],
    thr: Array,
    plan: _Plan,
    single: bool = False,
) -> dict[str, Array]:
    """Steps 3–9 on the prepared images (:func:`_prepare`, :func:`_smooth`); ``single``:
    not under ``vmap`` (data-dependent branches then skip work)."""
    Lb, V, I, strips = smooth.get("Lb", smooth["L"]), smooth["V"], smooth["I"], smooth["strips"]
    dt = Lb.dtype
    H, W = plan.h, plan.w
    K, R, C = plan.max_lights, plan.max_reps, plan.max_candidates
    Lbf = Lb.reshape(-1)

    # 3-5: samples and their neighbourhood maximum (on the pooled image: one value per
    # window column from V, the row from I; then the best 2×2 block's pixels), threshold
    cols, sx, sy, rr = _search_columns(plan)
    q = _pool_factor(plan)
    hq, wq = H // q, W // q
    row0 = jnp.asarray((sy // q) * wq, jnp.int32)
    vals = V.reshape(-1)[row0[:, None] + jnp.asarray(cols)]
    bc = jnp.take_along_axis(jnp.asarray(cols), jnp.argmax(vals, axis=1)[:, None], 1)[:, 0]
    by = jnp.asarray(sy // q, jnp.int32) + I.reshape(-1)[row0 + bc] - rr
    if plan.sphere:
        top_, bottom = by < 0, by >= hq
        bx = jnp.where(top_ | bottom, jnp.mod(bc + wq // 2, wq), bc)
        by = jnp.where(top_, -by - 1, jnp.where(bottom, 2 * hq - 1 - by, by))
    else:
        bx, by = bc, jnp.clip(by, 0, hq - 1)
    cand_y = (q * by)[:, None] + jnp.asarray([0, 0, 1, 1] if q == 2 else [0])[None, :]
    cand_x = (q * bx)[:, None] + jnp.asarray([0, 1, 0, 1] if q == 2 else [0])[None, :]
    vals = Lbf[cand_y * W + cand_x]
    pick4 = jnp.argmax(vals, axis=1)[:, None]
    m = jnp.take_along_axis(vals, pick4, 1)[:, 0]
    local = jnp.take_along_axis(cand_y * W + cand_x, pick4, 1)[:, 0]
    T = _threshold(smooth["top"], Lbf[jnp.asarray(sy * W + sx)], thr)
    safe_T = jnp.where(jnp.isfinite(T), T, 1.0)

    # 6: sort candidates
    is_cand = m > T
    cval, cidx = jax.lax.top_k(jnp.where(is_cand, m, -jnp.inf), C)
    cvalid = cval > T
    cflat = local[cidx]
    cy, cx = cflat // W, cflat % W

    if plan.sphere:
        ce, se, _ = (jnp.asarray(a, dt) for a in _row_geometry(H))
        ca, sa = (jnp.asarray(a, dt) for a in _col_geometry(W))

        def unit(x: Array, y: Array) -> Array:
            return jnp.stack([ce[y] * sa[x], se[y], -ce[y] * ca[x]], axis=-1)

        cdir = unit(cx, cy)
        close = (cdir @ cdir.T) > plan.nms_cos
    else:
        cpos = jnp.stack([cx, cy], -1).astype(dt)
        close = jnp.sum((cpos[:, None] - cpos[None]) ** 2, -1) < plan.nms_cos
    domega = jnp.asarray(_domega(plan), dt)

    # 7: Euclidean filter
    lead = _leaders(close, cvalid)
    rep_c, rvalid, crank = _compact(lead, R)
    cowner = _owner(close, lead, cvalid)
    rx, ry = cx[rep_c], cy[rep_c]
    rvalid = rvalid & cvalid[rep_c]

    # 8: Bresenham merge (fixed-length lines, seam-wrapped), for the pairs i < j only:
    # the greedy merge reads no other
    def line_test(n: int) -> Array:
        """The line test between the first ``n`` kept candidates, as an ``(R, R)`` mask."""
        S = plan.line_points
        pi, pj = (jnp.asarray(a, jnp.int32) for a in np.triu_indices(n, 1))
        t = (jnp.arange(1, S + 1, dtype=dt) / S)[None, :]
        ddx = (rx[pj] - rx[pi]).astype(dt)
        if plan.sphere:
            ddx = jnp.mod(ddx + W // 2, W) - W // 2
        ddy = (ry[pj] - ry[pi]).astype(dt)
        lx = jnp.round(rx[pi][:, None] + t * ddx[:, None]).astype(jnp.int32)
        ly = jnp.round(ry[pi][:, None] + t * ddy[:, None]).astype(jnp.int32)
        # |ddx| <= W/2: one wrap either way (cheaper than an integer mod)
        if plan.sphere:
            lx = jnp.where(lx < 0, lx + W, jnp.where(lx >= W, lx - W, lx))
        else:
            lx = jnp.clip(lx, 0, W - 1)
        ly = jnp.clip(ly, 0, H - 1)
        c = jnp.minimum(Lbf[ly * W + lx] / safe_T, LINE_CLAMP) - (1.0 - LINE_TOLERANCE)
        # running mean >= 1 - tol at every step  <=>  every prefix sum of c >= 0
        # (unrolled: a cumsum here became an O(S²) reduce-window on XLA:CPU)
        acc = c[:, 0]
        ok = acc >= 0
        for k in range(1, S):
            acc = acc + c[:, k]
            ok = ok & (acc >= 0)
        pair = np.full((R, R), pi.shape[0], np.int32)  # (i, j) -> its pair, else a False
        pair[np.triu_indices(n, 1)] = np.arange(pi.shape[0])
        return jnp.concatenate([ok, jnp.zeros(1, bool)])[jnp.asarray(pair)]

    # Usually few candidates are kept (one per light): a single map then tests only the
    # pairs among the first SMALL_REPS (the others are invalid and masked below). Under
    # vmap a cond would run both branches, so a batch always tests all pairs.
    n_small = min(R, SMALL_REPS)
    if single and n_small < R:
        passes = jax.lax.cond(
            jnp.sum(rvalid) <= n_small, lambda: line_test(n_small), lambda: line_test(R)
        )
    else:
        passes = line_test(R)
    if plan.sphere:
        rdir = cdir[rep_c]
        near = (rdir @ rdir.T) >= plan.merge_cos
    else:
        dx2 = (rx[None, :] - rx[:, None]).astype(dt)
        dy2 = (ry[None, :] - ry[:, None]).astype(dt)
        near = (dx2**2 + dy2**2) <= plan.merge_cos
    merge = passes & near & rvalid[:, None] & rvalid[None, :]
    llead = _leaders(merge, rvalid)
    light_rep, lvalid, _ = _compact(llead, K)
    lvalid = lvalid & rvalid[light_rep]
    n_found = jnp.sum(llead)
    rep_owner = _owner(merge, llead, rvalid)
    lrank = jnp.cumsum(llead) - 1
    rep_light = jnp.where(rep_owner >= 0, lrank[jnp.maximum(rep_owner, 0)], -1)
    rep_light = jnp.where(rep_light < K, rep_light, -1)

    # 9: grow each light over the connected pixels above T, in a window around the mean
    # of the local maxima its samples found (a flat-topped light's seed may sit on its
    # rim). On the sphere the window is twice as wide as high: it then spans max_radius
    # in angle up to 60° of elevation. Each window row is one slice of a channel (rows
    # past a pole: the opposite meridian's row, its centre shifted by W/2).
    def lights(K: int) -> dict[str, Array]:
        """Step 9 and the outputs for the first ``K`` lights (the rest are invalid)."""
        light_rep, lvalid = light_rep_all[:K], lvalid_all[:K]
        ry_, rx_ = plan.radius, plan.radius_x
        PY, PX = 2 * ry_ + 1, 2 * rx_ + 1
        sxk, syk = rx[light_rep], ry[light_rep]
        crep = jnp.where(cowner >= 0, crank[jnp.maximum(cowner, 0)], -1)
        clight = jnp.where((crep >= 0) & (crep < R), rep_light[jnp.clip(crep, 0, R - 1)], -1)

        def rel(x: Array, y: Array, owner: Array, cx: Array, cy: Array) -> tuple[Array, Array]:
            dx = x - cx[jnp.maximum(owner, 0)]
            if plan.sphere:
                dx = jnp.mod(dx + W // 2, W) - W // 2
            return dx, y - cy[jnp.maximum(owner, 0)]

        member = (clight[:, None] == jnp.arange(K)[None, :]) & cvalid[:, None]
        mdx, mdy = rel(cx, cy, clight, sxk, syk)
        n_mem = jnp.maximum(jnp.sum(member, axis=0), 1)
        ox = jnp.round(jnp.sum(member * mdx[:, None], axis=0) / n_mem).astype(sxk.dtype)
        oy = jnp.round(jnp.sum(member * mdy[:, None], axis=0) / n_mem).astype(syk.dtype)
        wx = jnp.mod(sxk + ox, W) if plan.sphere else jnp.clip(sxk + ox, 0, W - 1)
        wy = jnp.clip(syk + oy, 0, H - 1)
        offx = jnp.arange(-rx_, rx_ + 1, dtype=jnp.int32)
        Yw = wy[:, None] + jnp.arange(-ry_, ry_ + 1, dtype=jnp.int32)[None, :]  # (K, PY)
        if plan.sphere:
            top_, bottom = Yw < 0, Yw >= H
            Y = jnp.where(top_, -Yw - 1, jnp.where(bottom, 2 * H - 1 - Yw, Yw))
            x0 = jnp.mod(wx[:, None] + jnp.where(top_ | bottom, W // 2, 0), W)
            inside = jnp.broadcast_to(lvalid[:, None, None], (K, PY, PX))
        else:
            Y = jnp.clip(Yw, 0, H - 1)
            x0 = jnp.broadcast_to(wx[:, None], (K, PY))
            X = wx[:, None] + offx[None, :]
            inside = ((Yw >= 0) & (Yw < H))[:, :, None] & ((X >= 0) & (X < W))[:, None, :]
            inside = inside & lvalid[:, None, None]
        # materialised once: fused into each per-pixel consumer, XLA:CPU recomputed the
        # index arithmetic (rounding, wrapping) for every pixel of every window
        Y, x0 = jax.lax.optimization_barrier((Y, x0))

        def window(name: str, src: Array) -> Array:
            return _windows(src, strips[name], Y, x0, rx_)

        Lw = window("L", smooth["L"])
        above = inside & ((window("Lb", Lb) if plan.blur > 0 else Lw) > T)
        # seeds: every merged local maximum, placed in its light's window
        rdx, rdy = rel(rx, ry, rep_light, wx, wy)
        ok = (rep_light >= 0) & rvalid & (jnp.abs(rdx) <= rx_) & (jnp.abs(rdy) <= ry_)
        seeds = (
            jnp.zeros((K, PY, PX), bool)
            .at[jnp.where(ok, rep_light, K), rdy + ry_, rdx + rx_]
            .set(True, mode="drop")
        )
        big = PY * PX + 1
        filled, dist = _grow(seeds & above, above, big, history=single)
        # a pixel two lights reach goes to the nearer (geodesic steps), then the brighter: the
        # smallest key, by a scatter-min of the window rows into an image padded by rx_
        # columns each side (padded column j is column j − rx_); on the sphere the columns
        # that stand for the same one (j and j + W, j < 2 rx_) then get their minimum
        # key = (dist, k) packed in bits: k is its low bits (a mask, not a division)
        kbits = max(1, (K - 1).bit_length())
        kk = jnp.arange(K, dtype=jnp.int32)[:, None, None]
        none = big << kbits
        key = jnp.where(filled, (dist << kbits) | kk, none).astype(jnp.int32)
        rows_at = jnp.stack([Y.reshape(-1), x0.reshape(-1)], axis=-1)

        def onto_rows(scatter: Callable, fill: int, rows: Array) -> Array:
            """``rows`` (K, PY, PX) window rows scattered onto the seam-padded image."""
            return scatter(
                jnp.full((H, W + 2 * rx_), fill, jnp.int32),
                rows_at,
                rows.reshape(K * PY, PX),
                jax.lax.ScatterDimensionNumbers(
                    update_window_dims=(1,),
                    inserted_window_dims=(0,),
                    scatter_dims_to_operand_dims=(0, 1),
                ),
                mode=jax.lax.GatherScatterMode.PROMISE_IN_BOUNDS,
            )

        lab = onto_rows(jax.lax.scatter_min, none, key)
        r = rx_
        if plan.sphere:
            # both copies of the seam columns get their minimum, in place (a concatenate
            # copied the whole image)
            seam = jnp.minimum(lab[:, : 2 * r], lab[:, W:])
            lab = jax.lax.dynamic_update_slice(lab, seam, (0, 0))
            lab = jax.lax.dynamic_update_slice(lab, seam, (0, W))
        own = filled & (_row_slices(lab, Y, x0, PX) == key)

        def fold(raw: Array) -> Array:
            """The padded image's columns ``r … r + W − 1`` (on the sphere the padding is
            folded in by a maximum: no two lights own a pixel, −1 elsewhere)."""
            if not plan.sphere:
                return raw[:, r : r + W]
            left = jnp.maximum(raw[:, r : 2 * r], raw[:, W + r :])
            right = jnp.maximum(raw[:, W : W + r], raw[:, :r])
            # in place, then one slice (a concatenate copied the middle twice)
            raw = jax.lax.dynamic_update_slice(raw, left, (0, r))
            raw = jax.lax.dynamic_update_slice(raw, right, (0, W))
            return raw[:, r : r + W]

        # light properties from its pixels: first summed along each window row, as one
        # matrix product with per-column weights (1, the column offset, cos and sin of its
        # azimuth from the row's centre column x0), then over the rows with per-row
        # weights (dω, sin/cos of elevation and of x0's azimuth); ~10 reductions over the
        # whole windows cost several times more
        ownf = own.astype(dt)
        # the sums run on values times an exact power of two that brings the map's largest
        # luminance to at most 2^(maxexp/2) (1 for ordinary maps: the same bits): sums of
        # pixels near the float maximum overflowed (a NaN light position); energies and
        # colour sums beyond the float range saturate at the largest float
        lim = 2.0 ** (jnp.finfo(dt).maxexp // 2)
        top = smooth["top"]
        c = jnp.where(jnp.isfinite(top) & (top > lim), inverse_pow2(top) * lim, 1.0).astype(dt)
        offs = np.arange(-rx_, rx_ + 1)
        ang = offs * (2 * np.pi / W)
        colw = jnp.asarray(np.stack([np.ones(PX), offs, np.cos(ang), np.sin(ang)], 1), dt)
        A = ((Lw * c * ownf).reshape(K * PY, PX) @ colw).reshape(K, PY, 4)
        n_row = jnp.sum(ownf, axis=-1)  # (K, PY)
        rgb_w_ = window("rgb", rgb_w)  # (K, PY, PX, 3)
        csum = (
            (ownf[..., None] * (rgb_w_ * c)).reshape(K * PY, PX * 3)
            @ jnp.asarray(np.tile(np.eye(3), (PX, 1)), dt)
        ).reshape(K, PY, 3)
        dom = domega[Y]  # (K, PY)
        de = dom * A[..., 0]  # each row's energy
        energy_c = jnp.sum(de, axis=1)  # times c
        omega = jnp.sum(dom * n_row, axis=1)
        rgb_sum_c = jnp.sum(dom[..., None] * csum, axis=1)
        safe_omega = jnp.where(omega > 0, omega, 1.0)
        big = jnp.finfo(dt).max
        colour = jnp.clip(rgb_sum_c / safe_omega[:, None] / c, -big, big)
        mean_lum = jnp.minimum(energy_c / safe_omega / c, big)
        energy = jnp.minimum(energy_c / c, big)
        rgb_sum = jnp.clip(rgb_sum_c / c, -big, big)
        n_pix = jnp.sum(n_row, axis=1).astype(jnp.int32)
        lvalid = lvalid & (n_pix > 0) & (energy_c > 0)
        peak = jnp.max(jnp.where(own, window("peak", L_peak), 0), axis=(1, 2))
        # the map's energy times c (exact)
        total = smooth["total"] * (c * np.ldexp(1.0, _total_exp(plan)))
        share = energy_c / jnp.where(total > 0, total, 1.0)
        scale_x, scale_y = plan.in_w / W, plan.in_h / H
        if plan.sphere:
            # azimuth of column x0 + o: az(x0) + o·2π/W (sin/cos by the angle sum)
            dc = dom * ce[Y]
            c0, s0 = ca[x0], sa[x0]
            vec = jnp.stack(
                [
                    jnp.sum(dc * (s0 * A[..., 2] + c0 * A[..., 3]), axis=1),
                    jnp.sum(de * se[Y], axis=1),
                    -jnp.sum(dc * (c0 * A[..., 2] - s0 * A[..., 3]), axis=1),
                ],
                axis=-1,
            )
            norm = jnp.linalg.norm(vec, axis=-1, keepdims=True)
            direction = jnp.where(norm > 0, vec / jnp.where(norm > 0, norm, 1.0), unit(sxk, syk))
        else:
            direction = jnp.zeros((K, 3), dt)
            omega = jnp.zeros(K, dt)
        # energy-weighted mean pixel position, columns unwrapped around the window centre (no
        # trigonometry here: XLA:CPU compiles each transcendental into a large kernel; the
        # azimuth, elevation and angular size are computed from these on demand)
        safe_e = jnp.where(energy_c > 0, energy_c, 1.0)
        cxw = wx.astype(dt) + jnp.sum(dom * A[..., 1], axis=1) / safe_e
        cxw = jnp.mod(cxw + 0.5, W) - 0.5 if plan.sphere else cxw
        cyw = jnp.sum(de * Y, axis=1) / safe_e
        pixel = jnp.stack([(cxw + 0.5) * scale_x - 0.5, (cyw + 0.5) * scale_y - 0.5], axis=-1)
        peak_pixel = jnp.stack([(sxk + 0.5) * scale_x - 0.5, (syk + 0.5) * scale_y - 0.5], -1)

        # samples: which light holds each candidate's local maximum
        cl = lab.reshape(-1)[cy * (W + 2 * r) + cx + r]
        clab = jnp.where(cvalid & (cl < none), cl & ((1 << kbits) - 1), -1)
        n_samples = jnp.sum(clab[None, :] == jnp.arange(K)[:, None], axis=1)

        # largest energy first; relabel
        order = jnp.argsort(-jnp.where(lvalid, energy_c, -1.0), stable=True)
        inv = jnp.zeros(K, jnp.int32).at[order].set(jnp.arange(K, dtype=jnp.int32))
        lvalid = lvalid[order]
        count = jnp.sum(lvalid)

        def relabel(a: Array) -> Array:
            b = jnp.where(a >= 0, inv[jnp.maximum(a, 0)], -1)
            return jnp.where(b < count, b, -1).astype(jnp.int32)

        # the label image: each light's new label scattered over the pixels it owns (a
        # relabel pass over the whole image cost more)
        new_lab = jnp.where(own, relabel(jnp.arange(K, dtype=jnp.int32))[:, None, None], -1)
        labels = onto_rows(jax.lax.scatter_max, -1, new_lab)

        # one packed table, one gather: each separate output array is a kernel XLA compiles
        fields = {
            "direction": direction,
            "pixel": pixel,
            "peak_pixel": peak_pixel,
            "peak_luminance": peak,
            "mean_luminance": mean_lum,
            "colour": colour,
            "irradiance": rgb_sum,
            "solid_angle": omega,
            "area": n_pix * (scale_x * scale_y),
            "energy": energy,
            "energy_share": share,
            "n_samples": n_samples,
        }
        cols = [jnp.reshape(v, (K, -1)).astype(dt) for v in fields.values()]
        table = jnp.where(lvalid[:, None], jnp.concatenate(cols, axis=1)[order], 0)
        out: dict[str, Array] = {}
        start = 0
        for (name, v), c in zip(fields.items(), cols, strict=True):
            out[name] = table[:, start : start + c.shape[1]].reshape(v.shape)
            start += c.shape[1]
        out["n_samples"] = out["n_samples"].astype(jnp.int32)
        pad = K_all - K  # rows of the lights this call did not look at: invalid, zero
        out = {k: jnp.pad(v, [(0, pad)] + [(0, 0)] * (v.ndim - 1)) for k, v in out.items()}
        return dict(
            count=count.astype(jnp.int32),
            valid=jnp.pad(lvalid, (0, pad)),
            **out,
            labels=fold(labels),
            sample_light=relabel(clab),
        )

    # Most maps have a few lights: a single map then runs step 9 on the first SMALL_LIGHTS
    # only (exact: the others are invalid). Under vmap both branches would run.
    K_all, light_rep_all, lvalid_all = K, light_rep, lvalid
    if single and SMALL_LIGHTS < K:
        res = jax.lax.cond(n_found <= SMALL_LIGHTS, lambda: lights(SMALL_LIGHTS), lambda: lights(K))
    else:
        res = lights(K)
    scale_x, scale_y = plan.in_w / W, plan.in_h / H
    samples = jnp.stack(
        [
            (jnp.asarray(sx)[cidx] + 0.5) * scale_x - 0.5,
            (jnp.asarray(sy)[cidx] + 0.5) * scale_y - 0.5,
        ],
        axis=-1,
    )
    truncated = (jnp.sum(is_cand) > C) | (jnp.sum(lead) > R) | (n_found > K)
    return dict(
        n_found=n_found.astype(jnp.int32),
        truncated=truncated,
        **res,
        samples=jnp.where(cvalid[:, None], samples, 0).astype(dt),
        threshold=T,
    )


@functools.partial(jax.jit, static_argnames=("plan", "batch"))
def _prepare_batch(rgb: Array, plan: _Plan, batch: tuple[int, ...]) -> tuple[Array, Array]:
    return jax.vmap(lambda v: _prepare(v, plan))(flatten_batch_float(rgb, batch))


@functools.partial(jax.jit, static_argnames=("plan",))
def _smooth_batch(rgb_w: Array, L_peak: Array, plan: _Plan) -> dict[str, Array]:
    return jax.vmap(lambda x, p: _smooth(x, p, plan))(rgb_w, L_peak)


@functools.partial(jax.jit, static_argnames=("plan", "batch"))
def _find_batch(
    prepared: tuple[Array, Array],
    smooth: dict[str, Any],
    thr: Array,
    plan: _Plan,
    batch: tuple[int, ...],
) -> Lights:
    thr = flatten_batch(jnp.asarray(thr, prepared[0].dtype), batch)
    if math.prod(batch) == 1:  # no vmap: lets _find branch on the data
        first = jax.tree.map(lambda v: v[0], (prepared, smooth, thr))
        # mypy maps a star argument of unknown length onto every parameter (call-arg)
        one = _find(*first[0], first[1], first[2], plan, True)  # type: ignore[call-arg]
        out = jax.tree.map(lambda v: v[None], one)
    else:
        out = jax.vmap(lambda p, s, t: _find(*p, s, t, plan))(prepared, smooth, thr)  # type: ignore[call-arg]
    out = {k: v.reshape(batch + v.shape[1:]) for k, v in out.items()}
    return Lights(
        **out,
        projection="equirectangular" if plan.sphere else "plane",
        input_shape=(plan.in_h, plan.in_w),
    )


def _run(
    image: ArrayLike,
    name: str,
    sphere: bool,
    *,
    threshold: float | ArrayLike | None,
    **options: Any,
) -> Lights:
    batch, in_h, in_w = image_shape(image, name)
    if options.get("weights") is not None:
        options["weights"] = tuple(float(v) for v in options["weights"])
    plan = _cached_plan(sphere, in_h, in_w, **options)
    # always an array of the batch's shape: one compiled signature for every threshold
    if threshold is None:
        thr: Any = np.full(batch, np.nan, np.float32)
    elif isinstance(threshold, int | float):
        if not (math.isfinite(threshold) and threshold > 0):
            raise ValueError(f"threshold: expected a finite luminance > 0, got {threshold!r}")
        thr = np.full(batch, threshold, np.float64 if jax.config.jax_enable_x64 else np.float32)
    elif isinstance(threshold, jax.core.Tracer):
        thr = jnp.broadcast_to(threshold, batch)
    else:
        t = np.asarray(threshold, np.float64)
        if not np.all(np.isfinite(t) & (t > 0)) or np.broadcast_shapes(t.shape, batch) != batch:
            raise ValueError(f"threshold: expected finite luminances > 0 of shape {batch}")
        thr = np.broadcast_to(t, batch).astype(
            np.float64 if jax.config.jax_enable_x64 else np.float32
        )
    # Three compiled calls on purpose: in one, XLA:CPU fuses the reduction of the
    # full-resolution map into each of its consumers and the blur into every gather that
    # reads it, recomputing them per read (3x slower in total); a call boundary
    # materialises each image once.
    prepared = _prepare_batch(image, plan, batch)
    return _find_batch(prepared, _smooth_batch(*prepared, plan), thr, plan, batch)


def detect(
    envmap: Float[ArrayLike, "*batch H W 3"],
    *,
    width: int = DEFAULT_WIDTH,
    n_samples: int | None = None,
    threshold: float | Float[ArrayLike, "*batch"] | None = None,
    blur: float = DEFAULT_BLUR,
    max_radius: float = DEFAULT_MAX_RADIUS,
    max_lights: int = DEFAULT_MAX_LIGHTS,
    max_candidates: int | None = None,
    weights: Sequence[float] | None = None,
) -> Lights:
    """Find the light sources of an equirectangular environment map (module docstring).

    Args:
        envmap: linear RGB lat-long map(s), channels last, top row = zenith; leading batch
            axes go through one vmapped, compiled call.
        width: working width in pixels (the map is reduced to at most this; never enlarged).
        n_samples: Hammersley samples on the sphere; default ``0.006 × w × h`` of the working
            resolution (the listing's ``samplesMultiplier``), at least 64.
        threshold: luminance threshold in the map's units (per map for a batch);
            ``None`` → automatic (module docstring).
        blur: Gaussian sigma in working pixels (0 = none).
        max_radius: largest light radius in degrees: the merge distance limit and the mask
            window; larger bright regions become several lights.
        max_lights: size of the result (the brightest local maxima win when there are more).
        max_candidates: cap on the samples kept after the neighbourhood filter
            (default ``max(256, 8 max_lights)``).
        weights: luminance weights (default Rec.709; see :func:`hdrjax.luminance_weights`).

    Returns:
        :class:`Lights`, sorted by energy.

    Raises:
        ValueError: bad shapes or options (at trace time, never from inside the kernel).
    """
    return _run(
        envmap,
        "envmap",
        True,
        threshold=threshold,
        width=width,
        n_samples=n_samples,
        blur=blur,
        max_radius=max_radius,
        max_lights=max_lights,
        max_candidates=max_candidates,
        weights=weights,
    )


def detect_image(
    image: Float[ArrayLike, "*batch H W 3"],
    *,
    width: int = DEFAULT_WIDTH,
    n_samples: int | None = None,
    threshold: float | Float[ArrayLike, "*batch"] | None = None,
    blur: float = DEFAULT_BLUR,
    max_radius: float | None = None,
    max_lights: int = DEFAULT_MAX_LIGHTS,
    max_candidates: int | None = None,
    weights: Sequence[float] | None = None,
) -> Lights:
    """The same detection on a plain (flat) image: Halton samples on the plane, no seam.

    Distances are in pixels, energy is ∑ L over pixels, and the result has no directions
    (see :class:`Lights`). ``max_radius`` is in **working-resolution pixels** (default:
    ``w / 12``, at least 4). Other arguments as :func:`detect`.
    """
    x = jnp.asarray(image)
    w = min(x.shape[-2], int(width)) if x.ndim >= 3 else int(width)
    return _run(
        image,
        "image",
        False,
        threshold=threshold,
        width=width,
        n_samples=n_samples,
        blur=blur,
        max_radius=float(max_radius) if max_radius is not None else max(4.0, w / 12.0),
        max_lights=max_lights,
        max_candidates=max_candidates,
        weights=weights,
    )


__all__ = [
    "DEFAULT_BLUR",
    "DEFAULT_MAX_LIGHTS",
    "DEFAULT_MAX_RADIUS",
    "DEFAULT_SAMPLES_PER_PIXEL",
    "DEFAULT_WIDTH",
    "detect",
    "detect_image",
]
