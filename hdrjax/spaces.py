"""Working spaces: linear RGB converted between primaries and white points.

Every image is converted on reading into one *working space* (linear sRGB/BT.709 primaries
with a D65 white by default), so operators, false colour and measurements see the same
colours whatever the file stored. A space is named as in colour-science
(``colour.RGB_COLOURSPACES``: ``"sRGB"``, ``"ACEScg"``, ``"ACES2065-1"``,
``"ITU-R BT.2020"``, ``"Display P3"``…; case and separators do not matter), ``"CIE XYZ"``,
or given as OpenEXR's ``chromaticities`` 8-tuple ``(x_r, y_r, x_g, y_g, x_b, y_b, x_w, y_w)``.

The conversion is colour-science's ``RGB_to_RGB``: source RGB → XYZ (SMPTE RP 177
normalised primary matrix), chromatic adaptation from the source white to the target
white (von Kries form, CAT02 by default: Moroney et al. 2002, "The CIECAM02 color
appearance model", IS&T/SID CIC 10), XYZ → target RGB. ``"CIE XYZ"`` is colorimetric XYZ
of the source (no adaptation). Matrices are computed once in NumPy (float64) and applied in
JAX, so the conversion is differentiable and runs under jit/vmap; its transfer function is
linear (no encoding).

Luminance stays photometric: :func:`luminance_weights_in` gives the weights that, applied
to the converted pixels, return the Y of the file's own primaries. Those are the working
space's own weights when the two whites agree; across whites a von Kries transform moves
Y by up to a few per cent for saturated colours (CAT02 from E to D65: Y row
``(-0.029, 1.019, 0.010)``), and the adjusted weights undo exactly that.
"""

import dataclasses
import functools
from collections.abc import Sequence

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from . import _check
from ._colour import REC709_CHROMATICITIES, apply_matrix, normalised_primary_matrix
from ._scale import saturate_finite

DEFAULT_SPACE = "sRGB"
"""The default working space: linear sRGB/ITU-R BT.709 primaries, D65 white."""
XYZ_SPACE = "CIE XYZ"
DEFAULT_CAT = "CAT02"
XYZ_CHROMATICITIES: tuple[float, ...] = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0 / 3.0, 1.0 / 3.0)
"""Chromaticities of CIE XYZ stored as RGB (OpenEXR's convention: white E)."""

SpaceLike = str | Sequence[float] | None


@dataclasses.dataclass(frozen=True)
class Space:
    """A linear RGB space.

    Attributes:
        name: colour-science's name (``"sRGB"``), ``"CIE XYZ"``, or ``"file"`` for
            primaries given as numbers.
        chromaticities: ``(x_r, y_r, x_g, y_g, x_b, y_b, x_w, y_w)``.
        to_xyz: the RGB→XYZ matrix (float64, 3×3); for named spaces colour-science's own
            (sRGB: the IEC 61966-2-1 rounded matrix, whose Y row is BT.709's weights).
        from_xyz: the XYZ→RGB matrix: colour-science's for named spaces (for sRGB the
            standard's own rounded inverse, as colour-science), else the inverse of
            :attr:`to_xyz`.
    """

    name: str
    chromaticities: tuple[float, ...]
    to_xyz: np.ndarray = dataclasses.field(compare=False, repr=False)
    from_xyz: np.ndarray = dataclasses.field(compare=False, repr=False)

    @property
    def is_xyz(self) -> bool:
        """Whether this is CIE XYZ itself (converted to without adaptation)."""
        return self.name == XYZ_SPACE

    @property
    def white(self) -> tuple[float, float]:
        """The white point's CIE 1931 xy."""
        return (self.chromaticities[6], self.chromaticities[7])

    @property
    def weights(self) -> tuple[float, float, float]:
        """Luminance weights: the Y row of :attr:`to_xyz`."""
        return (float(self.to_xyz[1, 0]), float(self.to_xyz[1, 1]), float(self.to_xyz[1, 2]))

    @property
    def is_rec709(self) -> bool:
        """Whether the primaries and white are Rec.709/sRGB with D65 (to 1e-4)."""
        return _is_rec709(self.chromaticities)


def _is_rec709(c: Sequence[float]) -> bool:
    return bool(np.allclose(c, REC709_CHROMATICITIES, atol=1e-4))


SRGB_FROM_XYZ = (
    (3.2406, -1.5372, -0.4986),
    (-0.9689, 1.8758, 0.0415),
    (0.0557, -0.2040, 1.0570),
)
"""XYZ→sRGB matrix of IEC 61966-2-1:1999 (5.2), as the standard rounds it."""


@functools.cache
def _srgb() -> Space:
    # IEC 61966-2-1 gives the matrix to 4 decimals (its Y row: BT.709's weights), and
    # colour-science uses those figures: built here without importing colour (~2 s)
    m = np.round(normalised_primary_matrix(REC709_CHROMATICITIES), 4)
    return Space("sRGB", REC709_CHROMATICITIES, m, np.array(SRGB_FROM_XYZ))


@functools.lru_cache(maxsize=64)
def _named(key: str) -> Space:
    if key in ("srgb", "itu709", "iturbt709", "rec709", "linearrec709srgb"):
        return _srgb()
    if key in ("ciexyz", "xyz"):
        return Space(XYZ_SPACE, XYZ_CHROMATICITIES, np.eye(3), np.eye(3))
    import colour  # slow import (~2 s): only for spaces other than sRGB

    names = {_check.name_key(n): n for n in colour.RGB_COLOURSPACES}
    if key not in names:
        raise ValueError(
            f"working space: unknown name {key!r}; expected 'CIE XYZ' or a colour-science "
            "RGB colourspace such as 'sRGB', 'ACEScg', 'ACES2065-1', 'ITU-R BT.2020', "
            "'Display P3'"
        )
    cs = colour.RGB_COLOURSPACES[names[key]]
    c = tuple(float(v) for v in [*np.ravel(cs.primaries), *np.ravel(cs.whitepoint)])
    to_xyz = np.asarray(cs.matrix_RGB_to_XYZ, np.float64)
    return Space(cs.name, c, to_xyz, np.asarray(cs.matrix_XYZ_to_RGB, np.float64))


@functools.lru_cache(maxsize=64)
def _from_numbers(c: tuple[float, ...]) -> Space:
    if _is_rec709(c):
        return _srgb()
    if np.allclose(c, XYZ_CHROMATICITIES, atol=1e-6):
        return _named("ciexyz")
    try:
        with np.errstate(all="raise"):
            m = normalised_primary_matrix(c)
            np.linalg.inv(m)
    except (np.linalg.LinAlgError, FloatingPointError) as e:
        raise ValueError(f"chromaticities {list(c)} are degenerate: {e}") from None
    return Space("file", c, m, np.linalg.inv(m))


def space(value: SpaceLike = None) -> Space:
    """The :class:`Space` a name or chromaticities denote (``None``: sRGB).

    Raises:
        ValueError: an unknown name (the message lists examples), or chromaticities that
            are not 8 finite numbers or are degenerate.
    """
    if value is None:
        return _srgb()
    if isinstance(value, Space):
        return value
    if isinstance(value, str):
        return _named(_check.name_key(value))
    c = np.asarray(value, dtype=np.float64).reshape(-1)
    if c.shape != (8,) or not np.all(np.isfinite(c)):
        raise ValueError(
            f"chromaticities: expected 8 finite numbers (xr, yr, xg, yg, xb, yb, xw, yw), got "
            f"{np.asarray(value).tolist()!r}"
        )
    return _from_numbers(tuple(float(v) for v in c))


def check_cat(cat: str) -> str:
    """colour-science's name of a chromatic adaptation transform (case and separators do
    not matter). Raises ValueError naming the known ones."""
    if _check.name_key(cat) == "cat02":
        return DEFAULT_CAT
    import colour

    names = {_check.name_key(n): n for n in colour.CHROMATIC_ADAPTATION_TRANSFORMS}
    if _check.name_key(cat) not in names:
        raise ValueError(
            f"cat: unknown chromatic adaptation transform {cat!r}; expected one of "
            + ", ".join(sorted(colour.CHROMATIC_ADAPTATION_TRANSFORMS))
        )
    return names[_check.name_key(cat)]


@functools.lru_cache(maxsize=128)
def _matrix(source: Space, target: Space, cat: str) -> np.ndarray:
    if source == target:
        return np.eye(3)
    xyz = source.to_xyz
    # XYZ is colorimetric: its "white" E is the convention of XYZ stored as RGB, not the
    # white the scene was adapted to, so conversions from or to XYZ do not adapt
    if not (source.is_xyz or target.is_xyz):
        if not np.allclose(source.white, target.white, atol=1e-6):
            from colour.adaptation import matrix_chromatic_adaptation_VonKries

            def white(s: Space) -> np.ndarray:
                x, y = s.white
                return np.array([x / y, 1.0, (1.0 - x - y) / y])

            xyz = matrix_chromatic_adaptation_VonKries(white(source), white(target), cat) @ xyz
    return target.from_xyz @ xyz


def conversion_matrix(
    source: SpaceLike, target: SpaceLike = DEFAULT_SPACE, *, cat: str = DEFAULT_CAT
) -> np.ndarray:
    """The 3×3 matrix (float64) taking linear RGB in ``source`` to ``target``.

    Args:
        source: the file's space: a name, chromaticities, or ``None`` for sRGB.
        target: the working space (default ``"sRGB"``).
        cat: chromatic adaptation transform between different whites, one of
            colour-science's ``CHROMATIC_ADAPTATION_TRANSFORMS`` (``"CAT02"``,
            ``"Bradford"``, ``"CAT16"``, ``"XYZ Scaling"``…). Not applied when either side
            is ``"CIE XYZ"`` (colorimetric XYZ).

    Returns:
        ``M`` with ``rgb_target = M @ rgb_source``; the identity when the spaces agree.

    Raises:
        ValueError: unknown space or transform, or degenerate chromaticities.
    """
    return _matrix(space(source), space(target), check_cat(cat)).copy()


def is_identity(matrix: np.ndarray) -> bool:
    """Whether a conversion matrix is the identity to float32 rounding (no work to do)."""
    return bool(np.allclose(matrix, np.eye(3), rtol=0.0, atol=1e-7))


def luminance_weights_in(
    source: SpaceLike, target: SpaceLike = DEFAULT_SPACE, *, cat: str = DEFAULT_CAT
) -> tuple[float, float, float]:
    """Weights that give, from pixels converted to ``target``, the Y of ``source``.

    ``w_target = w_source M⁻¹`` with ``M`` = :func:`conversion_matrix`: luminance is
    photometric (the file's own Y) before and after conversion. Equal to the target's own
    weights (to 1e-6) when the whites agree.
    """
    m = conversion_matrix(source, target, cat=cat)
    w = np.asarray(space(source).weights) @ np.linalg.inv(m)
    if np.allclose(w, space(target).weights, rtol=0.0, atol=1e-6):
        w = np.asarray(space(target).weights)
    return (float(w[0]), float(w[1]), float(w[2]))


def convert(
    rgb: Float[ArrayLike, "*batch 3"], matrix: Float[ArrayLike, "3 3"], *, saturate: bool = True
) -> Float[Array, "*batch 3"]:
    """Apply a conversion matrix to linear RGB, channels last: ``rgb @ matrix.T``.

    Differentiable; runs under jit/vmap; float16 input is computed in float32. A NaN or
    Inf channel reaches the other channels of its own pixel only. Finite pixels stay
    finite: results beyond the dtype's range (inputs within a factor ~4 of its largest
    value) saturate at ± that value (``saturate=False`` skips that check, for callers whose
    values are known to be small).
    """
    x = _check.rgb_pixels(rgb)
    m = jnp.asarray(matrix, x.dtype)
    if m.shape != (3, 3):
        raise ValueError(f"matrix: expected a 3×3 matrix, got shape {m.shape}")
    y = apply_matrix(x, m)
    return saturate_finite(y, x) if saturate else y


def convert_to(
    rgb: Float[ArrayLike, "*batch 3"],
    source: SpaceLike,
    target: SpaceLike = DEFAULT_SPACE,
    *,
    cat: str = DEFAULT_CAT,
) -> Float[Array, "*batch 3"]:
    """Linear RGB in ``source`` converted to ``target`` (:func:`conversion_matrix`)."""
    return convert(rgb, conversion_matrix(source, target, cat=cat))


__all__ = [
    "DEFAULT_CAT",
    "DEFAULT_SPACE",
    "Space",
    "XYZ_CHROMATICITIES",
    "XYZ_SPACE",
    "check_cat",
    "conversion_matrix",
    "convert",
    "convert_to",
    "is_identity",
    "luminance_weights_in",
    "space",
]
