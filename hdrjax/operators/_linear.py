"""Linear operator: one parameter, the luminance mapped to white, set directly or by exposure.

Birukov et al. 2022 ("controlled by a single parameter, the maximum luminance, given directly or
through exposure time, f-number and camera sensitivity"). The photographic relation is ISO
12232:2006's saturation-based speed (ISO 12232:2006, "Photography — Digital still
cameras — Determination of exposure index, ISO speed ratings, standard output sensitivity,
and recommended exposure index"; as colour-hdri's ``exposure/dsc.py`` implements it):
``H = q L t / N²`` (focus at infinity, no flare) saturates at ``H_sat = 78 / S``, so the
luminance that just saturates the sensor is ``L_max = 78 N² / (q S t)`` with the lens factor
``q = (π/4) T v cos⁴θ = 0.6516`` (T = 0.9, v = 0.98, θ = 10°). With
``EV100 = log2(N² / t · 100 / S)`` this is ``L_max = 78 / (100 q) · 2^EV100`` (Lagarde &
de Rousiers 2014; colour-hdri ``photometric_exposure_scale_factor_Lagarde2014``).
"""

import math
from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike

from .._stats import Statistics
from ._base import (
    AbstractLuminanceCurve,
    StatisticsSettings,
    bound_stats,
    estimated,
    max_luminance,
    parameter,
    register,
    weights_field,
)

Q_FACTOR = (math.pi / 4.0) * 0.9 * 0.98 * math.cos(math.radians(10.0)) ** 4
"""ISO 12232 lens factor q with colour-hdri's defaults T = 0.9, v = 0.98, θ = 10° (0.6516)."""


def saturation_luminance(
    exposure_time: ArrayLike, f_number: ArrayLike, iso: ArrayLike, q: float = Q_FACTOR
) -> Array:
    """ISO 12232 saturation-based luminance ``78 N² / (q S t)`` in cd/m² (t in s)."""
    return 78.0 * jnp.square(f_number) / (q * jnp.asarray(iso) * jnp.asarray(exposure_time))


def ev100_luminance(ev100: ArrayLike, q: float = Q_FACTOR) -> Array:
    """``L_max = 78 / (100 q) · 2^EV100`` (cd/m²)."""
    return 78.0 / (100.0 * q) * jnp.exp2(jnp.asarray(ev100))


@register("linear")
class Linear(AbstractLuminanceCurve):
    """``display = L_w / L_max``: world luminance ``L_max`` maps to white, colour kept.

    Give exactly one of: ``L_max`` (image units, cd/m² for absolute images);
    ``exposure_time`` (s) + ``f_number`` + ``iso`` together; ``ev100``; or nothing, which
    maps the image's largest finite luminance to white.

    Input: linear RGB (absolute when set by exposure). Output: display-referred linear RGB,
    in [0, 1] up to ``L_max`` (brighter pixels exceed 1 and clip when encoded).
    """

    reference: ClassVar[str] = (
        "ISO 12232:2019 saturation-based speed; Lagarde, de Rousiers 2014, Moving Frostbite"
        " to physically based rendering (SIGGRAPH course)"
    )
    scale_invariant: ClassVar[bool] = True
    default_fit_params: ClassVar[tuple[str, ...]] = ("L_max",)
    only_feeds: ClassVar[dict[str, str]] = dict.fromkeys(
        ("exposure_time", "f_number", "iso", "ev100"), "L_max"
    )

    L_max: Array | None = estimated(
        "luminance mapped to white; None: from the exposure settings, else the image's"
        " largest finite luminance",
        unit="image units (cd/m² for absolute images)",
        pooling="max",
    )
    exposure_time: Array | None = parameter(
        None, help="exposure time (with f_number and iso)", unit="s", range="(0, inf)"
    )
    f_number: Array | None = parameter(
        None, help="aperture N (with exposure_time and iso)", range="(0, inf)"
    )
    iso: Array | None = parameter(
        None, help="ISO speed S (with exposure_time and f_number)", range="(0, inf)"
    )
    ev100: Array | None = parameter(
        None,
        help="exposure value at ISO 100: L_max = 78 / (100 q) 2^EV100",
        unit="EV",
        range="(-inf, inf)",
    )
    q: float = parameter(
        Q_FACTOR, help="ISO 12232 lens factor q (T v cos⁴θ π / 4)", range="(0, inf)", static=True
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        camera = (self.exposure_time, self.f_number, self.iso)
        n_cam = sum(v is not None for v in camera)
        if n_cam not in (0, 3):
            raise ValueError(
                "linear: exposure_time, f_number and iso must be given together"
                f" (got exposure_time={self.exposure_time}, f_number={self.f_number},"
                f" iso={self.iso})"
            )
        given = [n for n, v in (("L_max", self.L_max), ("ev100", self.ev100)) if v is not None]
        if n_cam:
            given.append("exposure_time/f_number/iso")
        if len(given) > 1:
            raise ValueError(f"linear: give only one of L_max, ev100, exposure; got {given}")

    def statistics_settings(self) -> StatisticsSettings | None:
        given = (self.L_max, self.ev100, self.exposure_time)
        return None if any(v is not None for v in given) else StatisticsSettings()

    def bind(self, stats: Statistics | None) -> "Linear":
        if self.L_max is not None:
            return self
        if self.ev100 is not None:
            L_max = ev100_luminance(self.ev100, self.q)
        elif self.exposure_time is not None:
            L_max = saturation_luminance(self.exposure_time, self.f_number, self.iso, self.q)
        else:
            L_max = max_luminance(bound_stats(self, stats))
        return Linear(L_max=L_max, q=self.q, weights=self.weights)

    def _curve(self, L: Array) -> Array:
        return L / self.L_max


__all__ = ["Linear", "Q_FACTOR", "ev100_luminance", "saturation_luminance"]
