"""Exposure fusion: a bracket blended straight into a display image (Mertens et al. 2007).

Mertens, T., Kautz, J., & Van Reeth, F. (2007). Exposure fusion. *Pacific Graphics 2007*,
382–390. DOI 10.1109/PG.2007.17.

No radiance map and no camera response: each pixel of each exposure gets a weight

    W_ij = C_ij^ω_C · S_ij^ω_S · E_ij^ω_E          (paper Eq. 1)

from its *contrast* ``C`` (absolute response of the 3 × 3 Laplacian filter
``[[0, 1, 0], [1, −4, 1], [0, 1, 0]]`` on the grey image, grey = 0.299 R + 0.587 G +
0.114 B), *saturation* ``S`` (standard deviation of R, G, B) and *well-exposedness*
``E = Π_c exp(−(I_c − 0.5)² / (2σ²))`` (σ = 0.2); the weights are normalised to sum to one
over the exposures (Eq. 2, with 1e-12 added so that a pixel every weight misses averages the
exposures). Blending the images with these weights directly leaves seams, so the paper blends
in a multiresolution pyramid (Burt & Adelson 1983): the Laplacian pyramid of each image times
the Gaussian pyramid of its weights, summed over exposures, collapsed (Eq. 3).

Pyramid filters as OpenCV's ``pyrDown``/``pyrUp`` (the binomial 5-tap kernel
``[1, 4, 6, 4, 1] / 16``; down-sampling keeps the even pixels, ``ceil(n / 2)`` of them; edges
reflected without repeating the edge pixel, and ``pyrUp`` repeats the last pixel at the far
edge), and the default depth is OpenCV's ``MergeMertens``: ``floor(log2(min(H, W))) + 1``
levels, down to one or two pixels. Output: the collapsed pyramid clipped to [0, 1]
(OpenCV's ``MergeMertens`` returns it unclipped).

Numeric contract: a bracket of uint8/uint16 code values (scaled to [0, 1] by the top code) or
float display values in [0, 1], ``(N, H, W, 3)``, any order of exposures, no exposure times;
returns display RGB ``(H, W, 3)`` in [0, 1] (float32, float64 under x64 for float64 input),
in the encoding of the inputs (for sRGB-encoded photographs: sRGB). JAX, jitted; batched
brackets of one size go through ``jax.vmap`` (pass float arrays or JAX arrays then).
"""

import math
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._bracket import as_codes

_KERNEL = (1.0, 4.0, 6.0, 4.0, 1.0)  # Burt & Adelson's binomial, /16
_GREY = (0.299, 0.587, 0.114)  # ITU-R BT.601 luma, OpenCV's RGB → grey
_EPS = 1e-12  # Mertens' weights: a pixel no exposure weights averages them


def _down_axis(x: Array, axis: int) -> Array:
    """Blur with the 5-tap kernel along ``axis`` and keep the even samples."""
    n = x.shape[axis]
    m = (n + 1) // 2
    if n == 1:
        return x
    pad = [(0, 0)] * x.ndim
    pad[axis] = (2, 2)
    p = jnp.pad(x, pad, mode="reflect")  # OpenCV's BORDER_REFLECT_101
    out = 0.0
    for k, c in enumerate(_KERNEL):
        out = out + c * jax.lax.slice_in_dim(p, k, k + 2 * m - 1, stride=2, axis=axis)
    return out / 16.0


def _up_axis(x: Array, size: int, axis: int) -> Array:
    """Double the samples along ``axis`` (zero insertion + the 5-tap kernel × 2), crop to ``size``.

    Even outputs ``(s[i−1] + 6 s[i] + s[i+1]) / 8``, odd ``(s[i] + s[i+1]) / 2``; at the near
    edge ``s[−1] = s[1]``, at the far edge ``s[n] = s[n−1]`` (as OpenCV's ``pyrUp``).
    """
    n = x.shape[axis]
    if n == 1:
        rep = [1] * x.ndim
        rep[axis] = size
        return jnp.tile(x, rep)
    first = jax.lax.slice_in_dim(x, 1, 2, axis=axis)
    last = jax.lax.slice_in_dim(x, n - 1, n, axis=axis)
    p = jnp.concatenate([first, x, last], axis=axis)  # s[-1] … s[n]
    prev = jax.lax.slice_in_dim(p, 0, n, axis=axis)
    here = jax.lax.slice_in_dim(p, 1, n + 1, axis=axis)
    nxt = jax.lax.slice_in_dim(p, 2, n + 2, axis=axis)
    even = (prev + 6.0 * here + nxt) / 8.0
    odd = (here + nxt) / 2.0
    both = jnp.stack([even, odd], axis=axis + 1)
    shape = list(x.shape)
    shape[axis] = 2 * n
    return jax.lax.slice_in_dim(both.reshape(shape), 0, size, axis=axis)


def _down(x: Array) -> Array:
    return _down_axis(_down_axis(x, 0), 1)


def _up(x: Array, shape: tuple[int, int]) -> Array:
    return _up_axis(_up_axis(x, shape[0], 0), shape[1], 1)


def _safe_pow(x: Array, p: Array) -> Array:
    """``x^p`` for ``x ≥ 0`` with ``0^0 = 1`` and finite gradients at 0."""
    pos = x > 0
    return jnp.where(pos, jnp.power(jnp.where(pos, x, 1.0), p), jnp.where(p == 0, 1.0, 0.0))


def _weights(img: Array, wc: Array, ws: Array, we: Array, sigma: Array) -> Array:
    """Mertens' un-normalised weight map ``(H, W)`` of one exposure ``(H, W, 3)`` in [0, 1]."""
    grey = img[..., 0] * _GREY[0] + img[..., 1] * _GREY[1] + img[..., 2] * _GREY[2]
    p = jnp.pad(grey, 1, mode="reflect")
    lap = p[:-2, 1:-1] + p[2:, 1:-1] + p[1:-1, :-2] + p[1:-1, 2:] - 4.0 * grey
    contrast = jnp.abs(lap)
    mean = jnp.mean(img, axis=-1, keepdims=True)
    var = jnp.mean(jnp.square(img - mean), axis=-1)
    saturation = jnp.sqrt(jnp.where(var > 0, var, 1.0)) * (var > 0)
    exposedness = jnp.prod(jnp.exp(-jnp.square(img - 0.5) / (2.0 * sigma**2)), axis=-1)
    return _safe_pow(contrast, wc) * _safe_pow(saturation, ws) * _safe_pow(exposedness, we) + _EPS


@partial(jax.jit, static_argnames=("levels",))
def _fuse(
    images: Float[Array, "N H W 3"],
    wc: Array,
    ws: Array,
    we: Array,
    sigma: Array,
    levels: int,
) -> Float[Array, "H W 3"]:
    w = jax.vmap(_weights, in_axes=(0, None, None, None, None))(images, wc, ws, we, sigma)
    w = w / jnp.sum(w, axis=0, keepdims=True)
    shapes = [images.shape[1:3]]
    for _ in range(levels - 1):
        h, wd = shapes[-1]
        shapes.append(((h + 1) // 2, (wd + 1) // 2))

    def blend(acc: tuple[Array, ...], item: tuple[Array, Array]) -> tuple[tuple[Array, ...], None]:
        img, wt = item
        gauss, weights = [img], [wt]
        for _ in range(levels - 1):
            gauss.append(_down(gauss[-1]))
            weights.append(_down(weights[-1]))
        lap = [g - _up(gn, s) for g, gn, s in zip(gauss[:-1], gauss[1:], shapes[:-1], strict=True)]
        lap.append(gauss[-1])
        pairs = zip(acc, lap, weights, strict=True)
        return tuple(a + lp * wt[..., None] for a, lp, wt in pairs), None

    zeros = tuple(jnp.zeros((*s, 3), images.dtype) for s in shapes)
    pyr, _ = jax.lax.scan(blend, zeros, (images, w))
    out = pyr[-1]
    for lvl in range(levels - 2, -1, -1):
        out = pyr[lvl] + _up(out, shapes[lvl])
    return jnp.clip(out, 0.0, 1.0)


def _as_unit(images: Any) -> Array:
    """Bracket → float display values ``(N, H, W, 3)`` in [0, 1] (JAX arrays pass through)."""
    if isinstance(images, jax.Array):
        if images.ndim != 4 or images.shape[-1] != 3 or images.shape[0] < 1:
            raise ValueError(
                f"images: expected N exposures of (H, W, 3) values, got shape {images.shape}"
            )
        if images.dtype == jnp.uint8 or images.dtype == jnp.uint16:
            top = 255.0 if images.dtype == jnp.uint8 else 65535.0
            return images.astype(jnp.float32) / top
        if not jnp.issubdtype(images.dtype, jnp.floating):
            raise ValueError(
                f"images: expected uint8/uint16 codes or floats in [0, 1], got {images.dtype}"
            )
        return images
    if isinstance(images, np.ndarray) and np.issubdtype(images.dtype, np.floating):
        arr = images
    elif (
        isinstance(images, list | tuple)
        and len(images) > 0
        and all(
            isinstance(im, np.ndarray) and np.issubdtype(im.dtype, np.floating) for im in images
        )
    ):
        if len({im.shape for im in images}) > 1:
            raise ValueError(
                f"images: the exposures must all have one size, got shapes "
                f"{sorted({im.shape for im in images})}"
            )
        arr = np.stack(images)
    else:
        codes = as_codes(images, name="images", need_times=False)
        return jnp.asarray(codes.codes, jnp.float32) / float(codes.levels - 1)
    if arr.ndim != 4 or arr.shape[-1] != 3 or 0 in arr.shape:
        raise ValueError(f"images: expected N exposures of (H, W, 3) values, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)) or arr.min() < 0 or arr.max() > 1:
        raise ValueError("images: float exposures must be finite display values in [0, 1]")
    return jnp.asarray(arr)


def _check_weight(value: Any, name: str) -> Array:
    if isinstance(value, jax.Array) and not isinstance(value, jax.core.Tracer):
        value = np.asarray(value)
    if isinstance(value, jax.core.Tracer):
        return value
    if isinstance(value, bool | str) or np.ndim(value) != 0:
        raise ValueError(f"{name}: expected a non-negative number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a non-negative number, got {value!r}") from None
    if not math.isfinite(v) or v < 0:
        raise ValueError(f"{name}: expected a non-negative finite number, got {value!r}")
    return jnp.asarray(v)


def fuse(
    images: Any,
    *,
    contrast: float = 1.0,
    saturation: float = 1.0,
    exposedness: float = 1.0,
    sigma: float = 0.2,
    levels: int | None = None,
) -> Float[Array, "H W 3"]:
    """Fuse a bracket into one display image (Mertens, Kautz & Van Reeth 2007).

    Args:
        images: ``(N, H, W, 3)`` uint8/uint16 code values, a list of ``(H, W, 3)`` arrays,
            or file paths (:func:`hdrjax.merge.as_codes`; codes are divided by the top
            code); or float display values in [0, 1] (NumPy or JAX; JAX arrays are not
            range-checked, so that ``jax.vmap`` over brackets works).
        contrast, saturation, exposedness: the exponents ω_C, ω_S, ω_E of the three
            measures (the paper's Eq. 1; 0 ignores a measure).
        sigma: width of the well-exposedness Gaussian around 0.5 (display units; the
            paper's 0.2).
        levels: pyramid levels including full size; default ``floor(log2(min(H, W))) + 1``
            (OpenCV's MergeMertens).

    Returns:
        Display RGB ``(H, W, 3)`` in [0, 1], same encoding as the inputs.
    """
    x = _as_unit(images)
    if not jnp.issubdtype(x.dtype, jnp.floating):
        x = x.astype(jnp.float32)
    h, w = x.shape[1:3]
    wc = _check_weight(contrast, "contrast")
    ws = _check_weight(saturation, "saturation")
    we = _check_weight(exposedness, "exposedness")
    sg = _check_weight(sigma, "sigma")
    if not isinstance(sg, jax.core.Tracer) and float(sg) == 0:
        raise ValueError(f"sigma: expected a positive number, got {sigma!r}")
    max_levels = int(math.floor(math.log2(min(h, w)))) + 1
    if levels is None:
        levels = max_levels
    elif isinstance(levels, bool) or not isinstance(levels, int | np.integer) or levels < 1:
        raise ValueError(f"levels: expected an integer ≥ 1, got {levels!r}")
    dt = x.dtype
    return _fuse(x, wc.astype(dt), ws.astype(dt), we.astype(dt), sg.astype(dt), levels=int(levels))
