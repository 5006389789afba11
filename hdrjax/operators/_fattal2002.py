"""Fattal, Lischinski & Werman 2002 gradient-domain compression, as ``pfstmo_fattal02``
(pfstools 2.2.0) computes it with its default, discrete-cosine-transform Poisson solver.

Reference:
    Fattal, Lischinski, Werman. "Gradient domain high dynamic range compression." ACM
    Transactions on Graphics 21(3):249–256, 2002 (Proc. SIGGRAPH).
    https://doi.org/10.1145/566654.566573

The steps, with ``Y`` the luminance of the input (any units; the operator is scale
invariant):

1. Log luminance, pfstmo's normalisation: ``H = ln(100 (Y − Y_min) / (Y_max − Y_min) +
   10⁻⁴)`` (``Y_min``, ``Y_max`` the image's extrema).
2. Gaussian pyramid ``H_0 = H``, ``H_{k+1}`` = the ``[1 2 1] / 4`` blur of ``H_k`` (edge
   pixels repeated) box-averaged over 2 × 2 pixels; levels ``k = 0 … d − 1`` while the
   smaller side is at least :data:`MIN_LEVEL_SIZE` pixels (pfstmo's ``MSIZE`` for its DCT
   solver).
3. Gradient magnitudes ``g = ‖∇H_k‖`` by central differences divided by ``2^(k+1)`` (the
   paper's), their mean ``ḡ_k``, and the paper's scaling per level, ``φ_k = (a_k / g)
   (g / a_k)^β`` with ``a_k = α ḡ_k``, with pfstmo's noise term (``g + n`` for ``g``) and
   where ``g > 10⁻⁴`` (1 elsewhere, pfstmo's cut).
4. Attenuation (the paper's): from the coarsest level down, ``Φ_k = L(Φ_{k+1})
   φ_k``, ``L`` the nearest-neighbour upsampling followed by the ``[1 2 1] / 4`` blur; only
   levels ``k ≥ detail_level`` (and always the coarsest) multiply their ``φ_k``
   (pfstmo's ``--detail-level``; the paper's is 0).
5. Attenuated gradients ``G = ∇H · Φ`` by forward differences, ``Φ`` averaged over the two
   pixels of each difference, zero across the image border, and the Poisson equation
   ``∇²I = div G`` with zero Neumann boundaries (the paper's) solved exactly by the
   discrete cosine transform (type II on both axes: the 5-point Laplacian with mirrored
   half-sample boundaries is diagonal there), the constant mode set to 0.
6. Output luminance, pfstmo's: ``L = (e^(γ I) − e^(γ I_lo)) / (e^(γ I_hi) − e^(γ I_lo))``
   with ``I_lo``, ``I_hi`` the ``black_point`` and ``100 − white_point`` percentiles of
   ``I``, floored at ``10⁻⁴``; colour ``C_d = max(C / Y, 0)^s L`` (the paper's colour
   ratios, as pfstmo's).

Deviations from ``pfstmo_fattal02`` (pfstools 2.2.0), each argued:

- Solver boundaries: pfstmo's DCT solver uses the type-I transform (whole-sample mirrored
  boundaries, ``I(−1) = I(1)``), and assembles the divergence to match; here the type-II
  transform (half-sample, ``I(−1) = I(0)``: the paper's zero-flux Neumann condition, as
  its multigrid solver), computed by real FFTs at the image's own size. The two differ
  only next to the border: float64 NumPy models of the two solvers agree to 10⁻⁴ in mean
  absolute sRGB-encoded difference on the fixture images (tests/operators).
- Colour ratios: pfstmo divides by ``max(Y, 10⁻⁴)`` in the input's units (darker colours
  for pixels below 10⁻⁴, and an operator that depends on the input's scale); here by
  ``Y`` itself (pixels with ``Y ≤ 0`` black).
- Percentiles: pfstmo takes the sorted values at ranks ``⌊q N⌋``, here interpolated
  linearly at ``q (N − 1)`` (less than one rank apart).
- Images smaller than :data:`MIN_LEVEL_SIZE` pixels on a side have one level here (pfstmo
  fails on them).
- A flat image (``I_lo = I_hi``) maps to 1 (pfstmo divides by zero).
- Non-finite pixels (pfstmo's output is NaN everywhere then): for ``Y_min``, ``Y_max``, the
  pyramid, the solve and the percentiles they take the luminance of the image's first
  finite pixel (raster order), so that the finite pixels map exactly as in the image with
  that copy in place; they are put back in the output (NaN stays NaN, +Inf is white).

Tiles: the Poisson solve couples every pixel with every other, so the operator declares an
infinite halo (:meth:`Fattal2002.halo`) and runs on the whole image only (``N log N`` time
for ``N`` pixels, memory a few image-sized buffers). Gradients: every step is
differentiable and the solve is linear (the transforms' transposes), so ``jax.grad`` is
exact through it; the percentiles' ranks and the ``g > 10⁻⁴`` cut are piecewise constant.
"""

import math
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._scale import quotient
from .._stats import percentile_by_selection
from ._base import (
    AbstractOperator,
    Prepared,
    filled_with_first_valid,
    parameter,
    register,
    weights_field,
)

REFERENCE = (
    "Fattal, Lischinski, Werman 2002, Gradient domain high dynamic range compression, ACM"
    " Transactions on Graphics 21(3):249-256, https://doi.org/10.1145/566654.566573"
)
MIN_LEVEL_SIZE = 8
"""Smallest side of a pyramid level (pfstmo's ``MSIZE`` with its DCT solver; the paper's
multigrid setting is 32)."""
GRADIENT_CUT = 1e-4
"""Gradient magnitudes at or below this are not scaled (pfstmo's)."""
LOG_OFFSET = 1e-4
"""Added to ``100 (Y − Y_min) / (Y_max − Y_min)`` before the logarithm (pfstmo's)."""
OUTPUT_FLOOR = 1e-4
"""Smallest output luminance (pfstmo's)."""
MAX_LOG_RATIO = 50.0
"""Cap of ``s ln(C / Y)``: only a channel far above its pixel's luminance (negative
channels beside it) reaches it, where ``exp`` would otherwise overflow."""


def levels(shape: tuple[int, ...]) -> int:
    """Pyramid levels for an image of ``shape``: halvings of the smaller side while it is at
    least :data:`MIN_LEVEL_SIZE` (at least one level)."""
    n, m = 0, min(int(shape[-2]), int(shape[-1]))
    while m >= MIN_LEVEL_SIZE:
        n, m = n + 1, m // 2
    return max(n, 1)


def blur_downsample(x: Array) -> Array:
    """The ``[1 2 1] / 4`` blur along both axes (edge pixels repeated) followed by the 2 × 2
    box average (a last odd row or column dropped), in one pass per axis: the kernel
    ``[1 3 3 1] / 8`` at every second pixel."""

    def last(x: Array) -> Array:
        n = x.shape[-1] // 2
        p = jnp.pad(x, ((0, 0), (1, 1)), mode="edge")
        a = p[:, : 2 * n].reshape(x.shape[0], n, 2)
        b = p[:, 2 : 2 * n + 2].reshape(x.shape[0], n, 2)
        return (a[..., 0] + b[..., 1] + 3.0 * (a[..., 1] + b[..., 0])) * 0.125

    def first(x: Array) -> Array:
        n = x.shape[0] // 2
        p = jnp.pad(x, ((1, 1), (0, 0)), mode="edge")
        a = p[: 2 * n].reshape(n, 2, x.shape[1])
        b = p[2 : 2 * n + 2].reshape(n, 2, x.shape[1])
        return (a[:, 0] + b[:, 1] + 3.0 * (a[:, 1] + b[:, 0])) * 0.125

    return first(last(x))


def upsample_blur(x: Array, shape: tuple[int, int]) -> Array:
    """Nearest-neighbour upsampling to ``shape`` (at most one more row or column than twice
    ``x``'s, which repeats the last) followed by the ``[1 2 1] / 4`` blur, in one pass per
    axis: new pixels ``(3 x_i + x_(i±1)) / 4``."""

    def last(x: Array, n: int) -> Array:
        p = jnp.pad(x, ((0, 0), (1, 1)), mode="edge")
        cur = 0.75 * x
        out = jnp.stack([cur + 0.25 * p[:, :-2], cur + 0.25 * p[:, 2:]], axis=-1)
        out = out.reshape(x.shape[0], 2 * x.shape[1])
        return jnp.concatenate([out, x[:, -1:]], axis=1) if n > out.shape[1] else out

    def first(x: Array, n: int) -> Array:
        p = jnp.pad(x, ((1, 1), (0, 0)), mode="edge")
        cur = 0.75 * x
        out = jnp.stack([cur + 0.25 * p[:-2], cur + 0.25 * p[2:]], axis=1)
        out = out.reshape(2 * x.shape[0], x.shape[1])
        return jnp.concatenate([out, x[-1:]], axis=0) if n > out.shape[0] else out

    return first(last(x, shape[1]), shape[0])


def gradient_magnitude(h: Array, k: int) -> Array:
    """``‖∇H_k‖``: central differences over two pixels (edge pixels repeated) divided by
    ``2^(k+1)``."""
    p = jnp.pad(h, 1, mode="edge")
    gx = p[1:-1, 2:] - p[1:-1, :-2]
    gy = p[2:, 1:-1] - p[:-2, 1:-1]
    sq = gx * gx + gy * gy
    pos = sq > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, sq, 1.0)), 0.0) / 2.0 ** (k + 1)


def attenuation(H: Array, alpha: Array, beta: Array, noise: Array, *, detail_level: int) -> Array:
    """``Φ_0`` (module docstring, steps 2–4) for the log luminance ``H`` (``(h, w)``)."""
    n = levels(H.shape)
    pyramid = [H]
    for _ in range(1, n):
        pyramid.append(blur_downsample(pyramid[-1]))
    phi = jnp.ones_like(pyramid[-1])
    for k in range(n - 1, -1, -1):
        if k >= detail_level or k == n - 1:
            g = gradient_magnitude(pyramid[k], k)
            a = alpha * jnp.mean(g)
            a = jnp.where(a > 0, a, 1.0)
            big = g > GRADIENT_CUT
            r = jnp.where(big, (g + noise) / a, 1.0)
            phi = phi * jnp.where(big, jnp.exp((beta - 1.0) * jnp.log(r)), 1.0)
        if k > 0:
            phi = upsample_blur(phi, pyramid[k - 1].shape)
    return phi


def divergence(H: Array, phi: Array) -> Array:
    """``div G`` of the attenuated forward differences ``G = ∇H Φ`` (``Φ`` averaged over the
    two pixels of each difference), zero across the border (module docstring, step 5)."""
    gx = (H[:, 1:] - H[:, :-1]) * 0.5 * (phi[:, 1:] + phi[:, :-1])
    gy = (H[1:] - H[:-1]) * 0.5 * (phi[1:] + phi[:-1])
    zx, zy = jnp.zeros_like(H[:, :1]), jnp.zeros_like(H[:1])
    return (
        jnp.concatenate([gx, zx], axis=1)
        - jnp.concatenate([zx, gx], axis=1)
        + jnp.concatenate([gy, zy], axis=0)
        - jnp.concatenate([zy, gy], axis=0)
    )


def _twiddle(n: int, x: Array) -> Array:
    """``e^(−iπk / 2n)``, ``k = 0 … ⌊n/2⌋``, along the last of ``x``'s axes."""
    k = np.arange(n // 2 + 1).reshape((1,) * (x.ndim - 1) + (-1,))
    return jnp.asarray(np.exp(-0.5j * np.pi * k / n), jnp.result_type(x.dtype, jnp.complex64))


def dct2_last(x: Array) -> Array:
    """Type-II DCT along the last axis, ``X_k = Σ_j x_j cos(π k (2j + 1) / 2n)``, by one real
    FFT of the even samples followed by the reversed odd ones (Makhoul 1980,
    https://doi.org/10.1109/TASSP.1980.1163351): ``Z = FFT(v) e^(−iπk / 2n)`` gives
    ``X_k = Re Z_k`` and ``X_(n−k) = −Im Z_k``. (``jax.scipy.fft.dct`` forms the complex
    FFT of the whole axis; this one is several times faster on CPU.)"""
    n = x.shape[-1]
    v = jnp.concatenate([x[..., 0::2], x[..., 1::2][..., ::-1]], axis=-1)
    z = jnp.fft.rfft(v, axis=-1) * _twiddle(n, x)
    return jnp.concatenate([z.real, -z.imag[..., 1 : (n + 1) // 2][..., ::-1]], axis=-1)


def idct2_last(X: Array) -> Array:
    """The inverse of :func:`dct2_last` (each of its steps undone)."""
    n = X.shape[-1]
    half, c = n // 2, (n + 1) // 2
    im = jnp.concatenate([jnp.zeros_like(X[..., :1]), X[..., ::-1][..., :half]], axis=-1)
    z = jax.lax.complex(X[..., : half + 1], -im) * jnp.conj(_twiddle(n, X))
    v = jnp.fft.irfft(z, n=n, axis=-1)
    even, odd = v[..., :c], v[..., c:][..., ::-1]
    if n % 2:
        odd = jnp.pad(odd, [(0, 0)] * (odd.ndim - 1) + [(0, 1)])
    return jnp.stack([even, odd], axis=-1).reshape(*X.shape[:-1], 2 * c)[..., :n]


def solve_poisson_neumann(f: Array) -> Array:
    """``I`` with ``∇²I = f − mean(f)`` (5-point Laplacian, zero-flux Neumann boundaries,
    ``I(−1) = I(0)``) and ``Σ I = 0``, for ``f`` of shape ``(h, w)``: the type-II DCT
    diagonalises the Laplacian with eigenvalues ``−4 sin²(π k / 2h) − 4 sin²(π l / 2w)``.
    Linear in ``f``, so its gradient is exact."""
    h, w = f.shape
    ky = np.sin(np.pi * np.arange(h) / (2 * h)) ** 2
    kx = np.sin(np.pi * np.arange(w) / (2 * w)) ** 2
    lam = -4.0 * (ky[:, None] + kx[None, :])
    lam[0, 0] = 1.0
    inv = 1.0 / lam
    inv[0, 0] = 0.0  # the constant mode: the solution is defined up to a constant
    F = dct2_last(dct2_last(f).T)  # (w, h): frequencies along h last
    return idct2_last(idct2_last(F * jnp.asarray(inv.T, f.dtype)).T)


def _log_luminance(Y: Array) -> Array:
    """``H`` (module docstring, step 1)."""
    lo, hi = jnp.min(Y), jnp.max(Y)
    # divided by the largest magnitude first, so that neither the span nor 100 × it
    # overflows for values near the float maximum
    s = jnp.maximum(jnp.abs(lo), jnp.abs(hi))
    s = jnp.where(s > 0, s, 1.0)
    lo_s = quotient(lo, s)
    span = quotient(hi, s) - lo_s
    r = quotient(quotient(Y, s) - lo_s, jnp.where(span > 0, span, 1.0))
    return jnp.log(100.0 * jnp.clip(r, 0.0, 1.0) + LOG_OFFSET)


@register("fattal2002")
class Fattal2002(AbstractOperator):
    """Fattal, Lischinski & Werman 2002 gradient-domain compression with pfstmo_fattal02's
    defaults (its DCT Poisson solver, detail level 3, gamma 0.8, noise 0.002); the steps
    and the departures from pfstmo are in the module docstring.

    Input: linear RGB, relative or absolute (the operator is scale invariant). Output:
    display-referred *linear* RGB (pfstmo tags its output ``LUMINANCE=RELATIVE``): the
    luminance's ``black_point`` percentile at 0 and ``100 − white_point`` percentile at 1,
    brighter pixels above 1 (clipped by the display).

    Attributes:
        alpha: pfstmo's ``--alpha`` (1): gradient magnitude left unchanged, relative to the
            level's mean magnitude (the paper's ``α = 0.1`` of the mean is its own
            suggestion; with pfstmo's output normalisation ``α`` only acts as a gamma).
        beta: pfstmo's ``--beta`` (0.9): exponent of the attenuation, ``< 1`` compresses
            large gradients and enhances small ones.
        gamma: pfstmo's ``--gamma`` (0.8): output luminance ``e^(γ I)``.
        saturation: pfstmo's ``--saturation`` (0.8): exponent of the colour ratios.
        noise: pfstmo's ``--noise`` (0.002): added to each gradient magnitude, so that
            small (noise) gradients are amplified less.
        detail_level: pfstmo's ``--detail-level`` (3): the finest pyramid levels left out
            of the attenuation (0: the paper's).
        black_point: pfstmo's ``--black-point`` (0.1): percent of pixels mapped below 0.
        white_point: pfstmo's ``--white-point`` (0.5): percent of pixels mapped above 1.
        weights: the luminance's weights (Rec. 709, pfstools' ``Y``).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("beta", "gamma")

    alpha: Array = parameter(
        1.0,
        help="pfstmo's --alpha: gradient magnitude kept unchanged, times the level's mean",
        range="(0, inf)",
    )
    beta: Array = parameter(
        0.9,
        help="pfstmo's --beta: attenuation exponent (< 1 compresses large gradients)",
        range="(0, inf)",
    )
    gamma: Array = parameter(
        0.8, help="pfstmo's --gamma: output luminance exp(gamma I)", range="(0, inf)"
    )
    saturation: Array = parameter(
        0.8, help="pfstmo's --saturation: exponent of the colour ratios", range="[0, inf)"
    )
    noise: Array = parameter(
        0.002,
        help="pfstmo's --noise: added to gradient magnitudes (less noise amplification)",
        unit="ln luminance per pixel",
        range="[0, inf)",
    )
    detail_level: int = parameter(
        3,
        help="pfstmo's --detail-level: finest pyramid levels left unattenuated (0: paper)",
        range="[0, 9]",
        static=True,
    )
    black_point: float = parameter(
        0.1,
        help="pfstmo's --black-point: percent of pixels mapped below 0",
        unit="%",
        range="[0, 50)",
        static=True,
    )
    white_point: float = parameter(
        0.5,
        help="pfstmo's --white-point: percent of pixels mapped above 1",
        unit="%",
        range="[0, 50)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        super().__check_init__()
        if int(self.detail_level) != self.detail_level or not 0 <= self.detail_level <= 9:
            raise ValueError(
                f"detail_level: expected an integer in [0, 9], got {self.detail_level!r}"
            )
        for name in ("black_point", "white_point"):
            v = getattr(self, name)
            if not 0.0 <= v < 50.0:
                raise ValueError(f"{name}: expected a value in [0, 50), got {v!r}")

    def halo(self, shape: tuple[int, ...]) -> tuple[float, float]:
        """The whole image (infinite): the Poisson solve couples every pixel."""
        del shape
        return (math.inf, math.inf)

    def _apply(self, p: Prepared) -> Array:
        dt = p.rgb.dtype
        H = _log_luminance(p.L if p.clean else filled_with_first_valid(p.L, p.valid()))
        phi = attenuation(
            H,
            self.alpha.astype(dt),
            self.beta.astype(dt),
            self.noise.astype(dt),
            detail_level=int(self.detail_level),
        )
        I = solve_poisson_neumann(divergence(H, phi))
        # percentiles of a positive shift of I (the selection reads positive values); the
        # shift cancels, so it carries no gradient
        shift = jax.lax.stop_gradient(1.0 - jnp.min(I))
        q = (float(self.black_point), 100.0 - float(self.white_point))
        lo, hi = percentile_by_selection(I + shift, jnp.asarray(q, dt), select=q) - shift
        g = self.gamma.astype(dt)
        floor = jnp.exp(g * (lo - hi))
        den = 1.0 - floor
        flat = den <= jnp.finfo(dt).eps
        L = quotient(jnp.exp(g * (I - hi)) - floor, jnp.where(flat, 1.0, den))
        L = jnp.maximum(jnp.where(flat, 1.0, L), OUTPUT_FLOOR)
        # C_d = (C / Y)^s L as exp(s (ln C − ln Y)) L, ln Y per pixel: one fused loop on
        # XLA:CPU (a per-pixel quotient broadcast to the channels is materialised instead)
        pos_y = p.L > 0
        log_y = jnp.log(jnp.where(pos_y, p.L, 1.0))
        L = jnp.where(pos_y, L, 0.0)
        s = self.saturation.astype(dt)
        pos = p.rgb > 0
        log_c = jnp.log(jnp.where(pos, p.rgb, 1.0))
        log_ratio = jnp.minimum(s * (log_c - log_y[..., None]), MAX_LOG_RATIO)
        colour = jnp.where(pos, jnp.exp(log_ratio), 0.0)
        return colour * L[..., None]


__all__ = [
    "Fattal2002",
    "attenuation",
    "dct2_last",
    "divergence",
    "idct2_last",
    "levels",
    "solve_poisson_neumann",
]
