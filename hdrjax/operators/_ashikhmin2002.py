"""Ashikhmin 2002 tone mapping: a local adaptation luminance and the perceptual capacity.

Reference:
    M. Ashikhmin. "A tone mapping algorithm for high contrast images." Proceedings of the
    13th Eurographics Workshop on Rendering (EGWR 2002), 145–156.
    https://doi.org/10.2312/EGWR/EGWR02/145-156

The steps, with ``L`` the luminance (Rec. 709 weights) in cd/m²:

1. Local adaptation: Gaussian-blurred luminances ``L_s`` at scales ``s = 1 … s_max`` and
   their normalised differences ``lc_s = |L_s − L_2s| / L_s``; the adaptation luminance
   ``L_a`` is ``L_s`` of the largest ``s`` whose ``lc_s`` is below the threshold (0.5),
   ``L_{s_max}`` where none is (a pixel whose ``L_s`` is 0 counts as below the threshold).
2. Tone mapping of the adaptation luminance by the paper's perceptual capacity ``C`` (the
   integral of ``1 / TVI`` of its threshold-versus-intensity model):
   ``C(L) = L / 0.0014`` below 0.0034 cd/m², ``2.4483 + ln(L / 0.0034) / 0.4027`` up to
   1 cd/m², ``16.563 + (L − 1) / 0.4027`` up to 7.2444 cd/m² and
   ``32.0693 + ln(L / 7.2444) / 0.0556`` above; the world's range ``L_min … L_max`` maps
   linearly in capacity to ``0 … L_dmax`` (in units of 100 cd/m²):
   ``TM(L_a) = (L_dmax / 100) (C(L_a) − C(L_min)) / (C(L_max) − C(L_min))``.
3. Detail: ``L_d = TM(L_a) · L / L_a``; colour kept, ``C_out = C · L_d / L =
   C · TM(L_a) / L_a`` (0 where ``L_a = 0``).

The blurs and constants are those of HDR Toolbox's ``AshikhminTMO`` (the reference peer):
the blur of scale ``s`` is MATLAB's ``fspecial('gaussian', w, s / 5)``, ``w`` the odd
number at or above ``max(round(s), 3)``, with the image's edge pixels replicated
(``imfilter(..., 'replicate')``), and ``L_min``, ``L_max`` are robust extremes (the
0.05th and 99.95th percentiles).

Deviation from HDR Toolbox, argued: it takes the robust extremes of the *adaptation*
luminance ``L_a``; here those of the luminance ``L`` itself, the world's range of the
paper's tone-mapping function, which also makes them mergeable statistics (tiles, chunks
and frames give the whole image's values without a second pass through the filters).
Where a small light source is in view the two differ widely (the blurs spread it over its
neighbours: 55 300 against 4 720 cd/m² for the upper end on a downscaled rooitou_park,
whose output is then darker here); elsewhere they are close. Pixels whose
input is NaN or ±Inf take no part in the blurs (normalised convolutions), so they reach
no neighbour.

Tiles: each pixel reads the pixels within the largest blur's radius (10 for
``s_max = 10``; :meth:`Ashikhmin2002.halo`), and the edge replication happens at the true
image edges in every window, so :func:`hdrjax.tile.apply` gives the whole image's result
to float rounding.
"""

import math
from typing import ClassVar, Literal

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._scale import inverse_pow2, quotient
from .._stats import Statistics
from ._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    checked_statistics,
    estimated,
    fill,
    parameter,
    register,
    weights_field,
)

REFERENCE = (
    "Ashikhmin 2002, A tone mapping algorithm for high contrast images, Eurographics"
    " Workshop on Rendering 2002, 145-156, https://doi.org/10.2312/EGWR/EGWR02/145-156"
)
LOW, HIGH = 0.0005, 0.9995
"""Quantiles of the luminance taken as the world's range ``L_min``, ``L_max``."""
CAPACITY = (
    # (lower end of the segment in cd/m², offset, slope, logarithmic?)
    (0.0, 0.0, 1.0 / 0.0014, False),
    (0.0034, 2.4483, 1.0 / 0.4027, True),
    (1.0, 16.5630, 1.0 / 0.4027, False),
    (7.2444, 32.0693, 1.0 / 0.0556, True),
)
"""The paper's perceptual capacity ``C(L)``, piecewise linear in ``L`` or ``ln L``."""


def capacity(L: Array) -> Array:
    """The perceptual capacity ``C(L)`` of luminance ``L`` in cd/m² (module docstring,
    step 2): the number of just-noticeable differences from 0 to ``L``."""
    out = jnp.zeros_like(L)
    for lo, offset, slope, log in CAPACITY:
        if log:
            x = jnp.log(jnp.where(L >= lo, L, lo) / lo)
        else:
            x = L - lo
        out = jnp.where(L >= lo, offset + slope * x, out)
    return out


def gaussian_taps(window: float) -> np.ndarray:
    """1-D factor of HDR Toolbox's blur of ``window``: MATLAB's ``fspecial('gaussian', w,
    window / 5)`` with ``w`` the odd number at or above ``max(round(window), 3)`` (the 2-D
    kernel is the outer product of these taps, which sum to 1)."""
    w = max(int(math.floor(window + 0.5)), 3)
    w += 1 - w % 2
    x = np.arange(w) - (w - 1) / 2
    g = np.exp(-(x**2) / (2.0 * (window / 5.0) ** 2))
    return g / g.sum()


def replicate_blurs(x: Array, windows: tuple[float, ...]) -> Array:
    """HDR Toolbox's blurs of ``x`` (``(N, H, W)``) for each of ``windows``, the image's edge
    pixels replicated (MATLAB's ``imfilter(x, h' * h, 'replicate')`` with ``h`` of
    :func:`gaussian_taps`): ``(N, len(windows), H, W)``.

    One separable convolution with a kernel per window (zero taps beyond a window's width
    up to the widest), so that the compiled program holds two convolutions whatever the
    number of windows."""
    taps = [gaussian_taps(w) for w in windows]
    r = max(len(t) for t in taps) // 2
    k = np.zeros((len(taps), 2 * r + 1))
    for i, t in enumerate(taps):
        k[i, r - len(t) // 2 : r + len(t) // 2 + 1] = t
    k = jnp.asarray(k, x.dtype)
    p = jnp.pad(x, ((0, 0), (r, r), (r, r)), mode="edge")[:, None]
    hi = jax.lax.Precision.HIGHEST
    dims = ("NCHW", "OIHW", "NCHW")
    rows = jax.lax.conv_general_dilated(
        p, k[:, None, :, None], (1, 1), "VALID", dimension_numbers=dims, precision=hi
    )
    return jax.lax.conv_general_dilated(
        rows,
        k[:, None, None, :],
        (1, 1),
        "VALID",
        dimension_numbers=dims,
        feature_group_count=len(taps),
        precision=hi,
    )


def masked_blurs(x: Array, mask: Array | None, windows: tuple[float, ...]) -> Array:
    """:func:`replicate_blurs` of ``x`` (``(H, W)``) over the pixels where ``mask`` (a
    normalised convolution; ``None``: every pixel): ``(len(windows), H, W)``. A window with
    no such pixel gives 0."""
    if mask is None:
        return replicate_blurs(x[None], windows)[0]
    m = mask.astype(x.dtype)
    num, den = replicate_blurs(jnp.stack([x * m, m]), windows)
    ok = den > 0
    return jnp.where(ok, quotient(num, jnp.where(ok, den, 1.0)), 0.0)


def adaptation_luminance(L: Array, mask: Array | None, *, s_max: int, threshold: float) -> Array:
    """The adaptation luminance ``L_a`` of ``L`` (``(H, W)``, any units: the selection
    depends only on ratios) by the scale selection of the module docstring, step 1."""
    windows = tuple(
        sorted({float(s) for s in range(1, s_max + 1)} | {2.0 * s for s in range(1, s_max + 1)})
    )
    blurred = dict(zip(windows, masked_blurs(L, mask, windows), strict=True))
    La = blurred[float(s_max)]
    for s in range(1, s_max + 1):
        Ls = blurred[float(s)]
        below = (Ls == 0) | (jnp.abs(Ls - blurred[2.0 * s]) < threshold * Ls)
        La = jnp.where(below, Ls, La)
    return La


@register("ashikhmin2002")
class Ashikhmin2002(AbstractOperator):
    """Ashikhmin 2002 tone mapping (module docstring) with HDR Toolbox's defaults
    (``AshikhminTMO``: ``L_dmax = 100`` cd/m², the local version, ``s_max = 10``, threshold
    0.5).

    Input: linear RGB in cd/m² (the capacity is a function of absolute luminance). Output:
    display-referred linear RGB, the adaptation luminance's capacity range mapped to
    ``[0, L_dmax / 100]`` and multiplied by the detail ``L / L_a`` (so details of bright
    regions exceed 1, clipped by the display; pixels whose ``L_a`` lies outside the robust
    range fall outside ``[0, L_dmax / 100]``).

    Attributes:
        L_dmax: the display's maximum luminance in cd/m²; output 1 is 100 cd/m².
        L_min, L_max: the world's luminance range (the 0.05th and 99.95th percentiles of
            the luminance); ``None`` → measured.
        adaptation: ``"local"`` (the scale selection) or ``"global"`` (``L_a = L``, the
            paper's global version).
        s_max: the largest blur scale (10).
        threshold: the largest normalised difference ``|L_s − L_2s| / L_s`` of a scale the
            adaptation may take (0.5).
        weights: the luminance weights (Rec. 709).
    """

    reference: ClassVar[str] = REFERENCE
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_dmax",)

    L_dmax: Array = parameter(
        100.0,
        help="the display's maximum luminance (output 1 is 100 cd/m2)",
        unit="cd/m2",
        range="(0, inf)",
    )
    L_min: Array | None = estimated(
        "the world's lowest luminance (0.05th percentile); None: measured",
        pooling="log_mean",
        unit="cd/m2",
        range="[0, inf)",
    )
    L_max: Array | None = estimated(
        "the world's highest luminance (99.95th percentile); None: measured",
        pooling="log_mean",
        unit="cd/m2",
        range="[0, inf)",
    )
    adaptation: Literal["local", "global"] = parameter(
        "local",
        help="the adaptation luminance: local (the scale selection) or global (L_a = L)",
        static=True,
        choices=("local", "global"),
    )
    s_max: int = parameter(
        10, help="the largest blur scale of the adaptation", range="[1, inf)", static=True
    )
    threshold: float = parameter(
        0.5,
        help="the largest normalised difference |L_s - L_2s| / L_s of an adaptation scale",
        range="(0, inf)",
        static=True,
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        if int(self.s_max) != self.s_max or self.s_max < 1:
            raise ValueError(f"s_max: expected an integer >= 1, got {self.s_max!r}")
        if not self.threshold > 0:
            raise ValueError(f"threshold: expected a value in (0, inf), got {self.threshold!r}")

    def halo(self, shape: tuple[int, ...]) -> tuple[int, int]:
        """The largest blur's radius (that of scale ``2 s_max``: 10 pixels for
        ``s_max = 10``), 0 for the global one; at most half the image per axis, where
        every window is the whole image anyway."""
        if self.adaptation == "global":
            return 0, 0
        r = len(gaussian_taps(2 * self.s_max)) // 2
        return min(r, -(-int(shape[0]) // 2)), min(r, -(-int(shape[1]) // 2))

    def statistics_settings(self) -> StatisticsSettings | None:
        return StatisticsSettings() if self.unset() else None

    def bind(self, stats: Statistics | None) -> "Ashikhmin2002":
        if not self.unset():
            return self
        raw = checked_statistics(self, stats)
        dt = raw.min_positive.dtype
        # the ranks run over every finite pixel; those below the smallest normal float
        # (L = 0) lie under the histogram of the positive ones
        n_fin = raw.n_finite.astype(dt)
        n_dark = n_fin - raw.n_positive.astype(dt)
        rank = jnp.array([LOW, HIGH], dt) * n_fin - n_dark
        frac = jnp.clip(rank / jnp.maximum(raw.n_positive, 1).astype(dt), 0.0, 1.0)
        q, _ = raw.quantile(jax.lax.stop_gradient(frac))
        q = jnp.where(jnp.isnan(q) | (rank < 0), 0.0, q)
        measured = dict(L_min=q[0], L_max=jnp.maximum(q[1], q[0]))
        return fill(self, **{k: v for k, v in measured.items() if getattr(self, k) is None})

    def _apply(self, p: Prepared) -> Array:
        assert self.L_min is not None and self.L_max is not None
        dt = p.rgb.dtype
        L = jnp.maximum(p.L, 0.0)
        if self.adaptation == "local":
            # blurred at a power-of-two scale with its maximum near 1 (exact; no sum of
            # values near the float maximum overflows)
            c = inverse_pow2(jnp.max(L))
            mask = None if p.clean else p.valid()
            La_c = adaptation_luminance(L * c, mask, s_max=self.s_max, threshold=self.threshold)
            # (a blur of pixels at the float maximum may round above it)
            La = jnp.minimum(La_c / c, jnp.finfo(dt).max)
        else:
            c = jnp.ones((), dt)
            La_c = La = L
        C_lo = capacity(self.L_min.astype(dt))
        span = capacity(self.L_max.astype(dt)) - C_lo
        span = jnp.where(span > 0, span, 1.0)
        tm = (self.L_dmax.astype(dt) / 100.0) * (capacity(La) - C_lo) / span
        ok = La_c > 0
        # C · TM(L_a) / L_a, as (C c) / (L_a c): both sides at the blur's scale
        gain = jnp.where(ok, quotient(tm, jnp.where(ok, La_c, 1.0)), 0.0)
        return p.rgb * c * gain[..., None]


__all__ = ["Ashikhmin2002", "adaptation_luminance", "capacity", "gaussian_taps", "masked_blurs"]
