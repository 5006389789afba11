"""Contrast-sensitivity scaling: match threshold visibility between scene and display.

A scene at world adaptation ``L_wa`` shown on a display adapted to ``L_da`` keeps the
visibility of just-noticeable differences when world luminance is multiplied by
``m = ΔL(L_da) / ΔL(L_wa)`` (the ratio of threshold increments): Ward 1994 with the
Blackwell threshold, or Radiance pcond's ``-s`` linear mode with the Ferwerda-based
combined TVI (``htcontrs``). The result is *display* luminance in cd/m²; show it with a
linear mapping (divide by the display's maximum). A tone-mapping operator that normalises
exposure itself (Reinhard, Tumblin…) cancels a global factor, so this effect only matters
before a linear display mapping.

References:
    G. Ward, "A contrast-based scalefactor for luminance display", Graphics Gems IV, 1994,
    pp. 415–421, doi:10.1016/B978-0-12-336156-1.50054-9 (banterle/HDR_Toolbox
    ``WardGlobalTMO.m``, tizian/tonemapper ``WardOperator.cpp``).
    G. Ward Larson et al. 1997, doi:10.1109/2945.646233; NREL/Radiance ``pcond.c``
    (``scalef = htcontrs(Lb(0.5(Bldmax + Bldmin))) / htcontrs(Lb(bwavg))``).
"""

import functools
from typing import Literal

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._photometry import LMIN, check_rgb, restore, sanitize
from .._thresholds import ward1994_scale
from ._pcond import tvi

ContrastModel = Literal["pcond", "ward1994"]

DISPLAY_MAX = 100.0
"""Default maximum display luminance, cd/m² (pcond.c ``LDMAX``)."""
DISPLAY_RANGE = 32.0
"""Default display dynamic range ``L_dmax/L_dmin`` (pcond.c v3.30 ``LDDYN``; older
versions of pcond used 100)."""
WEBER_ONSET = 10.0**1.9
"""cd/m²: above this the cone TVI is Weber's law ``ΔL ∝ L`` (Ferwerda et al. 1996), so the
visibility-matching scale differs from plain luminance scaling by a display constant only."""


def display_adaptation(
    model: ContrastModel, display_max: float = DISPLAY_MAX, display_range: float = DISPLAY_RANGE
) -> float:
    """Display adaptation luminance, cd/m²: pcond's geometric mean of the display range
    ``L_dmax/sqrt(L_ddyn)``, or Ward 1994's ``L_dmax/2``."""
    _check_display(display_max, display_range)
    if model == "pcond":
        return float(display_max) / float(display_range) ** 0.5
    if model == "ward1994":
        return float(display_max) / 2.0
    raise ValueError(f"model: expected 'pcond' or 'ward1994', got {model!r}")


def _check_display(display_max: float, display_range: float) -> None:
    if not (0 < float(display_max) < float("inf")):
        raise ValueError(f"display_max: expected a finite luminance > 0, got {display_max!r}")
    if not (1 < float(display_range) < float("inf")):
        raise ValueError(f"display_range: expected a finite ratio > 1, got {display_range!r}")


def contrast_scale(
    L_wa: Float[ArrayLike, "*shape"],
    *,
    model: ContrastModel = "pcond",
    display_max: float = DISPLAY_MAX,
    display_range: float = DISPLAY_RANGE,
) -> Float[Array, "*shape"]:
    """Visibility-matching scale ``m`` from world adaptation ``L_wa`` (cd/m²) to the display.

    ``"pcond"``: ``m = tvi(L_da)/tvi(L_wa)`` (:func:`hdrjax.vision.tvi`); ``"ward1994"``:
    :func:`ward1994_scale`. ``L_da`` is :func:`display_adaptation`.
    """
    _check.real(L_wa, "L_wa")
    L_da = display_adaptation(model, display_max, display_range)
    L_wa = jnp.maximum(_check.as_float(L_wa), LMIN)
    if model == "pcond":
        return tvi(L_da) / tvi(L_wa)
    return ward1994_scale(L_wa, L_da)


def contrast(
    rgb: Float[ArrayLike, "*batch 3"],
    adaptation: Float[ArrayLike, ""],
    *,
    model: ContrastModel = "pcond",
    display_max: float = DISPLAY_MAX,
    display_range: float = DISPLAY_RANGE,
) -> Float[Array, "*batch 3"]:
    """Scale world RGB (cd/m²) to display RGB (cd/m²) by :func:`contrast_scale`."""
    display_adaptation(model, display_max, display_range)  # validate outside the trace
    return _contrast(check_rgb(rgb), adaptation, model, float(display_max), float(display_range))


@functools.partial(jax.jit, static_argnums=(2, 3, 4))
def _contrast(
    rgb: Array, adaptation: ArrayLike, model: ContrastModel, dmax: float, drange: float
) -> Array:
    m = contrast_scale(adaptation, model=model, display_max=dmax, display_range=drange)
    x, ok = sanitize(rgb)  # a NaN pixel times m would give m a NaN gradient
    # m > 1 (dim adaptation) takes values near the float maximum past it: they saturate
    big = float(jnp.finfo(rgb.dtype).max)
    return restore(jnp.clip(x * m.astype(rgb.dtype), -big, big), rgb, ok)


__all__ = [
    "DISPLAY_MAX",
    "DISPLAY_RANGE",
    "WEBER_ONSET",
    "contrast",
    "contrast_scale",
    "display_adaptation",
]
