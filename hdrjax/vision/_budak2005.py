"""Perceptual colour-contrast reproduction after Budak & Petrovichev (Světlo 3/2005, seed 002).

The seed's algorithm (its Fig. 1): convert the rendered scene to a *uniform colour-contrast
system* whose brightness follows the Weber–Fechner law relative to the adaptation
luminance; re-adapt from the scene's adaptation luminance to the display's, which the seed
sets to half the display's maximum; convert back; apply gamma correction (the seed's
Eqs. 5–6, ``L = C0 i^g``, signal raised to ``1/g``).

What is *not* available, and what replaces it (formulas.md §4 — searched, not found):

- The seed's colour system (Belyaeva–Matveev ``n_č, n_z, n_m`` over the Nyberg–Yustova
  physiological RGB, its Eq. 1 with exponents n = 0.9/0.7, p = 0.6/1.0 for pixels brighter/
  darker than the background) — the equation itself, the Yustova primaries and the
  placement of n and p are unpublished in any source found. Replaced by
  :class:`ConeOpponentSpace`: CIELAB's opponent formulas (CIE 15:2004,
  ``a = 500 (f(·) - f(Y/Y_n))``, ``b = 200 (f(Y/Y_n) - f(·))``, ``f`` the cube root with
  its linear toe) applied to Hunt–Pointer–Estévez cone responses (colour-science
  ``MATRIX_XYZ_TO_HPE``): ``a`` compares the L cone with luminance, ``b`` luminance with
  the S cone (HPE's S is CIE Z, so ``b`` is CIELAB's b*), each relative to the background
  (the mean chromaticity of the image at the adaptation luminance, the seed's ``m'_p``).
  No increment/decrement asymmetry (the seed's n, p) is modelled.
- Shklover's brightness formula (the seed's Eq. 3) — not found. Replaced by Fechner's
  integral of Weber's law with the adaptation-dependent Weber fraction of the Ferwerda/pcond
  threshold curve, ``B = (L_a/ΔL(L_a)) ln(L/L_a)`` (:func:`fechner_brightness`): brightness
  in just-noticeable differences from the adaptation level, one JND = ``ΔL(L_a)`` at
  ``L = L_a`` (formulas.md §4's recommended equivalent).
- The seed's PSF step (acuity loss before display) is :mod:`hdrjax.vision`'s ``acuity``
  effect; apply :func:`hdrjax.vision.simulate` first to include it.

Keeping ``B`` fixed while re-adapting gives ``L_d = L_da (L/L_a)^(k_d/k_w)`` with
``k = ΔL/L_a`` the Weber fractions: a dark scene (large ``k_w``) is compressed, a daylight
one roughly kept. Values beyond the display's maximum clip; colours outside its gamut clip.
The colour space is pluggable: subclass :class:`AbstractContrastSpace` (e.g. with the
Nyberg–Yustova system once its coefficients are available) and pass it as ``space``.
"""

import abc
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._colour import luminance
from .._scale import quotient
from ..display import gamma_encode
from ._fovea import adaptation_luminance
from ._pcond import tvi
from ._photometry import LMIN, check_rgb, chroma_key, sanitize, xyz_matrices

HPE = (
    (0.38971, 0.68898, -0.07868),
    (-0.22981, 1.18340, 0.04641),
    (0.0, 0.0, 1.0),
)
"""XYZ → Hunt–Pointer–Estévez LMS (colour-science ``colour/appearance/hunt.py``)."""

_D = 6.0 / 29.0


def _f(t: Array) -> Array:
    """CIELAB's ``f``: cube root above (6/29)³, linear below (defined for any real ``t``)."""
    big = t > _D**3
    return jnp.where(big, jnp.cbrt(jnp.where(big, t, 1.0)), t / (3 * _D**2) + 4.0 / 29.0)


def _f_ratio(num: Array, den: Array) -> Array:
    """``_f(num / den)`` for ``den > 0``; where the quotient overflows (a pixel near the
    float maximum over a dim background), ``cbrt(num) / cbrt(den)`` (the same value,
    representable) — chosen before the root, so that neither branch's derivative is 0·∞."""
    q = num / den
    big = ~jnp.isfinite(jax.lax.stop_gradient(q)) & (num > 0)
    root = jnp.cbrt(jnp.where(big, num, 1.0)) / jnp.cbrt(den)
    return jnp.where(big, root, _f(jnp.where(big, 1.0, num) / den))


def _finv_scaled(u: Array, n: Array) -> Array:
    """``n · _finv(u)`` for ``n > 0``, with ``|u|`` capped so that it stays below
    :data:`SATURATION` of the float maximum (values beyond it saturate there)."""
    top = jnp.finfo(u.dtype).max * SATURATION
    cap = jax.lax.stop_gradient(jnp.cbrt(top) / jnp.cbrt(jnp.maximum(n, 1.0)))
    return n * _finv(jnp.clip(u, -cap, cap))


SATURATION = 2.0**-6
"""Fraction of the float maximum at which the re-adapted luminance and cone responses
saturate: the display RGB computed from them (inverse colour matrix, rows up to 5 in
absolute sum) then stays finite. Reached only by scene values within a factor of about
100 of the float maximum, or far above the display's adaptation."""


def _finv(u: Array) -> Array:
    return jnp.where(u > _D, u**3, 3 * _D**2 * (u - 4.0 / 29.0))


def fechner_brightness(
    L: Float[ArrayLike, "*shape"], L_a: Float[ArrayLike, ""]
) -> Float[Array, "*shape"]:
    """Brightness in JNDs from the adaptation level: ``B = (L_a/ΔL(L_a)) ln(L/L_a)``.

    ``ΔL`` is pcond's combined TVI (:func:`hdrjax.vision.tvi`); ``L`` and ``L_a`` in cd/m²,
    clamped below at 1e-7 cd/m². Stands in for Shklover's formula (seed 002, Eq. 3; not
    found). Inverse: :func:`fechner_luminance`.
    """
    _check.real(L, "L")
    L = jnp.maximum(_check.as_float(L), LMIN)
    L_a = jnp.maximum(_check.as_float(L_a), LMIN)
    # L / L_a overflows for L near the float maximum and a dim L_a: ln L − ln L_a there
    # (where-before-log, so that neither branch's derivative is 0·∞)
    big = ~jnp.isfinite(jax.lax.stop_gradient(L / L_a))
    ln = jnp.where(big, jnp.log(L) - jnp.log(L_a), jnp.log(jnp.where(big, L_a, L) / L_a))
    return (L_a / tvi(L_a)) * ln


def fechner_luminance(
    B: Float[ArrayLike, "*shape"], L_a: Float[ArrayLike, ""]
) -> Float[Array, "*shape"]:
    """Inverse of :func:`fechner_brightness`: ``L = L_a exp(B ΔL(L_a)/L_a)``."""
    _check.real(B, "B")
    L_a = jnp.maximum(_check.as_float(L_a), LMIN)
    arg = _check.as_float(B) * tvi(L_a) / L_a
    # saturates at SATURATION × the float maximum (+Inf, and NaN colours, before)
    top = jnp.log(jnp.finfo(arg.dtype).max * SATURATION)
    return L_a * jnp.exp(jnp.minimum(arg, top - jnp.maximum(jnp.log(L_a), 0.0)))


class AbstractContrastSpace(eqx.Module):
    """A colour-contrast space relative to a background at an adaptation luminance.

    ``forward`` maps XYZ (cd/m²) to three coordinates that the observer keeps constant when
    re-adapting; ``inverse`` maps them back at another adaptation. ``background`` is the
    XYZ of the adapting background (its Y is the adaptation luminance).
    """

    @abc.abstractmethod
    def forward(
        self, xyz: tuple[Array, Array, Array], background: tuple[Array, Array, Array]
    ) -> Float[Array, "*batch 3"]:
        """Coordinates ``(..., 3)`` of XYZ relative to the background."""

    @abc.abstractmethod
    def inverse(
        self, coords: Float[Array, "*batch 3"], background: tuple[Array, Array, Array]
    ) -> tuple[Array, Array, Array]:
        """XYZ (cd/m²) of coordinates relative to (another) background."""


class ConeOpponentSpace(AbstractContrastSpace):
    """Fechner brightness + CIELAB-style cone-opponent coordinates (module docstring).

    Coordinates ``(B, a, b)``: ``B`` = :func:`fechner_brightness` of Y at the background's
    luminance; ``a = 500 (f(Lc/Lc_n) - f(Y/Y_n))``; ``b = 200 (f(Y/Y_n) - f(Sc/Sc_n))`` with
    ``Lc``, ``Sc`` the first and third rows of ``cone_matrix`` (HPE by default) applied to
    XYZ and ``_n`` the background's values.

    Attributes:
        cone_matrix: XYZ → cone responses (3×3, row-major); rows 1 and 3 are used.
    """

    cone_matrix: tuple[tuple[float, float, float], ...] = eqx.field(static=True, default=HPE)

    def _cones(self, X: Array, Y: Array, Z: Array) -> tuple[Array, Array]:
        m = self.cone_matrix
        return (
            m[0][0] * X + m[0][1] * Y + m[0][2] * Z,
            m[2][0] * X + m[2][1] * Y + m[2][2] * Z,
        )

    def forward(self, xyz, background):
        X, Y, Z = xyz
        Lb, Sb = self._cones(*background)
        Yb = background[1]
        Lc, Sc = self._cones(X, Y, Z)
        fy = _f_ratio(Y, Yb)
        a = 500.0 * (_f_ratio(Lc, Lb) - fy)
        b = 200.0 * (fy - _f_ratio(Sc, Sb))
        return jnp.stack([fechner_brightness(Y, Yb), a, b], axis=-1)

    def inverse(self, coords, background):
        B, a, b = coords[..., 0], coords[..., 1], coords[..., 2]
        Lb, Sb = self._cones(*background)
        Yb = background[1]
        Y = fechner_luminance(B, Yb)
        fy = _f_ratio(Y, Yb)
        Lc = _finv_scaled(fy + a / 500.0, Lb)
        Sc = _finv_scaled(fy - b / 200.0, Sb)
        m = self.cone_matrix  # solve the L and S rows for X and Z given Y
        r1 = Lc - m[0][1] * Y
        r2 = Sc - m[2][1] * Y
        det = m[0][0] * m[2][2] - m[0][2] * m[2][0]
        X = (r1 * m[2][2] - m[0][2] * r2) / det
        Z = (m[0][0] * r2 - m[2][0] * r1) / det
        return X, Y, Z


class Budak2005(eqx.Module):
    """Seed 002's perceptual colour-contrast reproduction as a display step.

    ``__call__`` takes linear RGB in cd/m² and returns gamma-encoded display values in
    [0, 1]: coordinates in ``space`` relative to the scene background at ``adaptation``,
    inverse at the display background ``display_max/2`` (same chromaticity), division by
    ``display_max``, then :func:`hdrjax.display.gamma_encode` (clip to [0, 1], power
    ``1/gamma``).

    Attributes:
        display_max: the display's maximum luminance, cd/m².
        gamma: display gamma (the seed's ``g``; it gives no value — 2.2 is the nominal
            display gamma of IEC 61966-2-1, sRGB).
        adaptation: scene adaptation luminance, cd/m² (``None``: ``exp(mean ln L)`` over
            the pixels inside 1e-7–1e5 cd/m²; the seed notes that the definition matters
            little).
        space: the colour-contrast space (default :class:`ConeOpponentSpace`).
        chromaticities: the image's primaries (display primaries are taken equal).
    """

    display_max: float = eqx.field(static=True, default=100.0)
    gamma: float = eqx.field(static=True, default=2.2)
    adaptation: Array | None = None
    space: AbstractContrastSpace = ConeOpponentSpace()
    chromaticities: tuple[float, ...] | None = eqx.field(static=True, default=None)

    def __check_init__(self):
        if not (0 < self.display_max < float("inf")):
            raise ValueError(f"display_max: expected a luminance > 0, got {self.display_max!r}")
        if not (0 < self.gamma < float("inf")):
            raise ValueError(f"gamma: expected a number > 0, got {self.gamma!r}")

    def readapt(self, rgb: Float[ArrayLike, "H W 3"]) -> Float[Array, "H W 3"]:
        """Linear display RGB in cd/m² (before clipping and gamma)."""
        return _readapt(self, check_rgb(rgb, pooled=True))

    def __call__(self, rgb: Float[ArrayLike, "H W 3"]) -> Float[Array, "H W 3"]:
        """Display values in [0, 1]: :func:`hdrjax.display.gamma_encode` of the re-adapted
        image over ``display_max`` (it clips to [0, 1] and encodes NaN as 0)."""
        return _display(self, check_rgb(rgb, pooled=True))

    def _readapt(self, rgb: Array) -> Array:
        x, ok = sanitize(rgb)
        m, minv = xyz_matrices(chroma_key(self.chromaticities))
        X = x[..., 0] * m[0, 0] + x[..., 1] * m[0, 1] + x[..., 2] * m[0, 2]
        Y = luminance(x, tuple(m[1]))
        Z = x[..., 0] * m[2, 0] + x[..., 1] * m[2, 1] + x[..., 2] * m[2, 2]
        if self.adaptation is None:
            La = adaptation_luminance(jnp.where(ok, Y, jnp.nan).reshape(-1, 1), (1, 1))
        else:
            La = jnp.maximum(_check.as_float(self.adaptation), LMIN).astype(Y.dtype)
        # background chromaticity: mean XYZ of the finite pixels (the seed's m'_p)
        # (only their ratios are used: summed times 2^-k, k = ceil(log2 of the pixel
        # count), so that the sums cannot overflow, exact for pixels above 2^-100 cd/m²;
        # quotient, whose derivative has no mY²: NaN gradients at every pixel before)
        n = jnp.maximum(jnp.sum(ok), 1)
        k = np.ldexp(1.0, -int(np.ceil(np.log2(max(ok.size, 1)))))
        mX, mY, mZ = (jnp.sum(jnp.where(ok, c * k, 0.0)) / n for c in (X, Y, Z))
        good = (mY > 0) & (mX > 0) & (mZ > 0)
        wX, wZ = float(m[0].sum()), float(m[2].sum())  # white of the primaries, Y = 1
        rX = jnp.where(good, quotient(mX, jnp.where(good, mY, 1.0)), wX)
        rZ = jnp.where(good, quotient(mZ, jnp.where(good, mY, 1.0)), wZ)
        coords = self.space.forward((X, Y, Z), (rX * La, La, rZ * La))
        Lda = 0.5 * self.display_max
        Xd, Yd, Zd = self.space.inverse(coords, (rX * Lda, jnp.asarray(Lda, Y.dtype), rZ * Lda))
        out = jnp.stack(
            [Xd * minv[i, 0] + Yd * minv[i, 1] + Zd * minv[i, 2] for i in range(3)], axis=-1
        )
        return jnp.where(ok[..., None], out, rgb)


@eqx.filter_jit
def _readapt(step: Budak2005, rgb: Array) -> Array:
    return step._readapt(rgb)


@eqx.filter_jit
def _display(step: Budak2005, rgb: Array) -> Array:
    return gamma_encode(step._readapt(rgb) / step.display_max, step.gamma)


def perceptual_reproduction(
    rgb: Float[ArrayLike, "H W 3"],
    *,
    display_max: float = 100.0,
    gamma: float = 2.2,
    adaptation: float | None = None,
    space: AbstractContrastSpace | None = None,
    chromaticities: Sequence[float] | None = None,
) -> Float[Array, "H W 3"]:
    """Functional form of :class:`Budak2005`: display values in [0, 1] (gamma-encoded)."""
    return Budak2005(
        display_max=float(display_max),
        gamma=float(gamma),
        adaptation=None if adaptation is None else jnp.asarray(adaptation),
        space=ConeOpponentSpace() if space is None else space,
        chromaticities=chroma_key(chromaticities),
    )(rgb)


__all__ = [
    "HPE",
    "AbstractContrastSpace",
    "Budak2005",
    "ConeOpponentSpace",
    "fechner_brightness",
    "fechner_luminance",
    "perceptual_reproduction",
]
