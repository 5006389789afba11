"""Reinhard & Devlin 2005 photoreceptor operator, with pfstmo's parameters and defaults.

Reference:
    Reinhard, Devlin. "Dynamic range reduction inspired by photoreceptor physiology."
    IEEE TVCG 11(1), 2005. https://doi.org/10.1109/TVCG.2005.9

Per channel ``C`` of R, G, B, with ``L`` the pixel's luminance:
    ``V = C / (C + σ)``, ``σ = (e^−f I_a)^m`` (the photoreceptor response),
    ``I_a = l I_local + (1 − l) I_global`` (light adaptation ``l``),
    ``I_local = c C + (1 − c) L``, ``I_global = c C_av + (1 − c) L_av`` (chromatic
    adaptation ``c``; ``C_av`` the channel means, ``L_av`` the mean luminance).
Automatic contrast (``m = None``): ``m = 0.3 + 0.7 k^1.4`` from the key
    ``k = (ln L_max − ln L̄) / (ln L_max − ln L_min)``, ``L̄ = exp(mean(ln(L + δ)))``.
Normalisation: ``(V − V_min) / (V_max − V_min)``, ``V_min`` and ``V_max`` the smallest and
largest response over the image's pixels and channels.

:func:`photoreceptor` is the response both this module and :class:`Reinhard2004` (colour-hdri's
version of the same paper) evaluate; they differ in what they feed it (the class docstrings).
"""

from typing import Any, ClassVar, Literal

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._scale import quotient
from .._srgb import srgb_decode
from .._stats import Statistics
from ._base import (
    AbstractOperator,
    Prepared,
    StatisticsSettings,
    checked_statistics,
    estimated,
    fill,
    max_luminance,
    parameter,
    register,
    statistics_of,
    weights_field,
)

REFERENCE = (
    "Reinhard, Devlin 2005, Dynamic range reduction inspired by photoreceptor physiology,"
    " IEEE TVCG 11(1), https://doi.org/10.1109/TVCG.2005.9"
)
PFSTMO_DELTA = 2.3e-5
"""pfstmo's offset inside the log-average of the automatic contrast (``ln(2.3e-5 + L)``)."""


def photoreceptor(rgb: Array, I_local: Array, I_global: Array, a: Array, f: Array, m: Array):
    """Reinhard & Devlin 2005's response ``V = C / (C + (e^−f I_a)^m)`` of each channel ``C``
    of ``rgb`` (``≥ 0``), ``I_a = a I_local + (1 − a) I_global``.

    Evaluated as ``C' / (C' + σ')`` with ``C' = C / s`` and ``σ' = exp(m (ln I_a − f) −
    ln s)``, ``s`` the channel's global adaptation level: ``e^−f I_a`` and ``σ`` overflow
    for bright images (``f = −8`` multiplies by 2981) and underflow for dim ones, while
    ``C'`` and ``σ'`` stay near the image's contrast range; two transcendental functions
    per value. ``C ≤ 0`` gives 0; ``I_a ≤ 0`` (no light to adapt to) gives ``σ = 0``, so 1.
    """
    I_a = a * I_local + (1 - a) * I_global
    # (a channel sum that overflowed leaves I_global = +Inf: s is then the largest float)
    s = jnp.where(I_global > 0, jnp.minimum(I_global, jnp.finfo(rgb.dtype).max), 1.0)
    lit, adapted = rgb > 0, I_a > 0
    ln_a = jnp.log(jnp.where(adapted, I_a, 1.0))
    sigma = jnp.where(adapted, jnp.exp(m * (ln_a - f) - jnp.log(s)), 0.0)
    c = rgb * quotient(jnp.ones_like(s), s)  # (no 1 / s² in the derivative: dim images)
    den = c + sigma
    return jnp.where(lit, c / jnp.where(lit, den, 1.0), 0.0)


def automatic_contrast(log_average: Array, L_min: Array, L_max: Array) -> Array:
    """The paper's ``m = 0.3 + 0.7 k^1.4`` with the key ``k = (ln L_max − ln L̄) /
    (ln L_max − ln L_min)`` (``L̄`` the log-average), clipped to ``[0, 1]``; ``k = 0`` when
    ``L_min ≤ 0`` (its limit as ``ln L_min → −∞``, as pfstmo computes it) or when the image
    has a single value."""
    ln_max = jnp.log(L_max)
    has_min = L_min > 0
    ln_min = jnp.log(jnp.where(has_min, L_min, 1.0))
    span = ln_max - ln_min
    ok = has_min & (span > 0)
    k = jnp.clip((ln_max - jnp.log(log_average)) / jnp.where(ok, span, 1.0), 0.0, 1.0)
    k = jnp.where(ok, k, 0.0)
    pos = k > 0
    return 0.3 + 0.7 * jnp.where(pos, jnp.exp(1.4 * jnp.log(jnp.where(pos, k, 1.0))), 0.0)


_BLOCK = 4096 * 3


def _extremes(for_min: Array, for_max: Array) -> tuple[Array, Array]:
    """``(min(for_min), max(for_max))`` over all elements. XLA:CPU reduces an image to a
    scalar one element after another; reduced first down the columns of ``(-1, 12288)``
    blocks, 12288 contiguous lanes at once, the range pass is about 2.5 times faster
    (2048 × 1024 RGB, CPU time)."""
    n = for_min.size
    if n % _BLOCK or n < 2 * _BLOCK:
        return jnp.min(for_min), jnp.max(for_max)
    lo = jnp.min(jnp.min(for_min.reshape(-1, _BLOCK), axis=0))
    hi = jnp.max(jnp.max(for_max.reshape(-1, _BLOCK), axis=0))
    return lo, hi


def channel_average_field() -> Any:
    """The mean of each channel (the photoreceptor operators' chromatic adaptation)."""
    return estimated(
        "mean of each channel (R, G, B); None: measured",
        unit="image units",
        range="[0, inf)",
        pooling="mean",
        shape=(3,),
    )


def luminance_range_fields() -> tuple[Any, Any]:
    """``L_min``, ``L_max`` as the photoreceptor operators' automatic contrast uses them."""
    low = estimated(
        "smallest luminance (automatic m); None: measured",
        unit="image units",
        range="[0, inf)",
        pooling="min",
    )
    high = estimated(
        "largest luminance (automatic m); None: measured", unit="image units", pooling="max"
    )
    return low, high


def fill_photoreceptor_statistics(op: Any, stats: Statistics | None) -> Any:
    """``op`` with those of ``channel_average``, ``log_average``, ``L_min`` and ``L_max``
    that are ``None`` filled from ``stats`` (the photoreceptor operators' statistics)."""
    stats = checked_statistics(op, stats)
    st = stats.luminance_stats()
    measured = {
        "channel_average": stats.channel_average if op.channel_average is None else None,
        "log_average": st.log_average,
        "L_min": st.min,
        "L_max": max_luminance(st),
    }
    return fill(op, **{k: v for k, v in measured.items() if getattr(op, k) is None})


@register("reinhard2005")
class Reinhard2005(AbstractOperator):
    """Reinhard & Devlin 2005 photoreceptor operator with pfstmo's parameters and defaults
    (``pfstmo_reinhard05``): brightness ``f``, chromatic adaptation ``c``, light adaptation
    ``l``, automatic contrast ``m`` (module docstring for the equations).

    Input: linear RGB, relative or absolute (only ``delta``, an absolute offset inside the
    automatic contrast's log-average, depends on the scale). Output: display-referred linear
    RGB in [0, 1], the normalised response ``V``.

    Differences from ``reinhard2004`` (:class:`~hdrjax.operators.Reinhard2004`), which
    reproduces colour-hdri's version of the same paper:

    - names and defaults: light adaptation is ``l`` here (0.75), ``a`` there (0); chromatic
      adaptation ``c`` 0.5 here, 0 there; ``m`` automatic here, 0.3 there;
    - ``I_local = c C + (1 − c) L`` here (the paper), ``(c C + 1 − c) L`` there;
    - ``L_av`` in ``I_global`` is the mean luminance here (pfstmo), the log-average there;
    - automatic contrast: ``0.3 + 0.7 k^1.4`` with ``k`` the paper's ratio of logarithms
      here; colour-hdri subtracts the linear log-average from ``ln L_max`` and raises only
      the denominator to 1.4;
    - the response is stretched to [0, 1] here, by its extremes over the image's pixels and
      channels as pfstmo does (HDR Toolbox, whose documentation attributes the step to the
      paper, stretches the luminance of ``V`` instead), not there.

    ``compat="pfstmo"`` reproduces where pfstmo departs from the paper in a way a user would
    not expect: pfstmo hands the normalised ``V`` on as *sRGB-encoded* values (its
    sRGB-to-XYZ conversion decodes them), so its linear output is ``sRGB⁻¹(V)``, several
    times darker in the mid-tones than ``V``; the default (``"paper"``) returns ``V`` as
    display-linear values, to be encoded for the display as every operator's output is,
    as colour-hdri, Banterle's HDR Toolbox and ``reinhard2004`` do. Departures from
    pfstmo not reproduced: its sums skip the first pixel (and divide by all of them), which
    moves its results by up to 6e-5 (sRGB-encoded) on a 128 × 64 image, less on larger
    ones; pixels whose luminance is exactly 0 are left out of its ``V`` range; negative
    values make its statistics NaN (clamped to 0 here). Its manual page gives ``c = 0``,
    ``l = 1`` as defaults; the program uses 0.5 and 0.75, as here.

    The normalisation reads the whole mapped image: with ``V_min`` or ``V_max`` unset the
    operator is not pointwise (:meth:`halo` is infinite: no tiles or chunks); an operator
    from :meth:`measure` has them set and maps tiles, chunks or frames as the whole image.
    Frames of a sequence each normalise by their own range unless they are given.

    Attributes:
        f: brightness, ``e^−f`` multiplies the adaptation level (−8 … 8; 0).
        c: chromatic adaptation, 0: to luminance, 1: per channel (von Kries) (0.5).
        l: light adaptation, 0: to the image average, 1: to the pixel (0.75).
        m: contrast ``σ``'s exponent; ``None`` → automatic from the key (0.3 … 1).
        channel_average: mean of each channel (``C_av``; ``L_av = weights · C_av``).
        log_average, L_min, L_max: the key's statistics (automatic ``m`` only).
        V_min, V_max: responses mapped to 0 and 1; ``None`` → the mapped image's extremes.
        delta: offset inside the log-average (pfstmo's 2.3e-5, image units).
        compat: ``"paper"`` or ``"pfstmo"`` (see above).
        weights: luminance weights of the image's primaries.
    """

    reference: ClassVar[str] = REFERENCE
    default_fit_params: ClassVar[tuple[str, ...]] = ("m",)  # f can be ≤ 0: no log-space fit
    only_feeds: ClassVar[dict[str, str]] = {"log_average": "m", "L_min": "m", "L_max": "m"}

    f: Array = parameter(0.0, help="brightness: e^-f scales the adaptation level", range="[-8, 8]")
    c: Array = parameter(
        0.5, help="chromatic adaptation (0: to luminance, 1: per channel)", range="[0, 1]"
    )
    l: Array = parameter(  # noqa: E741 (pfstmo's name)
        0.75, help="light adaptation (0: to the image average, 1: to the pixel)", range="[0, 1]"
    )
    m: Array | None = estimated(
        "contrast (exponent of the adaptation term); None: 0.3 + 0.7 k^1.4 from the key k",
        range="(0, 1]",
        pooling="mean",
    )
    channel_average: Array | None = channel_average_field()
    log_average: Array | None = estimated(
        "log-average luminance of the key (automatic m); None: measured with delta",
        unit="image units",
        pooling="log_mean",
    )
    L_min: Array | None = luminance_range_fields()[0]
    L_max: Array | None = luminance_range_fields()[1]
    V_min: Array | None = parameter(
        None, help="response mapped to 0; None: the mapped image's smallest", range="[0, inf)"
    )
    V_max: Array | None = parameter(
        None, help="response mapped to 1; None: the mapped image's largest", range="[0, inf)"
    )
    delta: float = parameter(
        PFSTMO_DELTA,
        help="offset inside the key's log-average (pfstmo's 2.3e-5)",
        unit="image units",
        range="[0, inf)",
        static=True,
    )
    compat: Literal["paper", "pfstmo"] = parameter(
        "paper",
        help="paper: V is display-linear; pfstmo: V is sRGB-encoded (pfstmo_reinhard05)",
        static=True,
        choices=("paper", "pfstmo"),
    )
    weights: tuple[float, float, float] = weights_field()

    _STATISTICS: ClassVar[tuple[str, ...]] = (
        "m",
        "channel_average",
        "log_average",
        "L_min",
        "L_max",
    )

    def _unmeasured(self) -> tuple[str, ...]:
        return tuple(n for n in self._STATISTICS if getattr(self, n) is None)

    def statistics_settings(self) -> StatisticsSettings | None:
        if not self._unmeasured():
            return None
        return StatisticsSettings(delta=self.delta, channels=self.channel_average is None)

    def bind(self, stats: Statistics | None) -> "Reinhard2005":
        """Fills the parameters measured from image statistics; ``V_min`` and ``V_max``,
        which are extremes of the *output*, are left to :meth:`measure` or the call."""
        if not self._unmeasured():
            return self
        op = fill_photoreceptor_statistics(self, stats)
        if op.m is None:
            op = fill(op, m=automatic_contrast(op.log_average, op.L_min, op.L_max))
        return op

    def _measure(self, p: Prepared) -> "Reinhard2005":
        op = self.bind(statistics_of(p, self.statistics_settings()))
        if op.V_min is not None and op.V_max is not None:
            return op
        V = op._response(p)
        if p.clean:
            lo, hi = _extremes(V, V)
        else:
            valid = p.valid()[..., None]
            lo, hi = _extremes(jnp.where(valid, V, jnp.inf), jnp.where(valid, V, -jnp.inf))
        spread = hi > lo  # no spread (one value, or no finite pixel): V as it is
        measured = {"V_min": jnp.where(spread, lo, 0.0), "V_max": jnp.where(spread, hi, 1.0)}
        return fill(op, **{k: v for k, v in measured.items() if getattr(op, k) is None})

    def _response(self, p: Prepared) -> Array:
        """``V`` of every channel (statistics set)."""
        rgb = jnp.maximum(p.rgb, 0.0)
        L = jnp.maximum(p.L, 0.0)[..., None]
        C_av = self.channel_average.reshape((1,) * (rgb.ndim - 1) + (3,))
        L_av = jnp.sum(self.channel_average * np.asarray(self.weights_, rgb.dtype))
        I_local = self.c * rgb + (1 - self.c) * L
        I_global = self.c * C_av + (1 - self.c) * L_av
        return photoreceptor(rgb, I_local, I_global, self.l, self.f, self.m)

    def _apply(self, p: Prepared) -> Array:
        assert self.V_min is not None and self.V_max is not None
        V = self._response(p)
        spread = self.V_max > self.V_min
        lo = jnp.where(spread, self.V_min, 0.0)
        out = (V - lo) / jnp.where(spread, self.V_max - lo, 1.0)
        if self.compat == "pfstmo":
            out = srgb_decode(out).astype(out.dtype)
        return out

    def halo(self, shape: tuple[int, ...]) -> tuple[float, float]:
        """0 once ``V_min`` and ``V_max`` are set; else the whole image (infinite)."""
        del shape
        if self.V_min is None or self.V_max is None:
            return (float("inf"), float("inf"))
        return (0, 0)


__all__ = ["PFSTMO_DELTA", "Reinhard2005", "automatic_contrast", "photoreceptor"]
