"""Kuang, Johnson & Fairchild 2007 iCAM06 image appearance model, as a tone-mapping operator.

Reference:
    J. Kuang, G. M. Johnson, M. D. Fairchild. "iCAM06: A refined image appearance model for
    HDR image rendering." Journal of Visual Communication and Image Representation
    18(5):406–414, 2007. https://doi.org/10.1016/j.jvcir.2007.06.003

The steps, with the image first scaled so that its largest luminance is ``L_peak``
(20 000 cd/m², the paper's value for uncalibrated images), ``XYZ`` the image's CIE XYZ in
cd/m² (the primaries' matrix, Y row = the luminance weights) and every spatial scale a
fraction of the image's size:

1. Base and detail layers (section 2.2): per channel of ``XYZ``, a bilateral filter of
   ``log10(max(XYZ, 0) + ε)`` (``ε = 10⁻⁶`` cd/m²) with a spatial Gaussian of standard
   deviation ``σ_s = 2 %`` of ``min(H, W)`` pixels and a range Gaussian
   ``exp(−Δ² / 2σ_r²)``, ``σ_r = 0.35`` log10 units; base ``B = 10^bilateral``, detail
   ``D = 10^(log10(XYZ + ε) − bilateral)``. The filter is Durand & Dorsey 2002's
   piecewise-linear scheme, as ``durand2002`` computes it (its ``bilateral_base``, given
   ``σ_r √2`` and ``π σ_s`` for its own parametrisation), its nodes spanning the smallest
   to the largest log value of the three channels.
2. Adapting white ``W``: ``XYZ`` blurred by a Gaussian of standard deviation
   ``max(H, W) / 2`` pixels (truncated at 2.5 of them, the image's edge pixels
   replicated, as MATLAB's ``imfilter(..., 'replicate')``).
3. Chromatic adaptation (section 2.3, CIECAM02's CAT02 towards D65): ``RGB = M_CAT02 B``,
   ``RGB_c = RGB (D RGB_D65 / RGB_W + 1 − D)`` with ``RGB_W = M_CAT02 W``,
   ``RGB_D65 = M_CAT02 (95.047, 100, 108.883)``, ``D = 1 − e^(−(L_A + 42) / 92) / 3.6`` and
   ``L_A = 0.2 Y_W``; back to ``XYZ_c``.
4. Tone compression (section 2.4): cones in Hunt–Pointer–Estévez space,
   ``R' = M_HPE XYZ_c``, ``R'_a = 400 t / (27.13 + t) + 0.1`` with
   ``t = (F_L |R'| / Y_W)^p`` (the sign of ``R'`` kept), ``F_L = 0.2 k⁴ (5 L_A) +
   0.1 (1 − k⁴)² (5 L_A)^(1/3)``, ``k = 1 / (5 L_A + 1)``; rods by Hunt's model with
   ``S = Y`` of ``XYZ_c``, ``S_W = max Y_W``, ``L_LS = 5 L_A``,
   ``j = 10⁻⁵ / (L_LS + 10⁻⁵)``, ``F_LS = 3800 j² L_LS + 0.2 (1 − j²)⁴ L_LS^(1/6)``,
   ``B_S = 0.5 / (1 + 0.3 (L_LS S / S_W)^0.3) + 0.5 / (1 + 5 L_LS)``,
   ``A_S = 3.05 B_S · 400 t_S / (27.13 + t_S) + 0.3``, ``t_S = (F_LS S / S_W)^p``;
   ``XYZ_TC = M_HPE⁻¹ (R'_a + A_S)``.
5. Detail (section 2.5, Stevens effect): ``D^((F_L' + 0.8)^0.25)``, ``F_L'`` from
   ``L_A' = 0.2 Y`` of the base layer; ``XYZ_TC`` times it.
6. IPT (section 2.6, Ebner & Fairchild 1998): ``LMS = M_D65 XYZ``,
   ``IPT = M_IPT sign(LMS) |LMS|^0.43``; colourfulness (Hunt effect) ``P, T`` times
   ``(F_L' + 1)^0.2 (1.29 C² − 0.27 C + 0.42) / (C² − 0.31 C + 0.42)``,
   ``C = √(P² + T²)``; lightness (Bartleson–Breneman surround)
   ``I ← (I / I_max)^γ I_max``, ``γ`` 1 (average), 1.25 (dim), 1.5 (dark); back through
   IPT⁻¹ to ``XYZ`` and the primaries' RGB (D65 white).
7. Display range: the 1st and 99th percentiles of all channel values map to 0 and 1.

Constants: ``M_CAT02`` (Moroney et al. 2002, CIECAM02, as colour-science's
``CAT_CAT02``), ``M_HPE`` (CIECAM02's Hunt–Pointer–Estévez matrix as the paper prints it),
``M_D65`` and ``M_IPT`` (Ebner & Fairchild 1998, "Development and testing of a color space
(IPT) with improved hue uniformity", IS&T 6th Color Imaging Conference, 8–13).

Deviations from HDR Toolbox's ``KuangTMO`` (the reference peer), each argued:

- ``KuangTMO`` asks for the bilateral domain ``'log_10'``, which its ``bilateralSeparation``
  spells ``'log10'``: it filters *linear* XYZ with the log-unit ``σ_r``, which barely
  smooths (the detail layer is about 1). Here the paper's log10 filtering. The Toolbox also
  filters the three channels jointly (one range distance in XYZ); here each channel alone,
  the paper's (and Durand & Dorsey's) per-channel filter.
- The adapting white is blurred at full resolution, not on an image downsampled by 8.
- D65's ``X`` is CIE's 95.047 (``KuangTMO`` has 96.047).
- Negative cone responses keep their sign through the power ``p`` (CIECAM02's rule);
  Octave raises them to a complex power.
- The output is not clamped to [0, 1] (the display clips it); the Toolbox clamps.

The colourfulness factor's exponent (0.2) and the rods' constants (Hunt's exponent 0.3
and offset 0.3) are ``KuangTMO``'s.

Bad pixels: NaN and ±Inf pixels take the value of the first finite pixel (raster order)
for the filters and percentiles, so they reach no neighbour with their own value
(the operator's call then puts them back: NaN stays NaN, +Inf luminance is white).

Tiles: the filters' sizes are fractions of the image's size, and the white's Gaussian
spans half of it: the halo is the whole image (:meth:`Kuang2007.halo`).
"""

import functools
import math
from typing import ClassVar, Literal

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._colour import REC709_CHROMATICITIES, apply_matrix, normalised_primary_matrix
from .._scale import inverse_pow2, quotient
from .._stats import Statistics
from ._ashikhmin2002 import gaussian_taps
from ._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    checked_statistics,
    chromaticities_field,
    estimated,
    fill,
    filled_with_first_valid,
    parameter,
    register,
    weights_field,
)
from ._durand2002 import bilateral_base, spatial_radius

REFERENCE = (
    "Kuang, Johnson, Fairchild 2007, iCAM06: A refined image appearance model for HDR image"
    " rendering, Journal of Visual Communication and Image Representation 18(5):406-414,"
    " https://doi.org/10.1016/j.jvcir.2007.06.003"
)
M_CAT02 = np.array([[0.7328, 0.4296, -0.1624], [-0.7036, 1.6975, 0.0061], [0.0030, 0.0136, 0.9834]])
"""CIECAM02's CAT02 (XYZ → sharpened RGB), Moroney et al. 2002."""
M_HPE = np.array([[0.38971, 0.68898, -0.07868], [-0.22981, 1.18340, 0.04641], [0.0, 0.0, 1.0]])
"""CIECAM02's Hunt–Pointer–Estévez matrix (XYZ → cone responses), as the paper prints it."""
M_D65 = np.array([[0.4002, 0.7075, -0.0807], [-0.2280, 1.1500, 0.0612], [0.0, 0.0, 0.9184]])
"""XYZ → LMS normalised to D65 (Ebner & Fairchild 1998)."""
M_IPT = np.array([[0.4000, 0.4000, 0.2000], [4.4550, -4.8510, 0.3960], [0.8056, 0.3572, -1.1628]])
"""Non-linear LMS → IPT (Ebner & Fairchild 1998)."""
D65_XYZ = np.array([95.047, 100.0, 108.883])
"""CIE D65's white, ``Y = 100``."""
IPT_EXPONENT = 0.43
"""IPT's cone non-linearity (Ebner & Fairchild 1998)."""
HUNT_EXPONENT = 0.2
"""Exponent of ``F_L + 1`` in the colourfulness factor (HDR Toolbox's ``KuangTMO``)."""
SURROUND = {"average": 1.0, "dim": 1.25, "dark": 1.5}
"""The lightness exponent ``γ`` per surround (the paper's section 2.6)."""
EPSILON = 1e-6
"""cd/m² added before the logarithm of the bilateral filter (zero channels stay finite)."""
SPATIAL = 0.02
"""The bilateral filter's spatial standard deviation, a fraction of ``min(H, W)``."""
WHITE = 0.5
"""The adapting white's standard deviation, a fraction of ``max(H, W)``."""
LOW, HIGH = 0.01, 0.99
"""The percentiles of the output mapped to 0 and 1."""


def _mat(m: np.ndarray, x: Array) -> Array:
    """``m x`` for ``x`` of shape ``(..., 3)`` (channels last)."""
    return apply_matrix(x, jnp.asarray(m, x.dtype))


def _spow(x: Array, e: Array | float) -> Array:
    """``sign(x) |x|^e`` (0 at 0, finite gradients there for ``e ≥ 1``; masked below)."""
    a = jnp.abs(x)
    pos = a > 0
    return jnp.where(pos, jnp.sign(x) * jnp.exp(e * jnp.log(jnp.where(pos, a, 1.0))), 0.0)


def _ppow(x: Array, e: Array | float) -> Array:
    """``max(x, 0)^e``, 0 where ``x ≤ 0`` (gradient-safe)."""
    pos = x > 0
    return jnp.where(pos, jnp.exp(e * jnp.log(jnp.where(pos, x, 1.0))), 0.0)


def luminance_factor(L_A: Array) -> Array:
    """CIECAM02's luminance-level adaptation factor ``F_L`` of ``L_A`` in cd/m²."""
    k = 1.0 / (5.0 * L_A + 1.0)
    k4 = k**4
    return 0.2 * k4 * (5.0 * L_A) + 0.1 * (1.0 - k4) ** 2 * _ppow(5.0 * L_A, 1.0 / 3.0)


def _compress(x: Array, p: Array) -> Array:
    """``400 t / (27.13 + t)``, ``t = x^p`` (the sign of ``x`` kept)."""
    t = _spow(x, p)
    return 400.0 * t / (27.13 + jnp.abs(t))


def channel_bilateral(logs: Array, sigma_r: Array, sigma_px: float, max_segments: int) -> Array:
    """Step 1's base layer (log10) of each channel of ``logs`` (``(H, W, 3)``):
    :func:`~hdrjax.operators.bilateral_base` (range kernel ``exp(−Δ² / sigma_r²)``, spatial
    standard deviation ``sigma_px`` pixels) on the three channels stacked along the rows,
    separated by rows that take no part and are wider than the spatial kernel's reach, so
    that each channel is filtered alone by one filter (nodes spanning all three)."""
    H, W = logs.shape[:2]
    sigma_s = math.pi * sigma_px  # bilateral_base's unit: π pixels
    gap = spatial_radius(sigma_s)
    pad = jnp.zeros((gap, W), logs.dtype)
    rows = [logs[..., 0], pad, logs[..., 1], pad, logs[..., 2]]
    stacked = jnp.concatenate(rows, axis=0)
    on, off = np.ones((H, W), bool), np.zeros((gap, W), bool)
    valid = jnp.asarray(np.concatenate([on, off, on, off, on], axis=0))
    lo, hi = jnp.min(logs), jnp.max(logs)
    base = bilateral_base(
        stacked, valid, lo, hi, sigma_r, sigma_s=sigma_s, max_segments=max_segments
    )
    step = H + gap
    return jnp.stack([base[c * step : c * step + H] for c in range(3)], axis=-1)


@functools.lru_cache(maxsize=32)
def replicate_matrix(n: int, window: float) -> np.ndarray:
    """``(n, n)``: HDR Toolbox's 1-D Gaussian blur of ``window`` (MATLAB's
    ``fspecial('gaussian', w, window / 5)``) along an axis of ``n`` pixels with its edge
    pixels replicated, as a matrix (the replicated taps folded onto the edge pixels)."""
    t = gaussian_taps(window)
    r = len(t) // 2
    idx = np.clip(np.arange(n)[:, None] + np.arange(-r, r + 1)[None, :], 0, n - 1)
    m = np.zeros((n, n))
    np.add.at(m, (np.repeat(np.arange(n), 2 * r + 1), idx.reshape(-1)), np.tile(t, n))
    return m


def white_blur(x: Array) -> Array:
    """The adapting white of ``x`` (``(H, W, C)``): a Gaussian of standard deviation
    :data:`WHITE` ``· max(H, W)`` pixels over the whole image, edges replicated
    (module docstring, step 2)."""
    H, W = x.shape[:2]
    window = 5.0 * WHITE * max(H, W)
    hi = jax.lax.Precision.HIGHEST
    rows = jnp.asarray(replicate_matrix(H, window), x.dtype)
    cols = jnp.asarray(replicate_matrix(W, window), x.dtype)
    y = jnp.einsum("ij,jwc->iwc", rows, x, precision=hi)
    return jnp.einsum("vw,iwc->ivc", cols, y, precision=hi)


def _quantile_index(values: Array, q: float) -> Array:
    """MATLAB's ``MaxQuart``: the sorted ``values``' element number ``max(round(n q), 1)``."""
    n = values.shape[0]
    k = max(int(math.floor(n * q + 0.5)), 1) - 1
    return jnp.sort(values)[k]


@register("kuang2007")
class Kuang2007(AbstractOperator):
    """Kuang, Johnson & Fairchild 2007 iCAM06 (module docstring) with the paper's and HDR
    Toolbox's ``KuangTMO`` defaults.

    Input: linear RGB, relative or absolute: the image is scaled so that its largest
    luminance ``L_max`` is ``L_peak`` cd/m² (for a calibrated image in cd/m², set
    ``L_max = L_peak``, the Toolbox's ``'calibrated'``). Output: display-referred linear RGB
    (D65 white), the 1st percentile of all channel values at 0 and the 99th at 1 (values
    beyond, clipped by the display).

    Attributes:
        L_peak: the largest luminance of the scaled image, cd/m² (20 000).
        p: the exponent of the cone and rod compression (0.75; the paper's range
            0.6–0.85: lower is more contrast).
        sigma_r: the bilateral filter's range standard deviation, log10 units (0.35).
        surround: ``"average"``, ``"dim"`` or ``"dark"``: the lightness exponent ``γ``
            1, 1.25 or 1.5.
        L_max: the image's largest luminance (image units); ``None`` → measured.
        max_segments: most segments of the piecewise-linear bilateral filter.
        weights: the luminance weights (the Y row of the RGB → XYZ matrix).
        chromaticities: the image's primaries (``None``: Rec.709 with D65).
    """

    reference: ClassVar[str] = REFERENCE
    scale_invariant: ClassVar[bool] = True
    # the bilateral filter skips unused nodes by lax.cond, a select under vmap
    frames_in_sequence: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("p",)

    L_peak: Array = parameter(
        20000.0,
        help="the scaled image's largest luminance (the paper's 20000 cd/m2)",
        unit="cd/m2",
        range="(0, inf)",
    )
    p: Array = parameter(
        0.75,
        help="exponent of the cone and rod compression (the paper's 0.6-0.85; lower: more"
        " contrast)",
        range="(0, 1]",
    )
    sigma_r: Array = parameter(
        0.35,
        help="bilateral filter's range standard deviation (log10 units)",
        unit="log10 cd/m2",
        range="(0, inf)",
    )
    surround: Literal["average", "dim", "dark"] = parameter(
        "average",
        help="viewing surround: lightness exponent 1 (average), 1.25 (dim), 1.5 (dark)",
        static=True,
        choices=tuple(SURROUND),
    )
    L_max: Array | None = estimated(
        "the image's largest luminance (scaled to L_peak); None: measured",
        pooling="max",
        unit="image units",
    )
    max_segments: int = parameter(
        64,
        help="most segments of the piecewise-linear bilateral filter (wider ranges get wider"
        " segments)",
        range="[1, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()
    chromaticities: tuple[float, ...] | None = chromaticities_field()

    def __check_init__(self):
        if int(self.max_segments) != self.max_segments or self.max_segments < 1:
            raise ValueError(f"max_segments: expected an integer >= 1, got {self.max_segments!r}")

    def halo(self, shape: tuple[int, ...]) -> tuple[float, float]:
        """The whole image (infinite): the filters' sizes are fractions of the image's."""
        del shape
        return (math.inf, math.inf)

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings() if self.L_max is None else None

    def bind(self, stats: Statistics | None) -> "Kuang2007":
        if self.L_max is not None:
            return self
        st = checked_statistics(self, stats).luminance_stats()
        return fill(self, L_max=jnp.maximum(st.max, 0.0))

    def rgb_to_xyz(self) -> np.ndarray:
        """The primaries' RGB → XYZ matrix, its Y row the luminance weights."""
        c = REC709_CHROMATICITIES if self.chromaticities is None else self.chromaticities
        m = normalised_primary_matrix(c)
        if self.chromaticities is None:
            m = np.round(m, 4)  # IEC 61966-2-1's figures (HDR Toolbox's)
        m[1] = self.weights
        return m

    def _apply(self, p: Prepared) -> Array:
        assert self.L_max is not None
        dt = p.rgb.dtype
        valid = p.valid()
        rgb = p.rgb
        if not p.clean:  # bad pixels: the first finite pixel's value (module docstring)
            rgb = filled_with_first_valid(rgb, valid)
        rgb = jnp.maximum(rgb, 0.0)
        # scaled so that L_max is L_peak: both sides by a power of two first (exact), so
        # that neither the quotient nor its derivative leaves the float range
        L_max = self.L_max.astype(dt)
        c = inverse_pow2(L_max)
        lit = L_max * c > 0
        gain = self.L_peak.astype(dt) * quotient(1.0, jnp.where(lit, L_max * c, 1.0))
        gain = jnp.where(lit, gain, 0.0)
        to_xyz = self.rgb_to_xyz()
        XYZ = _mat(to_xyz, rgb * c) * gain
        out = self._appearance(XYZ, dt)
        rgb_out = _mat(np.linalg.inv(to_xyz), out)
        lo = _quantile_index(rgb_out.reshape(-1), LOW)
        hi = _quantile_index(rgb_out.reshape(-1), HIGH)
        span = hi - lo
        ok = span > 0
        res = quotient(rgb_out - lo, jnp.where(ok, span, 1.0))
        return jnp.where(lit & ok, res, 0.0)

    def _appearance(self, XYZ: Array, dt) -> Array:
        """Steps 1–6 of the module docstring on ``XYZ`` in cd/m² (``(H, W, 3)``)."""
        H, W = XYZ.shape[:2]
        logs = jnp.log10(jnp.maximum(XYZ, 0.0) + EPSILON)
        base_log = channel_bilateral(
            logs, math.sqrt(2.0) * self.sigma_r.astype(dt), SPATIAL * min(H, W), self.max_segments
        )
        ln10 = math.log(10.0)
        base = jnp.exp(ln10 * base_log)
        detail_log = logs - base_log  # log10 of the detail layer

        white = white_blur(XYZ)
        Y_W = white[..., 1]
        L_A = 0.2 * Y_W
        # chromatic adaptation (step 3)
        D = 1.0 - jnp.exp(-(L_A + 42.0) / 92.0) / 3.6
        rgb_w = _mat(M_CAT02, white)
        rgb_d65 = jnp.asarray(M_CAT02 @ D65_XYZ, dt)[None, None, :]
        okw = rgb_w > 0
        factor = jnp.where(okw, quotient(rgb_d65 * D[..., None], jnp.where(okw, rgb_w, 1.0)), 0.0)
        adapted = _mat(
            np.linalg.inv(M_CAT02), _mat(M_CAT02, base) * (factor + (1.0 - D)[..., None])
        )
        # tone compression (step 4)
        pp = self.p.astype(dt)
        F_L = luminance_factor(L_A)
        okY = Y_W > 0
        inv_Yw = jnp.where(okY, quotient(1.0, jnp.where(okY, Y_W, 1.0)), 0.0)
        cones = _compress(_mat(M_HPE, adapted) * (F_L * inv_Yw)[..., None], pp) + 0.1
        S = jnp.maximum(adapted[..., 1], 0.0)
        S_w = jnp.max(Y_W)
        S_t = jnp.where(S_w > 0, quotient(S, jnp.where(S_w > 0, S_w, 1.0)), 0.0)
        L_LS = 5.0 * L_A
        j2 = (1e-5 / (L_LS + 1e-5)) ** 2
        F_LS = 3800.0 * j2 * L_LS + 0.2 * (1.0 - j2) ** 4 * _ppow(L_LS, 1.0 / 6.0)
        B_S = 0.5 / (1.0 + 0.3 * _ppow(L_LS * S_t, 0.3)) + 0.5 / (1.0 + 5.0 * L_LS)
        A_S = 3.05 * B_S * _compress(F_LS * S_t, pp) + 0.3
        tc = _mat(np.linalg.inv(M_HPE), cones + A_S[..., None])
        # detail (step 5)
        F_L2 = luminance_factor(0.2 * base[..., 1])
        expo = jnp.exp(0.25 * jnp.log(F_L2 + 0.8))
        xyz = tc * jnp.exp(ln10 * detail_log * expo[..., None])
        # IPT (step 6)
        ipt = _mat(M_IPT, _spow(_mat(M_D65, xyz), IPT_EXPONENT))
        C2 = ipt[..., 1] ** 2 + ipt[..., 2] ** 2
        okc = C2 > 0
        C = jnp.where(okc, jnp.sqrt(jnp.where(okc, C2, 1.0)), 0.0)
        hunt = jnp.exp(HUNT_EXPONENT * jnp.log(F_L2 + 1.0)) * (
            (1.29 * C2 - 0.27 * C + 0.42) / (C2 - 0.31 * C + 0.42)
        )
        I = ipt[..., 0]
        gamma = SURROUND[self.surround]
        if gamma != 1.0:
            I_max = jnp.max(I)
            okI = I_max > 0
            r = quotient(I, jnp.where(okI, I_max, 1.0))
            I = jnp.where(okI, _spow(r, gamma) * I_max, I)
        ipt = jnp.stack([I, ipt[..., 1] * hunt, ipt[..., 2] * hunt], axis=-1)
        lms = _spow(_mat(np.linalg.inv(M_IPT), ipt), 1.0 / IPT_EXPONENT)
        return _mat(np.linalg.inv(M_D65), lms)


__all__ = ["Kuang2007", "luminance_factor", "replicate_matrix", "white_blur"]
