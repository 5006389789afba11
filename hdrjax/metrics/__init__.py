"""Quality metrics for tone-mapped and HDR images, differentiable in JAX.

- :func:`tmqi`: the tone-mapped image quality index (Yeganeh & Wang 2013), structural
  fidelity against the HDR image and statistical naturalness of the LDR image;
- :func:`pu21_encode`: the PU21 perceptually uniform encoding of absolute luminance
  (Mantiuk & Azimi 2021), and :func:`pu_psnr`, :func:`pu_ssim` on it;
- :func:`log_psnr`, :func:`mpsnr`: PSNR of log values and over exposures (HDR Toolbox);
- :func:`delta_e_itp`: the ΔE_ITP colour difference of ITU-R BT.2124 for HDR renditions;
- :func:`contrast_distortion`: the visible contrast distortion of a rendition on a display
  (Mantiuk, Daly & Kerofsky 2008), the quantity ``mantiuk2008`` minimises.

Every function is traceable (``jax.jit``, ``jax.vmap``, ``jax.grad``); see each module's
numeric contract (units of the inputs, range of the outputs).
"""

from ._contrast import contrast_distortion as contrast_distortion
from ._delta_e import delta_e_itp as delta_e_itp
from ._psnr import log_psnr as log_psnr, mpsnr as mpsnr, pu_psnr as pu_psnr
from ._pu21 import PU21_PARAMETERS as PU21_PARAMETERS, pu21_encode as pu21_encode
from ._ssim import pu_ssim as pu_ssim
from ._tmqi import TMQIScore as TMQIScore, tmqi as tmqi

__all__ = [
    "PU21_PARAMETERS",
    "TMQIScore",
    "contrast_distortion",
    "delta_e_itp",
    "log_psnr",
    "mpsnr",
    "pu21_encode",
    "pu_psnr",
    "pu_ssim",
    "tmqi",
]
