"""TMQI, the tone-mapped image quality index of Yeganeh & Wang (2013).

H. Yeganeh and Z. Wang, "Objective quality assessment of tone-mapped images", IEEE
Transactions on Image Processing 22(2):657–667, 2013, https://doi.org/10.1109/TIP.2012.2221725.

Numeric contract: the HDR image is linear RGB at any scale (relative or cd/m²: TMQI
normalises it to [0, 2³² − 1]); the LDR image is display-*encoded* RGB in [0, 1] (e.g.
:func:`hdrjax.display.encode` of an operator's output), which TMQI reads as 8-bit values
(times 255). Q, S and N lie in [0, 1]; higher is better.

The definitions are the authors' MATLAB code's (as HDR Toolbox ships it, ``TMQI.m`` and
``TMQI_*.m``), which the paper describes:

- luminance ``0.2126 R + 0.7152 G + 0.0722 B`` of both images; the HDR luminance mapped
  linearly to ``round((2³² − 1) / (L_max − L_min)) · (L − L_min)``;
- structural fidelity ``S = Π_l S_l^{w_l}`` over 5 scales, weights (0.0448, 0.2856,
  0.3001, 0.2363, 0.1333); between scales both images are averaged over 2×2 pixels
  (edges repeated) and subsampled by 2. At scale ``l`` (spatial frequency
  ``f = 16, 8, 4, 2, 1`` cycles/degree) ``S_l`` is the mean over the image of

  .. math::

      s = \\frac{2 \\sigma'_x \\sigma'_y + C_1}{\\sigma'^2_x + \\sigma'^2_y + C_1}
          \\cdot \\frac{\\sigma_{xy} + C_2}{\\sigma_x \\sigma_y + C_2},
      \\qquad C_1 = 0.01,\\ C_2 = 10,

  with local statistics in an 11×11 Gaussian window (σ = 1.5 pixels, zero padding at the
  edges, as MATLAB's ``filter2``) and ``σ' = Φ(σ; μ, μ/3)`` the normal CDF of the local
  standard deviation, ``μ = 128 / (1.4 · CSF(f))``,
  ``CSF(f) = 100 · 2.6 (0.0192 + 0.114 f) exp(−(0.114 f)^{1.1})`` (Mannos & Sakrison);
- statistical naturalness ``N = P_m P_d`` of the LDR luminance: ``P_m`` the normal
  density of its mean (μ = 115.94, σ = 27.99) and ``P_d`` the beta density
  (α = 4.4, β = 10.1) of the mean standard deviation of its 11×11 blocks divided by
  64.29, each divided by its maximum (so that ``N ≤ 1``);
- ``Q = a S^α + (1 − a) N^β`` with ``a = 0.8012``, ``α = 0.3046``, ``β = 0.7088``.

Deviations, each to keep the function finite and differentiable where the MATLAB code is
not: negative local fidelities ``S_l`` (anticorrelated images; MATLAB's product of their
powers is complex) count as 0; the powers ``S^α``, ``N^β`` have gradient 0 (not ∞) at 0;
a standard deviation of 0 has gradient 0. Non-finite pixels (NaN, ±Inf in either image)
are set to 0 in both images before anything is measured. Partial 11×11 blocks at the
right and bottom edges count with their own pixels, as MATLAB's ``blkproc`` does (GNU
Octave's ``blockproc`` zero-pads them). ``TMQI.m`` refuses images smaller than its
window; this function takes any size.
"""

from typing import NamedTuple

import jax
import jax.numpy as jnp
import jax.scipy.stats as jss
import numpy as np
from jaxtyping import ArrayLike, Float

from ._common import (
    finite_or,
    gaussian_filter,
    gaussian_taps,
    image_pair,
    luminance,
    plane_mean,
    safe_power,
    safe_sqrt,
)

A, ALPHA, BETA = 0.8012, 0.3046, 0.7088
"""``Q = A S^ALPHA + (1 − A) N^BETA`` (Yeganeh & Wang 2013, eq. 11)."""
SCALE_WEIGHTS = (0.0448, 0.2856, 0.3001, 0.2363, 0.1333)
"""Weights of the five scales' fidelities (finest first)."""
C1, C2 = 0.01, 10.0
"""Stabilising constants of the local structural fidelity."""
HDR_RANGE = 2.0**32 - 1
"""The HDR luminance is mapped linearly onto [0, HDR_RANGE]."""
LDR_SCALE = 255.0
"""The LDR image is read as 8-bit values: ``ldr · 255``."""
MEAN_MU, MEAN_SIGMA = 115.94, 27.99
"""Normal model of the mean LDR luminance (8-bit units)."""
STD_A, STD_B, STD_SCALE = 4.4, 10.1, 64.29
"""Beta model of the mean block standard deviation ``/ STD_SCALE``."""
BLOCK = 11
"""Block size (pixels) of the naturalness' standard deviations."""


class TMQIScore(NamedTuple):
    """TMQI's three numbers (each of shape ``*batch``), all in [0, 1], higher is better."""

    q: jax.Array
    """The overall quality ``Q``."""
    s: jax.Array
    """Structural fidelity ``S`` (multi-scale, against the HDR image)."""
    n: jax.Array
    """Statistical naturalness ``N`` (of the LDR image alone)."""


def _csf_mean(f: float) -> float:
    """``μ = 128 / (1.4 CSF(f))``: the local standard deviation at the threshold of
    visibility, for spatial frequency ``f`` (cycles/degree)."""
    csf = 100.0 * 2.6 * (0.0192 + 0.114 * f) * np.exp(-((0.114 * f) ** 1.1))
    return 128.0 / (1.4 * csf)


def _local_fidelity(x: jax.Array, y: jax.Array, hdr_scale: jax.Array, f: float) -> jax.Array:
    """Mean local structural fidelity of one scale; ``x`` the HDR luminance normalised to
    [0, 1] (times ``hdr_scale`` it is the reference's), ``y`` the LDR luminance (0–255)."""
    taps = gaussian_taps(11, 1.5)
    # one plane at a time: XLA compiles the shifted sums of a stack of planes far slower
    mu_x, mu_y, xx, yy, xy = (gaussian_filter(v, taps) for v in (x, y, x * x, y * y, x * y))
    sigma_x = safe_sqrt(xx - mu_x * mu_x) * hdr_scale
    sigma_y = safe_sqrt(yy - mu_y * mu_y)
    sigma_xy = (xy - mu_x * mu_y) * hdr_scale
    mu = _csf_mean(f)
    px = jss.norm.cdf(sigma_x, mu, mu / 3)
    py = jss.norm.cdf(sigma_y, mu, mu / 3)
    s_map = ((2 * px * py + C1) / (px * px + py * py + C1)) * (
        (sigma_xy + C2) / (sigma_x * sigma_y + C2)
    )
    return plane_mean(s_map)


def _downsample(x: jax.Array) -> jax.Array:
    """2×2 mean (the last row and column repeated when odd), every second pixel."""
    h, w = x.shape
    p = jnp.pad(x, ((0, h % 2), (0, w % 2)), mode="edge")
    h2, w2 = p.shape[0] // 2, p.shape[1] // 2
    rows = jnp.sum(p.reshape(h2, 2, 2 * w2), axis=1)
    # the pairs of columns by a matrix product over blocks of 16 columns: in the gradient
    # it is a matrix product too, which XLA's CPU backend does not fuse into the finer
    # scales — an elementwise upsampling there is fused scale into scale and recomputes
    # the coarse scales' filters for every fine pixel (4^l times over)
    k = 16 if w2 % 8 == 0 else 2
    pairs = np.kron(np.eye(k // 2), np.ones((2, 1))) * 0.25
    blocks = rows.reshape(h2, 2 * w2 // k, k) @ jnp.asarray(pairs, x.dtype)
    return blocks.reshape(h2, w2)


def _structural_fidelity(x: jax.Array, y: jax.Array, hdr_scale: jax.Array) -> jax.Array:
    s = jnp.asarray(1.0, x.dtype)
    f = 32.0
    for level, weight in enumerate(SCALE_WEIGHTS):
        f = f / 2
        s_l = _local_fidelity(x, y, hdr_scale, f)
        s = s * safe_power(s_l, weight)
        if level < len(SCALE_WEIGHTS) - 1:
            x, y = _downsample(x), _downsample(y)
    return s


def _block_std(y: jax.Array) -> jax.Array:
    """Mean over the 11×11 blocks (partial ones at the edges included, with their own
    pixels) of each block's sample standard deviation (``n − 1``; 0 for one pixel)."""
    h, w = y.shape
    bh, bw = -(-h // BLOCK), -(-w // BLOCK)
    pad = ((0, bh * BLOCK - h), (0, bw * BLOCK - w))
    yb = jnp.pad(y, pad).reshape(bh, BLOCK, bw, BLOCK)
    inside = jnp.pad(jnp.ones((h, w), y.dtype), pad).reshape(bh, BLOCK, bw, BLOCK)
    n = jnp.sum(inside, axis=(1, 3))
    mean = jnp.sum(yb, axis=(1, 3)) / n
    dev = (yb - mean[:, None, :, None]) * inside
    ss = jnp.sum(dev * dev, axis=(1, 3))
    var = ss / jnp.maximum(n - 1, 1)
    return jnp.mean(safe_sqrt(var))


def _naturalness(y: jax.Array) -> jax.Array:
    """``N = P_m P_d`` of the LDR luminance ``y`` (0–255)."""
    u = jnp.mean(y)
    pm = jnp.exp(-((u - MEAN_MU) ** 2) / (2 * MEAN_SIGMA**2))  # normal density / its peak
    t = _block_std(y) / STD_SCALE
    mode = (STD_A - 1) / (STD_A + STD_B - 2)
    inside = (t > 0) & (t < 1)
    ts = jnp.where(inside, t, mode)
    # beta density / its value at the mode (the normalising constants cancel)
    log_ratio = (STD_A - 1) * jnp.log(ts / mode) + (STD_B - 1) * jnp.log((1 - ts) / (1 - mode))
    pd = jnp.where(inside, jnp.exp(log_ratio), 0.0)
    return pm * pd


def _tmqi_one(hdr: jax.Array, ldr: jax.Array) -> TMQIScore:
    bad = ~(jnp.all(jnp.isfinite(hdr), axis=-1) & jnp.all(jnp.isfinite(ldr), axis=-1))
    L = jnp.where(bad, 0.0, luminance(finite_or(hdr)))
    y = jnp.where(bad, 0.0, luminance(finite_or(ldr))) * LDR_SCALE
    # (L − L_min) / (L_max − L_min) in [0, 1], from luminance divided by its largest
    # magnitude first, so that no range of finite values overflows
    big = jnp.max(jnp.abs(L))
    big = jnp.where(big > 0, big, 1.0)
    Ln = L / big
    lo, hi = jnp.min(Ln), jnp.max(Ln)
    span = hi - lo
    flat = span > 0
    span_safe = jnp.where(flat, span, 1.0)
    x = jnp.where(flat, (Ln - lo) / span_safe, 0.0)
    # the reference's factor round((2³² − 1) / range) · range, in the scale of x
    rng = span_safe * big
    q = HDR_RANGE / rng
    hdr_scale = jnp.where(q < 2.0**22, jnp.round(q) * rng, HDR_RANGE)
    hdr_scale = jax.lax.stop_gradient(hdr_scale)
    s = _structural_fidelity(x, y, hdr_scale)
    n = _naturalness(y)
    q_score = A * safe_power(s, ALPHA) + (1 - A) * safe_power(n, BETA)
    return TMQIScore(q_score, s, n)


@jax.jit
def _tmqi(hdr: jax.Array, ldr: jax.Array) -> TMQIScore:
    batch = hdr.shape[:-3]
    f = _tmqi_one
    for _ in batch:
        f = jax.vmap(f)
    return f(hdr, ldr)


def tmqi(hdr: Float[ArrayLike, "*batch H W 3"], ldr: Float[ArrayLike, "*batch H W 3"]) -> TMQIScore:
    """Tone-mapped image quality index (Yeganeh & Wang 2013), as the authors' code.

    Args:
        hdr: the HDR image, linear RGB at any scale (relative or cd/m²).
        ldr: its tone-mapped rendition, display-encoded RGB in [0, 1] (read as 8-bit values
            ``ldr · 255``; not quantised here), the shape of ``hdr``.

    Returns:
        :class:`TMQIScore` ``(q, s, n)``, each of shape ``*batch``, in [0, 1]: the quality
        ``Q``, the structural fidelity ``S`` and the statistical naturalness ``N``.
        Differentiable with respect to both images (see the module docstring for where the
        gradient departs from the MATLAB code's non-differentiable points).

    Reference: H. Yeganeh and Z. Wang, "Objective quality assessment of tone-mapped images",
    IEEE TIP 22(2):657–667, 2013, https://doi.org/10.1109/TIP.2012.2221725.
    """
    a, b = image_pair(hdr, ldr, ("hdr", "ldr"))
    return _tmqi(a, b)
