"""The automatic parameter estimates of the operators, as plain functions.

Each function takes one image and returns an :class:`Estimate`: the value an operator would
use for a parameter left at ``None``, and the image statistics it was computed from, so a
study can set the automatic choice beside a fitted one (:func:`hdrjax.fit.fit`).

Numeric contract: ``image`` is linear RGB ``(H, W, 3)`` (relative or cd/m²); values are in
the units the operators use (noted per function). Statistics use the finite pixels only.
Every function runs the operators' own code — the same :func:`hdrjax.stats.measure` call,
the same formula functions, the same NaN/Inf handling — so ``jgt_key(img).value`` equals
``Reinhard2002().measure(img).key`` (tests/fit/test_estimate.py checks each pairing).
The functions are jit-compiled; :class:`Estimate` is a pytree, so they also work under
``jax.vmap`` over a batch of images.

>>> import jax.numpy as jnp
>>> img = jnp.exp(jnp.linspace(-3.0, 3.0, 48)).reshape(4, 4, 3)
>>> est = log_average(img)
>>> sorted(est.statistics)
['delta', 'n_pixels']
"""

import functools
from collections.abc import Sequence
from typing import Literal

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from . import _check, _repr
from ._colour import REC709_WEIGHTS
from ._stats import DEFAULT_BINS, DEFAULT_DELTA
from .display._desaturate import PERCENT_ABOVE, THRESHOLD_FACTOR, threshold_and_l90
from .operators._base import as_float_image, count_valid, dispatch, statistics_of, stats_of
from .operators._reinhard2002 import jgt_key as _jgt_key, jgt_white_terms
from .operators._tumblin import STEVENS_EPS, adaptation_settings, adaptation_terms


class Estimate(eqx.Module):
    """An automatic estimate and the statistics it was computed from.

    Attributes:
        value: the estimate (a scalar array).
        statistics: the image statistics (and intermediate terms) it used, by name.
        name: which estimate (``"jgt_key"``, ``"jgt_white"`` ...).
    """

    __repr__ = _repr.fields_repr
    _repr_html_ = _repr.fields_html

    value: Float[Array, ""]
    statistics: dict[str, Array]
    name: str = eqx.field(static=True, default="")


_Weights = Sequence[float] | None
_Method = Literal["histogram", "exact"]


def _image(image: ArrayLike) -> Array:
    x = as_float_image(image, "image")
    if x.ndim != 3:
        raise ValueError(f"image: expected one image (H, W, 3), got shape {x.shape}; use vmap")
    return x


def _weights(weights: _Weights) -> tuple[float, float, float]:
    w = REC709_WEIGHTS if weights is None else tuple(float(v) for v in weights)
    if len(w) != 3:
        raise ValueError(f"weights: expected 3 luminance weights, got {weights!r}")
    return w  # type: ignore[return-value]


def _check_method(method: str, bins: int) -> None:
    if method not in ("histogram", "exact"):
        raise ValueError(f"percentile_method: expected 'histogram' or 'exact', got {method!r}")
    if int(bins) < 2:
        raise ValueError(f"bins: expected an integer >= 2, got {bins!r}")


def _measured(p, method: str, bins: int, delta: float):
    """The statistics the Reinhard operators measure (same call as their ``_measure``)."""
    return stats_of(p, method=method, bins=bins, delta=delta)


@functools.partial(jax.jit, static_argnums=(1, 2, 3, 4))
def _jgt_key_impl(x, weights, method, bins, delta):
    def fn(p):
        st = _measured(p, method, bins, delta)
        stats = {
            "p01": st.p01,
            "p99": st.p99,
            "log_average_trimmed": st.log_average_trimmed,
            "rel_error_bound": st.rel_error_bound,
        }
        return Estimate(_jgt_key(st), stats, "jgt_key")

    return dispatch(x, weights, fn, fix=False)


def jgt_key(
    image: Float[ArrayLike, "H W 3"],
    *,
    percentile_method: _Method = "histogram",
    bins: int = DEFAULT_BINS,
    delta: float = DEFAULT_DELTA,
    weights: _Weights = None,
) -> Estimate:
    """The JGT 2002 automatic key (Reinhard 2002 Eq. 4, J. Graphics Tools; the ``key`` of
    :class:`~hdrjax.operators.Reinhard2002` and ``Reinhard2002Local`` when ``None``).

    ``a = 0.18 · 4^((2 log2 L̄ − log2 L_1 − log2 L_99) / (log2 L_99 − log2 L_1))`` with
    ``L_1``, ``L_99`` the 1st/99th luminance percentiles and ``L̄`` the log-average of the
    positive pixels at or below ``L_99`` (0.18 when ``L_99 = L_1``). Unitless.

    Statistics: ``p01``, ``p99``, ``log_average_trimmed`` (image units) and
    ``rel_error_bound`` of the percentiles (0 for ``percentile_method="exact"``).
    The options are the operator's fields of the same names.
    """
    _check_method(percentile_method, bins)
    return _jgt_key_impl(_image(image), _weights(weights), percentile_method, int(bins), delta)


@functools.partial(jax.jit, static_argnums=(3, 4, 5, 6))
def _jgt_white_impl(x, key, lbar, weights, method, bins, delta):
    def fn(p):
        st = _measured(p, method, bins, delta)
        a = _jgt_key(st) if key is None else key
        lb = st.log_average if lbar is None else lbar
        scale = a / lb
        white, terms = jgt_white_terms(st, scale)
        stats = {
            "min_positive": st.min_positive,
            "max": st.max,
            "log_average_trimmed": st.log_average_trimmed,
            **terms,
            "key": jnp.asarray(a, x.dtype),
            "log_average": jnp.asarray(lb, x.dtype),
            "scale": scale,
        }
        return Estimate(white, stats, "jgt_white")

    return dispatch(x, weights, fn, fix=False)


def jgt_white(
    image: Float[ArrayLike, "H W 3"],
    *,
    key: float | ArrayLike | None = None,
    log_average: float | ArrayLike | None = None,
    percentile_method: _Method = "histogram",
    bins: int = DEFAULT_BINS,
    delta: float = DEFAULT_DELTA,
    weights: _Weights = None,
) -> Estimate:
    """The JGT 2002 automatic white point (Eq. 5; ``L_white`` of
    :class:`~hdrjax.operators.Reinhard2002` when ``None``), in *scaled* units.

    ``L_white = 1.5 · 2^(log2 L_max − log2 L_min − 5)``; where the image spans few zones
    (``log2(L_max / L_min) ≤ log2(s · L̄) + 4.415037`` with ``s = a / L̄_w`` and ``L̄`` the
    trimmed log-average: hdritools' guard, evaluated in scaled units so that the estimate is
    scale invariant — hdritools compares with ``log2 L̄`` in image units, see
    :mod:`hdrjax.operators._reinhard2002`) it is ``1.5 · L_max · s`` instead.
    ``key``/``log_average``: the operator's ``a`` and ``L̄_w`` (``None``: the automatic
    ones, as the operator does).

    Statistics: ``min_positive``, ``max``, ``log_average_trimmed`` (image units), ``zones``
    (``log2 L_max − log2 L_min``), ``guard`` (whether the guard applied), ``key``,
    ``log_average`` and ``scale = a / L̄_w``.
    """
    _check.positive(key, "key")
    _check_method(percentile_method, bins)
    x = _image(image)
    k = None if key is None else jnp.asarray(key, x.dtype)
    lb = None if log_average is None else jnp.asarray(log_average, x.dtype)
    return _jgt_white_impl(x, k, lb, _weights(weights), percentile_method, int(bins), delta)


@functools.partial(jax.jit, static_argnums=(1, 2))
def _log_average_impl(x, weights, delta):
    def fn(p):
        st = _measured(p, "histogram", 2, delta)
        stats = {"delta": jnp.asarray(delta, x.dtype), "n_pixels": count_valid(p)}
        return Estimate(st.log_average, stats, "log_average")

    return dispatch(x, weights, fn, fix=False)


def log_average(
    image: Float[ArrayLike, "H W 3"],
    *,
    delta: float = DEFAULT_DELTA,
    weights: _Weights = None,
) -> Estimate:
    """Reinhard 2002 Eq. 1 log-average luminance ``L̄_w = exp(mean(ln(δ + max(L, 0))))``
    over the finite pixels (``log_average`` of the Reinhard operators when ``None``), in
    image units.

    Statistics: ``delta`` and ``n_pixels`` (the finite pixels averaged).
    """
    _check.positive(delta, "delta", zero=True)
    return _log_average_impl(_image(image), _weights(weights), float(delta))


@functools.partial(jax.jit, static_argnums=(1, 2, 3))
def _adaptation_impl(x, weights, method, bins):
    def fn(p):
        value, terms = adaptation_terms(statistics_of(p, adaptation_settings(bins)), method)
        if method == "log_average":
            terms = {"eps": jnp.asarray(STEVENS_EPS, x.dtype), **terms}
        return Estimate(
            value, terms, "adaptation_luminance" + ("_robust" if method == "trimmed" else "")
        )

    return dispatch(x, weights, fn, fix=False)


def adaptation_luminance(
    image: Float[ArrayLike, "H W 3"],
    *,
    robust: bool = False,
    bins: int = DEFAULT_BINS,
    weights: _Weights = None,
) -> Estimate:
    """World adaptation luminance ``L_wa`` of the Tumblin–Rushmeier operators when ``None``
    (image units, cd/m² for absolute images).

    ``robust=False`` (``adaptation="log_average"``): ``exp(mean(ln(L + 2.3·10⁻⁵)))`` over the
    finite pixels (colour-hdri, HDR Toolbox). ``robust=True`` (``adaptation="trimmed"``):
    ``exp(mean(ln L))`` over the positive pixels between the 1st and 99th percentiles.

    Statistics: ``n_pixels`` (pixels averaged); ``eps`` (2.3e-5) for the plain one;
    ``p01``, ``p99`` and their ``rel_error_bound`` for the robust one.
    """
    _check_method("histogram", bins)
    method = "trimmed" if robust else "log_average"
    return _adaptation_impl(_image(image), _weights(weights), method, int(bins))


def desaturation_threshold(
    image: Float[ArrayLike, "H W 3"],
    *,
    method: _Method = "histogram",
    bins: int = DEFAULT_BINS,
    weights: _Weights = None,
) -> Estimate:
    """The automatic highlight-desaturation threshold ``T = 2 · L₉₀``
    (:func:`hdrjax.display.highlight_threshold`, used by
    :func:`hdrjax.display.desaturate_highlights` when ``threshold=None``), in image units.

    ``L₉₀`` is the luminance that only 10 % of the finite pixels exceed; ``T`` is at most
    the largest finite float of the image's dtype (where ``L₉₀`` exceeds half of it).

    Statistics: ``L90``, its ``rel_error_bound`` (0 for ``method="exact"``),
    ``percent_above`` (10) and ``factor`` (2).
    """
    x = _image(image)
    T, L90, err = threshold_and_l90(x, weights=_weights(weights), method=method, bins=bins)
    stats = {
        "L90": L90,
        "rel_error_bound": err,
        "percent_above": jnp.asarray(PERCENT_ABOVE, x.dtype),
        "factor": jnp.asarray(THRESHOLD_FACTOR, x.dtype),
    }
    return Estimate(T, stats, "desaturation_threshold")


__all__ = [
    "Estimate",
    "adaptation_luminance",
    "desaturation_threshold",
    "jgt_key",
    "jgt_white",
    "log_average",
]
