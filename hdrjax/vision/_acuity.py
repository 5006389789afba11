"""Loss of visual acuity: resolution limited by the local adaptation luminance.

Radiance ``pcond``'s method (Ward Larson et al. 1997, doi:10.1109/2945.646233;
NREL/Radiance ``src/px/pcond4.c``, ``initacuity``/``acuscan``/``acusample``): the local
sample spacing, in pixels, is ``s = (pixels per degree) / R(L_fovea)`` with ``R`` the
acuity in cycles/degree (:func:`hdrjax.vision.acuity`) of the foveal (~1°) adaptation
luminance and "pixels per degree" ``1/sqrt(pixel solid angle)``; it is interpolated
bilinearly from the foveal grid to every pixel. The image is read through a MIP pyramid of
2×2 box averages (level ``k`` averages ``2^k × 2^k`` pixels); each pixel takes the two
levels that bracket ``s`` (``2^k <= s < 2^(k+1)``), each bilinearly interpolated, blended
linearly in ``s`` (pcond's ``acusample``). Where ``s <= 1`` the pixel is unchanged.

Deviations from pcond: the last row/column of pyramid blocks average only the pixels that
exist (pcond truncates the scanline length); interpolation holds the edge value instead of
extrapolating; NaN/Inf pixels are left out of every average and returned unchanged.
"""

import functools
import math
from collections.abc import Sequence

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._colour import luminance
from .._photometry import LMIN, check_rgb, chroma_key, restore, sanitize, weights_of
from ._fovea import block_mean, mean2x2, upsample
from ._pcond import acuity
from ._view import ResolvedView, View, resolve_view


def pixels_per_degree(view: ResolvedView) -> float:
    """``1/sqrt(pixel solid angle)`` in pixels per degree (pcond ``initacuity``)."""
    return 1.0 / math.sqrt(view.pixel_deg_x * view.pixel_deg_y)


def max_levels(view: ResolvedView, L_min: float = LMIN) -> int:
    """Pyramid levels needed when the darkest foveal adaptation is ``L_min`` (cd/m²).

    ``ceil(log2(ppd / R(L_min)))``, at most the level where the image is one block.
    """
    with jax.ensure_compile_time_eval():  # a Python number even inside a jax.jit trace
        s = pixels_per_degree(view) / float(acuity(max(L_min, LMIN)))
    need = max(0, math.ceil(math.log2(max(s, 1.0))))
    cap = max(0, math.ceil(math.log2(max(view.height, view.width))))
    return min(need, cap)


def sample_spacing(
    rgb: Float[ArrayLike, "H W 3"],
    view: "View | ResolvedView | float | None" = None,
    *,
    chromaticities: Sequence[float] | None = None,
) -> Float[Array, "H W"]:
    """pcond's local sample spacing ``s`` (pixels, >= 1) at every pixel."""
    x, ok = sanitize(check_rgb(rgb, image=True))
    view = resolve_view(view, x.shape[0], x.shape[1])
    w = weights_of(chroma_key(chromaticities))
    L = luminance(x, w)
    by, bx = view.fovea_block
    fov, _ = block_mean(L, ok, by, bx)
    s = pixels_per_degree(view) / acuity(jnp.maximum(fov, LMIN))
    return jnp.maximum(upsample(s, (by, bx), rgb.shape[:2]), 1.0)


def acuity_loss(
    rgb: Float[ArrayLike, "H W 3"],
    view: "View | ResolvedView | float | None" = None,
    *,
    levels: int | None = None,
    chromaticities: Sequence[float] | None = None,
) -> Float[Array, "H W 3"]:
    """Blur the image to the resolution the eye has at each pixel's adaptation luminance.

    Args:
        rgb: linear RGB in cd/m², ``(H, W, 3)``.
        view: field of view (:class:`View`, horizontal degrees, resolved, or ``None``).
        levels: pyramid levels (static); default :func:`max_levels` for the darkest possible
            adaptation. Spacings beyond ``2^levels`` pixels are clamped to it.
        chromaticities: the image's primaries (luminance weights).

    Returns:
        RGB in cd/m², same shape; non-finite pixels are returned unchanged.
    """
    rgb = check_rgb(rgb, image=True)
    view = resolve_view(view, rgb.shape[0], rgb.shape[1])
    K = max_levels(view) if levels is None else int(levels)
    if K < 0:
        raise ValueError(f"levels: expected an integer >= 0, got {levels!r}")
    return _acuity_loss(rgb, view, K, chroma_key(chromaticities))


@functools.partial(jax.jit, static_argnums=(1, 2, 3))
def _acuity_loss(
    rgb: Array, view: ResolvedView, K: int, chromaticities: tuple[float, ...] | None
) -> Array:
    x, ok = sanitize(rgb)
    s = jnp.clip(sample_spacing(x, view, chromaticities=chromaticities), 1.0, 2.0**K)
    mean, C = x, ok[..., None].astype(x.dtype)  # level k: 2^k × 2^k means and weights
    out = jnp.zeros_like(x)
    for k in range(K + 1):
        if k > 0:
            mean, C = mean2x2(mean, C)
        f = 2**k
        lo = (s - f / 2) / (f / 2) if k > 0 else jnp.ones_like(s)
        w = jnp.where(s <= f, jnp.clip(lo, 0.0, 1.0), jnp.clip((2 * f - s) / f, 0.0, 1.0))
        if k == K:
            w = jnp.where(s >= f, 1.0, w)
        up = mean if k == 0 else upsample(mean, (f, f), rgb.shape[:2])
        out = out + w[..., None] * up
    return restore(out, rgb, ok)


__all__ = ["acuity_loss", "max_levels", "pixels_per_degree", "sample_spacing"]
