"""Perceptual fit targets: quality metrics of the rendition to maximise.

Numeric contract: as every target, these take the *display-referred linear RGB* an
operator returns (``(H, W, 3)``, nominally [0, 1]); values beyond display white are
clipped first, as a display would. Each metric ``m`` is at most 1 (1 for a perfect
rendition) and the residual is ``r = weight · (1 − m)``, so the least-squares loss
``Σ r² = weight² (1 − m)²`` falls as ``m`` rises: :func:`hdrjax.fit.fit` maximises the
metric, and the loss of :func:`hdrjax.study.sweep` maps it (``m = 1 − √loss / weight``).
The residual of a metric that is not reached (``m < 1``, the usual case) is not driven to
zero: the fit stops where the metric is stationary.

- :class:`TMQI`: the tone-mapped image quality index ``Q`` of Yeganeh & Wang (2013) of the
  rendition against the operator's input (:func:`hdrjax.metrics.tmqi`). It takes the
  source image (``takes_source``): the fit passes the image the operator was applied to.
- :class:`Naturalness`: TMQI's statistical naturalness ``N`` of the rendition alone.
- :class:`PUSSIM`: SSIM of PU21-encoded luminance (Mantiuk & Azimi 2021,
  :func:`hdrjax.metrics.pu_ssim`) against a reference rendition in cd/m², with the display
  image shown on a display of given peak and black level.

TMQI reads the rendition as display-*encoded* 8-bit values: the display image is clipped to
[0, 1], encoded with the sRGB transfer function of IEC 61966-2-1 (or ``x^(1/gamma)``) and
read as ``255 · v`` (not quantised, so that the metric has a gradient).
"""

from collections.abc import Callable
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jax.custom_derivatives import SymbolicZero
from jaxtyping import Array, Float

from .. import _check
from ..display import gamma_encode, srgb_encode
from ..metrics import PU21_PARAMETERS, pu_ssim, tmqi
from ._targets import AbstractTarget, as_float_array, display_array


def _encoded(display: Array, gamma: float | None) -> Array:
    """Display-encoded RGB in [0, 1] of the clipped display image; NaN where a channel of
    the display pixel is not finite (TMQI then leaves the pixel out of both images)."""
    display = display_array(display)
    finite = jnp.all(jnp.isfinite(display), axis=-1, keepdims=True)
    v = srgb_encode(display) if gamma is None else gamma_encode(display, gamma)
    return jnp.where(finite, v.astype(display.dtype), jnp.nan)


def _jvp_by_vjp(f: Callable[..., Array]) -> Callable[..., Array]:
    """``f(*arrays) -> (m,)`` with a JVP assembled from ``m`` reverse passes (vmapped):
    ``J = [vjp(e_i)]`` with respect to the arguments whose tangents are not zero, then
    ``ḟ = Σ ⟨J, ẋ⟩``. :func:`hdrjax.metrics.tmqi`'s zero-padded filters define only a
    reverse-mode derivative (a custom VJP), while :func:`hdrjax.fit.fit` differentiates
    residuals in forward mode; for a metric's few outputs of a whole image the reverse
    passes are also the cheaper way to its Jacobian."""

    @jax.custom_jvp
    def g(*args):
        return f(*args)

    def rule(primals, tangents):
        live = [i for i, t in enumerate(tangents) if not isinstance(t, SymbolicZero)]

        def of_live(*xs):
            args = list(primals)
            for i, x in zip(live, xs, strict=True):
                args[i] = x
            return f(*args)

        out, vjp = jax.vjp(of_live, *(primals[i] for i in live))
        if not live:
            return out, jnp.zeros_like(out)
        basis = jnp.eye(out.shape[0], dtype=out.dtype)
        # one output: a plain reverse pass (a vmap of one batches every op, slower to compile)
        rows = jax.vmap(vjp)(basis) if out.shape[0] > 1 else [r[None] for r in vjp(basis[0])]
        dot = [
            jnp.tensordot(r, tangents[i].astype(r.dtype), axes=tangents[i].ndim)
            for r, i in zip(rows, live, strict=True)
        ]
        return out, sum(dot[1:], dot[0]).astype(out.dtype)

    g.defjvp(rule, symbolic_zeros=True)
    return g


def _tmqi_scores(display: Array, source: Array, gamma: float | None) -> Array:
    """``(Q, S, N)`` of the encoded display image against the source."""
    ldr = _encoded(display, gamma)
    score = tmqi(source, ldr)
    return jnp.stack([score.q, score.s, score.n]).astype(ldr.dtype)


def _naturalness(display: Array, gamma: float | None) -> Array:
    """``(N,)`` of the encoded display image."""
    ldr = _encoded(display, gamma)
    # N depends on the LDR image alone (any HDR image will do); under jit the unused
    # structural fidelity is dead code
    return tmqi(ldr, ldr).n.astype(ldr.dtype)[None]


def _check_gamma(gamma: float | None) -> None:
    if gamma is not None:
        _check.positive(gamma, "gamma")


class TMQI(AbstractTarget):
    """Maximise the TMQI ``Q`` (Yeganeh & Wang 2013) of the rendition against the source.

    ``statistics = (Q, S, N)`` (quality, structural fidelity, statistical naturalness, each
    in [0, 1], from :func:`hdrjax.metrics.tmqi` of the source and the encoded display
    image); ``residuals = (weight · (1 − Q),)``. The source is the image the operator was
    given (linear RGB at any scale: TMQI normalises its luminance), of the display image's
    height and width; :func:`hdrjax.fit.fit`, :func:`~hdrjax.fit.fit_batch` (per frame),
    :func:`~hdrjax.fit.fit_sequence` and :func:`hdrjax.study.sweep` pass it.

    Attributes:
        weight: residual weight (1).
        gamma: ``None`` (default): sRGB encoding (IEC 61966-2-1) before TMQI reads the
            rendition as 8-bit values; a number ``γ``: ``x^(1/γ)``.

    Reference: H. Yeganeh and Z. Wang, "Objective quality assessment of tone-mapped images",
    IEEE TIP 22(2):657–667, 2013, https://doi.org/10.1109/TIP.2012.2221725.

    >>> import jax.numpy as jnp
    >>> hdr = jnp.exp(jnp.linspace(-4.0, 4.0, 16 * 16 * 3)).reshape(16, 16, 3)
    >>> curve = TMQI().statistics(hdr / (1 + hdr), source=hdr)  # (Q, S, N)
    >>> clipped = TMQI().statistics(jnp.clip(hdr, 0.0, 1.0), source=hdr)
    >>> bool(curve[0] > clipped[0]), bool(curve[1] > clipped[1])
    (True, True)
    """

    takes_source: ClassVar[bool] = True
    maximises: ClassVar[bool] = True

    weight: Array = eqx.field(default=1.0, converter=as_float_array)
    gamma: float | None = eqx.field(static=True, default=None)

    def __check_init__(self):
        _check_gamma(self.gamma)

    def statistics(
        self, display: Float[Array, "H W 3"], source: Float[Array, "H W 3"] | None = None
    ) -> Float[Array, " 3"]:
        return self._scores(display, source, 3)

    def residuals(
        self, display: Float[Array, "H W 3"], source: Float[Array, "H W 3"] | None = None
    ) -> Float[Array, " 1"]:
        return self.weight * (1 - self._scores(display, source, 1))

    def _scores(self, display: Array, source: Array | None, m: int) -> Array:
        """The first ``m`` of ``(Q, S, N)`` (the residual needs ``Q`` alone: one reverse
        pass for its forward-mode derivative instead of three)."""
        if source is None:
            raise ValueError(
                "source: TMQI needs the operator's input image (H, W, 3) to compare the"
                " rendition with, got None (hdrjax.fit and hdrjax.study.sweep pass it)"
            )
        display = display_array(display)
        gamma = self.gamma
        return _jvp_by_vjp(lambda d, s: _tmqi_scores(d, s, gamma)[:m])(display, source)


class Naturalness(AbstractTarget):
    """Maximise TMQI's statistical naturalness ``N`` (Yeganeh & Wang 2013) of the rendition.

    ``N = P_m P_d`` in [0, 1] of the encoded display image alone (its mean and mean 11×11
    block standard deviation against the models fitted to natural images; see
    :func:`hdrjax.metrics.tmqi`); ``statistics = (N,)``, ``residuals = (weight · (1 − N),)``.
    It needs no source image. Alone it rewards any rendition of natural mean and contrast,
    whatever the scene: combine it with a fidelity target (``TMQI``, ``PUSSIM``,
    ``Reference``) to keep the scene's structure.

    Attributes:
        weight: residual weight (1).
        gamma: ``None``: sRGB encoding; a number ``γ``: ``x^(1/γ)`` (as :class:`TMQI`).

    Reference: H. Yeganeh and Z. Wang, IEEE TIP 22(2):657–667, 2013,
    https://doi.org/10.1109/TIP.2012.2221725.
    """

    maximises: ClassVar[bool] = True

    weight: Array = eqx.field(default=1.0, converter=as_float_array)
    gamma: float | None = eqx.field(static=True, default=None)

    def __check_init__(self):
        _check_gamma(self.gamma)

    def statistics(self, display: Float[Array, "H W 3"]) -> Float[Array, " 1"]:
        gamma = self.gamma
        return _jvp_by_vjp(lambda d: _naturalness(d, gamma))(display_array(display))

    def residuals(self, display: Float[Array, "H W 3"]) -> Float[Array, " 1"]:
        return self.weight * (1 - self.statistics(display))


class PUSSIM(AbstractTarget):
    """Maximise the PU21 SSIM (Mantiuk & Azimi 2021) of the rendition, as a display shows
    it, against a reference rendition in cd/m².

    The display image (linear RGB, white = 1) is shown on a display of white ``peak`` and
    black level ``black`` (cd/m²): ``L = black + (peak − black) · clip(rgb, 0, 1)`` per
    channel; ``statistics = (pu_ssim(L, reference),)`` in [−1, 1]
    (:func:`hdrjax.metrics.pu_ssim`: each channel PU21-encoded, SSIM with an 11×11
    Gaussian window) and ``residuals = (weight · (1 − statistics),)``.

    The reference is *display-referred* linear RGB in cd/m², the light the fitted rendition
    should reproduce: e.g. a graded rendition as it appears on that display
    (``black + (peak − black) · rgb`` of a display image in [0, 1]), or an HDR rendition in
    absolute units for a brighter display. PU21 encodes 0.005–10000 cd/m²; darker and
    brighter values are clamped. It must have the shape of the image being fitted (after any
    downscaling: pass ``max_size=None`` to :func:`hdrjax.fit.fit`, or a reference
    box-filtered to the fit's size with :func:`hdrjax.fit.downscale`).

    Attributes:
        reference: display-referred linear RGB in cd/m², ``(H, W, 3)``.
        weight: residual weight (1).
        peak: display white, cd/m² (100: a typical SDR display).
        black: display black level, cd/m² (0.1: 1000:1 contrast).
        params: the PU21 parameter set (``"banding_glare"``, the authors' default).

    References: R. K. Mantiuk and M. Azimi, "PU21: A novel perceptually uniform encoding for
    adapting existing quality metrics for HDR", PCS 2021,
    https://doi.org/10.1109/PCS50896.2021.9477471; Z. Wang et al., IEEE TIP 13(4):600–612,
    2004, https://doi.org/10.1109/TIP.2003.819861.
    """

    maximises: ClassVar[bool] = True

    reference: Array = eqx.field(converter=as_float_array)
    weight: Array = eqx.field(default=1.0, converter=as_float_array)
    peak: float = eqx.field(static=True, default=100.0, converter=float)
    black: float = eqx.field(static=True, default=0.1, converter=float)
    params: str = eqx.field(static=True, default="banding_glare")

    def __check_init__(self):
        if self.reference.ndim != 3 or self.reference.shape[-1] != 3:
            raise ValueError(f"reference: expected (H, W, 3) in cd/m², got {self.reference.shape}")
        _check.positive(self.peak, "peak")
        if not 0.0 <= self.black < self.peak:
            raise ValueError(f"black: expected 0 <= black < peak ({self.peak}), got {self.black}")
        if self.params not in PU21_PARAMETERS:
            raise ValueError(
                f"params: expected one of {sorted(PU21_PARAMETERS)}, got {self.params!r}"
            )

    def luminance(self, display: Float[Array, "H W 3"]) -> Float[Array, "H W 3"]:
        """The light of each channel (cd/m²) the display shows for ``display``."""
        display = display_array(display)
        return self.black + (self.peak - self.black) * jnp.clip(display, 0.0, 1.0)

    def statistics(self, display: Float[Array, "H W 3"]) -> Float[Array, " 1"]:
        display = display_array(display)
        if display.shape != self.reference.shape:
            raise ValueError(
                f"display: expected the shape of the reference {self.reference.shape}, got"
                f" {display.shape} (a fit downscales the image: pass max_size=None or a"
                " reference box-filtered with hdrjax.fit.downscale)"
            )
        return pu_ssim(self.luminance(display), self.reference, params=self.params)[None]

    def residuals(self, display: Float[Array, "H W 3"]) -> Float[Array, " 1"]:
        return self.weight * (1 - self.statistics(display))


__all__ = ["PUSSIM", "TMQI", "Naturalness"]
