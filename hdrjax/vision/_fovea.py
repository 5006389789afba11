"""Foveal sampling: ~1° block averages, bilinear upsampling, and the adaptation luminance.

Radiance ``pcond`` (Ward Larson, Rushmeier & Piatko 1997, doi:10.1109/2945.646233) takes
its adaptation statistics from a *foveal image* — the picture box-filtered to about one
sample per degree (``FOVDIA`` = 1°) — plus random pixel samples with the same total weight.
Here the foveal image is the mean of the finite pixels in integer blocks of
:attr:`ResolvedView.fovea_block` pixels, and a regular grid of pixels — at least 16 per
foveal sample, as many as pcond draws — stands in for pcond's random subset
(deterministic: the same image always gets the same verdicts).
"""

import functools
from collections.abc import Callable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._interp import lerp
from .._photometry import LMAX, LMIN
from .._stats import accurate_sum


def block_sums(x: Array, w: Array, by: int, bx: int) -> tuple[Array, Array]:
    """Sums of ``x * w`` and of ``w`` over ``by × bx`` blocks of the first two axes.

    The image is zero-padded (weight 0) to whole blocks, so the last row/column of blocks
    averages only the pixels that exist.
    """
    H, W = x.shape[:2]
    Hb, Wb = -(-H // by), -(-W // bx)
    pad = ((0, Hb * by - H), (0, Wb * bx - W)) + ((0, 0),) * (x.ndim - 2)
    xw = jnp.pad(x * w, pad)
    ww = jnp.pad(jnp.broadcast_to(w, x.shape), pad)
    shape = (Hb, by, Wb, bx) + x.shape[2:]
    return xw.reshape(shape).sum(axis=(1, 3)), ww.reshape(shape).sum(axis=(1, 3))


SLICE_BLOCK_MAX = 64
"""Largest block side reduced by strided slices in :func:`block_reduce` (larger blocks: a
reshape reduction; the unrolled slices would make the program too long)."""


def block_reduce(
    x: Array, by: int, bx: int, op: Callable[[Array, Array], Array], fill: float
) -> Array:
    """Reduce ``by × bx`` blocks of the first two axes of ``x`` with ``op`` (add/min/max).

    Partial blocks at the bottom/right edge reduce the pixels that exist (``fill``, the
    identity of ``op``, stands for the others). Blocks up to :data:`SLICE_BLOCK_MAX` pixels
    a side are reduced as ``op`` over strided slices (``x[i::by]``, then ``[:, j::bx]``),
    each padded on its own to whole blocks: elementwise operations that XLA:CPU fuses and
    vectorises, 3–5× faster than the ``(Hb, by, Wb, bx)`` reshape reduction of a padded
    copy on 2048×1024 with 6×6 blocks.
    """
    H, W = x.shape[:2]
    Hb, Wb = -(-H // by), -(-W // bx)
    if max(by, bx) > SLICE_BLOCK_MAX:
        pad = ((0, Hb * by - H), (0, Wb * bx - W)) + ((0, 0),) * (x.ndim - 2)
        x = jnp.pad(x, pad, constant_values=fill)
        red = {jnp.add: jnp.sum, jnp.minimum: jnp.min, jnp.maximum: jnp.max}[op]
        r = red(x.reshape((Hb, by, Wb * bx) + x.shape[2:]), axis=1)
        return red(r.reshape((Hb, Wb, bx) + x.shape[2:]), axis=2)

    def strided(a: Array, axis: int, step: int, n: int) -> list[Array]:
        out = []
        for i in range(step):
            s = jax.lax.slice_in_dim(a, i, a.shape[axis], step, axis=axis)
            if s.shape[axis] < n:  # this row/column is missing from the last block
                widths = [(0, 0)] * a.ndim
                widths[axis] = (0, n - s.shape[axis])
                s = jnp.pad(s, widths, constant_values=fill)
            out.append(s)
        return out

    r = functools.reduce(op, strided(x, 0, by, Hb))
    return functools.reduce(op, strided(r, 1, bx, Wb))


def block_mean(x: Array, valid: Array, by: int, bx: int) -> tuple[Array, Array]:
    """Mean of the ``valid`` entries of ``x`` in ``by × bx`` blocks, and the valid count.

    Entries that are not valid are ignored (they may be NaN); blocks without a valid entry
    give 0. The sums run over ``x/(by·bx)``, so they never exceed the largest ``|x|`` (no
    overflow near the dtype's maximum) and no global maximum is needed.
    """
    v = valid.astype(x.dtype)
    if v.ndim < x.ndim:
        v = v.reshape(v.shape + (1,) * (x.ndim - v.ndim))
    inv = 1.0 / (by * bx)
    num, frac = block_sums(jnp.where(v > 0, x, 0.0) * inv, v, by, bx)
    frac = frac * inv
    ok = frac > 0
    return jnp.where(ok, num / jnp.where(ok, frac, 1.0), 0.0), frac * (by * bx)


def mean2x2(S: Array, C: Array) -> tuple[Array, Array]:
    """One MIP step: 2×2 averages of ``S`` (weighted means) with weights ``C``.

    Returns the next level's ``(S, C)`` with ``C`` the mean weight of the four, zero-padded
    to even sizes; strided slices (not a reshape) keep channels-last arrays fast on CPU.
    """
    H, W = S.shape[:2]
    pad = ((0, H % 2), (0, W % 2)) + ((0, 0),) * (S.ndim - 2)
    SC, Cp = jnp.pad(S * C, pad), jnp.pad(C, pad)

    def q(a: Array) -> Array:
        return (a[0::2, 0::2] + a[1::2, 0::2] + a[0::2, 1::2] + a[1::2, 1::2]) * 0.25

    num, c = q(SC), q(Cp)
    ok = c > 0
    return jnp.where(ok, num / jnp.where(ok, c, 1.0), 0.0), c


@functools.lru_cache(maxsize=256)
def _gather_plan(n_out: int, n_in: int, f: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    u = np.clip((np.arange(n_out) + 0.5) / f - 0.5, 0.0, n_in - 1.0)
    i0 = np.minimum(np.floor(u).astype(np.int32), max(n_in - 2, 0))
    w = u - i0 if n_in > 1 else np.zeros(n_out)
    return i0, np.minimum(i0 + 1, n_in - 1), w


def upsample(a: Array, factor: tuple[int, int], shape: tuple[int, int]) -> Array:
    """Bilinear upsampling of ``a`` ``(h, w, ...)`` by integer factors to ``shape``.

    Output sample ``i`` sits at input coordinate ``(i + 0.5)/f - 0.5`` (centre-aligned, as
    pcond's ``addveil``/``acuscan``); beyond the first/last input sample the edge value is
    held (pcond extrapolates; holding keeps a veil or a blur weight from turning negative).
    Each value lies between the two it blends, up to the float maximum (:func:`lerp`).
    """
    out = a
    for axis, (f, n_out) in enumerate(zip(factor, shape, strict=True)):
        if int(f) != f or f < 1:
            raise ValueError(f"upsample: integer factors >= 1 expected, got {factor}")
        i0, i1, w = _gather_plan(int(n_out), out.shape[axis], int(f))
        wshape = [1] * out.ndim
        wshape[axis] = int(n_out)
        wj = jnp.asarray(w, out.dtype).reshape(wshape)
        out = lerp(jnp.take(out, i0, axis=axis), jnp.take(out, i1, axis=axis), wj)
    return out


class Samples(NamedTuple):
    """pcond's adaptation samples of one luminance image (see :func:`adaptation_samples`)."""

    fovea: Array  # (fy, fx) block means, cd/m²
    fovea_ok: Array  # which foveal samples lie inside (LMIN, LMAX)
    pixels: Array  # the regular pixel subsample, cd/m²
    pixels_ok: Array  # which of those lie inside (LMIN, LMAX)


def pixel_stride(block: tuple[int, int]) -> tuple[int, int]:
    """Stride of the pixel subsample: ``(by // 4, bx // 4)`` (at least 1), i.e. at least 16
    pixels per foveal sample, as pcond's ``16 × (foveal samples)`` random pixels."""
    return max(1, block[0] // 4), max(1, block[1] // 4)


def adaptation_samples(L: Float[Array, "H W"], block: tuple[int, int]) -> Samples:
    """pcond's adaptation samples: the foveal image and a pixel subsample.

    The foveal image is the block mean of the finite pixels; the pixel samples are a
    regular grid with :func:`pixel_stride` (pcond draws ``16 × (foveal samples)`` pixels at
    random: the grid is deterministic and has at least as many). Samples outside pcond's
    visible range ``(LMIN, LMAX)`` = (1e-7, 1e5) cd/m² are masked out, as pcond leaves them
    out of its histogram.
    """
    fovea, cnt = block_mean(L, jnp.isfinite(L), *block)
    return _with_pixels(L, block, fovea, cnt)


def _with_pixels(L: Array, block: tuple[int, int], fovea: Array, cnt: Array) -> Samples:
    fovea_ok = (cnt > 0) & (fovea > LMIN) & (fovea < LMAX)
    sy, sx = pixel_stride(block)
    sub = L[sy // 2 :: sy, sx // 2 :: sx]
    sub_ok = jnp.isfinite(sub) & (sub > LMIN) & (sub < LMAX)
    return Samples(fovea, fovea_ok, sub, sub_ok)


def _mean_log(L: Array, ok: Array) -> tuple[Array, Array]:
    n = jnp.sum(ok)
    lnL = jnp.log(jnp.where(ok, L, 1.0))
    return accurate_sum(lnL, ok) / jnp.maximum(n, 1), n


def mean_brightness(s: Samples) -> Float[Array, ""]:
    """``exp(bwavg)``: the mean of ``ln L`` over foveal and pixel samples, the two groups
    weighted equally (pcond ``comphist``); ``LMIN`` when there is no sample."""
    mf, nf = _mean_log(s.fovea, s.fovea_ok)
    mp, npx = _mean_log(s.pixels, s.pixels_ok)
    wf = (nf > 0).astype(mf.dtype)
    wp = (npx > 0).astype(mp.dtype)
    b = (wf * mf + wp * mp) / jnp.maximum(wf + wp, 1.0)
    return jnp.where(wf + wp > 0, jnp.exp(b), LMIN)


def adaptation_luminance(L: Float[Array, "H W"], block: tuple[int, int]) -> Float[Array, ""]:
    """Global adaptation luminance, cd/m²: pcond's mean brightness ``exp(bwavg)``.

    Args:
        L: luminance, cd/m² (NaN/Inf and out-of-range values are left out).
        block: foveal block size ``(by, bx)`` in pixels (:attr:`ResolvedView.fovea_block`).

    Returns:
        ``exp`` of the mean of ``ln L`` over the foveal samples and the pixel samples, the
        two groups weighted equally (:func:`adaptation_samples`); ``LMIN`` without samples.
    """
    return mean_brightness(adaptation_samples(L, block))


__all__ = [
    "Samples",
    "adaptation_luminance",
    "adaptation_samples",
    "block_mean",
    "block_reduce",
    "block_sums",
    "mean2x2",
    "mean_brightness",
    "pixel_stride",
    "upsample",
]
