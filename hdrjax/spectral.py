"""Spectral images integrated to CIE XYZ against the colour-matching functions.

Numeric contract: a spectral image has one channel per wavelength, channels last
``(..., n_bands)``, the band centres given in nm. :func:`spectral_to_xyz` returns CIE XYZ,
channels last ``(..., 3)``:

- ``kind="emissive"``: spectral radiance in W/(sr·m²·nm) gives photometric XYZ, ``Y`` the
  luminance in cd/m²: ``X = K_m ∫ x̄(λ) L_e,λ(λ) dλ`` (likewise ``Y``, ``Z``) with
  ``K_m = 683 lm/W`` (CIE 015:2018, Colorimetry, https://doi.org/10.25039/TR.015.2018).
  For the CIE 1931 observer ``ȳ`` is the photopic luminous efficiency ``V(λ)``, so ``Y``
  is the luminance of photometry; other observers give their own ``Y``.
- ``kind="reflective"``: reflectance (or transmittance) factors in [0, 1] give the XYZ of
  the surface under an illuminant (D65 by default), scaled so that a perfect white
  reflector has ``Y = 1`` (CIE 015:2018's ``k = 100 / ∫ S(λ) ȳ(λ) dλ``, divided by 100 so
  that white matches RGB white 1 in the rest of the toolkit; colour-science's
  ``msds_to_XYZ`` returns 100 times these values).

How the integral is taken is colour-science's, not a new quadrature: the bands are aligned
to the colour-matching functions' own sampling (1 nm) by ``MultiSpectralDistributions``'
interpolation (Sprague 1880, the fifth-order interpolation CIE 167:2005 recommends, for
regularly spaced bands; a cubic spline otherwise) and constant extrapolation beyond the
first and last band, then summed (``method="Integration"``). Interpolation, extrapolation
and the sum are all linear in the samples, so the whole path is one matrix ``W``
(``n_bands × 3``) with ``XYZ = spectrum @ W``. :func:`spectral_weights` finds ``W`` once
per (wavelengths, observer, illuminant, kind) by pushing the ``n_bands`` unit impulses
through that path in NumPy (float64, cached); :func:`spectral_to_xyz` applies it in JAX,
so it is differentiable and runs under jit/vmap, and a NaN band reaches its own pixel only.

The alignment is done in colour-science's two steps, interpolation onto the CMF samples
that lie between the first and last band, then extrapolation to the CMF range.
``align(cmfs.shape)`` is the same two steps when the first band lies on a CMF sample, but
keeps an off-grid start (403.7 nm) as its first sample, a domain that ``msds_to_XYZ``
cannot integrate (it raises a shape error); stepping onto the grid first is the result
colour-science would give if it could.

Spectral OpenEXR files (Fichet, Pacanowski & Wilkie 2021, "An OpenEXR layout for spectral
images", JCGT 10(3), http://jcgt.org/published/0010/03/01/) store emissive spectra as
``S0.<λ>nm`` channels and reflective ones as ``T.<λ>nm``; :func:`spectral_kind` tells
which a :class:`~hdrjax.layers.LayeredImage` read by :func:`hdrjax.io.read` holds.
"""

import functools
import re
import warnings
from collections.abc import Sequence
from typing import Any, Literal

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from . import _check
from ._scale import inverse_pow2, saturate_finite

K_M = 683.0
"""Maximum luminous efficacy of photopic vision, lm/W (CIE 015:2018; the SI candela's
``K_cd`` at 540 THz). The value of colour-science's ``colour.constants.CONSTANT_K_M``."""

DEFAULT_OBSERVER = "CIE 1931 2 Degree Standard Observer"
"""The colour-matching functions used unless another observer is named."""
DEFAULT_ILLUMINANT = "D65"
"""The illuminant of reflective images unless another is named."""

KINDS = ("emissive", "reflective")
"""What the channels hold: spectral radiance, or reflectance factors."""

# Short names for the two observers users mean most often; full colour-science names (and
# its own aliases, cie_2_1931 and cie_10_1964) are accepted as well, case and separators
# ignored.
_OBSERVER_ALIASES = {
    "1931": "CIE 1931 2 Degree Standard Observer",
    "cie1931": "CIE 1931 2 Degree Standard Observer",
    "1964": "CIE 1964 10 Degree Standard Observer",
    "cie1964": "CIE 1964 10 Degree Standard Observer",
}

_REFLECTIVE_CHANNEL = re.compile(r"^T\.\d+(?:[.,]\d+)?nm$")

IlluminantLike = Any
"""An illuminant name from ``colour.SDS_ILLUMINANTS`` (``"D65"``, ``"A"``, ``"FL2"``…) or a
``colour.SpectralDistribution``."""


def _observer_name(observer: str) -> str:
    if not isinstance(observer, str):
        raise ValueError(
            f"observer: expected a colour-science standard observer name, got {observer!r}"
        )
    key = _check.name_key(observer)
    if key in _OBSERVER_ALIASES:
        return _OBSERVER_ALIASES[key]
    from colour.colorimetry import MSDS_CMFS_STANDARD_OBSERVER  # slow import (~2 s)

    names = {_check.name_key(n): n for n in MSDS_CMFS_STANDARD_OBSERVER}
    if key not in names:
        raise ValueError(
            f"observer: unknown standard observer {observer!r}; expected '1931', '1964' or "
            "one of " + ", ".join(repr(n) for n in MSDS_CMFS_STANDARD_OBSERVER if " " in n)
        )
    # colour-science's aliases (cie_2_1931) map to the full name of the same data
    return MSDS_CMFS_STANDARD_OBSERVER[names[key]].name


def _illuminant_key(illuminant: IlluminantLike, kind: str) -> tuple | None:
    """A hashable description of the illuminant: ``None`` (emissive), ``("name", str)`` or
    ``("sd", wavelengths, values)``."""
    if kind == "emissive":
        if illuminant is not None:
            raise ValueError(
                "illuminant: an emissive image is its own light source; expected None for "
                f"kind='emissive', got {illuminant!r}"
            )
        return None
    if illuminant is None:
        illuminant = DEFAULT_ILLUMINANT
    if isinstance(illuminant, str):
        import colour

        names = {_check.name_key(n): n for n in colour.SDS_ILLUMINANTS}
        if _check.name_key(illuminant) not in names:
            raise ValueError(
                f"illuminant: unknown illuminant {illuminant!r}; expected a name from "
                "colour.SDS_ILLUMINANTS such as 'D65', 'D50', 'A', 'FL2', or a "
                "colour.SpectralDistribution"
            )
        return ("name", names[_check.name_key(illuminant)])
    domain = getattr(illuminant, "domain", None)
    values = getattr(illuminant, "values", None)
    if domain is None or values is None or np.ndim(values) != 1:
        raise ValueError(
            "illuminant: expected a name from colour.SDS_ILLUMINANTS or a "
            f"colour.SpectralDistribution, got {type(illuminant).__name__}"
        )
    return (
        "sd",
        tuple(float(v) for v in np.asarray(domain, np.float64)),
        tuple(float(v) for v in np.asarray(values, np.float64)),
    )


def _check_kind(kind: str) -> str:
    k = kind.strip().lower() if isinstance(kind, str) else None
    if k not in KINDS:
        raise ValueError(f"kind: expected 'emissive' or 'reflective', got {kind!r}")
    return k


def _wavelength_tuple(wavelengths: Any) -> tuple[float, ...]:
    """The band centres as Python floats, checked: 1-D, finite, strictly increasing."""
    if isinstance(wavelengths, jax.core.Tracer):
        raise ValueError(
            "wavelengths: expected concrete values in nm (a NumPy array or a sequence), got "
            "a traced JAX array; pass them from outside jax.jit"
        )
    try:
        wl = np.asarray(wavelengths, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(
            f"wavelengths: expected a 1-D array of nm, got {type(wavelengths).__name__}"
        ) from None
    if wl.ndim != 1 or wl.size == 0:
        raise ValueError(f"wavelengths: expected a non-empty 1-D array of nm, got shape {wl.shape}")
    if not np.all(np.isfinite(wl)):
        raise ValueError(f"wavelengths: expected finite values in nm, got {wl.tolist()}")
    step = np.diff(wl)
    if np.any(step <= 0):
        i = int(np.argmax(step <= 0))
        raise ValueError(
            "wavelengths: expected strictly increasing nm, got "
            f"{wl[i]:g} followed by {wl[i + 1]:g} (bands {i} and {i + 1})"
        )
    return tuple(float(v) for v in wl)


def _illuminant_sd(key: tuple) -> Any:
    import colour

    if key[0] == "name":
        return colour.SDS_ILLUMINANTS[key[1]]
    return colour.SpectralDistribution(np.array(key[2]), np.array(key[1]), name="illuminant")


@functools.lru_cache(maxsize=64)
def _weights(
    wavelengths: tuple[float, ...], observer: str, illuminant: tuple | None, kind: str
) -> np.ndarray:
    import colour
    from colour.utilities import is_uniform

    cmfs = colour.MSDS_CMFS[observer]
    grid = np.asarray(cmfs.wavelengths, np.float64)
    wl = np.asarray(wavelengths)
    inside = grid[(grid >= wl[0]) & (grid <= wl[-1])]
    lo, hi = float(grid[0]), float(grid[-1])
    if inside.size == 0:
        where = (
            "outside"
            if wl[-1] < lo or wl[0] > hi
            else f"between two {cmfs.shape.interval:g} nm samples of"
        )
        raise ValueError(
            f"wavelengths: expected bands spanning at least one sample of the {observer}'s "
            f"{lo:g}-{hi:g} nm range, got {wl[0]:g}-{wl[-1]:g} nm ({where} it)"
        )
    n = wl.size
    # colour-science interpolates regular bands with Sprague (1880), which needs 6 samples,
    # and irregular ones with SciPy's cubic spline, which needs 4
    if n < 4 or (n < 6 and is_uniform(wl)):
        raise ValueError(
            f"wavelengths: expected at least 6 regularly spaced bands (Sprague 1880 "
            f"interpolation, as colour-science) or 4 irregular ones (cubic spline), got {n}"
        )
    impulses = colour.MultiSpectralDistributions(np.eye(n), wl)
    with warnings.catch_warnings():
        # colour-science warns about every alignment it performs: here they are the point
        warnings.simplefilter("ignore")
        impulses.interpolate(colour.SpectralShape(inside[0], inside[-1], cmfs.shape.interval))
        impulses.extrapolate(cmfs.shape)
        if kind == "emissive":
            # With k given, colour-science divides by 100 ("absolute" values), which the
            # equal-energy illuminant E (S = 100) cancels: X = K_m Σ x̄ L Δλ.
            xyz = colour.msds_to_XYZ(
                impulses,
                cmfs,
                colour.SDS_ILLUMINANTS["E"],
                k=K_M,
                method="Integration",
            )
        else:
            xyz = (
                colour.msds_to_XYZ(impulses, cmfs, _illuminant_sd(illuminant), method="Integration")
                / 100.0
            )
    w = np.ascontiguousarray(np.asarray(xyz, np.float64).reshape(n, 3))
    w.setflags(write=False)
    return w


def spectral_weights(
    wavelengths: Float[ArrayLike, " n"],
    *,
    observer: str = DEFAULT_OBSERVER,
    illuminant: IlluminantLike = None,
    kind: Literal["emissive", "reflective"] = "emissive",
) -> Float[np.ndarray, "n 3"]:
    """The matrix ``W`` (``n_bands × 3``, float64) with ``XYZ = spectrum @ W``.

    ``W[i]`` is colour-science's XYZ of the unit impulse in band ``i`` (see the module
    doc): ``colour.msds_to_XYZ(..., method="Integration")`` after its own alignment to the
    observer's 1 nm sampling, in cd/m² per W/(sr·m²·nm) for emissive images, and divided
    by 100 (white ``Y = 1``) for reflective ones. Computed once per argument set (cached).

    Args:
        wavelengths: band centres in nm, strictly increasing (concrete values).
        observer: colour-science standard observer name
            (``"CIE 1931 2 Degree Standard Observer"``, ``"CIE 1964 10 Degree Standard
            Observer"``, the CIE 2015 ones), or ``"1931"`` / ``"1964"``; case and
            separators do not matter.
        illuminant: for ``kind="reflective"``: a ``colour.SDS_ILLUMINANTS`` name or a
            ``colour.SpectralDistribution``; ``None`` means D65. Must be ``None`` for
            emissive images.
        kind: ``"emissive"`` (radiance) or ``"reflective"`` (reflectance factors).

    Returns:
        A read-only float64 array of shape ``(n_bands, 3)``.

    Raises:
        ValueError: wavelengths not 1-D, not finite, not strictly increasing, not
            overlapping the observer's range, or too few for colour-science's
            interpolation; unknown observer, illuminant or kind; an illuminant for an
            emissive image.

    Example:
        >>> w = spectral_weights(np.arange(360.0, 831.0, 5.0), kind="reflective")
        >>> round(float(w[:, 1].sum()), 6)  # a perfect white reflector
        1.0
    """
    k = _check_kind(kind)
    return _weights(
        _wavelength_tuple(wavelengths), _observer_name(observer), _illuminant_key(illuminant, k), k
    )


def _matmul(x: Array, w: Array) -> Array:
    # HIGHEST: on GPUs the default float32 matmul rounds its inputs to TF32 (10-bit
    # mantissa), an error of ~1e-3 that would show in luminance
    return jnp.matmul(x, w, precision=jax.lax.Precision.HIGHEST)


@jax.jit
def _apply(x: Array, w: Array) -> Array:
    """``x @ w``; pixels near the float maximum whose products overflow to ±Inf of both
    signs (the weights have small negative lobes) would sum to NaN: where a finite pixel
    gives NaN, the image is integrated again with each pixel scaled into ``[0.5, 1)`` and
    scaled back (±Inf, which the caller saturates). The rescue runs only when needed
    (``lax.cond``)."""
    y = _matmul(x, w)
    finite = jnp.all(jnp.isfinite(x), axis=-1, keepdims=True)

    def rescued(y):
        f = inverse_pow2(jnp.max(jnp.where(finite, jnp.abs(x), 0.0), axis=-1, keepdims=True))
        return jnp.where(finite & jnp.isnan(y), _matmul(x * f, w) / f, y)

    return jax.lax.cond(jnp.any(finite & jnp.isnan(y)), rescued, lambda y: y, y)


def spectral_to_xyz(
    image: Float[ArrayLike, "*batch n"],
    wavelengths: Float[ArrayLike, " n"],
    *,
    observer: str = DEFAULT_OBSERVER,
    illuminant: IlluminantLike = None,
    kind: Literal["emissive", "reflective"] = "emissive",
) -> Float[Array, "*batch 3"]:
    """CIE XYZ of a spectral image (channels last) by colour-science's integration.

    Emissive images (spectral radiance, W/(sr·m²·nm)) give ``Y`` in cd/m²:
    ``Y = 683 lm/W × ∫ ȳ(λ) L_e,λ(λ) dλ`` (CIE 015:2018), so a flat 1 W/(sr·m²·nm) gives
    ``683 × Σ ȳ Δλ ≈ 72983 cd/m²`` with the CIE 1931 observer. Reflective images
    (reflectance factors, [0, 1]) give XYZ under ``illuminant`` with a perfect white
    reflector at ``Y = 1``. Both equal colour-science's ``msds_to_XYZ(...,
    method="Integration")`` after its alignment of the bands to the observer's 1 nm
    sampling, including its constant extrapolation beyond the first and last band (a
    400–700 nm image is taken to continue at its end values to 360 and 830 nm).

    The weights are computed once in NumPy (:func:`spectral_weights`) and applied as one
    matrix product: differentiable, runs under jit/vmap (``wavelengths`` must then come
    from outside the traced function); a NaN band makes its own pixel NaN only. float16
    and integer input is computed in float32 (float64 with x64).

    Args:
        image: spectral image ``(..., n_bands)``, e.g. ``(H, W, n_bands)``.
        wavelengths: the bands' centres in nm, strictly increasing, ``n_bands`` of them.
        observer: standard observer (see :func:`spectral_weights`); default CIE 1931 2°.
        illuminant: reflective images only: a ``colour.SDS_ILLUMINANTS`` name or a
            ``colour.SpectralDistribution``; ``None`` means D65.
        kind: ``"emissive"`` or ``"reflective"``.

    Returns:
        XYZ ``(..., 3)``: cd/m² (emissive) or relative to a perfect white, ``Y = 1``
        (reflective).

    Raises:
        ValueError: bad wavelengths (see :func:`spectral_weights`), or a channel count
            that differs from the number of wavelengths.

    Example:
        >>> xyz = spectral_to_xyz(np.ones((1, 1, 31)), np.arange(400, 701, 10.0))
        >>> round(float(xyz[0, 0, 1]))  # cd/m² of 1 W/(sr·m²·nm), extrapolated 360-830 nm
        72983
    """
    _check.real(image, "image")
    shape = tuple(int(s) for s in np.shape(image))
    w = spectral_weights(wavelengths, observer=observer, illuminant=illuminant, kind=kind)
    if len(shape) < 1 or shape[-1] != w.shape[0]:
        raise ValueError(
            f"image: expected shape (..., {w.shape[0]}) with one channel per wavelength "
            f"({w.shape[0]} wavelengths given), got shape {shape}"
        )
    x = _check.as_float(image)
    return saturate_finite(_apply(x, jnp.asarray(w, x.dtype)), x)


def spectral_kind(channels: Sequence[str]) -> Literal["emissive", "reflective"]:
    """Whether a spectral image read from a file holds radiance or reflectance.

    Fichet et al. 2021's OpenEXR layout names reflective bands ``T.<λ>nm`` and emissive
    ones ``S0.<λ>nm``; :func:`hdrjax.io.read` keeps the ``T.`` prefix in the channel names
    of a reflective image (``LayeredImage.channels``) and drops ``S0.``.

    Returns:
        ``"reflective"`` when every channel is named ``T.<λ>nm``, else ``"emissive"``.
    """
    names = list(channels)
    if names and all(isinstance(c, str) and _REFLECTIVE_CHANNEL.match(c) for c in names):
        return "reflective"
    return "emissive"


__all__ = [
    "DEFAULT_ILLUMINANT",
    "DEFAULT_OBSERVER",
    "K_M",
    "KINDS",
    "spectral_kind",
    "spectral_to_xyz",
    "spectral_weights",
]
