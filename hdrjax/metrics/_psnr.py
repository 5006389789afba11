"""Peak signal-to-noise ratios for HDR images: on PU21 values (Mantiuk & Azimi 2021), on
log luminance, and over exposures (mPSNR, Munkberg et al. 2006, as HDR Toolbox computes it).

Numeric contract: both images are linear RGB ``(..., H, W, 3)`` of one shape — absolute
(cd/m²) for :func:`pu_psnr`, any positive scale for :func:`log_psnr` and :func:`mpsnr`.
Results in dB, one per image of the batch; ``+inf`` for identical images (the gradient is
then 0). Pixels that are not finite in either image are left out of the mean squared error
(NaN when no pixel is left).
"""

import functools

import jax
import jax.numpy as jnp
from jaxtyping import ArrayLike, Float

from ._common import image_pair, luminance
from ._pu21 import pu21_encode, pu21_parameters

PU_PEAK = 256.0
"""Peak value of PSNR and dynamic range of SSIM on PU21 values (Mantiuk & Azimi 2021's
``pu21_metric``: 100 cd/m² ↦ 256)."""


def _valid(a: jax.Array, b: jax.Array) -> jax.Array:
    """Pixels ``(..., H, W, 1)`` finite in both images."""
    ok = jnp.all(jnp.isfinite(a), axis=-1, keepdims=True) & jnp.all(
        jnp.isfinite(b), axis=-1, keepdims=True
    )
    return ok


def masked_mse(a: jax.Array, b: jax.Array, ok: jax.Array) -> jax.Array:
    """Mean over ``(H, W, C)`` of ``(a − b)²`` where ``ok`` (non-finite pixels left out)."""
    d = jnp.where(ok, a, 0.0) - jnp.where(ok, b, 0.0)
    n = jnp.sum(jnp.broadcast_to(ok, d.shape), axis=(-3, -2, -1))
    return jnp.sum(d * d, axis=(-3, -2, -1)) / n


def psnr_db(mse: jax.Array, peak: jax.Array | float) -> jax.Array:
    """``10 log10(peak² / mse)``: +inf at ``mse = 0`` with gradient 0, NaN for NaN."""
    pos = mse > 0
    val = 10 * jnp.log10(peak**2 / jnp.where(pos, mse, 1.0))
    return jnp.where(pos, val, jnp.where(mse == 0, jnp.inf, jnp.nan))


@functools.partial(jax.jit, static_argnames="params")
def _pu_psnr(test, reference, params):
    ok = _valid(test, reference)
    a = pu21_encode(jnp.where(ok, test, 1.0), params=params)
    b = pu21_encode(jnp.where(ok, reference, 1.0), params=params)
    a = jnp.where(test == reference, b, a)  # equal values, equal codes (XLA may round apart)
    return psnr_db(masked_mse(a, b, ok), PU_PEAK)


def pu_psnr(
    test: Float[ArrayLike, "*batch H W 3"],
    reference: Float[ArrayLike, "*batch H W 3"],
    *,
    params: str = "banding_glare",
) -> Float[jax.Array, "*batch"]:
    """PSNR of PU21-encoded images (Mantiuk & Azimi 2021).

    Each linear RGB channel (cd/m², clamped to [0.005, 10000]) is encoded with
    :func:`pu21_encode`, then ``PSNR = 10 log10(256² / MSE)``, the mean over pixels and
    channels, with the peak 256 of the authors' ``pu21_metric`` (the PU value of 100 cd/m²).

    Args:
        test: the distorted image, linear RGB in cd/m².
        reference: the reference image, linear RGB in cd/m², the shape of ``test``.
        params: the PU21 parameter set (:data:`PU21_PARAMETERS`).

    Returns:
        PSNR in dB, shape ``*batch``.

    Reference: R. K. Mantiuk and M. Azimi, "PU21: A novel perceptually uniform encoding for
    adapting existing quality metrics for HDR", PCS 2021,
    https://doi.org/10.1109/PCS50896.2021.9477471.
    """
    pu21_parameters(params)
    a, b = image_pair(test, reference, ("test", "reference"))
    return _pu_psnr(a, b, params)


@functools.partial(jax.jit, static_argnames="floor")
def _log_psnr(test, reference, floor):
    ok = _valid(test, reference)
    a = jnp.log10(jnp.maximum(jnp.where(ok, test, 1.0), floor))
    b = jnp.log10(jnp.maximum(jnp.where(ok, reference, 1.0), floor))
    a = jnp.where(test == reference, b, a)  # equal values, equal logs (XLA may round apart)
    peak = jnp.max(jnp.where(ok, b, jnp.log10(floor)), axis=(-3, -2, -1)) - jnp.log10(floor)
    return psnr_db(masked_mse(a, b, ok), jnp.maximum(peak, 1e-6))


def log_psnr(
    test: Float[ArrayLike, "*batch H W 3"],
    reference: Float[ArrayLike, "*batch H W 3"],
    *,
    floor: float = 1e-5,
) -> Float[jax.Array, "*batch"]:
    """PSNR of ``log10`` values (the "log PSNR" of HDR Toolbox's ``PSNR(…, 'log10')``).

    Values are clamped to ``floor`` (HDR Toolbox's 1e-5) and the peak is the reference's
    log range, ``log10(max(reference)) − log10(floor)``. (HDR Toolbox takes
    ``|log10(max(reference))|`` as the peak, which is 0 for a reference whose maximum is 1:
    its result then depends on the units, this one does not below the floor.)

    Args:
        test: the distorted image, linear RGB (any positive scale; the scale of
            ``reference``).
        reference: the reference image, the shape of ``test``.
        floor: smallest value (same units), > 0.

    Returns:
        PSNR in dB, shape ``*batch``.
    """
    if not (isinstance(floor, int | float) and floor > 0):
        raise ValueError(f"floor: expected a positive number, got {floor!r}")
    a, b = image_pair(test, reference, ("test", "reference"))
    return _log_psnr(a, b, float(floor))


def _quantise8(x: jax.Array, exposure: jax.Array) -> jax.Array:
    """HDR Toolbox's 8-bit rendition at one exposure: ``clamp(round(255 (2^e x)^(1/2.2)))``."""
    v = jnp.maximum(x * exposure, 0.0) ** (1 / 2.2)
    return jnp.clip(jnp.round(255 * v), 0.0, 255.0)


@functools.partial(jax.jit, static_argnames="span")
def _mpsnr(test, reference, span):
    ok = _valid(test, reference)
    # piecewise constant (8-bit renditions): gradient 0, and no 0 · ∞ from x^(1/2.2) at 0
    a = jax.lax.stop_gradient(jnp.where(ok, test, 0.0))
    b = jax.lax.stop_gradient(jnp.where(ok, reference, 0.0))
    La, Lb = luminance(a), luminance(b)
    big = jnp.finfo(a.dtype).max
    lo = jnp.minimum(
        jnp.min(jnp.where(La > 0, La, big), axis=(-2, -1)),
        jnp.min(jnp.where(Lb > 0, Lb, big), axis=(-2, -1)),
    )
    hi = jnp.maximum(jnp.max(La, axis=(-2, -1)), jnp.max(Lb, axis=(-2, -1)))
    e_min = -jnp.round(jnp.log2(jnp.where(hi > 0, hi, 1.0)))
    e_max = -jnp.round(jnp.log2(jnp.where(lo < big, lo, 1.0)))
    widen = e_max == e_min
    e_min, e_max = jnp.where(widen, e_min - 1, e_min), jnp.where(widen, e_max + 1, e_max)
    n = jnp.sum(jnp.broadcast_to(ok, a.shape), axis=(-3, -2, -1))

    def step(acc, k):
        e = e_min + k
        scale = jnp.exp2(e)[..., None, None, None]
        qb = _quantise8(b, scale)
        qa = _quantise8(a, scale)
        mean = jnp.sum(jnp.where(ok, qb, 0.0), axis=(-3, -2, -1)) / n / 255
        use = (e <= e_max) & (mean > 0.1) & (mean < 0.9)
        d = jnp.where(ok, qa - qb, 0.0)
        mse = jnp.sum(d * d, axis=(-3, -2, -1)) / n
        return (acc[0] + jnp.where(use, mse, 0.0), acc[1] + use), None

    zero = jnp.zeros(e_min.shape, a.dtype)
    (total, used), _ = jax.lax.scan(step, (zero, zero), jnp.arange(span, dtype=a.dtype))
    return jnp.where(used > 0, psnr_db(total, 255.0), -1.0)


def mpsnr(
    test: Float[ArrayLike, "*batch H W 3"],
    reference: Float[ArrayLike, "*batch H W 3"],
    *,
    span: int = 64,
) -> Float[jax.Array, "*batch"]:
    """Multi-exposure PSNR (Munkberg et al. 2006), as HDR Toolbox's ``mPSNR.m`` computes it.

    Both images are rendered at the exposures ``2^e`` for the integers ``e`` from
    ``−round(log2 L_max)`` to ``−round(log2 L_min)`` (the brightest and dimmest positive
    luminance of the two images; one stop either side when they are equal) as 8-bit values
    ``clamp(round(255 (2^e x)^{1/2.2}), 0, 255)``; the exposures whose reference rendition
    has a mean in (0.1, 0.9) (of 255) count. ``mPSNR = 10 log10(255² / Σ_e MSE_e)``:
    the Toolbox *sums* the exposures' mean squared errors (it divides the sum by
    ``length(eMax)``, which is 1), where Munkberg et al. average them — this function
    follows the Toolbox, so that its values compare with published Toolbox numbers.
    −1 when no exposure counts (the Toolbox's value).

    The rounding makes the metric piecewise constant: its gradient is 0 wherever it is
    defined (use :func:`pu_psnr` or :func:`log_psnr` as a fit objective).

    Args:
        test: the distorted image, linear RGB ≥ 0 (any scale; the scale of ``reference``).
        reference: the reference image, the shape of ``test``.
        span: most exposures (stops) evaluated, from ``e_min`` up (static; 64 stops cover
            every float32 image whose positive luminances lie within 64 stops).

    Returns:
        mPSNR in dB, shape ``*batch``.

    Reference: J. Munkberg, P. Clarberg, J. Hasselgren and T. Akenine-Möller, "High
    dynamic range texture compression for graphics hardware", ACM Transactions on Graphics
    25(3):698–706, 2006, https://doi.org/10.1145/1141911.1141942.
    """
    if isinstance(span, bool) or not isinstance(span, int) or span < 1:
        raise ValueError(f"span: expected a positive integer, got {span!r}")
    a, b = image_pair(test, reference, ("test", "reference"))
    return _mpsnr(a, b, span)
