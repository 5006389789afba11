"""Highlight desaturation (Birukov et al., GraphiCon 2022, section 4.2).

Numeric contract: input is linear RGB ``(..., H, W, 3)``, scene-referred (relative or cd/m²)
by default, before tone mapping; the output has the same shape and units. Per pixel, as in
the paper:

1. ``μ = (R + G + B) / 3``, the mean of the channels;
2. ``d_c = c − μ`` for each channel;
3. ``s = clip((L − T) / (L_max − T), 0, 1)``: 0 at and below the threshold ``T``, 1 at the
   image's largest luminance ``L_max``, linear in between (``L`` is the pixel's luminance,
   :func:`hdrjax.luminance`);
4. ``c' = c − s · d_c``: each channel moves towards the mean, fully so at ``L_max``.

Automatic threshold (the paper's final version): ``T = 2 · L₉₀``, where ``L₉₀`` is the
luminance that only 10 % of the image's finite pixels exceed. It comes from
:func:`hdrjax.stats.percentile`'s fixed-grid histogram (relative error at most
``rel_error_bound``, returned by :func:`highlight_threshold`: ``2^-10`` = 0.098 % with the
default 8192 bins, whatever the dynamic range) or, with ``method="exact"``, from a sort.
``T`` is at most the dtype's largest finite float (``L₉₀`` above half of it would double
past it), which is still at or above every finite pixel.
Manual mode takes ``T`` directly.

Why before tone mapping (the default): the threshold and ``L_max`` are statistics of the
physical luminances, as in the paper, where the step belongs to the HDR module. After a
tone curve that clips, the brightest pixels all share the display maximum and the ramp
between ``T`` and ``L_max`` collapses; hdrjax's operators scale RGB by ``L_d / L_w``, so
the channel ratios set here survive tone mapping and the highlights come out white. The
function is plain arithmetic on linear RGB and can also run on display-referred linear RGB.

Speed (automatic threshold, histogram): one pass over the luminance gives the histogram
for ``L₉₀``, ``L_max`` and the test that every pixel is finite
(:func:`hdrjax._stats.summarise_histogram`), then one fused loop reads RGB, recomputes the luminance
and the mean and writes the output (reading a luminance image back would cost ~30 % more
at 4096²). Images with NaN or ±Inf pixels, the exact method and a manual threshold take the
masked path.

Differentiable in the image and in ``T`` (a manual threshold; the histogram percentile is a
constant for ``jax.grad``, the exact one is differentiable). Leading axes are a batch: each
image gets its own automatic threshold and maximum. Pixels with a NaN or infinite channel
are returned unchanged and are left out of the statistics; when ``T ≥ L_max`` nothing
changes.
"""

import functools
from collections.abc import Sequence
from typing import Literal

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .. import _check, _repr
from .._colour import channel_min, luminance
from .._scale import inverse_pow2
from .._stats import DEFAULT_BINS, Statistics, percentile, summarise, summarise_histogram
from ..operators._base import as_float_image

PERCENT_ABOVE = 10.0
"""The automatic threshold doubles the luminance exceeded by this share of pixels (%)."""
THRESHOLD_FACTOR = 2.0


def _check_method(method: str, bins: int) -> None:
    if method not in ("histogram", "exact"):
        raise ValueError(f"method: expected 'histogram' or 'exact', got {method!r}")
    if int(bins) < 2:
        raise ValueError(f"bins: expected an integer >= 2, got {bins!r}")


def _over_batch(fn, lead: int, *arrays):
    """Apply a one-image function over ``lead`` leading batch axes."""
    for _ in range(lead):
        fn = jax.vmap(fn)
    return fn(*arrays)


def _rank_q(n_finite: Array, n_pos: Array, dtype) -> tuple[Array, Array]:
    """``(rank_pos, q)``: the 90th percentile of all ``n_finite`` pixels as a rank and a
    quantile among the ``n_pos`` positive ones (what :func:`hdrjax.stats.percentile` ranks).

    numpy.percentile's rank among all n finite pixels is 0.9 (n − 1); the n − n_pos
    non-positive ones come first, so among the positive ones it is
    rank_pos = n_pos − 1 − 0.1 (n − 1)."""
    frac = 1.0 - PERCENT_ABOVE / 100.0
    rank_pos = n_pos.astype(dtype) - 1 - (1 - frac) * (n_finite.astype(dtype) - 1)
    q = jnp.clip(rank_pos / jnp.maximum(n_pos - 1, 1).astype(dtype), 0.0, 1.0)
    return rank_pos, q


def _threshold_of(L90: Array) -> Array:
    """``T = 2 · L₉₀``, at most the largest finite float: a threshold past it is still at or
    above every finite luminance (nothing is desaturated either way), and stays finite."""
    return jnp.minimum(THRESHOLD_FACTOR * L90, jnp.finfo(L90.dtype).max)


def _statistics(L: Array, finite: Array | None, bins: int) -> Statistics:
    """The statistics of the finite pixels of one image (``finite``: their mask, ``None``
    when every pixel is: the clean branch of :func:`_clean_or_masked`, which needs no mask
    and no log sum)."""
    if finite is None:
        return summarise_histogram(L, bins=bins)[1]
    return summarise(jnp.where(finite, L, jnp.nan), bins=bins, keep_source=False)[1]


def _l90(st: Statistics, L: Array, finite: Array | None, method: str) -> tuple[Array, Array]:
    """``(L₉₀, rel_error_bound)`` from the statistics ``st`` of the finite pixels of one
    image, the exact method from a sort of ``L`` (``finite``: the mask, as above)."""
    rank_pos, q = _rank_q(st.n_finite, st.n_positive, L.dtype)
    if method == "exact":
        value, err = percentile(L, 100.0 * q, method="exact", where=finite)
    else:
        value, err = st.quantile(q)
    # the 90th percentile lies among the non-positive pixels: the threshold is 0
    return jnp.where((st.n_positive > 0) & (rank_pos >= 0), value, 0.0), err


def _threshold_one(
    L: Array, finite: Array | None, method: str, bins: int
) -> tuple[Array, Array, Array]:
    """``(T, L₉₀, rel_error_bound)``: ``L₉₀`` the luminance exceeded by 10 % of the finite
    pixels of one image (``finite``: their mask, ``None`` when every pixel is)."""
    value, err = _l90(_statistics(L, finite, bins), L, finite, method)
    return _threshold_of(value), value, err


def _one_pass_threshold(L: Array, bins: int) -> tuple[Array, Array, Array]:
    """``(finite, threshold, L_max)`` of a whole image in one pass over its luminance
    (:func:`hdrjax._stats.summarise_histogram`: the fixed-grid histogram and the extrema
    together); the threshold and ``L_max`` are those of :func:`_threshold_one` and of the
    mapping when ``finite`` (every pixel finite), meaningless otherwise."""
    finite, st = summarise_histogram(L, bins=bins)
    value = _l90(st, L, None, "histogram")[0]
    return finite, _threshold_of(value), st.max


def highlight_threshold(
    rgb: Float[ArrayLike, "*batch H W 3"],
    *,
    weights: Sequence[float] | None = None,
    method: Literal["histogram", "exact"] = "histogram",
    bins: int = DEFAULT_BINS,
) -> tuple[Float[Array, "*batch"], Float[Array, "*batch"]]:
    """The automatic desaturation threshold ``T = 2 · L₉₀`` of each image.

    Args:
        rgb: linear RGB, channels last; leading axes are a batch.
        weights: luminance weights (Rec.709 by default).
        method: ``"histogram"`` (fast, error-bounded) or ``"exact"`` (sort, differentiable).
        bins: histogram resolution (:func:`hdrjax.stats.percentile`: ``2^(ceil(log2 bins)
            − 3)`` bins per octave).

    Returns:
        ``(threshold, rel_error_bound)`` per image, in the image's luminance units; the bound
        is on the relative error of ``L₉₀`` (0 for ``"exact"``). A threshold past the largest
        finite float (``L₉₀`` above half of it) is that float: still at or above every
        pixel, so nothing is desaturated.
    """
    T, _, err = threshold_and_l90(rgb, weights=weights, method=method, bins=bins)
    return T, err


def threshold_and_l90(
    rgb: Float[ArrayLike, "*batch H W 3"],
    *,
    weights: Sequence[float] | None = None,
    method: Literal["histogram", "exact"] = "histogram",
    bins: int = DEFAULT_BINS,
) -> tuple[Float[Array, "*batch"], Float[Array, "*batch"], Float[Array, "*batch"]]:
    """``(threshold, L₉₀, rel_error_bound)``: :func:`highlight_threshold` and the
    percentile it doubles (``hdrjax.estimate`` reports both; ``T / 2`` is not ``L₉₀`` where
    the threshold is clamped to the largest float)."""
    x = as_float_image(rgb)
    _check_method(method, bins)
    w = None if weights is None else tuple(float(v) for v in weights)
    return _threshold_impl(x, w, method, int(bins))


@functools.partial(jax.jit, static_argnums=(1, 2, 3))
def _threshold_impl(x, weights, method, bins):
    def one(img):
        return _clean_or_masked(img, weights, lambda L, f: _threshold_one(L, f, method, bins))

    return _over_batch(one, x.ndim - 3, x)


def _finite_rgb(x: Array) -> Array:
    # per-channel slices, not a reduction over the last axis: XLA:CPU fuses them
    return jnp.isfinite(x[..., 0]) & jnp.isfinite(x[..., 1]) & jnp.isfinite(x[..., 2])


def _clean_or_masked(x: Array, weights, fn):
    """``fn(L, None)`` on the luminance when every channel of every pixel is finite (one
    sum decides), else ``fn(L, finite)`` with the pixel mask and the non-finite pixels'
    luminance set to 0. The clean branch skips every mask: on XLA:CPU a select inside a
    reduction materialises a full-size temporary (:mod:`hdrjax._stats`, "Speed")."""
    L_raw = luminance(x, weights)

    def clean(x):
        return fn(L_raw, None)

    def masked(x):
        finite = _finite_rgb(x)
        return fn(luminance(jnp.where(finite[..., None], x, 0.0), weights), finite)

    # NaN or ±Inf in a channel makes the luminance sum non-finite (0 · Inf is NaN)
    return jax.lax.cond(jnp.isfinite(jnp.sum(L_raw)), clean, masked, x)


def _mapping(x: Array, L: Array, t: Array, L_max: Array) -> Array:
    """Steps 1–4 of the module docstring on an image whose pixels are all finite.

    Computed on the image times ``c``, a power of two that brings ``L_max`` into [0.5, 4):
    exact, so ordinary images give the same bits, while the channel sum cannot overflow
    near the float maximum and the ramp's gradient ``1 / span²`` neither overflows for dim
    images nor underflows for bright ones."""
    c = inverse_pow2(L_max)
    span = (L_max - t) * c
    # a ramp narrower than the rounding of the luminance itself (a few ulps of L_max) is no
    # ramp: a threshold at the maximum as another luminance routine computed it must leave
    # the image as it is, not turn its brightest pixel grey
    ok = span > 4 * jnp.finfo(x.dtype).eps * (L_max * c)
    s = jnp.where(ok, jnp.clip((L * c - t * c) / jnp.where(ok, span, 1.0), 0.0, 1.0), 0.0)
    xc = x * c
    # the mean as the smallest channel plus the mean excess over it: exact for a grey
    # pixel (whose (3 x) / 3 may round away from x), so grey pixels keep every bit
    lo = channel_min(xc, keepdims=True)
    d = xc - lo
    mean = lo + ((d[..., 0] + d[..., 1] + d[..., 2]) / 3.0)[..., None]
    # x itself unscaled: pixels below the threshold (s = 0) keep every bit, even those that
    # scaling would take below the smallest normal float
    return x - s[..., None] * ((xc - mean) / c)


@jax.custom_jvp
def _max_of(L: Array, value: Array) -> Array:
    """``value``, which is ``max(L)`` measured elsewhere, with ``jnp.max``'s derivative in
    ``L`` (shared equally by tied pixels), so that ``L_max`` stays differentiable."""
    return jax.lax.stop_gradient(value)


@_max_of.defjvp
def _max_of_jvp(primals, tangents):
    (L, value), (t, _) = primals, tangents
    hit = (L == value).astype(L.dtype)
    return _max_of(L, value), jnp.sum(t * hit) / jnp.maximum(jnp.sum(hit), 1.0)


def _desaturate_one(x: Array, T: Array | None, weights, method: str, bins: int) -> Array:
    def run(L, finite):
        t = _threshold_one(L, finite, method, bins)[0] if T is None else T
        if finite is None:
            return _mapping(x, L, t, jnp.max(L))
        L_max = jnp.max(jnp.where(finite, L, -jnp.inf))
        safe = jnp.where(finite[..., None], x, 0.0)
        return jnp.where(finite[..., None], _mapping(safe, L, t, L_max), x)

    if T is not None or method != "histogram":
        return _clean_or_masked(x, weights, run)
    # automatic threshold from the histogram: the statistics pass also tells whether the
    # image is finite (no separate sum), and the clean mapping recomputes the luminance
    # from RGB in its own loop instead of reading the luminance image back
    L = luminance(x, weights)
    L = jax.lax.optimization_barrier(L.reshape(-1)).reshape(L.shape)  # one luminance image
    finite, t, L_max = _one_pass_threshold(L, bins)

    def clean(x, t, L_max):
        L = luminance(x, weights)
        return _mapping(x, L, t, _max_of(L, L_max))

    def masked(x, *_):
        finite = _finite_rgb(x)
        return run(luminance(jnp.where(finite[..., None], x, 0.0), weights), finite)

    return jax.lax.cond(finite, clean, masked, x, t, L_max)


def desaturate_highlights(
    rgb: Float[ArrayLike, "*batch H W 3"],
    threshold: Float[ArrayLike, "*batch"] | None = None,
    *,
    weights: Sequence[float] | None = None,
    method: Literal["histogram", "exact"] = "histogram",
    bins: int = DEFAULT_BINS,
) -> Float[Array, "*batch H W 3"]:
    """Move the channels of bright pixels towards their mean (see the module docstring).

    Args:
        rgb: linear RGB ``(..., H, W, 3)``, scene-referred by default; a batch is allowed.
        threshold: ``T`` in the image's luminance units (manual mode; a scalar or one value
            per image), or ``None`` for the automatic ``2 · L₉₀`` of each image.
        weights: luminance weights (Rec.709 by default; pass the file's for other primaries).
        method: how the automatic threshold's percentile is found (``"histogram"``/``"exact"``).
        bins: histogram bins for ``method="histogram"``.

    Returns:
        Linear RGB of the same shape and units.

    Example:
        >>> import jax.numpy as jnp
        >>> rgb = jnp.array([[[1.0, 1.0, 1.0], [4.0, 2.0, 0.0], [8.0, 4.0, 0.0]]])
        >>> out = desaturate_highlights(rgb, threshold=2.0)
        >>> [round(v, 4) for v in out[0, 2].tolist()]  # the brightest pixel becomes grey
        [4.0, 4.0, 4.0]
        >>> out[0, 0].tolist()  # below the threshold: unchanged
        [1.0, 1.0, 1.0]
    """
    _check.positive(threshold, "threshold", zero=True, finite=False)
    x = as_float_image(rgb)
    _check_method(method, bins)
    w = None if weights is None else tuple(float(v) for v in weights)
    if threshold is None:
        return _desaturate_auto(x, w, method, int(bins))
    T = jnp.broadcast_to(jnp.asarray(threshold, x.dtype), x.shape[:-3])
    return _desaturate_manual(x, T, w)


@functools.partial(jax.jit, static_argnums=(1, 2, 3))
def _desaturate_auto(x, weights, method, bins):
    def one(img):
        return _desaturate_one(img, None, weights, method, bins)

    return _over_batch(one, x.ndim - 3, x)


@functools.partial(jax.jit, static_argnums=(2,))
def _desaturate_manual(x, T, weights):
    def one(img, t):
        return _desaturate_one(img, t, weights, "exact", 2)

    return _over_batch(one, x.ndim - 3, x, T)


class DesaturateHighlights(eqx.Module):
    """:func:`desaturate_highlights` as a Module (``threshold=None``: automatic), so that it
    composes with operators under ``jit``/``vmap``/``grad``; ``threshold`` is a parameter."""

    __repr__ = _repr.fields_repr
    _repr_html_ = _repr.fields_html

    threshold: Array | None = None
    weights: tuple[float, ...] | None = eqx.field(static=True, default=None)
    method: str = eqx.field(static=True, default="histogram")
    bins: int = eqx.field(static=True, default=DEFAULT_BINS)

    def __call__(self, rgb: Float[ArrayLike, "*batch H W 3"]) -> Float[Array, "*batch H W 3"]:
        return desaturate_highlights(
            rgb, self.threshold, weights=self.weights, method=self.method, bins=self.bins
        )
