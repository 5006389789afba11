"""Weighting functions for merging an exposure bracket: how much each code value is trusted.

Numeric contract: a per-code weight is a ``(levels,)`` table of non-negative weights over the
integer code values ``z = 0 … levels − 1`` (``z_max = levels − 1``), peak 1. Merging
(:func:`hdrjax.merge.merge`) additionally gives the black (0) and saturated (top) codes weight
0 whatever the table says: they bound the exposure, they do not measure it.

- ``"hat"`` — Reinhard, E., Ward, G., Pattanaik, S., Debevec, P., Heidrich, W., &
  Myszkowski, K. (2010). *High Dynamic Range Imaging* (2nd ed.), Morgan Kaufmann, §5.7: the
  broad hat ``w(z) = 1 − (2z/z_max − 1)¹²``, flat over the mid-tones and falling to 0 at both
  ends.
- ``"triangle"`` — Debevec, P. E., & Malik, J. (1997). Recovering high dynamic range radiance
  maps from photographs. *SIGGRAPH 97*, 369–378. DOI 10.1145/258734.258884:
  ``w(z) = z − z_min`` for ``z ≤ (z_min + z_max)/2``, ``z_max − z`` above, here divided by its
  peak: ``w(z) = 1 − |2z/z_max − 1|``.
- ``"gaussian"`` — Robertson, M. A., Borman, S., & Stevenson, R. L. (2003). Estimation-
  theoretic approach to dynamic range enhancement using multiple exposures. *Journal of
  Electronic Imaging*, 12(2), 219–228. DOI 10.1117/1.1557695:
  ``w(z) = exp(−4 (z − c)² / c²)``, ``c = z_max/2``.
- ``"granados2010"`` — Granados, M., Ajdin, B., Wand, M., Theobalt, C., Seidel, H.-P., &
  Lensch, H. P. A. (2010). Optimal HDR reconstruction with linear digital cameras. *CVPR
  2010*, 215–222. DOI 10.1109/CVPR.2010.5540208. Not a per-code table: the weight of an
  exposure is the inverse variance of its irradiance estimate ``X_j / t_j`` under the
  camera noise model ``σ²(y) = K y + σ_R²`` (photon shot noise with the gain ``K`` in code
  values per electron, plus read noise ``σ_R`` in code values; the paper's dark current is
  left out, the bias is assumed subtracted), which with ``y = z_max t_j E`` gives
  ``w_j = t_j² / (K z_max t_j E + σ_R²)`` (:func:`granados2010_weight`). It depends on the
  unknown irradiance ``E``, which :func:`hdrjax.merge.merge` estimates first (see there). It
  is meant for linear (RAW) data; on a non-linear response the noise model is applied to the
  linearised exposure ``X = exp g(z)``.
"""

import functools

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

WEIGHTS: tuple[str, ...] = ("hat", "triangle", "gaussian", "granados2010")
"""Names of the weighting functions :func:`hdrjax.merge.merge` accepts."""

PER_CODE: tuple[str, ...] = ("hat", "triangle", "gaussian")
"""The weights that are a table over code values (all but ``"granados2010"``)."""

FULL_WELL_ELECTRONS = 20000.0
"""Default electrons at saturation for ``"granados2010"``: gain ``K = z_max / 20000``."""

READ_NOISE_ELECTRONS = 3.0
"""Default read noise for ``"granados2010"``, in electrons (``σ_R = 3 K`` code values)."""


def weight_key(name: object) -> str:
    """The :data:`WEIGHTS` name of ``name`` (case and separators ignored); ``ValueError``
    naming ``weights`` otherwise."""
    key = str(name).lower().replace("-", "").replace("_", "").replace(" ", "")
    if not isinstance(name, str) or key not in WEIGHTS:
        raise ValueError(f"weights: expected one of {list(WEIGHTS)} or a table, got {name!r}")
    return key


def weight_function(name: str, levels: int = 256) -> Float[Array, " levels"]:
    """The weight of every code value ``0 … levels − 1`` for a per-code weighting function.

    Args:
        name: ``"hat"``, ``"triangle"`` or ``"gaussian"`` (see the module docstring); case
            and separators ignored. ``"granados2010"`` depends on the exposure time and the
            irradiance, not on the code alone: use :func:`granados2010_weight`.
        levels: number of code values (256 for 8-bit, 65536 for 16-bit).

    Returns:
        ``(levels,)`` weights in [0, 1] (float32, float64 under x64).

    >>> [round(float(v), 3) for v in weight_function("triangle", 5)]
    [0.0, 0.5, 1.0, 0.5, 0.0]
    """
    key = weight_key(name)
    if key not in PER_CODE:
        raise ValueError(
            "name: 'granados2010' weights depend on exposure time and irradiance, not on the "
            "code alone; pass weights='granados2010' to merge or use granados2010_weight"
        )
    if isinstance(levels, bool) or not isinstance(levels, int) or levels < 2:
        raise ValueError(f"levels: expected an integer ≥ 2, got {levels!r}")
    return jnp.asarray(weight_table(key, levels), jnp.result_type(float))


@functools.lru_cache(maxsize=16)
def weight_table(key: str, levels: int) -> np.ndarray:
    """:func:`weight_function` for a :data:`PER_CODE` key, float64 NumPy, computed once."""
    u = 2.0 * np.arange(levels, dtype=np.float64) / (levels - 1) - 1.0
    if key == "hat":
        w = 1.0 - u**12
    elif key == "triangle":
        w = 1.0 - np.abs(u)
    else:
        w = np.exp(-4.0 * np.square(u))
    w.setflags(write=False)
    return w


def granados2010_weight(
    exposure_time: ArrayLike,
    irradiance: ArrayLike,
    *,
    gain: ArrayLike,
    read_noise: ArrayLike,
    levels: int = 256,
) -> Array:
    """Granados et al. (2010) inverse-variance weight ``t² / (K z_max t E + σ_R²)``.

    Args:
        exposure_time: ``t`` in seconds.
        irradiance: ``E`` in sensor-exposure units per second (``X = E t``, ``X = 1``
            saturates).
        gain: ``K``, code values per electron.
        read_noise: ``σ_R``, standard deviation of the read noise in code values.
        levels: code values of the data (``z_max = levels − 1``).

    Returns:
        The weight (broadcast of the inputs); its scale is arbitrary, only ratios matter.
    """
    t = jnp.asarray(exposure_time)
    e = jnp.maximum(jnp.asarray(irradiance), 0.0)
    var = gain * (levels - 1) * t * e + jnp.square(read_noise)
    return jnp.square(t) / jnp.maximum(var, jnp.finfo(jnp.result_type(float)).tiny)


__all__ = ["WEIGHTS", "granados2010_weight", "weight_function"]
