"""Veiling glare: the point-spread function of Spencer, Shirley, Zimmerman & Greenberg (1995).

Reference: G. Spencer, P. Shirley, K. Zimmerman, D. P. Greenberg, "Physically-based glare
effects for digital images", SIGGRAPH 1995, pp. 325–334, doi:10.1145/218380.218466, with
the erratum on F. Durand's Interactive Tone Mapping page (θ in degrees, 19.75 in f3);
weights as in snogglethorpe/snogray, Opioid/sprout and RichardBruce/RAPTor.

With θ in degrees and λ in nm, the components are

- ``f0(θ) = 2.61e6 exp(-(θ/0.02)²)`` (central peak),
- ``f1(θ) = 20.91/(θ + 0.02)³``, ``f2(θ) = 72.37/(θ + 0.02)²`` (scattering),
- ``f3(θ, λ) = 436.9 (568/λ) exp(-19.75 (θ - 3λ/568)²)`` (lenticular halo),

each about one per steradian when integrated over the sphere (``∫ f dΩ`` ≈ 1 sr⁻¹·sr;
``f2``'s integral grows like ``ln θ`` and reaches 1 near 74°). The PSF is
``P = Σ w_i f_i`` with photopic weights (0.384, 0.478, 0.138, 0), mesopic
(0.368, 0.478, 0.138, 0.016) and scotopic (0.282, 0.478, 0.207, 0.033); each set sums to 1.
Which variant applies is not documented in any source found; this module picks it from the
global adaptation luminance against pcond's mesopic limits 5.62e-3 and 5.62 cd/m² (Radiance
``pcond.h``; the choice is hdrjax's, neither paper makes it).

Discretisation (:func:`glare_kernel`): a pixel's weight is ``∫_pixel P dΩ`` over the
pixel's square (flat angles, ``pixel_deg`` on each side): ``f0`` exactly (it is separable:
erf differences), ``f1``/``f2`` exactly over the equal-area disc for the centre pixel, by a
16×16 midpoint rule within 3 pixels of it and at the pixel centre beyond; ``f3`` by a
midpoint rule fine enough for its 0.16° ring width. Light whose scattering angle falls
outside the kernel's support (``radius_deg``, or the whole image) stays in its own pixel, so
every kernel sums to exactly 1 and the convolution conserves energy (except the light it
scatters beyond the image border, which leaves the field of view). Should the weights add up
to more than 1 (fields much wider than 90°), they are divided by their sum instead.
``f3`` is evaluated at 611, 549 and 467 nm for R, G and B (RAPTor's choice).

The kernel-size/accuracy trade-off: the default kernel reaches across the whole image (FFT
grid ≈ 2H × 2W, exact linear convolution). ``radius_deg`` truncates it; the scattered
light beyond the radius is then missing from distant pixels (kept in the source pixel).
benchmarks/bench_vision.py measures error against the full kernel and time for several radii.
"""

import functools
import math
from typing import Literal

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._photometry import BOT_MESOPIC, TOP_MESOPIC, check_rgb, restore, sanitize
from . import _fft
from ._view import ResolvedView, View, resolve_view

Variant = Literal["photopic", "mesopic", "scotopic"]

WEIGHTS: dict[str, tuple[float, float, float, float]] = {
    "photopic": (0.384, 0.478, 0.138, 0.0),
    "mesopic": (0.368, 0.478, 0.138, 0.016),
    "scotopic": (0.282, 0.478, 0.207, 0.033),
}
"""Weights of (f0, f1, f2, f3) per adaptation regime (Spencer et al. 1995)."""

WAVELENGTHS_RGB: tuple[float, float, float] = (611.0, 549.0, 467.0)
"""Wavelengths (nm) at which the halo term f3 is evaluated for R, G, B (RAPTor)."""

_A = 0.02  # degrees, in f0..f2
_SR = (math.pi / 180.0) ** 2  # steradians per square degree


def _f0(t):
    return 2.61e6 * np.exp(-((t / _A) ** 2))


def _f1(t):
    return 20.91 / (t + _A) ** 3


def _f2(t):
    return 72.37 / (t + _A) ** 2


def _f3(t, lam):
    return 436.9 * (568.0 / lam) * np.exp(-19.75 * (t - 3.0 * lam / 568.0) ** 2)


def spencer1995_psf(
    theta_deg: Float[ArrayLike, "*shape"],
    variant: Variant = "photopic",
    wavelength_nm: float = 568.0,
) -> Float[Array, "*shape"]:
    """Spencer et al. 1995 point-spread function ``P(θ)``, per steradian.

    Args:
        theta_deg: angle from the point source, degrees (>= 0).
        variant: ``"photopic"``, ``"mesopic"`` or ``"scotopic"`` weights.
        wavelength_nm: wavelength for the halo term ``f3`` (unused by ``"photopic"``).

    Returns:
        ``Σ w_i f_i(θ)`` (see the module docstring), same shape as ``theta_deg``.
    """
    _check.real(theta_deg, "theta_deg")
    w = _weights(variant)
    t = jnp.maximum(_check.as_float(theta_deg), 0.0)
    lam = float(wavelength_nm)
    # Written so that no intermediate overflows, nor its derivative, up to the float max:
    # 1/(θ + a) before the power (the derivative of 20.91/(θ + a)³ is otherwise formed from
    # (θ + a)² = inf and ((θ + a)³)⁻² = 0 at 1e32° in float32: NaN), and the Gaussians'
    # arguments clipped where exp(-·) is already 0 in float64 (exp(-2500), exp(-1975)),
    # which leaves their values unchanged.
    u = 1.0 / (t + _A)
    p = (
        w[0] * 2.61e6 * jnp.exp(-((jnp.minimum(t, 1.0) / _A) ** 2))
        + w[1] * 20.91 * u**3
        + w[2] * 72.37 * u**2
    )
    if w[3]:
        d = jnp.clip(t - 3.0 * lam / 568.0, -10.0, 10.0)
        p = p + w[3] * 436.9 * (568.0 / lam) * jnp.exp(-19.75 * d**2)
    return p


def _weights(variant: str) -> tuple[float, float, float, float]:
    if variant not in WEIGHTS:
        raise ValueError(f"variant: expected one of {sorted(WEIGHTS)}, got {variant!r}")
    return WEIGHTS[variant]


def variant_for(adaptation: float) -> Variant:
    """The PSF variant for a global adaptation luminance (cd/m²): scotopic at or below
    5.62e-3, photopic at or above 5.62, mesopic between (pcond's mesopic limits)."""
    if adaptation <= BOT_MESOPIC:
        return "scotopic"
    if adaptation >= TOP_MESOPIC:
        return "photopic"
    return "mesopic"


def _midpoint(f, dy, dx, py, px, s):
    """Mean of ``f(θ)`` over each pixel (offsets ``dy``, ``dx`` grids) with ``s×s`` points."""
    acc = np.zeros(np.broadcast(dy, dx).shape)
    for i in range(s):
        oy = ((i + 0.5) / s - 0.5) * py
        for j in range(s):
            ox = ((j + 0.5) / s - 0.5) * px
            acc += f(np.hypot(dy * py + oy, dx * px + ox))
    return acc / (s * s)


def _disc_energy(which: int, r: float) -> float:
    """``∫_0^r f(θ) 2πθ dθ`` (square degrees × f) for f1 (which=1) or f2 (which=2)."""
    a = _A
    if which == 1:
        return 2 * math.pi * 20.91 * (1 / (2 * a) - 1 / (r + a) + a / (2 * (r + a) ** 2))
    return 2 * math.pi * 72.37 * (math.log((r + a) / a) + a / (r + a) - 1.0)


@functools.lru_cache(maxsize=8)
def _kernel_cached(
    ry: int, rx: int, py: float, px: float, variant: str, radius_deg: float | None
) -> np.ndarray:
    from scipy.special import erf  # NumPy-side, once per kernel

    w = _weights(variant)
    oy = np.arange(-ry, ry + 1, dtype=np.float64)[:, None]
    ox = np.arange(-rx, rx + 1, dtype=np.float64)[None, :]
    omega = py * px * _SR  # pixel solid angle, sr
    # f0: separable Gaussian, integrated exactly over each pixel (square degrees).
    gy = 0.5 * math.sqrt(math.pi) * _A * (erf((oy + 0.5) * py / _A) - erf((oy - 0.5) * py / _A))
    gx = 0.5 * math.sqrt(math.pi) * _A * (erf((ox + 0.5) * px / _A) - erf((ox - 0.5) * px / _A))
    k0 = 2.61e6 * gy * gx * _SR
    # f1, f2: pixel centres, a 16×16 midpoint rule near the centre, the disc at the centre.
    theta = np.hypot(oy * py, ox * px)
    k1 = _f1(theta) * omega
    k2 = _f2(theta) * omega
    n = 3
    cy, cx = (
        slice(ry - min(n, ry), ry + min(n, ry) + 1),
        slice(rx - min(n, rx), rx + min(n, rx) + 1),
    )
    k1[cy, cx] = _midpoint(_f1, oy[cy], ox[:, cx], py, px, 16) * omega
    k2[cy, cx] = _midpoint(_f2, oy[cy], ox[:, cx], py, px, 16) * omega
    r_eq = math.sqrt(py * px / math.pi)
    k1[ry, rx] = _disc_energy(1, r_eq) * _SR
    k2[ry, rx] = _disc_energy(2, r_eq) * _SR
    base = w[0] * k0 + w[1] * k1 + w[2] * k2
    k = np.repeat(base[None], 3 if w[3] else 1, axis=0)
    if w[3]:
        # f3 lives within ~2° of θ0 = 3λ/568 (exp(-19.75·4) ≈ 0 beyond): integrate there.
        s3 = max(1, math.ceil(max(py, px) / 0.05))
        for c, lam in enumerate(WAVELENGTHS_RGB):
            t_hi = 3.0 * lam / 568.0 + 2.0
            hy, hx = min(ry, math.ceil(t_hi / py)), min(rx, math.ceil(t_hi / px))
            sl = (slice(ry - hy, ry + hy + 1), slice(rx - hx, rx + hx + 1))
            f3 = _midpoint(lambda t, lam=lam: _f3(t, lam), oy[sl[0]], ox[:, sl[1]], py, px, s3)
            k[c][sl] += w[3] * f3 * omega
    if radius_deg is not None:
        k = k * (theta <= radius_deg)[None]
    total = k.sum(axis=(1, 2))
    for c in range(k.shape[0]):
        if total[c] <= 1.0:
            k[c, ry, rx] += 1.0 - total[c]  # scattering beyond the support stays in place
        else:
            k[c] /= total[c]
    k.setflags(write=False)
    return k


def glare_kernel(
    view: ResolvedView, variant: Variant = "photopic", *, radius_deg: float | None = None
) -> np.ndarray:
    """Discrete glare kernels for an image and view, float64 ``(C, 2ry+1, 2rx+1)``.

    ``C`` is 1 for the photopic variant (the same kernel for every channel) and 3 otherwise
    (R, G, B differ through the halo term). The kernel radius ``(ry, rx)`` in pixels covers
    the whole image (``H - 1``, ``W - 1``) or, with ``radius_deg``, that angle. Each kernel
    sums to 1 (see the module docstring for the discretisation).

    Args:
        view: the resolved field of view (pixel sizes and image size).
        variant: PSF weights, ``"photopic"``, ``"mesopic"`` or ``"scotopic"``.
        radius_deg: truncate the PSF at this angle (degrees); ``None``: whole image.
    """
    _weights(variant)
    ry, rx = kernel_radius(view, radius_deg)
    rd = None if radius_deg is None else float(radius_deg)
    return _kernel_cached(ry, rx, view.pixel_deg_y, view.pixel_deg_x, variant, rd)


def kernel_radius(view: ResolvedView, radius_deg: float | None) -> tuple[int, int]:
    """Kernel radius in pixels ``(ry, rx)``: the whole image, or ``radius_deg`` of it."""
    ry, rx = view.height - 1, view.width - 1
    if radius_deg is not None:
        if not (radius_deg > 0 and math.isfinite(radius_deg)):
            raise ValueError(f"radius_deg: expected a finite angle > 0, got {radius_deg!r}")
        ry = min(ry, math.ceil(radius_deg / view.pixel_deg_y))
        rx = min(rx, math.ceil(radius_deg / view.pixel_deg_x))
    return ry, rx


@functools.lru_cache(maxsize=8)
def _spectrum_cached(
    view: ResolvedView, variant: str, radius_deg: float | None, circular: bool, dtype: str
) -> tuple[Array, tuple[int, int]]:
    ry, rx = kernel_radius(view, radius_deg)
    size = _fft.fft_size(view.height, view.width, ry, rx, circular=circular)
    # concrete even when first called inside jax.jit/vmap: a cached tracer would leak
    with jax.ensure_compile_time_eval():
        spec = _fft.kernel_spectrum(glare_kernel(view, variant, radius_deg=radius_deg), size)  # type: ignore[arg-type]
        return jnp.asarray(spec.astype(dtype)), size


def glare_spectrum(
    view: ResolvedView,
    variant: Variant = "photopic",
    *,
    radius_deg: float | None = None,
    dtype: "jnp.dtype | str" = "float32",
    circular: bool = False,
) -> tuple[Array, tuple[int, int]]:
    """The kernel's FFT (complex, matching the real ``dtype``) and the FFT grid size.

    Cached: building the kernel is NumPy work on the order of the image size, done once
    per (view, variant, radius, dtype).
    """
    cdt = "complex128" if jnp.dtype(dtype) == jnp.float64 else "complex64"
    rd = None if radius_deg is None else float(radius_deg)
    return _spectrum_cached(view, variant, rd, bool(circular), cdt)


@functools.partial(jax.jit, static_argnums=2)
def apply_glare(rgb: Array, spectrum: Array, size: tuple[int, int]) -> Array:
    """Convolve finite pixels with a precomputed glare spectrum (non-finite restored).

    Only light scatters: negative values (noise from colour conversion in real files) stay
    in their pixel, and the scattered image is clipped at 0, which removes the FFT's
    round-off below zero (relative size ~1e-8 of the total light, float32).
    """
    x, ok = sanitize(rgb)
    spectrum = spectrum.astype(jnp.result_type(x.dtype, jnp.complex64))
    scattered = jnp.maximum(_fft.convolve(jnp.maximum(x, 0.0), spectrum, size), 0.0)
    return restore(scattered + jnp.minimum(x, 0.0), rgb, ok)


def glare(
    rgb: Float[ArrayLike, "H W 3"],
    view: "View | ResolvedView | float | None" = None,
    *,
    variant: Variant = "photopic",
    radius_deg: float | None = None,
) -> Float[Array, "H W 3"]:
    """Veiling glare: convolve the image with the Spencer et al. 1995 PSF (zero-padded FFT).

    Args:
        rgb: linear RGB in cd/m², ``(H, W, 3)``.
        view: field of view (:class:`View`, horizontal degrees, a resolved view, or
            ``None``: pcond's 40° across the longer side).
        variant: ``"photopic"``, ``"mesopic"`` or ``"scotopic"`` PSF weights.
        radius_deg: truncate the PSF at this angle; ``None`` (default) spans the image.

    Returns:
        RGB in cd/m², same shape. Energy is conserved except what scatters past the image
        border; NaN/Inf pixels are left out of the convolution and returned unchanged;
        negative values are not scattered (they stay in their pixel). float32 accuracy:
        FFT round-off of about 1e-8 of the image's total light per pixel, which matters
        only for pixels some 1e6 times darker than the brightest sources (use float64).
    """
    rgb = check_rgb(rgb, image=True)
    rv = resolve_view(view, rgb.shape[0], rgb.shape[1])
    spec, size = glare_spectrum(rv, variant, radius_deg=radius_deg, dtype=rgb.dtype)
    return apply_glare(rgb, spec, size)


__all__ = [
    "WAVELENGTHS_RGB",
    "WEIGHTS",
    "apply_glare",
    "glare",
    "glare_kernel",
    "glare_spectrum",
    "kernel_radius",
    "spencer1995_psf",
    "variant_for",
]
