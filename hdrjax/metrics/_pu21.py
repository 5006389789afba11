"""PU21: the perceptually uniform encoding of absolute luminance for HDR quality metrics.

R. K. Mantiuk and M. Azimi, "PU21: A novel perceptually uniform encoding for adapting
existing quality metrics for HDR", Picture Coding Symposium (PCS), 2021,
https://doi.org/10.1109/PCS50896.2021.9477471.

Numeric contract: the encoding takes absolute luminance (or a linear RGB channel) in cd/m²,
clamped to the encoding's range [0.005, 10000] cd/m², and returns PU values from 0 to about
600, scaled so that 100 cd/m² (the peak of a typical SDR display) maps to about 256: the
range SDR metrics expect of 8-bit values.
"""

import jax
import jax.numpy as jnp
from jaxtyping import ArrayLike, Float

from .. import _check

L_MIN = 0.005
"""Smallest luminance (cd/m²) of the encoding; darker values are clamped to it."""
L_MAX = 10000.0
"""Largest luminance (cd/m²) of the encoding; brighter values are clamped to it."""

PU21_PARAMETERS: dict[str, tuple[float, ...]] = {
    # fitted to contrast sensitivity (banding) data
    "banding": (
        1.070275272,
        0.4088273932,
        0.153224308,
        0.2520326168,
        1.063512885,
        1.14115047,
        521.4527484,
    ),
    # banding, with the loss of sensitivity from glare in the eye (the recommended default)
    "banding_glare": (
        0.353487901,
        0.3734658629,
        8.277049286e-05,
        0.9062562627,
        0.09150303166,
        0.9099517204,
        596.3148142,
    ),
    # fitted to the peak sensitivity of the contrast sensitivity function
    "peaks": (
        1.043882782,
        0.6459495343,
        0.3194584211,
        0.374025247,
        1.114783422,
        1.095360363,
        384.9217577,
    ),
    # peaks, with glare
    "peaks_glare": (
        816.885024,
        1479.463946,
        0.001253215609,
        0.9329636822,
        0.06746643971,
        1.573435413,
        419.6006374,
    ),
}
"""The parameter sets ``p_1 … p_7`` of Mantiuk & Azimi (2021), as their reference code
(``pu21_encoder.m``, parameters of 2020-02-06) publishes them; ``p_7`` scales the
encoding so that 100 cd/m² maps to about 256."""


def pu21_parameters(params: str) -> tuple[float, ...]:
    """The seven parameters of a named PU21 set; ``ValueError`` naming ``params`` otherwise."""
    if params not in PU21_PARAMETERS:
        raise ValueError(f"params: expected one of {sorted(PU21_PARAMETERS)}, got {params!r}")
    return PU21_PARAMETERS[params]


def pu21_encode(
    L: Float[ArrayLike, "*shape"], *, params: str = "banding_glare"
) -> Float[jax.Array, "*shape"]:
    """PU21 encoding of absolute luminance (Mantiuk & Azimi 2021).

    .. math::

        V = \\max\\Bigl(p_7 \\Bigl[\\Bigl(\\frac{p_1 + p_2 Y^{p_4}}{1 + p_3 Y^{p_4}}\\Bigr)^{p_5}
        - p_6\\Bigr],\\ 0\\Bigr), \\qquad Y = \\operatorname{clamp}(L, 0.005, 10000)

    Args:
        L: absolute luminance in cd/m² (or one linear RGB channel in cd/m²), any shape.
            Values outside [0.005, 10000] cd/m² are clamped, as published (their gradient
            is then 0); NaN stays NaN.
        params: the parameter set, one of ``"banding"``, ``"banding_glare"`` (the
            authors' recommended default), ``"peaks"``, ``"peaks_glare"``
            (:data:`PU21_PARAMETERS`).

    Returns:
        PU values (about 0 to 600; 100 cd/m² ↦ about 256), the shape of ``L``, in ``L``'s
        float dtype (float16 and integers are computed in JAX's default float).

    Reference: R. K. Mantiuk and M. Azimi, "PU21: A novel perceptually uniform encoding for
    adapting existing quality metrics for HDR", PCS 2021,
    https://doi.org/10.1109/PCS50896.2021.9477471.
    """
    p = pu21_parameters(params)
    _check.real(L, "L")
    L = _check.as_float(L)
    Y = jnp.clip(L, L_MIN, L_MAX)
    Yp = Y ** p[3]
    V = p[6] * (((p[0] + p[1] * Yp) / (1 + p[2] * Yp)) ** p[4] - p[5])
    return jnp.maximum(V, 0.0).astype(L.dtype)
