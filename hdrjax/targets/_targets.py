"""Target statistics of a tone-mapped image, for :func:`hdrjax.fit.fit`.

Numeric contract: a target takes the *display-referred linear RGB* an operator returns
(``(H, W, 3)``, nominally [0, 1]) and returns a vector of statistics ``s`` and the residuals
``r = weight · (s − value)`` that a least-squares solver drives to zero. Every statistic is
differentiable with respect to the display image (and so to the operator's parameters):

- display luminance ``L_d = luminance(clip(rgb, 0, 1))`` (Rec. 709 weights by default):
  values beyond display white are clipped first, as a display would.
- percentiles are exact order statistics (partial selection with ``jax.lax.top_k`` for
  percentiles away from the median, else a sort), whose gradient is that of the interpolated
  order statistics; a full sort costs ~0.7 Mpixel/s on CPU, which is one reason
  :func:`hdrjax.fit.fit` works on a downscaled image by default.
- the clipped fraction and the histogram are *soft* (logistic steps of width ``softness``),
  so they have useful gradients; they converge to the hard counts as ``softness → 0``.

Non-finite display pixels (NaN input pixels) are excluded from every statistic.

Targets compose: ``t1 + t2`` concatenates residual vectors (a weighted sum of squared
residuals), ``2.0 * t`` scales a target's weight.

Targets that compare the display image with the operator's *input* (TMQI's structural
fidelity, :class:`hdrjax.targets.TMQI`) declare ``takes_source = True``: their
``statistics`` and ``residuals`` take that input image as the keyword ``source`` (the
image the operator was applied to, of the display image's height and width: in
:func:`hdrjax.fit.fit` and :func:`hdrjax.study.sweep` the downscaled input).
:meth:`AbstractTarget.statistics_for` and :meth:`AbstractTarget.residuals_for` pass it to
the targets that take it and call the others with the display image alone, so a target
written for the display image alone needs no change.
"""

import abc
from collections.abc import Sequence
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .. import _check, _repr
from .._colour import REC709_WEIGHTS, apply_matrix, luminance
from .._stats import percentile_by_selection, selection_range
from ..display import srgb_encode


def as_float_array(x: ArrayLike) -> Array:
    """``x`` as a JAX array; integers and bools in the default float."""
    x = jnp.asarray(x)
    if not jnp.issubdtype(x.dtype, jnp.floating):
        x = x.astype(jnp.result_type(float))
    return x


def _vec(x: ArrayLike) -> Array:
    return jnp.atleast_1d(as_float_array(x))


def display_array(rgb: ArrayLike) -> Array:
    """The display image as an array; half floats are computed in the default float."""
    _check.shape(rgb, "display")
    rgb = jnp.asarray(rgb)
    if rgb.dtype in (jnp.float16, jnp.bfloat16):
        rgb = rgb.astype(jnp.result_type(float))
    return rgb


def _display_luminance(rgb: Array, weights: tuple[float, float, float]) -> tuple[Array, Array]:
    """Clipped display luminance and the mask of finite pixels."""
    rgb = display_array(rgb)
    finite = jnp.all(jnp.isfinite(rgb), axis=-1)
    safe = jnp.where(finite[..., None], rgb, 0.0)
    return luminance(jnp.clip(safe, 0.0, 1.0), weights), finite


def _masked_mean(x: Array, mask: Array) -> Array:
    return jnp.sum(jnp.where(mask, x, 0.0)) / jnp.maximum(jnp.sum(mask), 1)


def _weights(w) -> tuple[float, float, float]:
    return tuple(float(v) for v in w)  # type: ignore[return-value]


class AbstractTarget(eqx.Module):
    """A vector of statistics of a display image and the values they should take.

    ``takes_source`` (a class variable, ``False`` here): ``True`` for targets whose
    ``statistics`` and ``residuals`` also take the operator's input image as the keyword
    ``source`` (see the module docstring); callers go through :meth:`statistics_for` and
    :meth:`residuals_for`, which pass it only to those.

    ``maximises`` (a class variable, ``False`` here): ``True`` for targets whose residual is
    ``weight · (1 − metric)`` of a quality metric that is maximised, not met: their loss
    keeps a positive minimum (see :func:`hdrjax.fit.fit`'s default solver).
    """

    __repr__ = _repr.fields_repr
    _repr_html_ = _repr.fields_html

    takes_source: ClassVar[bool] = False
    maximises: ClassVar[bool] = False

    def statistics_for(
        self, display: Float[Array, "H W 3"], source: Float[Array, "H W 3"] | None
    ) -> Float[Array, " n"]:
        """:meth:`statistics` of ``display``, made by an operator from ``source`` (passed to
        targets that take it)."""
        if self.takes_source:
            return self.statistics(display, source=source)  # type: ignore[call-arg]
        return self.statistics(display)

    def residuals_for(
        self, display: Float[Array, "H W 3"], source: Float[Array, "H W 3"] | None
    ) -> Float[Array, " m"]:
        """:meth:`residuals` of ``display``, made by an operator from ``source`` (passed to
        targets that take it)."""
        if self.takes_source:
            return self.residuals(display, source=source)  # type: ignore[call-arg]
        return self.residuals(display)

    @abc.abstractmethod
    def statistics(self, display: Float[Array, "H W 3"]) -> Float[Array, " n"]:
        """The statistics of one display image (display-referred linear RGB)."""

    @abc.abstractmethod
    def residuals(self, display: Float[Array, "H W 3"]) -> Float[Array, " m"]:
        """Residuals whose sum of squares is the loss (zero when the target is met)."""

    def __add__(self, other: "AbstractTarget") -> "Combined":
        if not isinstance(other, AbstractTarget):
            return NotImplemented
        return Combined(_parts(self) + _parts(other))

    def __mul__(self, scale: float) -> "Scaled":
        return Scaled(self, scale)

    __rmul__ = __mul__


def _parts(t: AbstractTarget) -> tuple[AbstractTarget, ...]:
    return t.targets if isinstance(t, Combined) else (t,)


class AbstractStatisticTarget(AbstractTarget):
    """A target whose residuals are ``weight · (statistics − value)``."""

    value: eqx.AbstractVar[Array]
    weight: eqx.AbstractVar[Array]

    def residuals(self, display: Float[Array, "H W 3"]) -> Float[Array, " n"]:
        s = self.statistics(display)
        return jnp.broadcast_to(self.weight, s.shape) * (s - jnp.broadcast_to(self.value, s.shape))


class MeanLuminance(AbstractStatisticTarget):
    """Mean display luminance: ``s = mean(L_d)`` with ``L_d`` the clipped display luminance.

    Attributes:
        value: the wanted mean, in display units [0, 1] (e.g. 0.18–0.4).
        weight: residual weight (1).
        weights: luminance weights (Rec. 709).

    >>> import jax.numpy as jnp
    >>> float(MeanLuminance(0.5).residuals(jnp.full((2, 2, 3), 0.25))[0])
    -0.25
    """

    value: Array = eqx.field(converter=as_float_array)
    weight: Array = eqx.field(default=1.0, converter=as_float_array)
    weights: tuple[float, float, float] = eqx.field(
        static=True, default=REC709_WEIGHTS, converter=_weights
    )

    def __check_init__(self):
        _check.in_range(self.value, "value", 0.0, 1.0)  # display luminance

    def statistics(self, display: Float[Array, "H W 3"]) -> Float[Array, " 1"]:
        L, finite = _display_luminance(display, self.weights)
        return _masked_mean(L, finite)[None]


class Percentiles(AbstractStatisticTarget):
    """Display-luminance percentiles: ``s_i = P_{q_i}(L_d)`` (linear interpolation between
    order statistics, as ``numpy.percentile``; pixels with ``L_d ≤ 0`` are excluded).

    Percentiles far from the median are found by partial selection instead of a full sort
    (:func:`hdrjax.stats.percentile_by_selection`: ``jax.lax.top_k`` over the few pixels
    that can hold them). The selection size is fixed when the target is built (from the
    concrete ``q``); a ``q`` changed later that falls outside it, or a selection larger than
    a quarter of the image, sorts instead. Both give the same values and gradients.

    Attributes:
        q: percentiles in [0, 100], e.g. ``(1, 99)``.
        value: the wanted display luminances, e.g. ``(0.02, 0.95)``.
        weight: residual weight(s) (1).
        weights: luminance weights (Rec. 709).
        select: ``(largest q below 50, smallest q from 50)`` served by partial selection,
            set from ``q`` at construction (``None``: always sort).
    """

    # field order: mypy reads the parent's abstract `weight` (given a default here) as
    # coming before `q`; the class has its own __init__, so the order binds no argument
    q: Array = eqx.field(converter=_vec)  # type: ignore[misc]
    value: Array = eqx.field(converter=_vec)
    weight: Array = eqx.field(default=1.0, converter=as_float_array)
    weights: tuple[float, float, float] = eqx.field(
        static=True, default=REC709_WEIGHTS, converter=_weights
    )
    select: tuple[float | None, float | None] | None = eqx.field(static=True, default=None)

    def __init__(
        self,
        q: ArrayLike,
        value: ArrayLike,
        weight: ArrayLike = 1.0,
        weights: Sequence[float] = REC709_WEIGHTS,
    ):
        self.q = _vec(q)
        self.value = _vec(value)
        self.weight = as_float_array(weight)
        self.weights = _weights(weights)
        self.select = selection_range(self.q)

    def __check_init__(self):
        _check.in_range(self.q, "q", 0.0, 100.0)
        if self.q.shape != self.value.shape:
            raise ValueError(
                f"q: expected one value per percentile, got q of shape {self.q.shape} and"
                f" value of shape {self.value.shape}"
            )

    def statistics(self, display: Float[Array, "H W 3"]) -> Float[Array, " n"]:
        L, finite = _display_luminance(display, self.weights)
        return percentile_by_selection(L, self.q, select=self.select, where=finite)


class ClippedFraction(AbstractStatisticTarget):
    """Soft fraction of pixels at or above display white:
    ``s = mean(σ((max_c rgb_c − threshold) / softness))`` with ``σ`` the logistic function.

    A pixel is "clipped" when any channel reaches ``threshold`` (1.0). ``softness`` (0.01, in
    display units) sets the width of the step; the hard count is the limit ``softness → 0``.

    Attributes:
        value: the wanted fraction in [0, 1] (e.g. 0.01).
        weight: residual weight (1).
        threshold: display value counted as clipped (1.0). softness: step width (0.01).
    """

    value: Array = eqx.field(converter=as_float_array)
    weight: Array = eqx.field(default=1.0, converter=as_float_array)
    threshold: float = eqx.field(static=True, default=1.0)
    softness: float = eqx.field(static=True, default=0.01)

    def __check_init__(self):
        _check.in_range(self.value, "value", 0.0, 1.0)  # a fraction of the pixels
        _check.positive(self.softness, "softness")

    def statistics(self, display: Float[Array, "H W 3"]) -> Float[Array, " 1"]:
        display = display_array(display)
        finite = jnp.all(jnp.isfinite(display), axis=-1)
        # channel max as two elementwise maxima: fuses with its consumers; the reduction's
        # JVP (an equality mask over the channel axis) made full-resolution fits ~4x slower
        m = jnp.maximum(jnp.maximum(display[..., 0], display[..., 1]), display[..., 2])
        m = jnp.where(finite, m, 0.0)
        step = jax.nn.sigmoid((m - self.threshold) / self.softness)
        return _masked_mean(step, finite)[None]


class Histogram(AbstractStatisticTarget):
    """Soft histogram of sRGB-encoded display luminance ``v = srgb_encode(L_d)``.

    ``s_k = mean(σ((v − e_k) / h) − σ((v − e_{k+1}) / h))`` for ``K`` equal bins with edges
    ``e_0 = 0 … e_K = 1`` (the outer edges are pushed out so every pixel counts) and
    ``h = softness / K``; the ``s_k`` sum to 1.

    Attributes:
        value: the wanted bin fractions, shape ``(K,)`` (normalised here to sum to 1).
        weight: residual weight (1).
        softness: step width as a fraction of a bin (0.5).
        weights: luminance weights (Rec. 709).
    """

    value: Array = eqx.field(converter=lambda v: _vec(v) / jnp.sum(_vec(v)))
    weight: Array = eqx.field(default=1.0, converter=as_float_array)
    softness: float = eqx.field(static=True, default=0.5)
    weights: tuple[float, float, float] = eqx.field(
        static=True, default=REC709_WEIGHTS, converter=_weights
    )

    def statistics(self, display: Float[Array, "H W 3"]) -> Float[Array, " K"]:
        L, finite = _display_luminance(display, self.weights)
        v = srgb_encode(L)
        k = self.value.shape[0]
        edges = jnp.linspace(0.0, 1.0, k + 1, dtype=v.dtype)
        edges = edges.at[0].set(-1e3).at[-1].set(1e3)
        h = self.softness / k
        cdf = jax.nn.sigmoid((v.reshape(-1, 1) - edges[None, :]) / h)  # (N, K+1)
        cdf = jnp.where(finite.reshape(-1, 1), cdf, 0.0)
        counts = jnp.sum(cdf[:, :-1] - cdf[:, 1:], axis=0)
        return counts / jnp.maximum(jnp.sum(finite), 1)


def _lab(rgb: Array) -> Array:
    """CIE 1976 L*a*b* (D65) of linear Rec. 709 RGB in [0, 1] (display white → L* = 100)."""
    m = jnp.asarray(
        [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]],
        rgb.dtype,
    )
    white = jnp.asarray([0.95047, 1.0, 1.08883], rgb.dtype)
    xyz = apply_matrix(rgb, m) / white.reshape((1,) * (rgb.ndim - 1) + (3,))
    d = 6.0 / 29.0
    pos = xyz > d**3
    f = jnp.where(pos, jnp.cbrt(jnp.where(pos, xyz, 1.0)), xyz / (3 * d * d) + 4.0 / 29.0)
    return jnp.stack(
        [116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])],
        axis=-1,
    )


class Reference(AbstractTarget):
    """Agreement with a reference display image (a camera JPEG decoded to linear, or another
    operator's output), pixel by pixel, in a perceptual-ish space.

    ``space="log"``: ``r = weight · (ln(eps + clip(rgb)) − ln(eps + ref)) / √N``;
    ``space="lab"``: ``r = weight · (Lab(clip(rgb)) − Lab(ref)) / (100 √N)`` (CIE 1976 L*a*b*,
    D65, the Rec. 709 → XYZ matrix of IEC 61966-2-1; divided by 100 to put L* in [0, 1]),
    over the ``N`` finite pixels, so the loss ``Σ r²`` is a mean squared error.
    ``statistics`` returns the root mean squared error.

    The reference must have the shape of the image being fitted (after any downscaling:
    pass ``max_size=None`` to :func:`hdrjax.fit.fit`, or a reference of the downscaled size).

    Attributes:
        reference: display-referred linear RGB, ``(H, W, 3)``, in [0, 1].
        weight: residual weight (1). space: ``"log"`` (default) or ``"lab"``.
        eps: offset of the logarithm (1/256).
    """

    reference: Array = eqx.field(converter=as_float_array)
    weight: Array = eqx.field(default=1.0, converter=as_float_array)
    space: str = eqx.field(static=True, default="log")
    eps: float = eqx.field(static=True, default=1.0 / 256.0)

    def __check_init__(self):
        if self.space not in ("log", "lab"):
            raise ValueError(f"space: expected 'log' or 'lab', got {self.space!r}")
        if self.reference.ndim != 3 or self.reference.shape[-1] != 3:
            raise ValueError(f"reference: expected (H, W, 3), got {self.reference.shape}")

    def _diff(self, display: Array) -> tuple[Array, Array]:
        if display.shape != self.reference.shape:
            raise ValueError(
                f"Reference: image {display.shape} and reference {self.reference.shape} differ"
            )
        display, reference = display_array(display), display_array(self.reference)
        finite = jnp.all(jnp.isfinite(display), axis=-1) & jnp.all(jnp.isfinite(reference), axis=-1)
        a = jnp.clip(jnp.where(finite[..., None], display, 0.0), 0.0, 1.0)
        b = jnp.clip(jnp.where(finite[..., None], reference, 0.0), 0.0, 1.0)
        if self.space == "log":
            d = jnp.log(self.eps + a) - jnp.log(self.eps + b)
        else:
            d = (_lab(a) - _lab(b)) / 100.0
        d = jnp.where(finite[..., None], d, 0.0)
        return d.reshape(-1), jnp.maximum(jnp.sum(finite), 1).astype(d.dtype)

    def residuals(self, display: Float[Array, "H W 3"]) -> Float[Array, " m"]:
        d, n = self._diff(display)
        return self.weight * d / jnp.sqrt(n)

    def statistics(self, display: Float[Array, "H W 3"]) -> Float[Array, " 1"]:
        d, n = self._diff(display)
        ms = jnp.sum(d * d) / n
        # the RMSE is |d|-like at a perfect match: use the subgradient 0 there, not ∞ (a fit
        # that reaches the reference exactly would otherwise report non-finite sensitivities)
        pos = ms > 0
        return jnp.where(pos, jnp.sqrt(jnp.where(pos, ms, 1.0)), 0.0)[None]


class Scaled(AbstractTarget):
    """A target with its residuals multiplied by ``scale`` (``scale * target``); ``source``
    is passed on to a target that takes it."""

    takes_source: ClassVar[bool] = True

    target: AbstractTarget
    scale: Array = eqx.field(converter=as_float_array)

    def statistics(
        self, display: Float[Array, "H W 3"], source: Float[Array, "H W 3"] | None = None
    ) -> Float[Array, " n"]:
        return self.target.statistics_for(display, source)

    def residuals(
        self, display: Float[Array, "H W 3"], source: Float[Array, "H W 3"] | None = None
    ) -> Float[Array, " m"]:
        return self.scale * self.target.residuals_for(display, source)


class Combined(AbstractTarget):
    """Several targets at once: statistics and residuals are concatenated, so the loss is
    the sum of the parts' losses (``t1 + t2``; weight each with ``w * t``). ``source`` is
    passed on to the parts that take it."""

    takes_source: ClassVar[bool] = True

    targets: tuple[AbstractTarget, ...]

    def __init__(self, targets: Sequence[AbstractTarget]):
        targets = tuple(targets)
        if not targets or not all(isinstance(t, AbstractTarget) for t in targets):
            raise ValueError("Combined: expected one or more targets")
        self.targets = targets

    def statistics(
        self, display: Float[Array, "H W 3"], source: Float[Array, "H W 3"] | None = None
    ) -> Float[Array, " n"]:
        return jnp.concatenate([t.statistics_for(display, source) for t in self.targets])

    def residuals(
        self, display: Float[Array, "H W 3"], source: Float[Array, "H W 3"] | None = None
    ) -> Float[Array, " m"]:
        return jnp.concatenate([t.residuals_for(display, source) for t in self.targets])


__all__ = [
    "AbstractStatisticTarget",
    "AbstractTarget",
    "ClippedFraction",
    "Combined",
    "Histogram",
    "MeanLuminance",
    "Percentiles",
    "Reference",
    "Scaled",
]
