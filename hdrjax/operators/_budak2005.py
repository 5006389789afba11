"""Perceptual colour-contrast reproduction after Budak & Petrovichev (2005), an operator.

V. P. Budak and A. V. Petrovičev, "Realistické modelování zobrazení osvětlení 3D scén na
stínítku počítače" (realistic modelling of the display of lit 3D scenes on a computer
screen), Světlo 3/2005. The algorithm (the paper's Fig. 1): convert the rendered scene
to a *uniform colour-contrast system* whose brightness follows the Weber–Fechner law
(its Eqs. 1 and 3); convert back with the display's adaptation luminance, which the paper
sets to half the display's maximum (its Eq. 2). Display gamma is the output encoding's
(:mod:`hdrjax.display`; :class:`hdrjax.vision.Budak2005` applies the paper's power law
``L = C0 i^g``, its Eqs. 5–6, itself).

What is *not* available, and what replaces it:

- The paper's colour system (Belyaeva–Matveev ``n_č, n_z, n_m`` over the Nyberg–Yustova
  physiological RGB, its Eq. 1 with exponents n = 0.9/0.7, p = 0.6/1.0 for pixels brighter/
  darker than the background) — the equation itself, the Yustova primaries and the
  placement of n and p are unpublished in any source found. Replaced by
  :class:`ConeOpponentSpace`: CIELAB's opponent formulas (CIE 15:2004,
  ``a* = 500 (f(·) - f(Y/Y_n))``, ``b* = 200 (f(Y/Y_n) - f(·))``, ``f`` the cube root with
  its linear toe) applied to Hunt–Pointer–Estévez cone responses (colour-science
  ``MATRIX_XYZ_TO_HPE``) relative to the background (the mean chromaticity of the image at
  the adaptation luminance, the paper's ``m'_p``), *divided by the pixel's own*
  ``f(Y/Y_n)``: a contrast of chromaticities, as the paper's Eq. 1 relates trichromatic
  coordinates ``m'_o/m'_p``, rather than CIELAB's chroma, which grows with lightness. Kept
  while brightness is compressed, CIELAB's chroma would be a larger share of a compressed
  pixel's lightness: in a 10 cd/m² interior a near-white window at 1e5 cd/m² came out four
  times as saturated as it is, and blue glass left the display's gamut (a negative red,
  clipped: cyan). Scaled by the share of colour vision at the adaptation luminance
  (pcond's mesopic weight, 0 at or below 5.62e-3 cd/m², 1 at or above 5.62 cd/m²): a
  starlit scene is seen without colour. No increment/decrement asymmetry (the paper's
  n, p) is modelled.
- Shklover's brightness formula (the paper's Eq. 3) — not found. Replaced by Fechner's
  law, brightness counted in just-noticeable differences above the threshold, with the
  adaptation-dependent threshold ``ΔL(L_a)`` of the Ferwerda et al. 1996 curve as Radiance's
  pcond evaluates it: ``B = (L_a/ΔL(L_a)) ln(L/ΔL(L_a))`` (:func:`fechner_brightness`). The
  threshold is the zero of brightness, as in Fechner's law, so that ``B`` of the adaptation
  level itself grows with it: counted from the adaptation level instead, every scene's
  adaptation level had brightness 0 and was shown at half the display's maximum, a
  starlit street as bright as a sunlit one.
- The paper's PSF step (acuity loss before display) is :mod:`hdrjax.vision`'s ``acuity``
  effect; apply :func:`hdrjax.vision.simulate` first to include it.

Keeping ``B`` fixed while re-adapting gives ``L_d = ΔL_d (L/ΔL_w)^(k_d/k_w)`` with
``ΔL_w = ΔL(L_a)``, ``ΔL_d = ΔL(L_da)``, ``L_da`` the display's adaptation (half its
maximum) and ``k = ΔL/L_a`` the Weber fractions: a scene dimmer than ``L_da`` (larger
``k_w``) is compressed towards the display's threshold, dim and flat (a starlit scene's
adaptation level, below its own threshold, lies below ``ΔL_d`` = 3.1 cd/m² on a
100 cd/m² display). A scene adapted above ``L_da`` would have more JNDs above threshold
than the display's adaptation level; it is shown as in the paper, whose inverse
transform (Eq. 2) puts the scene's background at the display's: ``B`` is lowered by the
excess, which gives
``L_d = L_da (L/L_a)^(k_d/k_w)``. The two meet at ``L_a = L_da``. Chromaticity is kept
where both the scene and the display value lie in the cube-root part (from about 2 decades
below their backgrounds up), up to the mesopic factor. A colour beyond the display's white
(a channel above ``display_max``) is moved towards the white of its own luminance until it
fits, and a luminance above ``display_max`` is white: a window far brighter than the
display fades to white at its own hue (the paper: the brightest parts' colour scale is
adjusted) instead of being clipped per channel to another hue. The colour space is
pluggable: subclass :class:`AbstractContrastSpace` (e.g. with the Nyberg–Yustova system
once its coefficients are available) and pass it as ``space``.
"""

import abc
from typing import Any, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._colour import channel_min
from .._photometry import (
    LMAX,
    LMIN,
    mesopic_weight,
    tvi,
    weights_of,
    xyz_matrices,
)
from .._scale import quotient
from .._stats import Statistics
from ._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    checked_statistics,
    chromaticities_field,
    estimated,
    fill,
    parameter,
    register,
)

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
    """``_f(num / den)`` for ``den > 0``. In the cube-root part, ``cbrt(num) / cbrt(den)``
    (the same value): the quotient overflows for a pixel near the float maximum over a dim
    background, and its derivative in ``den``, ``num / den²``, long before it (a 1e30 cd/m²
    pixel at 1e-7 cd/m² adaptation); the branch is chosen before the root, so that neither
    branch's derivative is 0·∞."""
    big = jax.lax.stop_gradient(num / den) > _D**3  # +Inf included
    root = jnp.cbrt(jnp.where(big, num, 1.0)) / jnp.cbrt(jnp.where(big, den, 1.0))
    return jnp.where(big, root, _f(jnp.where(big, 0.0, num) / den))


def _finv_scaled(u: Array, n: Array) -> Array:
    """``n · _finv(u)`` for ``n > 0``, with ``|u|`` capped so that it stays below
    :data:`SATURATION` of the float maximum (values beyond it saturate there, constants for
    ``jax.grad`` as clipped values are: their derivative in ``n``, about the float maximum,
    would overflow)."""
    top = jnp.finfo(u.dtype).max * SATURATION
    cap = jax.lax.stop_gradient(jnp.cbrt(top) / jnp.cbrt(jnp.maximum(n, 1.0)))
    over = jax.lax.stop_gradient(jnp.abs(u) > cap)
    inner = n * _finv(jnp.where(over, 0.0, u))
    saturated = jax.lax.stop_gradient(n * _finv(jnp.sign(u) * cap))
    return jnp.where(over, saturated, inner)


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
    """Brightness in JNDs above the threshold: ``B = (L_a/ΔL(L_a)) ln(L/ΔL(L_a))``.

    Fechner's integral of Weber's law with the Weber fraction ``ΔL(L_a)/L_a`` of the
    adaptation level; ``ΔL`` is pcond's combined TVI (:func:`hdrjax.vision.tvi`), and a
    luminance at the threshold has brightness 0. ``L`` and ``L_a`` in cd/m², clamped below
    at 1e-7 cd/m². Stands in for Shklover's formula (Budak & Petrovichev 2005, Eq. 3; not
    found). Inverse: :func:`fechner_luminance`.

    Example:
        >>> round(float(fechner_brightness(1.0, 1.0)), 3)  # ln(1/0.3913)/0.3913
        2.398
    """
    _check.real(L, "L")
    L = jnp.maximum(_check.as_float(L), LMIN)
    L_a = jnp.maximum(_check.as_float(L_a), LMIN)
    dL = tvi(L_a)
    # L / ΔL overflows for L near the float maximum: ln L − ln ΔL there (where-before-log,
    # so that neither branch's derivative is 0·∞)
    big = ~jnp.isfinite(jax.lax.stop_gradient(L / dL))
    ln = jnp.where(big, jnp.log(L) - jnp.log(dL), jnp.log(jnp.where(big, dL, L) / dL))
    return (L_a / dL) * ln


def fechner_luminance(
    B: Float[ArrayLike, "*shape"], L_a: Float[ArrayLike, ""]
) -> Float[Array, "*shape"]:
    """Inverse of :func:`fechner_brightness`: ``L = ΔL(L_a) exp(B ΔL(L_a)/L_a)``."""
    _check.real(B, "B")
    L_a = jnp.maximum(_check.as_float(L_a), LMIN)
    dL = tvi(L_a)
    arg = _check.as_float(B) * dL / L_a
    # saturates at SATURATION × the float maximum (+Inf, and NaN colours, before)
    top = jnp.log(jnp.finfo(arg.dtype).max * SATURATION)
    return dL * jnp.exp(jnp.minimum(arg, top - jnp.maximum(jnp.log(dL), 0.0)))


class AbstractContrastSpace(eqx.Module):
    """A colour-contrast space relative to a background at an adaptation luminance.

    ``forward`` maps XYZ (cd/m²) to three coordinates that the observer keeps constant when
    re-adapting; ``inverse`` maps them back at another adaptation. ``background`` is the
    XYZ of the adapting background (its Y is the adaptation luminance). Coordinate 0 is the
    brightness (the paper's ``B``): :class:`Budak2005` lowers it by the excess of the
    scene background's over the display background's, so that a scene adapted above the
    display shows its background at the display's.
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
    """Fechner brightness + cone-opponent contrasts of chromaticity (module docstring).

    Coordinates ``(B, a, b)``: ``B`` = :func:`fechner_brightness` of Y at the background's
    luminance;

        ``a = 500 c (f(Lc/Lc_n) / f(Y/Y_n) - 1)``,
        ``b = 200 c (1 - f(Sc/Sc_n) / f(Y/Y_n))``,

    with ``Lc``, ``Sc`` the first and third rows of ``cone_matrix`` (HPE by default) applied
    to XYZ, ``_n`` the background's values, ``f`` CIELAB's, and ``c`` =
    :func:`hdrjax.vision.mesopic_weight` of the background luminance ``Y_n``. For a pixel
    at the background's luminance in photopic light (``f(Y/Y_n) = 1``, ``c = 1``) ``a``,
    ``b`` are CIELAB's a*, b* of the cone responses; elsewhere they are divided by
    ``f(Y/Y_n)``, so that in the cube-root part (``Y/Y_n`` above (6/29)³) they depend on
    chromaticity alone, and a colour keeps its chromaticity whatever brightness it is
    re-adapted to. (CIELAB's own a*, b* grow with the pixel's lightness: kept under a
    compressed lightness, they inflated the saturation of highlights.) The inverse at a
    background without colour vision (``c = 0``) is grey.

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
        # f(Y/Y_n) >= 4/29 for Y >= 0; a negative Y (out-of-gamut noise) is taken as 0 here
        fy = _f_ratio(jnp.maximum(Y, 0.0), Yb)
        c = mesopic_weight(Yb)
        a = (500.0 * c) * (_f_ratio(Lc, Lb) / fy - 1.0)
        b = (200.0 * c) * (1.0 - _f_ratio(Sc, Sb) / fy)
        return jnp.stack([fechner_brightness(Y, Yb), a, b], axis=-1)

    def inverse(self, coords, background):
        B, a, b = coords[..., 0], coords[..., 1], coords[..., 2]
        Lb, Sb = self._cones(*background)
        Yb = background[1]
        Y = fechner_luminance(B, Yb)
        fy = _f_ratio(Y, Yb)
        c = mesopic_weight(Yb)
        seen = c > 0  # without colour vision at the background: the grey of the same Y
        safe_c = jnp.where(seen, c, 1.0)
        sa = jnp.where(seen, a / (500.0 * safe_c), 0.0)
        sb = jnp.where(seen, b / (200.0 * safe_c), 0.0)
        Lc = _finv_scaled(fy * (1.0 + sa), Lb)
        Sc = _finv_scaled(fy * (1.0 - sb), Sb)
        m = self.cone_matrix  # solve the L and S rows for X and Z given Y
        r1 = Lc - m[0][1] * Y
        r2 = Sc - m[2][1] * Y
        det = m[0][0] * m[2][2] - m[0][2] * m[2][0]
        X = (r1 * m[2][2] - m[0][2] * r2) / det
        Z = (m[0][0] * r2 - m[2][0] * r1) / det
        return X, Y, Z


BUDAK2005 = (
    "Budak, Petrovičev 2005, Realistické modelování zobrazení osvětlení 3D scén na stínítku"
    " počítače (realistic modelling of the display of lit 3D scenes), Světlo 3/2005"
)


@register("budak2005")
class Budak2005(AbstractOperator):
    """Budak & Petrovichev 2005 perceptual colour-contrast reproduction (module docstring).

    Coordinates in ``space`` relative to the scene background at ``adaptation`` (brightness
    lowered to the display background's where the scene's is higher), inverse at the display
    background ``display_max/2`` (the same chromaticity), divided by ``display_max``:
    display-referred linear RGB, 1 at the display's maximum; colours beyond it rolled off
    towards white at their hue, so that no channel exceeds 1 (negative channels, from
    colours outside the primaries' gamut, are left to the display encoding). Input in
    cd/m² (the Weber fractions depend on absolute luminance).

    Attributes:
        display_max: the display's maximum luminance, cd/m².
        adaptation: scene adaptation luminance, cd/m²; ``None``: ``exp(mean ln L)`` over
            the pixels inside pcond's visible range 1e-7–1e5 cd/m² (without any: 1e5 when
            a pixel lies above it, else 1e-7).
        background: the scene background's colour (mean RGB of the finite pixels); only
            its chromaticity is used; ``None``: measured.
        space: the colour-contrast space (default :class:`ConeOpponentSpace`).
        chromaticities: the image's primaries as OpenEXR's 8-tuple (``None``: Rec.709 with
            D65); they give the RGB → XYZ matrix and the luminance weights.
    """

    reference: ClassVar[str] = BUDAK2005
    default_fit_params: ClassVar[tuple[str, ...]] = ("adaptation",)
    # the way back from cone-opponent coordinates to RGB (matrix rows up to 3.2 in absolute
    # value, cancelling for saturated colours) amplifies float32 rounding about twentyfold
    rounding: ClassVar[float] = 2e-5

    display_max: Array = parameter(
        100.0, help="the display's maximum luminance", unit="cd/m²", range="(0, inf)"
    )
    adaptation: Array | None = estimated(
        "scene adaptation; None: log-average of the pixels in 1e-7–1e5 cd/m²",
        unit="cd/m²",
        pooling="log_mean",
    )
    background: Array | None = estimated(
        "scene background colour (only its chromaticity is used); None: the mean RGB"
        " of the finite pixels",
        unit="cd/m²",
        range="[0, inf)",
        pooling="mean",
        shape=(3,),
    )
    space: "AbstractContrastSpace" = parameter(
        ConeOpponentSpace(),
        help="the colour-contrast space (a hdrjax.operators.AbstractContrastSpace)",
        static=True,
        shape=None,
    )
    chromaticities: tuple[float, ...] | None = chromaticities_field()

    @property
    def weights_(self) -> tuple[float, float, float]:
        return weights_of(self.chromaticities)

    def statistics_settings(self) -> StatisticsSettings | None:
        if not self.unset():
            return None
        return StatisticsSettings(channels=self.background is None)

    def bind(self, stats: Statistics | None) -> "Budak2005":
        if not self.unset():
            return self
        stats = checked_statistics(self, stats)
        measured: dict[str, Any] = {}
        if self.adaptation is None:
            value, n = stats.range_log_average(LMIN, LMAX)
            # no pixel inside the visible range: the end of the range the scene lies
            # beyond (pcond has no samples then; a scene above 1e5 cd/m² is not adapted
            # to 1e-7)
            nearest = jnp.where(stats.max >= LMAX, LMAX, LMIN)
            measured["adaptation"] = jnp.where(n > 0, value, nearest)
        if self.background is None:
            measured["background"] = stats.channel_average
        return fill(self, **measured)

    def _apply(self, p: Prepared) -> Array:
        m, minv = xyz_matrices(self.chromaticities)
        dt = p.rgb.dtype
        # channels saturate at SATURATION × the float maximum (X and Z, rows summing to
        # more than 1, would overflow there); such pixels are far beyond any display
        x = jnp.minimum(p.rgb, jnp.finfo(dt).max * SATURATION)
        X, Y, Z = (x @ jnp.asarray(m[i], dt) for i in range(3))
        # background chromaticity X/Y and Z/Y (the white of the primaries where the
        # background is not a positive finite colour: no light, or its sums overflowed)
        bg = jnp.asarray(self.background, dt)
        bX, bY, bZ = (bg[0] * m[i, 0] + bg[1] * m[i, 1] + bg[2] * m[i, 2] for i in range(3))
        good = jnp.isfinite(bX + bY + bZ) & (bX > 0) & (bY > 0) & (bZ > 0)
        safe_y = jnp.where(good, bY, 1.0)
        rX = jnp.where(good, quotient(jnp.where(good, bX, 1.0), safe_y), float(m[0].sum()))
        rZ = jnp.where(good, quotient(jnp.where(good, bZ, 1.0), safe_y), float(m[2].sum()))
        La = jnp.maximum(jnp.asarray(self.adaptation, dt), LMIN)
        Lda = 0.5 * jnp.asarray(self.display_max, dt)
        scene, display = (rX * La, La, rZ * La), (rX * Lda, Lda, rZ * Lda)
        coords = self.space.forward((X, Y, Z), scene)
        # a scene brighter than the display's adaptation shows its background at the
        # display's (the paper's Eq. 2, background at half the display maximum); a dimmer
        # one keeps its brightness above threshold, and looks as dim as it is
        excess = self.space.forward(scene, scene)[0] - self.space.forward(display, display)[0]
        coords = coords.at[..., 0].add(-jnp.maximum(excess, 0.0))
        Xd, Yd, Zd = self.space.inverse(coords, display)
        out = jnp.stack(
            [Xd * minv[i, 0] + Yd * minv[i, 1] + Zd * minv[i, 2] for i in range(3)], axis=-1
        )
        top = jnp.asarray(self.display_max, dt)
        out = _roll_off_to_white(out / top, Yd / top)
        # no light in, no light out (the brightness scale starts at 1e-7 cd/m², which
        # would otherwise map a black pixel to a dim grey)
        return jnp.where((Y > 0)[..., None], out, 0.0)


def _roll_off_to_white(rgb: Array, Y: Array) -> Array:
    """Display RGB (white 1) with each colour beyond white moved towards the white of its
    own luminance ``Y``, just far enough that its largest channel is 1 (luminance and hue,
    the direction from grey, kept; saturation given up), and white where ``Y >= 1``.

    A window brighter than the display then fades to white as its luminance rises, each
    channel monotone, instead of being clipped per channel: that kept the channels below
    1 and turned a blue window cyan and an orange one yellow before white.
    """
    Yc = Y[..., None]
    over = (rgb > 1.0) & (Yc < 1.0)
    # the largest s in [0, 1] with Y + s (c - Y) <= 1 for every channel c (c > 1 > Y)
    room = jnp.where(over, rgb - Yc, 1.0)
    s = channel_min(jnp.where(over, (1.0 - Yc) / room, 1.0), keepdims=True)
    return jnp.where(Yc < 1.0, Yc + s * (rgb - Yc), 1.0)


__all__ = [
    "BUDAK2005",
    "HPE",
    "AbstractContrastSpace",
    "Budak2005",
    "ConeOpponentSpace",
    "fechner_brightness",
    "fechner_luminance",
]
