"""Median filters with three criteria, over channels-last images or plain planes.

Numeric contract: any float image (float32 by default, float64 under x64); the output has
the input's shape and is made of input values only (each output pixel is one window pixel,
or per channel one window value), so no value is created, rounded or clipped.

Criteria (Birukov et al., GraphiCon 2022, section 4.1, discuss all three):

- ``"luminance"`` (default): one physical value per pixel — the luminance
  ``Y = w·RGB`` (:func:`hdrjax.luminance`) — chooses the window's median pixel and its
  whole RGB is taken, so colours are never mixed. Ties in luminance go to the earlier pixel
  in row-major image order.
- ``"channels"``: each channel independently; bit-identical to
  ``scipy.ndimage.median_filter(x, size, mode=mode)`` per channel.
- ``"vector"``: the vector median — the window pixel minimising the sum of Euclidean
  distances to the other window pixels (Astola et al. 1990). O(k⁴) per pixel.

NaN: NaN sorts above +Inf (as in ``numpy.sort``). A window's median is NaN only when more
than half of its values are NaN, so a NaN never spreads beyond its own window, and an
isolated NaN pixel is replaced by its neighbours' median. The vector median never picks a
pixel with a non-finite channel (unless the whole window is non-finite: then the centre).

Edges: ``mode`` as in SciPy — ``"nearest"`` (replicate, the default), ``"reflect"``,
``"mirror"``, ``"wrap"``. Each pass is a k×k filter; ``passes`` repeats it.

Speed: windows up to 7×7 use comparator networks (min/max on order-preserving integer
keys, two rows' medians sharing one network) over row strips; a single plane of up to
2²¹ pixels called eagerly on the CPU skips the strips (the whole interior in one kernel,
then the edges: ~45 kernel launches instead of ~280 at 1366×768); larger windows find the
median bit by bit (32 compare-and-count rounds of k² per pixel), which compiles in about a
second for any k where a 15×15 network would take minutes. See
``benchmarks/bench_filters.py`` and the README for measured ratios to OpenCV and SciPy.
Ordering is that of the keys: −0 sorts before +0. Gradients: each output is one input
value, so the gradient flows to the selected pixel (for ``"channels"``, to the first window
value equal to the median).
"""

import functools
from collections.abc import Sequence
from typing import Literal

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._colour import luminance
from ._api import (
    call,
    check_layout,
    check_passes,
    check_size,
    check_strip_rows,
    eager_cpu,
    float_image,
    map_channels,
)
from ._keys import to_key
from ._median_core import (
    NETWORK_MAX,
    SMALL_PIXELS,
    argmedian_plane,
    median_finish,
    median_pairs,
    median_plane,
)
from ._strips import check_mode, padded_block
from ._vector_core import argvector_plane

Criterion = Literal["luminance", "channels", "vector"]
CRITERIA: tuple[str, ...] = ("luminance", "channels", "vector")


@functools.partial(jax.custom_jvp, nondiff_argnums=(1, 2, 3))
def _median_plane(x: Array, k: int, mode: str, rows: int | None) -> Array:
    return median_plane(x, k, mode, rows)


@_median_plane.defjvp
def _median_plane_jvp(k, mode, rows, primals, tangents):
    (x,), (t,) = primals, tangents
    y = median_plane(x, k, mode, rows)
    # the tangent of the first window value (row-major) that equals the median, bitwise
    h, w = x.shape
    r = k // 2
    xk = to_key(padded_block(x, r, mode, 0, h, 0, w))
    tp = padded_block(t, r, mode, 0, h, 0, w)
    yk = to_key(y)
    found = jnp.zeros(y.shape, bool)
    out = jnp.zeros_like(t)
    for i in range(k):
        for j in range(k):
            hit = (jax.lax.slice(xk, (i, j), (i + h, j + w)) == yk) & ~found
            out = jnp.where(hit, jax.lax.slice(tp, (i, j), (i + h, j + w)), out)
            found = found | hit
    return y, out


def _gather(img: Array, idx: Array) -> Array:
    """Pixels of an (H, W, C) image at flat indices (H, W) → (H, W, C)."""
    h, w, c = img.shape
    return jnp.take(img.reshape(h * w, c), idx.reshape(-1), axis=0).reshape(h, w, c)


def _median_impl(x, *, size, criterion, passes, mode, weights, planes, rows):
    if planes or criterion == "channels" or x.shape[-1] == 1:

        def one(plane):
            return _median_plane(plane, size, mode, rows)

        def step(img):
            return map_channels(one, img, planes)

    else:
        lead = x.ndim - 3

        def pick(img):  # one (H, W, C) image
            if criterion == "luminance":
                idx = argmedian_plane(
                    jax.lax.stop_gradient(luminance(img, weights)), size, mode, rows
                )
            else:
                idx = argvector_plane(img, size, mode, rows)
            return _gather(img, idx)

        def step(img):
            if lead == 0:
                return pick(img)
            flat = img.reshape((-1,) + img.shape[lead:])
            return jax.vmap(pick)(flat).reshape(img.shape)

    if passes == 1:
        return step(x)
    return jax.lax.fori_loop(0, passes, lambda _, img: step(img), x)


_STATIC = ("size", "criterion", "passes", "mode", "weights", "planes", "rows")


def median_filter(
    image: Float[ArrayLike, "*batch H W C"] | Float[ArrayLike, "*batch H W"],
    size: int = 5,
    *,
    criterion: Criterion = "luminance",
    passes: int = 1,
    mode: Literal["nearest", "reflect", "mirror", "wrap"] = "nearest",
    weights: Sequence[float] | None = None,
    channel_axis: int | None = -1,
    strip_rows: int | None = None,
) -> Float[Array, "*batch H W C"] | Float[Array, "*batch H W"]:
    """Median filter with a k×k window (see the module docstring for the criteria).

    Args:
        image: channels-last ``(..., H, W, C)`` (any units; linear or not), or ``(..., H, W)``
            planes with ``channel_axis=None``. Leading axes are a batch.
        size: window side k, odd (1 returns the image).
        criterion: ``"luminance"`` (default; needs C = 3, or C = 1 where all criteria agree),
            ``"channels"`` or ``"vector"``. Ignored for planes (all three agree on scalars).
        passes: how many times the filter is applied (0 returns the image).
        mode: edge handling; ``"nearest"`` replicates the edge pixels.
        weights: luminance weights for ``"luminance"`` (Rec.709 by default).
        channel_axis: ``-1`` for channels last, ``None`` for planes.
        strip_rows: rows per strip (default: about 256 KiB of keys, and no strips for a
            single plane of up to 2²¹ pixels); results do not depend on it, only speed and
            the size of temporaries.

    Returns:
        The filtered image, same shape, float32 (float64 for float64 input under x64).

    Raises:
        ValueError: on an even or non-positive size, an unknown criterion or mode, or a
            shape that does not fit ``channel_axis``/``criterion``.
    """
    x = float_image(image)
    check_layout(x, channel_axis)
    size = check_size(size)
    passes = check_passes(passes)
    mode = check_mode(mode)
    rows = check_strip_rows(strip_rows)
    if criterion not in CRITERIA:
        raise ValueError(f"criterion: expected one of {', '.join(CRITERIA)}, got {criterion!r}")
    planes = channel_axis is None
    if not planes and criterion == "luminance" and x.shape[-1] not in (1, 3):
        raise ValueError(
            f"criterion 'luminance' needs 3 channels (RGB), got {x.shape[-1]}; "
            "use criterion='channels' or 'vector'"
        )
    w = None if weights is None else tuple(float(v) for v in weights)
    if size == 1 or passes == 0:
        return x
    if (
        planes
        and x.ndim == 2
        and passes == 1
        and rows is None
        and size <= NETWORK_MAX
        and 4096 < x.size <= SMALL_PIXELS
        and min(x.shape) > size
        and eager_cpu(x)
    ):  # one small plane: two compiled stages, no strips (same values)
        pairs = call(median_pairs, ("k",), x, k=size)
        return call(median_finish, ("k", "mode"), pairs, x, k=size, mode=mode)
    return call(
        _median_impl,
        _STATIC,
        x,
        size=size,
        criterion=criterion,
        passes=passes,
        mode=mode,
        weights=w,
        planes=planes,
        rows=rows,
    )
