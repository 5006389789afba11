"""SSIM (Wang et al. 2004) of PU21-encoded HDR images (Mantiuk & Azimi 2021).

Numeric contract: both images are linear RGB ``(..., H, W, 3)`` in cd/m², one shape;
result in [−1, 1] (1 for identical images), one per image of the batch.
"""

import functools

import jax
import jax.numpy as jnp
from jaxtyping import ArrayLike, Float

from ._common import gaussian_filter, gaussian_taps, image_pair
from ._psnr import PU_PEAK
from ._pu21 import pu21_encode, pu21_parameters

K1, K2 = 0.01, 0.03
"""SSIM's constants: ``C1 = (K1 L)²``, ``C2 = (K2 L)²`` with the dynamic range ``L``."""


def ssim_map(a: jax.Array, b: jax.Array, dynamic_range: float) -> jax.Array:
    """Wang et al. (2004)'s SSIM of each pixel of the planes ``(..., H, W)``: 11×11 Gaussian
    window (σ = 1.5), edges replicated (MATLAB's ``ssim``)."""
    c1, c2 = (K1 * dynamic_range) ** 2, (K2 * dynamic_range) ** 2
    taps = gaussian_taps(11, 1.5)
    mu_a, mu_b, aa, bb, ab = (
        gaussian_filter(v, taps, mode="edge") for v in (a, b, a * a, b * b, a * b)
    )
    va = aa - mu_a * mu_a
    vb = bb - mu_b * mu_b
    cov = ab - mu_a * mu_b
    return ((2 * mu_a * mu_b + c1) * (2 * cov + c2)) / (
        (mu_a * mu_a + mu_b * mu_b + c1) * (va + vb + c2)
    )


@functools.partial(jax.jit, static_argnames="params")
def _pu_ssim(test, reference, params):
    ok = jnp.all(jnp.isfinite(test), axis=-1) & jnp.all(jnp.isfinite(reference), axis=-1)
    a = pu21_encode(jnp.where(ok[..., None], test, 0.0), params=params)
    b = pu21_encode(jnp.where(ok[..., None], reference, 0.0), params=params)
    # channels first: one SSIM map per channel
    s = ssim_map(jnp.moveaxis(a, -1, -3), jnp.moveaxis(b, -1, -3), PU_PEAK)
    w = ok[..., None, :, :].astype(s.dtype)
    return jnp.sum(s * w, axis=(-3, -2, -1)) / (3 * jnp.sum(w[..., 0, :, :], axis=(-2, -1)))


def pu_ssim(
    test: Float[ArrayLike, "*batch H W 3"],
    reference: Float[ArrayLike, "*batch H W 3"],
    *,
    params: str = "banding_glare",
) -> Float[jax.Array, "*batch"]:
    """SSIM of PU21-encoded images (Mantiuk & Azimi 2021's ``pu21_metric``).

    Each linear RGB channel (cd/m²) is encoded with :func:`pu21_encode`; SSIM (Wang et al.
    2004) with the dynamic range ``L = 256`` (the PU value of 100 cd/m²), ``K1 = 0.01``,
    ``K2 = 0.03``, an 11×11 Gaussian window of σ = 1.5 pixels and replicated edges (MATLAB's
    ``ssim``, which ``pu21_metric`` calls), averaged over the pixels and the three channels
    (each channel a plane: MATLAB's ``ssim`` would filter an ``H×W×3`` array in 3-D).
    Pixels that are not finite in either image are set to 0 cd/m² (the encoding's floor)
    before filtering and left out of the mean.

    Args:
        test: the distorted image, linear RGB in cd/m².
        reference: the reference image, linear RGB in cd/m², the shape of ``test``.
        params: the PU21 parameter set (:data:`PU21_PARAMETERS`).

    Returns:
        Mean SSIM in [−1, 1], shape ``*batch``; 1 for identical images.

    References: Z. Wang, A. C. Bovik, H. R. Sheikh and E. P. Simoncelli, "Image quality
    assessment: from error visibility to structural similarity", IEEE TIP 13(4):600–612,
    2004, https://doi.org/10.1109/TIP.2003.819861; R. K. Mantiuk and M. Azimi, PCS 2021,
    https://doi.org/10.1109/PCS50896.2021.9477471.
    """
    pu21_parameters(params)
    a, b = image_pair(test, reference, ("test", "reference"))
    return _pu_ssim(a, b, params)
