"""Budak & Petrovichev (2005)'s perceptual colour-contrast reproduction as a display step.

The model and its documented stand-ins live in the registered tone-mapping operator
:class:`hdrjax.operators.Budak2005` (``hdrjax tonemap --method budak2005``); this module's
:class:`Budak2005` adds the paper's display gamma (its Eqs. 5–6, ``L = C0 i^g``, signal
raised to ``1/g``) and returns display values, and passes the pixels it cannot re-adapt
(NaN/Inf channels) through unchanged.
"""

from collections.abc import Sequence

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._photometry import check_rgb, chroma_key, sanitize
from ..display import gamma_encode
from ..operators._budak2005 import (
    AbstractContrastSpace,
    Budak2005 as Budak2005Operator,
    ConeOpponentSpace,
)


class Budak2005(eqx.Module):
    """Budak & Petrovichev 2005's perceptual colour-contrast reproduction as a display step.

    ``__call__`` takes linear RGB in cd/m² and returns gamma-encoded display values in
    [0, 1]: :class:`hdrjax.operators.Budak2005` (coordinates in ``space`` relative to the
    scene background at ``adaptation``, inverse at the display background
    ``display_max/2``, division by ``display_max``, colours beyond the display's white
    rolled off towards white at their hue), then :func:`hdrjax.display.gamma_encode` (clip
    to [0, 1], power ``1/gamma``).

    Attributes:
        display_max: the display's maximum luminance, cd/m².
        gamma: display gamma (the paper's ``g``; it gives no value — 2.2 is the nominal
            display gamma of IEC 61966-2-1, sRGB).
        adaptation: scene adaptation luminance, cd/m² (``None``: ``exp(mean ln L)`` over
            the pixels inside 1e-7–1e5 cd/m²; the paper notes that the definition matters
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

    def operator(self) -> Budak2005Operator:
        """The tone-mapping operator this step applies (display-referred linear RGB)."""
        return Budak2005Operator(
            display_max=self.display_max,
            adaptation=self.adaptation,
            space=self.space,
            chromaticities=self.chromaticities,
        )

    def readapt(self, rgb: Float[ArrayLike, "H W 3"]) -> Float[Array, "H W 3"]:
        """Linear display RGB in cd/m² (before clipping and gamma)."""
        return _readapt(self, check_rgb(rgb, pooled=True))

    def __call__(self, rgb: Float[ArrayLike, "H W 3"]) -> Float[Array, "H W 3"]:
        """Display values in [0, 1]: :func:`hdrjax.display.gamma_encode` of the re-adapted
        image over ``display_max`` (it clips to [0, 1] and encodes NaN as 0)."""
        return _display(self, check_rgb(rgb, pooled=True))

    def _readapt(self, rgb: Array) -> Array:
        _, ok = sanitize(rgb)
        out = self.operator()(rgb) * jnp.asarray(self.display_max, rgb.dtype)
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


__all__ = ["Budak2005", "perceptual_reproduction"]
