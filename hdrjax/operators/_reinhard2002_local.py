"""Reinhard et al. 2002 local operator ("automatic dodging-and-burning") and the JGT switch.

Implements the local operator of Reinhard, Stark, Shirley & Ferwerda 2002 (ACM TOG 21(3),
https://doi.org/10.1145/566654.566575) following Reinhard's reference code (as
ported in LuminanceHDR and hdritools): Gaussian responses ``V1_i = L ⊗ R(s_i)`` at scales
``s_i = s_low (s_high / s_low)^(i / num)`` (defaults 1, 43, 8, i.e. ≈ 1.6^i), each kernel
integrated over the pixel with erf (``w(x) = erf(c (x + ½)) − erf(c (x − ½))``,
``c = 1 / (α₁ s)``, ``α₁ = 1 / (2√2)``); centre–surround activity
``V_i = (V1_i − V1_{i+1}) / (2^φ a / s_i² + V1_i)``; the scale ``m`` is the first ``i`` with
``|V_i| > ε`` (``num − 1`` if none) and ``L_d = L / (1 + V1_m)``.

Deviation from the reference code: its FFT convolution is circular; here the image is
zero-padded and the result divided by the convolution of the valid-pixel mask (normalised
convolution), so borders see only the image and NaN/Inf pixels do not reach their
neighbours. ``reinhard2002_auto`` applies the local operator when the image spans more than
11 zones (``log2(L_max / L_min) > 11``, hdritools) and the global one otherwise.
"""

import math
from typing import ClassVar, Literal

import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._scale import inverse_pow2, quotient
from .._stats import Statistics
from ._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    bound_stats,
    estimated,
    fill,
    parameter,
    register,
    weights_field,
)
from ._reinhard2002 import (
    REFERENCE,
    Reinhard2002,
    bins_setting,
    delta_setting,
    jgt_key_and_log_average,
    jgt_settings,
    key_parameter,
    log_average_parameter,
    percentile_method_setting,
    white_parameter,
)

ALPHA1 = 1.0 / (2.0 * math.sqrt(2.0))
AUTO_ZONES = 11.0


def scales(s_low: float, s_high: float, num: int) -> list[float]:
    """``s_i = s_low (s_high / s_low)^(i / num)`` for i = 0 … num − 1."""
    return [s_low * (s_high / s_low) ** (i / num) for i in range(num)]


def erf_kernel_1d(s: float, radius: int, dtype) -> Array:
    """Per-axis weights of the reference code's pixel-integrated Gaussian (sums to 2)."""
    c = 1.0 / (ALPHA1 * s)
    x = jnp.arange(-radius, radius + 1, dtype=dtype)
    return jax.scipy.special.erf(c * (x + 0.5)) - jax.scipy.special.erf(c * (x - 0.5))


def gaussian_radius(s: float) -> int:
    """Half-width in pixels of :func:`gaussian_stack`'s kernel of scale ``s`` (also the
    halo a tile needs around it)."""
    return max(1, math.ceil(4.0 * ALPHA1 * s))  # exp(-16): < 1e-7 of the peak


def gaussian_stack(L: Array, valid: Array, ss: list[float]) -> Array:
    """Normalised convolutions of ``L`` (where ``valid``) with each scale's kernel.

    Returns ``(len(ss), H, W)``. Zero padding by the largest radius, so no wrap-around.
    """
    H, W = L.shape
    r = gaussian_radius(max(ss))
    Hp, Wp = H + 2 * r, W + 2 * r
    v = valid.astype(L.dtype)
    f_img = jnp.fft.rfft2(jnp.pad(L * v, r), s=(Hp, Wp))
    f_msk = jnp.fft.rfft2(jnp.pad(v, r), s=(Hp, Wp))
    out = []
    for s in ss:
        rs = gaussian_radius(s)
        k = erf_kernel_1d(s, rs, L.dtype)
        k2 = jnp.outer(k, k) / 4.0
        kp = jnp.zeros((Hp, Wp), L.dtype).at[: 2 * rs + 1, : 2 * rs + 1].set(k2)
        kp = jnp.roll(kp, (-rs, -rs), axis=(0, 1))  # kernel centre at the origin
        fk = jnp.fft.rfft2(kp)
        num = jnp.fft.irfft2(f_img * fk, s=(Hp, Wp))[r : r + H, r : r + W]
        den = jnp.fft.irfft2(f_msk * fk, s=(Hp, Wp))[r : r + H, r : r + W]
        out.append(num / jnp.maximum(den, 1e-6))
    return jnp.stack(out)


def local_adaptation(
    Ls: Array,
    valid: Array,
    key: Array,
    *,
    phi: float,
    epsilon: float,
    ss: list[float],
    unit: Array | float = 1.0,
) -> Array:
    """``V1_m`` with the reference code's scale selection (scaled luminance in); the
    operator is ``L_d = L / (1 + V1_m)``.

    ``unit``: ``Ls`` is the scaled luminance times ``unit`` (a power of two that brings its
    maximum near 1, so that the FFTs cannot overflow), and so is the result."""
    V1 = gaussian_stack(Ls, valid, ss)
    s2 = jnp.asarray(ss, Ls.dtype)[:-1, None, None] ** 2
    act = (V1[:-1] - V1[1:]) / ((2.0**phi) * key / s2 * unit + V1[:-1])
    over = jnp.abs(act) > epsilon
    m = jnp.where(jnp.any(over, axis=0), jnp.argmax(over, axis=0), len(ss) - 1)
    return jnp.maximum(jnp.take_along_axis(V1, m[None], axis=0)[0], 0.0)


def _phi():
    return parameter(
        8.0,
        help="sharpening φ (8, reference code; pfstmo's GUI uses 1)",
        range="[0, inf)",
        static=True,
    )


def _epsilon():
    return parameter(
        0.05, help="activity threshold ε of the scale selection", range="(0, inf)", static=True
    )


@register("reinhard2002_local")
class Reinhard2002Local(AbstractOperator):
    """Reinhard et al. 2002 local dodging-and-burning operator, JGT 2002 automatic key
    (module docstring).

    Input: linear RGB, relative or absolute. Output: display-referred linear RGB in [0, 1).

    Attributes:
        key: the key ``a``; ``None`` → JGT Eq. 4 estimate.
        log_average: ``L̄_w``; ``None`` → measured with ``delta``.
        phi: sharpening ``φ`` (8, reference code; pfstmo's GUI uses 1).
        epsilon: activity threshold ``ε`` (0.05).
        s_low, s_high, num: the scale range and count (1, 43, 8).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("key",)

    key: Array | None = key_parameter()
    log_average: Array | None = log_average_parameter()
    phi: float = _phi()
    epsilon: float = _epsilon()
    s_low: float = parameter(
        1.0, help="smallest Gaussian scale s_1", unit="pixels", range="(0, inf)", static=True
    )
    s_high: float = parameter(
        43.0,
        help="largest Gaussian scale (exclusive)",
        unit="pixels",
        range="(0, inf)",
        static=True,
    )
    num: int = parameter(8, help="number of scales", range="[2, inf)", static=True)
    delta: float = delta_setting()
    percentile_method: Literal["histogram", "exact"] = percentile_method_setting()
    bins: int = bins_setting()
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        if not (self.num >= 2 and 0 < self.s_low < self.s_high):
            raise ValueError(
                f"reinhard2002_local: need num >= 2 and 0 < s_low < s_high, got num={self.num},"
                f" s_low={self.s_low}, s_high={self.s_high}"
            )

    def halo(self, shape: tuple[int, ...]) -> tuple[int, int]:
        """The radius of the largest Gaussian, ``ceil(4 s_max / (2√2))`` (39 pixels for the
        default scales): a tile's responses then equal the whole image's."""
        del shape
        r = gaussian_radius(max(scales(self.s_low, self.s_high, self.num)))
        return r, r

    def statistics_settings(self) -> StatisticsSettings | None:
        return jgt_settings(self)

    def bind(self, stats: Statistics | None) -> "Reinhard2002Local":
        if not self.unset():
            return self
        _, key, lbar = jgt_key_and_log_average(self, stats)
        return fill(self, key=key, log_average=lbar)

    def _apply(self, p: Prepared) -> Array:
        assert self.key is not None and self.log_average is not None
        scale = self.key / self.log_average
        valid = p.valid()
        # the scaled luminance times a power of two c = c_s c_L that brings its maximum near
        # 1: near the float maximum the FFTs' sums (or scale · L itself) would overflow;
        # scaling by powers of two is exact, so ordinary images give the same bits
        L = jnp.maximum(p.L, 0.0)
        c_s = inverse_pow2(scale)
        c_L = inverse_pow2(jnp.max(L))
        _, e_s = jnp.frexp(c_s)
        _, e_L = jnp.frexp(c_L)
        top = jnp.finfo(L.dtype).maxexp - 2
        unit = jnp.ldexp(jnp.ones((), L.dtype), jnp.clip(e_s + e_L - 2, -top, top))
        # (key c_s) / L̄_w: the same bits as (key / L̄_w) c_s (c_s is a power of two), and a
        # derivative that never meets d(out)/d(scale) ~ out / scale, which overflows when
        # the scale is near the smallest normal (an image near the float maximum)
        sc = quotient(self.key * c_s, self.log_average)
        V1m = local_adaptation(
            sc * (L * c_L),
            valid,
            self.key,
            phi=self.phi,
            epsilon=self.epsilon,
            ss=scales(self.s_low, self.s_high, self.num),
            unit=unit,
        )
        # L_d / L_w = scale / (1 + V1_m) = (scale c_s) / (c + c V1_m) · c_L: no division by
        # the pixel's own luminance, and c_L applied to RGB first (the ratio alone can fall
        # below the smallest normal float when L_max is near the largest)
        ratio = jnp.where(p.L > 0, quotient(sc, unit + V1m), 0.0)
        return (p.rgb * c_L) * ratio[..., None]


@register("reinhard2002_auto")
class Reinhard2002Auto(AbstractOperator):
    """JGT 2002 automatic choice: local operator iff ``log2(L_max / L_min) > 11`` zones.

    Both branches use the JGT automatic key; the global branch also the JGT white point.
    Attributes are those of :class:`Reinhard2002Local` plus ``L_white`` for the global one
    and ``local``, the choice (measured: the image spans more than ``zones`` stops).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("key",)

    key: Array | None = key_parameter()
    L_white: Array | None = white_parameter()
    log_average: Array | None = log_average_parameter()
    zones: float = parameter(
        AUTO_ZONES,
        help="dynamic range above which the local operator runs (hdritools: 11)",
        unit="stops",
        range="[0, inf)",
        static=True,
    )
    phi: float = _phi()
    epsilon: float = _epsilon()
    delta: float = delta_setting()
    percentile_method: Literal["histogram", "exact"] = percentile_method_setting()
    bins: int = bins_setting()
    weights: tuple[float, float, float] = weights_field()
    local: Array | None = estimated(
        "1: the local operator, 0: the global one; None: the local one where the image"
        " spans more than zones stops",
        range="[0, 1]",
        pooling="max",
    )

    def halo(self, shape: tuple[int, ...]) -> tuple[int, int]:
        """That of the local operator it may choose (default scales)."""
        return Reinhard2002Local(phi=self.phi, epsilon=self.epsilon).halo(shape)

    def branches(self) -> tuple[Reinhard2002Local, Reinhard2002]:
        """The local and the global operator, with this operator's parameters."""
        common = dict(
            key=self.key,
            log_average=self.log_average,
            delta=self.delta,
            percentile_method=self.percentile_method,
            bins=self.bins,
            weights=self.weights,
        )
        local = Reinhard2002Local(phi=self.phi, epsilon=self.epsilon, **common)
        return local, Reinhard2002(L_white=self.L_white, **common)

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings(self.percentile_method, self.bins, self.delta)

    def bind(self, stats: Statistics | None) -> "Reinhard2002Auto":
        if self.local is not None and not self.unset():
            return self
        st = bound_stats(self, stats)
        use = (st.n_positive > 0) & (st.dynamic_range_stops > self.zones)
        if self.local is not None:
            use = self.local
        # both branches' automatic values: the key and log-average they share, the
        # global one's white
        glob = self.branches()[1].bind(stats)
        return fill(
            self,
            key=glob.key,
            L_white=glob.L_white,
            log_average=glob.log_average,
            local=use,
        )

    def _apply(self, p: Prepared) -> Array:
        local, glob = self.branches()
        return jax.lax.cond(
            self.local > 0.5, lambda q: local._apply(q), lambda q: glob._apply(q), p
        )


__all__ = [
    "Reinhard2002Auto",
    "Reinhard2002Local",
    "gaussian_radius",
    "local_adaptation",
    "scales",
]
