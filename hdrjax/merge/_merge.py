"""Merging an exposure bracket into linear radiance.

Numeric contract: integer code values ``(N, H, W, 3)`` (uint8/uint16) with exposure times in
seconds and an inverse response ``g`` ``(levels, 3)`` (natural-log sensor exposure per code,
``g`` = 0 at the top code) go in; linear radiance ``E`` ``(H, W, 3)`` comes out in sensor
exposure per second (``X = E t``; ``X = 1`` just saturates the sensor —
:func:`hdrjax.merge.calibrate` turns it into cd/m²), float32 (float64 under x64).

Per-code weights (``"hat"``, ``"triangle"``, ``"gaussian"`` or a table) merge in the log
domain, as Debevec & Malik (1997, DOI 10.1145/258734.258884, eq. 6) do:

    ln E = Σ_j w(z_j) (g(z_j) − ln t_j) / Σ_j w(z_j)

per pixel and channel. ``"granados2010"`` (Granados et al. 2010, DOI
10.1109/CVPR.2010.5540208) is the maximum-likelihood estimate of a linear camera with Poisson
and read noise, an inverse-variance weighted mean in the linear domain:

    E = Σ_j w_j X_j / t_j / Σ_j w_j,   w_j = t_j² / (K z_max t_j E + σ_R²),   X_j = exp g(z_j)

The weights need the irradiance ``E`` they estimate: it is first estimated with the hat weights
(log domain, above), then the inverse-variance mean is evaluated twice, each time with the
weights of the previous estimate (a fixed-point iteration that settles in one or two rounds,
since ``w`` changes slowly with ``E``). ``K`` (gain, code values per electron) and ``σ_R``
(read noise, code values) are not estimated from the bracket — the paper calibrates them from
flat and dark frames — and default to a sensor with a 20 000-electron full well and 3
electrons of read noise (``K = z_max / 20000``, ``σ_R = 3 K``); pass a camera's values.

Codes 0 (black) and the top code (saturated) get weight 0 under every weighting (they bound
the exposure, they do not measure it), and so do codes whose ``g`` is not finite (``−inf``:
no exposure gives them). Pixels with no weighted member in a channel:

- saturated in every exposure (the shortest exposure's code is in the upper half): the value
  of the shortest exposure, ``exp(g(z) − ln t_min)`` — a lower bound of the radiance;
- black in every exposure: the value of the longest exposure, an upper bound (0 when
  ``g(0) = −inf``, as for the true response of a curve through 0);
- masked out in every exposure (``mask``): the middle exposure (the median exposure time).

The pixel work is one pure JAX function (:func:`merge_codes`) of the codes, the log exposure
times and the tables: the codes stay integers into the compiled kernel, which gathers
``w(z)`` and ``w(z) g(z)`` from small per-code tables and accumulates the sums over the
exposures in one pass (no float copy of the stack is made). It compiles once per bracket shape
and number of exposures, and ``jax.vmap`` over a batch of brackets of one size works.
"""

import os
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float, Integer

from ._bracket import as_codes, check_response
from ._weights import (
    FULL_WELL_ELECTRONS,
    PER_CODE,
    READ_NOISE_ELECTRONS,
    weight_key,
    weight_table,
)

RESPONSE_METHODS: tuple[str, ...] = ("debevec", "robertson", "mitsunaga1999")
"""Response names that :func:`merge` recovers from the bracket itself."""

_GRANADOS_ROUNDS = 2
"""Inverse-variance re-weightings after the hat estimate (see the module docstring)."""


def _flat_tables(response: Array, weights: Array) -> tuple[Array, Array, Array]:
    """Censored ``w``, ``w g`` and ``g`` as flat ``(3 · levels,)`` tables (channel-major)."""
    levels = response.shape[0]
    w = jnp.broadcast_to(weights.reshape(levels, -1), response.shape)
    code = jnp.arange(levels)[:, None]
    ok = jnp.isfinite(response) & (code > 0) & (code < levels - 1)
    w = jnp.where(ok, w, 0.0)
    g_safe = jnp.where(jnp.isfinite(response), response, 0.0)
    return w.T.reshape(-1), (w * g_safe).T.reshape(-1), response.T.reshape(-1)


def _channel_offset(levels: int) -> Array:
    """``(1, 1, 3)`` index offsets of the channels in a flat table."""
    return (jnp.arange(3, dtype=jnp.int32) * levels).reshape(1, 1, 3)


def _log_sums(codes, log_t, w_flat, wg_flat, mask, order):
    """``Σ_j w(z_j)(g(z_j) − ln t_j)`` and ``Σ_j w(z_j)`` per pixel, and the codes of the
    shortest, middle and longest members.

    Both sums come from one gather per code: ``w (g − ln t_j)`` and ``w`` are packed as the
    real and imaginary parts of one complex table per exposure, so each code value is looked
    up once and the sums accumulate in one pass (two real gathers of one index made XLA
    write each gathered image out first; measured 3.7 times slower on CPU).
    """
    offset = _channel_offset(w_flat.shape[0] // 3)
    n = codes.shape[0]
    pick = (order[0], order[(n - 1) // 2], order[-1])
    acc = None
    picked: list[Any] = [None, None, None]
    for j in range(n):
        z = codes[j]
        table = jax.lax.complex(wg_flat - w_flat * log_t[j], w_flat)
        term = table[z.astype(jnp.int32) + offset]
        if mask is not None:
            term = jnp.where(mask[j][..., None], term, 0.0)
        acc = term if acc is None else acc + term
        picked = [
            z if p is None else jnp.where(k == j, z, p) for k, p in zip(pick, picked, strict=True)
        ]
    return acc.real, acc.imag, picked


def _fallback(picked, log_t, g_flat, order, mask):
    """Log radiance of pixels with no weighted member (see the module docstring)."""
    levels = g_flat.shape[0] // 3
    offset = _channel_offset(levels)
    n = log_t.shape[0]
    z_short, z_mid, z_long = (z.astype(jnp.int32) for z in picked)
    value = jnp.where(
        2 * z_short >= levels,
        g_flat[z_short + offset] - log_t[order[0]],
        g_flat[z_long + offset] - log_t[order[-1]],
    )
    if mask is not None:
        masked = ~jnp.any(mask, axis=0)[..., None]
        value = jnp.where(masked, g_flat[z_mid + offset] - log_t[order[(n - 1) // 2]], value)
    return value


def merge_codes(
    codes: Integer[ArrayLike, "N H W 3"],
    log_times: Float[ArrayLike, " N"],
    response: Float[ArrayLike, "levels 3"],
    weights: Float[ArrayLike, " levels"] | Float[ArrayLike, "levels 3"],
    mask: Bool[ArrayLike, "N H W"] | None = None,
    noise: tuple[ArrayLike, ArrayLike] | None = None,
) -> Float[Array, "H W 3"]:
    """The merge kernel: a pure JAX function of arrays (jit, vmap and grad go through it).

    Args:
        codes: ``(N, H, W, 3)`` integer code values (kept integer: they index the tables).
        log_times: ``(N,)`` natural-log exposure times (s).
        response: ``(levels, 3)`` inverse response ``g`` (``−inf`` allowed where no exposure
            gives the code).
        weights: ``(levels,)`` or ``(levels, 3)`` per-code weights (the hat first estimate
            for ``noise``); codes 0, top and those with non-finite ``g`` are censored.
        mask: optional ``(N, H, W)`` bool, ``True`` where a member's pixel is usable.
        noise: ``None`` for the log-domain per-code merge; ``(gain, read_noise)`` (code values
            per electron, code values) for Granados et al.'s (2010) inverse-variance merge.

    Returns:
        ``(H, W, 3)`` radiance (sensor exposure per second), finite or 0 (see the module
        docstring for pixels no exposure measured).
    """
    codes = jnp.asarray(codes)
    dtype = jnp.result_type(float)
    log_t = jnp.asarray(log_times, dtype)
    g = jnp.asarray(response, dtype)
    w_flat, wg_flat, g_flat = _flat_tables(g, jnp.asarray(weights, dtype))
    mask = None if mask is None else jnp.asarray(mask, bool)
    order = jnp.argsort(log_t)
    num, den, picked = _log_sums(codes, log_t, w_flat, wg_flat, mask, order)
    measured = den > 0
    log_e = jnp.where(
        measured, num / jnp.where(measured, den, 1.0), _fallback(picked, log_t, g_flat, order, mask)
    )
    if noise is None:
        return jnp.exp(log_e)
    e = _granados(codes, log_t, g_flat, w_flat, mask, noise, log_e)
    return jnp.where(measured, e, jnp.exp(log_e))


def _granados(codes, log_t, g_flat, w_flat, mask, noise, log_e):
    """Granados et al. (2010) inverse-variance merge, started from ``exp(log_e)``."""
    levels = g_flat.shape[0] // 3
    offset = _channel_offset(levels)
    gain, read_noise = (jnp.asarray(v, log_t.dtype) for v in noise)
    x_flat = jnp.exp(g_flat)
    usable_flat = w_flat > 0
    t = jnp.exp(log_t)
    e = jnp.exp(log_e)
    for _ in range(_GRANADOS_ROUNDS):
        num = den = 0.0
        for j in range(codes.shape[0]):
            idx = codes[j].astype(jnp.int32) + offset
            usable = usable_flat[idx]
            if mask is not None:
                usable = usable & mask[j][..., None]
            var = gain * (levels - 1) * t[j] * e + jnp.square(read_noise)
            w = jnp.where(usable, jnp.square(t[j]) / var, 0.0)
            num = num + w * x_flat[idx] / t[j]
            den = den + w
        e = num / jnp.where(den > 0, den, 1.0)
    return e


_merge_jit = jax.jit(merge_codes)


def _response_table(response: Any, images: Any, times: Any, levels: int) -> np.ndarray | Array:
    if response is None:
        response = "debevec"
    if isinstance(response, str):
        key = response.lower().replace("-", "").replace("_", "").replace(" ", "")
        if key == "linear":
            with np.errstate(divide="ignore"):
                g = np.log(np.arange(levels) / (levels - 1))
            return np.repeat(g[:, None], 3, axis=1)
        if key in RESPONSE_METHODS:
            from ._response import recover_response

            return recover_response(images, times, method=key)
        if not (os.path.exists(response) or os.path.splitext(response)[1]):
            raise ValueError(
                f"response: expected a (levels, 3) table, a file, 'linear' or one of "
                f"{list(RESPONSE_METHODS)}, got {response!r}"
            )
    if isinstance(response, str | os.PathLike):
        from ._response import load_response

        return load_response(response)
    return response


def _weight_table(weights: Any, levels: int) -> tuple[Any, bool]:
    """(table, granados?) for the ``weights`` argument."""
    if isinstance(weights, str):
        key = weight_key(weights)
        if key in PER_CODE:
            return weight_table(key, levels), False
        return weight_table("hat", levels), True
    shape = np.shape(weights)
    if shape not in ((levels,), (levels, 3)):
        raise ValueError(
            f"weights: expected a name or a ({levels},) or ({levels}, 3) table, got shape {shape}"
        )
    if not isinstance(weights, jax.core.Tracer):
        w = np.asarray(weights, np.float64)
        if not np.all(np.isfinite(w) & (w >= 0)):
            raise ValueError("weights: expected non-negative finite weights")
    return weights, False


def merge(
    images: Any,
    exposure_times: ArrayLike | None = None,
    response: Any = None,
    weights: Any = "hat",
    *,
    mask: ArrayLike | None = None,
    gain: float | None = None,
    read_noise: float | None = None,
) -> Float[Array, "H W 3"]:
    """Merge an exposure bracket into linear radiance (see the module docstring).

    Args:
        images: ``(N, H, W, 3)`` uint8/uint16 codes, a list of ``(H, W, 3)`` arrays, or file
            paths (exposure times then come from EXIF unless given).
        exposure_times: ``(N,)`` seconds.
        response: the inverse response ``g`` as a ``(levels, 3)`` table; a method recovering
            it from this bracket (``"debevec"``, ``"robertson"``, ``"mitsunaga1999"``:
            :func:`hdrjax.merge.recover_response`); a response file
            (:func:`hdrjax.merge.load_response`); or ``"linear"`` for linear (RAW) data,
            ``g(z) = ln(z / z_max)``. ``None``: ``"debevec"``.
        weights: ``"hat"`` (Reinhard et al. 2010), ``"triangle"`` (Debevec & Malik 1997),
            ``"gaussian"`` (Robertson et al. 2003), ``"granados2010"`` (Granados et al. 2010,
            noise-based, for RAW), or a ``(levels,)``/``(levels, 3)`` table of weights.
        mask: ``(N, H, W)`` bool, ``True`` where a member's pixel may be used (e.g. not a
            ghost); pixels masked in every member take the middle exposure.
        gain, read_noise: ``"granados2010"`` only: the camera's gain ``K`` (code values per
            electron) and read noise ``σ_R`` (code values); defaults ``z_max / 20000`` and
            ``3 K``.

    Returns:
        ``(H, W, 3)`` linear radiance (``X / t``, ``X = 1`` saturating; float32, float64
        under x64), never NaN or infinite.

    Raises:
        ValueError: one line naming the argument (bracket, times, response, weights, mask).
    """
    bracket = as_codes(images, exposure_times)
    codes, levels, times = bracket.codes, bracket.levels, bracket.exposure_times
    assert times is not None
    table, granados = _weight_table(weights, levels)
    if not granados and (gain is not None or read_noise is not None):
        raise ValueError("gain: only weights='granados2010' uses gain and read_noise")
    g = check_response(_response_table(response, codes, times, levels), levels)
    if mask is not None:
        m = np.asarray(mask)
        if m.shape != codes.shape[:3] or m.dtype != np.bool_:
            raise ValueError(
                f"mask: expected a {codes.shape[:3]} bool array (N, H, W), got {m.dtype} {m.shape}"
            )
        mask = m
    noise = None
    if granados:
        k = (levels - 1) / FULL_WELL_ELECTRONS if gain is None else gain
        sr = READ_NOISE_ELECTRONS * k if read_noise is None else read_noise
        if not (np.isfinite(k) and k > 0 and np.isfinite(sr) and sr >= 0):
            raise ValueError(f"gain: expected gain > 0 and read_noise ≥ 0, got {k}, {sr}")
        noise = (float(k), float(sr))
    # an explicit device_put: handing the NumPy stack to the jitted call copied it (on CPU)
    return _merge_jit(jax.device_put(codes), np.log(times), g, table, mask, noise)


__all__ = ["merge", "merge_codes"]
