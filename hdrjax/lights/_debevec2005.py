"""Debevec's median-cut light extraction, vectorised in JAX (the comparison method).

Reference:
    P. Debevec, "A Median Cut Algorithm for Light Probe Sampling", SIGGRAPH 2005 Posters;
    also Reinhard, Ward, Pattanaik, Debevec, *High Dynamic Range Imaging*, Morgan Kaufmann
    2005, ch. 9, pp. 430–433. https://vgl.ict.usc.edu/Research/MedianCut/

Algorithm (as published): start with the whole lat-long map as one region; ``levels``
times, split every region along its longest dimension — the width measured at the region's
central latitude, i.e. scaled by ``cos(el)`` — at the point that halves its energy; place
one light per final region at its energy centroid, with the summed pixel values as its
colour. Energy is luminance times the pixel's solid angle (the paper's cos-weighting).

Vectorised form: all regions of a level split at once. Each region's energy per column
(per row) comes from per-column (per-row) prefix sums — not a 2-D summed-area table, whose
float32 differences of large prefixes would lose small regions — and the cut is the column
(row) whose cumulative energy is nearest half the region's. A region of one pixel in the
split direction cannot be split: its second half is empty (zero energy), so the result
still has ``2**levels`` rows
and the lights' energies still sum to the map's. Non-finite pixels count as zero; negative
values are clamped to zero.
"""

import functools
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._colour import luminance
from .._stats import accurate_sum
from ._geometry import azel_to_direction
from ._result import MedianCutLights
from ._working_map import flatten_batch_float, image_shape, weights_key, working_rgb, working_size

SCALE_EXP = 4
"""Energies are summed times ``2^-SCALE_EXP`` (see :func:`_median_cut_one`)."""


def _prefix(x: Array) -> Array:
    """Row prefix sums with a leading zero column: ``(H, W + 1)``."""
    return jnp.concatenate([jnp.zeros_like(x[:, :1]), jnp.cumsum(x, axis=1)], axis=1)


def _median_cut_one(
    rgb: Array,
    levels: int,
    factor: int,
    hw: tuple[int, int],
    in_hw: tuple[int, int],
    weights: tuple[float, float, float] | None,
) -> dict[str, Array]:
    H, W = hw
    rgb_w, _ = working_rgb(rgb, factor, hw, weights)
    dt = rgb_w.dtype
    L = jnp.maximum(luminance(rgb_w, weights), 0)
    el = np.pi * (0.5 - (np.arange(H) + 0.5) / H)
    theta = np.pi * np.arange(H + 1) / H
    # solid angles times 2^-SCALE_EXP (exact): the sphere's 4π < 2^SCALE_EXP, so no sum of
    # E or RGB dω overflows for pixels up to the float maximum (the map's total 4π·1e38 did:
    # +Inf energy, NaN share); ratios and cuts are unchanged, the sums scaled back at the end
    domega = jnp.asarray(
        np.ldexp(2 * np.pi * (np.cos(theta[:-1]) - np.cos(theta[1:])) / W, -SCALE_EXP), dt
    )
    az = 2 * np.pi * ((np.arange(W) + 0.5) / W - 0.5)
    ce, se = jnp.asarray(np.cos(el), dt), jnp.asarray(np.sin(el), dt)
    ca, sa = jnp.asarray(np.cos(az), dt), jnp.asarray(np.sin(az), dt)
    E = L * domega[:, None]
    PE = _prefix(E)  # (H, W + 1): energy of row y left of column x
    PEt = _prefix(E.T)  # (W, H + 1): energy of column x above row y
    rows = jnp.arange(H)
    cols = jnp.arange(W)

    def cut(profile: Array, lo: Array, hi: Array) -> Array:
        """Index s in [lo + 1, hi − 1] whose prefix of ``profile`` is nearest half its sum.

        ``profile`` is each region's energy per column (or row), zero outside the region.
        """
        before = jnp.cumsum(profile, axis=1) - profile  # energy left of index s
        half = jnp.sum(profile, axis=1, keepdims=True) / 2
        idx = jnp.arange(profile.shape[1])[None, :]
        ok = (idx >= lo[:, None] + 1) & (idx <= hi[:, None] - 1)
        return jnp.argmin(jnp.where(ok, jnp.abs(before - half), jnp.inf), axis=1)

    x0 = jnp.zeros(1, jnp.int32)
    x1 = jnp.full(1, W, jnp.int32)
    y0 = jnp.zeros(1, jnp.int32)
    y1 = jnp.full(1, H, jnp.int32)
    for _ in range(levels):
        in_cols = (cols[None, :] >= x0[:, None]) & (cols[None, :] < x1[:, None])
        in_rows = (rows[None, :] >= y0[:, None]) & (rows[None, :] < y1[:, None])
        col_e = jnp.where(
            in_cols, PEt[cols[None, :], y1[:, None]] - PEt[cols[None, :], y0[:, None]], 0
        )
        row_e = jnp.where(
            in_rows, PE[rows[None, :], x1[:, None]] - PE[rows[None, :], x0[:, None]], 0
        )
        lat = np.pi / 2 - np.pi * (y0 + y1).astype(dt) / (2 * H)
        width = (x1 - x0).astype(dt) * (2 * np.pi / W) * jnp.cos(lat)
        height = (y1 - y0).astype(dt) * (np.pi / H)
        can_x, can_y = (x1 - x0) >= 2, (y1 - y0) >= 2
        along_x = can_x & ((width >= height) | ~can_y)
        sx = cut(col_e, x0, x1).astype(jnp.int32)
        sy = cut(row_e, y0, y1).astype(jnp.int32)
        # a region that cannot be split keeps everything in its first half
        sy = jnp.where(can_y, sy, y1)
        nx1 = jnp.where(along_x, sx, x1)
        nx0 = jnp.where(along_x, sx, x0)
        ny1 = jnp.where(along_x, y1, sy)
        ny0 = jnp.where(along_x, y0, sy)
        x0, x1, y0, y1 = (
            jnp.stack([x0, nx0], 1).reshape(-1),
            jnp.stack([nx1, x1], 1).reshape(-1),
            jnp.stack([y0, ny0], 1).reshape(-1),
            jnp.stack([ny1, y1], 1).reshape(-1),
        )

    # region sums of the separable moments: E, E cos az, E sin az, RGB dω
    inside = (rows[None, :] >= y0[:, None]) & (rows[None, :] < y1[:, None])

    def region_sum(P: Array, row_weight: Array | None = None) -> Array:
        d = P[rows[None, :], x1[:, None]] - P[rows[None, :], x0[:, None]]
        if row_weight is not None:
            d = d * row_weight[None, :]
        return jnp.sum(jnp.where(inside, d, 0), axis=1)

    energy = region_sum(PE)
    vx = region_sum(_prefix(E * sa[None, :]), ce)
    vy = region_sum(PE, se)
    vz = -region_sum(_prefix(E * ca[None, :]), ce)
    vec = jnp.stack([vx, vy, vz], -1)
    norm = jnp.linalg.norm(vec, axis=-1, keepdims=True)
    # an empty region sits at its box centre
    cx = (x0 + x1).astype(dt) / 2
    cy = (y0 + y1).astype(dt) / 2
    box_az = 2 * np.pi * (cx / W - 0.5)
    box_el = np.pi * (0.5 - cy / H)
    box = azel_to_direction(box_az, box_el)
    direction = jnp.where(norm > 0, vec / jnp.where(norm > 0, norm, 1.0), box)
    rgb_dw = rgb_w * domega[:, None, None]
    irr = jnp.stack([region_sum(_prefix(rgb_dw[..., c])) for c in range(3)], -1)
    total = accurate_sum(E)
    top = jnp.finfo(dt).max

    def unscale(v: Array) -> Array:  # saturates beyond the float range
        return jnp.clip(v * 2.0**SCALE_EXP, -top, top)

    in_h, in_w = in_hw
    return dict(
        direction=direction,
        irradiance=unscale(irr),
        energy=unscale(energy),
        energy_share=energy / jnp.where(total > 0, total, 1.0),
        region=jnp.stack([x0, y0, x1, y1], -1).astype(jnp.int32),
    )


@functools.partial(jax.jit, static_argnames=("levels", "factor", "hw", "in_hw", "weights", "batch"))
def _median_cut_batch(
    rgb: Array,
    levels: int,
    factor: int,
    hw: tuple[int, int],
    in_hw: tuple[int, int],
    weights: tuple[float, float, float] | None,
    batch: tuple[int, ...],
) -> MedianCutLights:
    x = flatten_batch_float(rgb, batch)
    out = jax.vmap(lambda v: _median_cut_one(v, levels, factor, hw, in_hw, weights))(x)
    out = {k: v.reshape(batch + v.shape[1:]) for k, v in out.items()}
    return MedianCutLights(**out, input_shape=in_hw)


def median_cut(
    envmap: Float[ArrayLike, "*batch H W 3"],
    *,
    n_lights: int = 16,
    width: int = 1024,
    weights: Sequence[float] | None = None,
) -> MedianCutLights:
    """Debevec's median cut: ``n_lights`` lights of (nearly) equal energy (module docstring).

    Args:
        envmap: linear RGB lat-long map(s), channels last, top row = zenith.
        n_lights: a power of two (``2**levels`` regions).
        width: working width (the map is box-reduced to at most this many columns).
        weights: luminance weights (default Rec.709).

    Returns:
        :class:`MedianCutLights`; ``irradiance`` sums to the map's ∑ RGB dω and
        ``energy_share`` to 1 (the regions partition the map). A region's ``energy`` or
        ``irradiance`` beyond the float range (pixels near the float maximum) saturates at
        the largest float; ``energy_share`` stays exact.
    """
    if isinstance(n_lights, bool) or int(n_lights) != n_lights or n_lights < 1:
        raise ValueError(f"n_lights: expected a power of two >= 1, got {n_lights!r}")
    levels = int(n_lights).bit_length() - 1
    if 1 << levels != n_lights:
        raise ValueError(f"n_lights: expected a power of two, got {n_lights!r}")
    batch, in_h, in_w = image_shape(envmap, "envmap")
    factor, h, w = working_size(in_h, in_w, width)
    if (1 << levels) > h * w:
        raise ValueError(f"n_lights: {n_lights} regions need at least that many pixels")
    wts = weights_key(weights)
    return _median_cut_batch(envmap, levels, factor, (h, w), (in_h, in_w), wts, batch)


__all__ = ["median_cut"]
