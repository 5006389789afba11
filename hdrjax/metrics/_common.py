"""What the metrics share: the pair-of-images check, the luminance of a pair and a
separable Gaussian window (Wang et al. 2004's 11×11, σ = 1.5 pixels)."""

import functools
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .. import _check
from .._colour import REC709_WEIGHTS


def image_pair(test: Any, reference: Any, names: tuple[str, str]) -> tuple[jax.Array, jax.Array]:
    """Two RGB images ``(..., H, W, 3)`` of one shape, as float arrays of one dtype (the
    policy of ``hdrjax._check``); one-line ``ValueError`` naming the argument otherwise."""
    s_a = _check.shape(test, names[0])
    s_b = _check.shape(reference, names[1])
    if s_a != s_b:
        raise ValueError(f"{names[1]}: expected the shape of {names[0]} {s_a}, got shape {s_b}")
    a = _check.as_float(test)
    b = _check.as_float(reference)
    dt = jnp.result_type(a.dtype, b.dtype)
    return a.astype(dt), b.astype(dt)


def luminance(rgb: jax.Array) -> jax.Array:
    """Rec.709 luminance ``0.2126 R + 0.7152 G + 0.0722 B`` (HDR Toolbox's ``lum``)."""
    w = REC709_WEIGHTS
    return w[0] * rgb[..., 0] + w[1] * rgb[..., 1] + w[2] * rgb[..., 2]


def finite_or(x: jax.Array, value: float = 0.0) -> jax.Array:
    """``x`` with NaN and ±Inf replaced by ``value`` (before any arithmetic on them, so
    gradients stay finite)."""
    return jnp.where(jnp.isfinite(x), x, value)


def gaussian_taps(size: int = 11, sigma: float = 1.5) -> np.ndarray:
    """The 1-D factor of MATLAB's ``fspecial('gaussian', size, sigma)`` (which is its outer
    product with itself, normalised to sum 1)."""
    r = (size - 1) / 2
    x = np.arange(size) - r
    g = np.exp(-(x**2) / (2 * sigma**2))
    return g / g.sum()


def _filter_axis(x: jax.Array, taps: np.ndarray, axis: int, mode: str) -> jax.Array:
    """Correlate the last-but-``axis`` axis with ``taps`` (odd length), output the same size;
    zero padding (``"constant"``) or edge replication (``"edge"``)."""
    r = len(taps) // 2
    n = x.shape[axis]
    pad = [(0, 0)] * x.ndim
    pad[axis] = (r, r)
    p = jnp.pad(x, pad, mode=mode)
    out = None
    for k, t in enumerate(taps):
        term = jax.lax.slice_in_dim(p, k, k + n, axis=axis) * jnp.asarray(t, x.dtype)
        out = term if out is None else out + term
    return out


def gaussian_filter(x: jax.Array, taps: np.ndarray, mode: str = "constant") -> jax.Array:
    """Separable 2-D filter of the last two axes (``H, W``), the output the input's size:
    MATLAB's ``filter2(window, x, 'same')`` for ``mode="constant"`` (zero padding), and
    ``imgaussfilt(..., 'Padding', 'replicate')`` for ``mode="edge"``."""
    if mode == "constant":
        return _zero_padded(x, tuple(float(t) for t in taps))
    return _filter_axis(_filter_axis(x, taps, x.ndim - 2, mode), taps, x.ndim - 1, mode)


@functools.partial(jax.custom_vjp, nondiff_argnums=(1,))
def _zero_padded(x: jax.Array, taps: tuple[float, ...]) -> jax.Array:
    t = np.asarray(taps)
    return _filter_axis(_filter_axis(x, t, x.ndim - 2, "constant"), t, x.ndim - 1, "constant")


def _zero_padded_fwd(x, taps):
    return _zero_padded(x, taps), None


def _zero_padded_bwd(taps, _, ct):
    # a symmetric kernel with zero padding is a symmetric linear map: its transpose is
    # itself (autodiff's transpose of the shifted slices is several times slower)
    if taps != taps[::-1]:
        raise ValueError("taps: expected a symmetric kernel")
    return (_zero_padded(ct, taps),)


_zero_padded.defvjp(_zero_padded_fwd, _zero_padded_bwd)


def plane_mean(x: jax.Array) -> jax.Array:
    """Mean of an ``(H, W)`` plane as ``1ᵀ x 1 / (H W)``: XLA's CPU backend fuses a plain
    ``jnp.mean`` into the filters that compute ``x``, and that reduction runs them many
    times slower (measured on one filtered plane); the matrix products keep them apart."""
    h, w = x.shape
    return (jnp.ones(h, x.dtype) @ x @ jnp.ones(w, x.dtype)) / (h * w)


def safe_sqrt(v: jax.Array) -> jax.Array:
    """``sqrt(max(v, 0))`` whose gradient is 0 (not inf) where ``v <= 0``."""
    pos = v > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, v, 1.0)), 0.0)


def safe_power(x: jax.Array, p: float) -> jax.Array:
    """``max(x, 0) ** p`` for ``0 < p < 1`` with a finite gradient (0) at ``x <= 0``."""
    pos = x > 0
    return jnp.where(pos, jnp.where(pos, x, 1.0) ** p, 0.0)
