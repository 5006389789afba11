"""Ferradans, Bertalmío, Provenzi & Caselles 2011 visual adaptation and local contrast
enhancement, as ``pfstmo_ferradans11`` (pfstools 2.2.0) computes it.

Reference:
    Ferradans, Bertalmío, Provenzi, Caselles. "An analysis of visual adaptation and
    contrast perception for tone mapping." IEEE Transactions on Pattern Analysis and
    Machine Intelligence 33(10):2002–2012, 2011. https://doi.org/10.1109/TPAMI.2011.46

Two stages, each colour channel ``I`` (linear RGB in the image's units, which the model
reads as cd/m²; negative values set to 0, then ``10⁻⁶`` added) by itself:

1. Visual adaptation (the paper's first stage, pfstmo's constants). The adaptation level
   ``μ = √(mean I) · √(median I)``, moved by ``ρ``: ``μ ← μ · 10^z``,
   ``z = −0.37 (log₁₀ μ + 4 − ρ) + 1.9`` (the semi-saturation constant against the
   background of Valeton & van Norren 1983). Below ``I_r = 10^r μ`` (``r = 2``, half the
   four decades of the photoreceptor's range) Weber–Fechner,
   ``K log₁₀(I + I₀) + c`` with ``I₀ = μ / 10^1.2`` and the Fechner fraction
   ``K = 100 / 1.85`` (R, G) or ``100 / 8.7`` (B) (Wyszecki & Stiles); above it the
   Naka–Rushton response ``Iⁿ / (Iⁿ + μⁿ)``, ``n = 0.74``; ``c`` joins the two at
   ``I_r``. The response is rescaled to [0, 1] (its minimum to 0, its maximum to 1):
   ``I₀(x)``, the initial image of the second stage.
2. Local contrast enhancement: the paper's energy
   ``E(u) = α/2 Σ (u − μ₀)² + β/2 Σ (u − I₀)² − γ/2 ΣΣ w(x, y) S(u(x) − u(y))``
   (``μ₀`` the mean of ``I₀``, ``w`` a normalised Gaussian of standard deviation
   ``σ = min(H, W) / inv_alpha`` pixels, ``S′ = s`` a sigmoid of slope 10) descended by
   the semi-implicit scheme ``u ← (u + Δt (α μ₀ + β I₀ + γ R(u))) / (1 + Δt (α + β))``,
   clipped to [0, 1], with ``Δt = 0.2``, ``α = 255/253``, ``β = 1``, ``γ = 1/2``.
   ``R(u)(x) = Σ_y w(x − y) s(u(x) − u(y))`` with pfstmo's odd polynomial of degree 7
   for ``s`` (:data:`SLOPE_POLYNOMIAL`), so that ``R`` expands into the Gaussian
   convolutions of ``u, u², …, u⁷`` (the paper's fast scheme, after Bertalmío et al.
   2007): ``R`` clipped to [−1, 1] and divided by its largest magnitude. The scheme stops
   after the first iteration whose change, the mean absolute change summed over the
   channels, is at most ``tol`` (pfstmo's ``Δt / 20``), or after ``max_iterations``.
3. Each channel's result rescaled to [0, 1] (minimum to 0, maximum to 1): pfstmo's output,
   which it hands to pfstools as *sRGB-encoded* values; here decoded (IEC 61966-2-1) to
   display-linear RGB, so that the display's encoding gives pfstmo's values back.

Deviations from ``pfstmo_ferradans11`` (pfstools 2.2.0), each argued:

- Convolutions: pfstmo convolves by full-size circular FFTs (the image is periodic), with
  the sampled Gaussian's minimum subtracted before normalising (kept here, a correction
  by the image mean, exactly). Here too a circular convolution, computed on a coarser
  grid where the image is large: each axis is box-averaged by the largest factor ``f`` of
  its length that leaves at least ``kernel_grid`` samples, convolved there by FFT and
  interpolated back linearly (periodically). The box and the interpolation widen the
  Gaussian by about ``f / 2`` pixels in quadrature against ``σ`` (``σ = 205`` pixels at
  1024 × 2048 with pfstmo's ``inv_alpha``). Measured against full-size convolutions
  after 10 iterations on 512 × 1024 crops of two test images: largest display difference
  4·10⁻⁵ with factors 2 × 4 (``kernel_grid`` 256) and 1.5·10⁻⁴ with 4 × 8 (128), below
  the float16 rounding of [0, 1]. Sides shorter than ``2 kernel_grid`` (and sides without such a
  factor) convolve at full size, as pfstmo.
- Odd sizes: pfstmo's ``fftshift`` of the sampled kernel is exact for even sizes only
  (odd sides get a kernel shifted by one row or column on one side); here the periodic
  distance is used on every side.
- Median: pfstmo takes the lower median by selection; here by bisection of counts
  (:func:`lower_median`: the same pixel unless another value lies within ``10⁻⁵``
  relative below it), far cheaper than a sort on XLA:CPU.
- ``s``: pfstmo's polynomial has even coefficients of ``10⁻¹⁵``, rounding residue of its
  least-squares fit (with a wrong expansion of the sixth-power term): left out here.
- Degenerate images: a channel whose contrast term is 0 everywhere, or whose result is
  flat, has no rescaling (pfstmo divides by zero, and on a flat image its NaN never meets
  the stopping test: it runs forever); a flat image maps to 0. Pixels with a non-finite channel
  take the channel values of the image's first finite pixel for the statistics and the
  convolutions, and are put back in the output (NaN stays NaN).

Tiles: the adaptation level, the rescalings and the circular convolutions read the whole
image, so the operator declares an infinite halo (:meth:`Ferradans2011.halo`) and runs on
the whole image only. Gradients: every step is differentiable and ``jax.grad`` goes
through the iterations (each recomputed from its input, ``jax.checkpoint``, so that
reverse mode keeps one image per iteration); the stopping iteration, the clips, the
median's pixel and the extrema are piecewise constant. The iterations run under
``lax.cond`` (the skipped ones cost nothing on one image); under ``vmap`` every frame pays
for ``max_iterations``, so batches map frame by frame
(:attr:`~hdrjax.operators.AbstractOperator.frames_in_sequence`).
"""

import math
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._fusion import written_out
from .._srgb import srgb_decode
from ._base import AbstractOperator, Prepared, filled_with_first_valid, parameter, register

REFERENCE = (
    "Ferradans, Bertalmio, Provenzi, Caselles 2011, An analysis of visual adaptation and"
    " contrast perception for tone mapping, IEEE Transactions on Pattern Analysis and"
    " Machine Intelligence 33(10):2002-2012, https://doi.org/10.1109/TPAMI.2011.46"
)
OFFSET = 1e-6
"""Added to every channel value (image units) before the adaptation (pfstmo's)."""
EXPONENT = 0.74
"""``n`` of the Naka–Rushton response (Valeton & van Norren 1983)."""
HALF_RANGE = 2.0
"""``r``: decades above ``μ`` where Weber–Fechner gives way to Naka–Rushton."""
I0_DECADES = 1.2
"""``I₀ = μ / 10^1.2`` in the Weber–Fechner part."""
FECHNER = (100.0 / 1.85, 100.0 / 1.85, 100.0 / 8.7)
"""``K`` per channel: the Fechner fractions 1.85 % (R, G) and 8.7 % (B) (Wyszecki &
Stiles, as pfstmo)."""
TIME_STEP = 0.2
"""``Δt`` of the semi-implicit scheme (pfstmo's)."""
ALPHA, BETA, GAMMA = 255.0 / 253.0, 1.0, 0.5
"""Weights of the attachment to the mean, to the adapted image and of the contrast term
(pfstmo's)."""
SLOPE_POLYNOMIAL = (3.7891, -11.013, 15.836, -7.7456)
"""pfstmo's odd polynomial for the sigmoid of slope 10: coefficients of ``d, d³, d⁵,
d⁷``."""


def axis_factor(length: int, grid: int) -> int:
    """The box factor of an axis of ``length`` pixels: the largest divisor of ``length``
    leaving at least ``grid`` samples (1 when ``length ≤ grid``)."""
    length = int(length)
    return max(f for f in range(1, max(1, length // max(grid, 1)) + 1) if length % f == 0)


@jax.custom_jvp
def _row_max(x: Array) -> Array:
    """``jnp.max`` over the last axis of ``(C, N)``, whose derivative is the mean of the
    tangents at the elements within 4 ulps of the maximum: ``jnp.max``'s divides by the
    count of elements *equal* to it, which XLA:CPU can find to be 0 (NaN) when it computes
    the elements twice with different rounding (once contracted into fused multiply-adds:
    seen with LLVM's optimisation level 0). ``argmax`` instead would be robust, and many
    times slower on XLA:CPU."""
    return jnp.max(x, axis=-1)


@_row_max.defjvp
def _row_max_jvp(primals, tangents):
    (x,), (t,) = primals, tangents
    top = jnp.max(x, axis=-1)
    tiny = 4.0 * jnp.finfo(x.dtype).eps
    near = x >= (top - tiny * jnp.abs(top))[:, None]
    count = jnp.sum(near, axis=-1).astype(x.dtype)
    return top, jnp.sum(jnp.where(near, t, 0.0), axis=-1) / jnp.maximum(count, 1.0)


def _extremes(x: Array) -> tuple[Array, Array]:
    """The smallest and largest value of each row of ``x`` (``(C, N)``), by
    :func:`_row_max`."""
    return -_row_max(-x), _row_max(x)


MEDIAN_STEPS = 24
"""Bisection steps of :func:`lower_median` (the bracket ends ``2^-24`` of the image's
log range apart, at most ``10⁻⁵`` relative for a range of 128 octaves)."""


def lower_median(I: Array) -> Array:
    """The lower median of each row of ``I`` (``(C, N)``, positive): the value of rank
    ``⌊(N − 1) / 2⌋`` (pfstmo's selection), as the smallest value above the lower end of a
    bracket bisected :data:`MEDIAN_STEPS` times in log2 (the median itself unless another
    value lies within the bracket's width below it). A pixel's value, so that the gradient
    reaches that pixel as the median's; a loop of counts (a sort is 50 times slower on
    XLA:CPU for 2 Mpixels)."""
    log_i = jax.lax.stop_gradient(jnp.log2(I))
    rank = (I.shape[-1] - 1) // 2
    lo = jnp.min(log_i, axis=-1) - 1.0
    hi = jnp.max(log_i, axis=-1)

    def halve(_, bracket):
        lo, hi = bracket
        mid = 0.5 * (lo + hi)
        below = jnp.sum(log_i <= mid[:, None], axis=-1) > rank
        return jnp.where(below, lo, mid), jnp.where(below, mid, hi)

    lo, _ = jax.lax.fori_loop(0, MEDIAN_STEPS, halve, (lo, hi))
    above = log_i > lo[:, None]
    pick = jnp.argmin(jnp.where(above, log_i, jnp.inf), axis=-1)
    return jnp.take_along_axis(I, pick[:, None], axis=-1)[:, 0]


def adapted(rgb: Array, rho: Array) -> Array:
    """The first stage (module docstring, step 1): each channel of ``(H, W, 3)`` linear RGB
    through the adaptation model, rescaled to [0, 1]; ``(3, H, W)``."""
    channels = jnp.moveaxis(jnp.maximum(rgb, 0.0) + OFFSET, -1, 0)
    medians = lower_median(channels.reshape(3, -1))
    out = []
    for c in range(3):
        I = channels[c]
        mu = jnp.sqrt(jnp.mean(I)) * jnp.sqrt(medians[c])
        log_mu = jnp.log10(mu)
        log_mu = log_mu - 0.37 * (log_mu + 4.0 - rho) + 1.9
        mu = 10.0**log_mu
        I_r = 10.0 ** (log_mu + HALF_RANGE)
        I_0 = mu / 10.0**I0_DECADES
        K = FECHNER[c]
        mu_n = mu**EXPONENT
        top = I_r**EXPONENT / (I_r**EXPONENT + mu_n)
        c_join = top - K * jnp.log10(I_r + I_0)
        I_n = I**EXPONENT
        r = jnp.where(I <= I_r, K * jnp.log10(I + I_0) + c_join, I_n / (I_n + mu_n))
        lo, hi = _extremes(r.reshape(1, -1))
        out.append((r - lo[0]) / (hi[0] - lo[0] + 1e-12))
    return jnp.stack(out)


def _kernel_1d(length: int, factor: int, sigma: Array) -> tuple[Array, Array]:
    """The periodic Gaussian along an axis of ``length`` pixels sampled every ``factor``
    pixels: its DFT normalised to 1 at frequency 0 (``(length / factor,)``, real) and the
    full-resolution sum ``Σ_d exp(−d² / 2σ²)`` over the periodic distances."""
    n = length // factor
    d = np.arange(n)
    d = factor * np.minimum(d, n - d).astype(np.float64)
    g = jnp.exp(-(jnp.asarray(d, sigma.dtype) ** 2) / (2.0 * sigma**2))
    hat = jnp.real(jnp.fft.fft(g)) / jnp.sum(g)
    d_full = np.arange(length)
    d_full = np.minimum(d_full, length - d_full).astype(np.float64)
    total = jnp.sum(jnp.exp(-(jnp.asarray(d_full, sigma.dtype) ** 2) / (2.0 * sigma**2)))
    return hat, total


def _interpolation_weights(factor: int, dtype) -> tuple[Array, Array, Array]:
    """Linear interpolation from coarse samples to the ``factor`` pixels of each (sample
    centres aligned with the box averages'): the weights of the previous, the same and the
    next coarse sample, ``(factor,)`` each."""
    offset = (np.arange(factor) + 0.5) / factor - 0.5  # in coarse samples
    return (
        jnp.asarray(np.maximum(-offset, 0.0), dtype),
        jnp.asarray(1.0 - np.abs(offset), dtype),
        jnp.asarray(np.maximum(offset, 0.0), dtype),
    )


def _upsample(a: Array, factors: tuple[int, int]) -> Array:
    """Periodic linear interpolation of coarse fields ``(C, h + 2, w + 2)``, wrapped by one
    sample on each side (:func:`contrast_coefficients`), to the phase layout
    ``(C, h, f_h, f_w, w)`` (:func:`to_phases`): each phase weighs the coarse sample's
    3 × 3 neighbourhood (one broadcast expression, which XLA fuses with its use; one for
    all the fields at once materialises them and ran twice as slow)."""
    fh, fw = factors
    h, w = a.shape[-2] - 2, a.shape[-1] - 2
    wh = _interpolation_weights(fh, a.dtype)
    ww = _interpolation_weights(fw, a.dtype)
    out = 0.0
    for i, dh in enumerate((1, 0, -1)):
        if fh == 1 and dh:
            continue
        for j, dw in enumerate((1, 0, -1)):
            if fw == 1 and dw:
                continue
            weight = (wh[i][:, None] * ww[j][None, :])[None, None, :, :, None]
            shifted = a[:, 1 - dh : 1 - dh + h, 1 - dw : 1 - dw + w]
            out = out + weight * shifted[:, :, None, None, :]
    return out


def to_phases(x: Array, factors: tuple[int, int]) -> Array:
    """``(C, H, W)`` as ``(C, H / f_h, f_h, f_w, W / f_w)``: pixel ``(f_h i + r, f_w j + s)``
    at ``[:, i, r, s, j]``, so that box sums are sums over middle axes and the
    interpolation broadcasts along the last (XLA:CPU vectorises those, not short
    reductions or broadcasts along the last axis)."""
    C, H, W = x.shape
    fh, fw = factors
    return x.reshape(C, H // fh, fh, W // fw, fw).transpose(0, 1, 2, 4, 3)


def from_phases(x: Array) -> Array:
    """The inverse of :func:`to_phases`."""
    C, h, fh, fw, w = x.shape
    return x.transpose(0, 1, 2, 4, 3).reshape(C, h * fh, w * fw)


def contrast_coefficients(u: Array, sigma: Array, shape: tuple[int, int]) -> Array:
    """The coefficients ``a_0 … a_6`` of ``R(u) = Σ_m a_m u^m`` (module docstring, step 2)
    for ``u`` in [0, 1] in the phase layout ``(C, h, f_h, f_w, w)`` of an
    ``(H, W) = shape`` image (:func:`to_phases`), from the convolutions of the powers of
    ``u``: coarse fields ``(7, C, h + 2, w + 2)``, wrapped by one sample on each side for
    the periodic interpolation."""
    C, h, fh, fw, w = u.shape
    H, W = shape
    powers = [u]
    for _ in range(6):
        powers.append(powers[-1] * u)
    coarse = jnp.stack([jnp.mean(q, axis=(2, 3)) for q in powers], axis=1)  # (C, 7, h, w)
    means = jnp.mean(coarse, axis=(2, 3), keepdims=True)
    hat_h, sum_h = _kernel_1d(H, fh, sigma)
    hat_w, sum_w = _kernel_1d(W, fw, sigma)
    hat = (hat_h[:, None] * hat_w[None, : w // 2 + 1])[None, None]
    blurred = jnp.fft.irfft2(jnp.fft.rfft2(coarse) * hat, s=(h, w)).astype(u.dtype)
    # pfstmo's kernel is (g − g_min) / Σ (g − g_min): in terms of the normalised g, the
    # blur less β times the mean, over 1 − β
    g_min = jnp.exp(-((H // 2) ** 2 + (W // 2) ** 2) / (2.0 * sigma**2))
    beta = (g_min * (H * W) / (sum_h * sum_w)).astype(u.dtype)
    M = (blurred - beta * means) / (1.0 - beta)  # (C, 7, h, w): moments M_1 … M_7
    # a_m = Σ_k c_k C(k, m) (−1)^(k−m) M_(k−m), M_0 = 1
    a = []
    for m in range(7):
        a_m = jnp.zeros_like(M[:, 0])
        for k, c_k in zip((1, 3, 5, 7), SLOPE_POLYNOMIAL, strict=True):
            if k >= m:
                term = c_k * math.comb(k, m) * (-1.0) ** (k - m)
                a_m = a_m + (term if k == m else term * M[:, k - m - 1])
        a.append(a_m)
    return jnp.pad(jnp.stack(a), ((0, 0), (0, 0), (1, 1), (1, 1)), mode="wrap")


def contrast_term(u: Array, coefficients: Array) -> Array:
    """``R(u)`` of the module docstring (step 2), before its clip and normalisation, for
    ``u`` in the phase layout (:func:`to_phases`) with :func:`contrast_coefficients`
    (Horner's scheme over the interpolated fields)."""
    factors = (u.shape[2], u.shape[3])
    R = jnp.full_like(u, SLOPE_POLYNOMIAL[-1])
    for m in range(6, -1, -1):
        R = R * u + _upsample(coefficients[m], factors)
    return R


def enhance(
    I0: Array,
    inv_alpha: Array,
    *,
    tol: float,
    max_iterations: int,
    kernel_grid: int,
) -> tuple[Array, Array]:
    """The second stage (module docstring, step 2) from ``I0`` of shape ``(3, H, W)``:
    the result and the number of iterations run."""
    _, H, W = I0.shape
    factors = (axis_factor(H, kernel_grid), axis_factor(W, kernel_grid))
    sigma = min(H, W) / inv_alpha
    I0 = to_phases(I0, factors)
    axes = (1, 2, 3, 4)
    mean = jnp.mean(I0, axis=axes, keepdims=True)
    target = (ALPHA * mean + BETA * I0) * TIME_STEP
    scale = 1.0 / (1.0 + TIME_STEP * (ALPHA + BETA))

    def update(u, coefficients):
        R = jnp.clip(contrast_term(u, coefficients), -1.0, 1.0)
        top = _row_max(jnp.abs(R).reshape(R.shape[0], -1)).reshape(-1, 1, 1, 1, 1)
        R = jnp.where(top > 0, R / jnp.where(top > 0, top, 1.0), 0.0)
        new = jnp.clip((u + target + (TIME_STEP * GAMMA) * R) * scale, 0.0, 1.0)
        change = jnp.sum(jnp.mean(jnp.abs(new - u), axis=axes))
        return new, change <= tol

    @jax.checkpoint
    def step(u, done):
        # the wrapped fields written out: fused into the interpolation, their wrap costs a
        # branch per pixel and tap (11× slower)
        coefficients = contrast_coefficients(u, sigma, (H, W))
        return written_out(~done, update, lambda v, _: (v, done), u, coefficients)

    def body(carry, _):
        u, done, n = carry
        u, now = jax.lax.cond(done, lambda v, d: (v, d), step, u, done)
        return (u, now, n + jnp.where(done, 0, 1)), None

    init = (I0, jnp.asarray(False), jnp.asarray(0, jnp.int32))
    (u, _, n), _ = jax.lax.scan(body, init, None, length=int(max_iterations))
    return from_phases(u), n


@register("ferradans2011")
class Ferradans2011(AbstractOperator):
    """Ferradans, Bertalmío, Provenzi & Caselles 2011 visual adaptation followed by the
    variational local contrast enhancement, with ``pfstmo_ferradans11``'s defaults; the
    steps and the departures from pfstmo are in the module docstring.

    Input: linear RGB in cd/m² (the adaptation model reads absolute values; pfstmo takes
    the file's values as they are). Output: display-referred *linear* RGB in [0, 1]
    (pfstmo's result is sRGB-encoded: it is decoded here), each channel spanning [0, 1].

    Attributes:
        rho: pfstmo's ``--rho`` (−2): moves the adaptation level by ``0.37 ρ`` decades;
            larger is darker.
        inv_alpha: pfstmo's ``--inv_alpha`` (5): the contrast kernel's standard deviation
            is ``min(H, W) / inv_alpha`` pixels; larger gives more local contrast.
        tol: the scheme stops after an iteration that changes the channels by at
            most this much (mean absolute change, summed over channels; pfstmo's 0.01).
        max_iterations: most iterations of the scheme.
        kernel_grid: fewest samples per axis of the grid the convolutions run on.
    """

    reference: ClassVar[str] = REFERENCE
    per_channel: ClassVar[bool] = True
    frames_in_sequence: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("rho",)

    rho: Array = parameter(
        -2.0,
        help="pfstmo's --rho: adaptation level offset (larger is darker)",
        range="[-10, 10]",
    )
    inv_alpha: Array = parameter(
        5.0,
        help="pfstmo's --inv_alpha: contrast kernel of std min(H, W)/inv_alpha pixels",
        range="[0.1, 100]",
    )
    tol: float = parameter(
        TIME_STEP / 20.0,
        help="stop after an iteration changing the channels by at most this (mean, summed)",
        range="[0, inf)",
        static=True,
    )
    max_iterations: int = parameter(
        50, help="most iterations of the contrast enhancement", range="[1, inf)", static=True
    )
    kernel_grid: int = parameter(
        256,
        help="fewest samples per axis of the grid the Gaussian convolutions run on",
        range="[1, inf)",
        static=True,
    )

    def __check_init__(self):
        super().__check_init__()
        for name in ("max_iterations", "kernel_grid"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ValueError(f"{name}: expected an integer >= 1, got {v!r}")
        if not self.tol >= 0:
            raise ValueError(f"tol: expected a value in [0, inf), got {self.tol!r}")

    def halo(self, shape: tuple[int, ...]) -> tuple[float, float]:
        """The whole image (infinite): the adaptation level, the rescalings and the
        circular convolutions read every pixel."""
        del shape
        return (math.inf, math.inf)

    def iterations(self, rgb: Array) -> Array:
        """The number of iterations the scheme runs on ``rgb`` (``(H, W, 3)``, finite)."""
        I0 = adapted(jnp.asarray(rgb), jnp.asarray(self.rho, jnp.asarray(rgb).dtype))
        return enhance(I0, jnp.asarray(self.inv_alpha, I0.dtype), **self._settings())[1]

    def _settings(self) -> dict:
        return dict(
            tol=float(self.tol),
            max_iterations=int(self.max_iterations),
            kernel_grid=int(self.kernel_grid),
        )

    def _apply(self, p: Prepared) -> Array:
        # half-precision images compute in float32 (the moments' expansion cancels to
        # 10⁻⁵, and XLA's FFT takes float32 at least)
        dt = jnp.promote_types(p.rgb.dtype, jnp.float32)
        rgb = p.rgb if p.clean else filled_with_first_valid(p.rgb, p.valid())
        I0 = adapted(rgb.astype(dt), self.rho.astype(dt))
        u, _ = enhance(I0, self.inv_alpha.astype(dt), **self._settings())
        lo, hi = (v.reshape(-1, 1, 1) for v in _extremes(u.reshape(u.shape[0], -1)))
        span = hi - lo
        u = jnp.where(span > 0, (u - lo) / jnp.where(span > 0, span, 1.0), u)
        return srgb_decode(jnp.moveaxis(u, 0, -1)).astype(p.rgb.dtype)


__all__ = [
    "Ferradans2011",
    "adapted",
    "lower_median",
    "axis_factor",
    "contrast_term",
    "enhance",
    "from_phases",
    "to_phases",
]
