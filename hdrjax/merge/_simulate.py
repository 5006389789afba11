"""Synthetic exposure brackets with a known truth: radiance, camera curve, exposures.

A bracket is what a camera records of a scene radiance ``E`` (linear RGB, relative or
cd/m²) at exposure times ``t_j``: the sensor exposure ``X = k E t_j`` (``k`` scales the
middle exposure's 99th percentile to ``fill``), plus noise, clipped to [0, 1], passed
through the camera curve ``f`` and quantised to ``2^bits`` code values. Its inverse
response — the log exposure ``ln f⁻¹(z)`` of each code value ``z`` — is the quantity that
Debevec & Malik (1997) recover, known here exactly (:func:`true_response`).

The curves are monotone maps [0, 1] → [0, 1]: ``"linear"``, ``"gamma"`` (1/2.2),
``"srgb"`` (IEC 61966-2-1), ``"scurve"`` (a film-like toe and shoulder,
``f(X) = (1 + c) X^γ / (X^γ + c)``, γ = 1.6, c = 0.3) and ``"per_channel"`` (gammas 1/2.0,
1/2.2, 1/2.5 for R, G, B), or a callable ``f(X, channel)``.

Used by the tests and benchmarks of :mod:`hdrjax.merge` and by anyone studying how a
method behaves on a bracket whose answer is known. NumPy, float64, not jitted.
"""

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

CurveLike = str | Callable[[np.ndarray, int], np.ndarray]

_PER_CHANNEL_GAMMA = (2.0, 2.2, 2.5)


def _srgb(x: np.ndarray) -> np.ndarray:
    return np.where(
        x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055
    )


def _scurve(x: np.ndarray, gamma: float = 1.6, c: float = 0.3) -> np.ndarray:
    p = np.power(x, gamma)
    return (1.0 + c) * p / (p + c)


CURVES: dict[str, Callable[[np.ndarray, int], np.ndarray]] = {
    "linear": lambda x, ch: x,
    "gamma": lambda x, ch: np.power(x, 1 / 2.2),
    "srgb": lambda x, ch: _srgb(x),
    "scurve": lambda x, ch: _scurve(x),
    "per_channel": lambda x, ch: np.power(x, 1 / _PER_CHANNEL_GAMMA[ch]),
}
"""Camera curves ``f(X, channel)`` by name: sensor exposure in [0, 1] to code value in [0, 1]."""


def camera_curve(curve: CurveLike) -> Callable[[np.ndarray, int], np.ndarray]:
    """The curve ``f(X, channel)`` for a name of :data:`CURVES` or a callable."""
    if callable(curve):
        return curve
    try:
        return CURVES[curve]
    except (KeyError, TypeError):
        raise ValueError(
            f"curve: expected one of {sorted(CURVES)} or a callable f(X, channel), got {curve!r}"
        ) from None


def true_response(curve: CurveLike = "srgb", levels: int = 256) -> np.ndarray:
    """The exact inverse response of ``curve``: ``(levels, 3)`` natural-log sensor exposure
    ``ln f⁻¹(z / (levels − 1))`` at each code value ``z`` (``-inf`` at code 0, which
    zero exposure gives).

    Same convention as :func:`hdrjax.merge.recover_response` up to an additive constant
    per channel (a response is defined up to the scale of exposure).
    """
    f = camera_curve(curve)
    grid = np.concatenate([[0.0], np.geomspace(1e-12, 1.0, 200_001)])
    out = np.empty((levels, 3))
    z = np.arange(levels) / (levels - 1)
    for ch in range(3):
        y = f(grid, ch)
        # f is monotone: invert by interpolation on a fine log grid
        out[:, ch] = np.interp(z, y, grid, left=0.0, right=1.0)
    with np.errstate(divide="ignore"):
        return np.log(out)


class Bracket(NamedTuple):
    """A synthetic bracket: ``codes`` ``(N, H, W, 3)`` uint8/uint16, ``exposure_times``
    ``(N,)`` s, ``radiance`` the truth ``(H, W, 3)`` scaled so that ``X = radiance · t``,
    ``shifts`` ``(N, 2)`` integer (dx, dy) of each member, ``response`` the true inverse
    response ``(levels, 3)`` (:func:`true_response`)."""

    codes: np.ndarray
    exposure_times: np.ndarray
    radiance: np.ndarray
    shifts: np.ndarray
    response: np.ndarray


def simulate_bracket(
    radiance: ArrayLike,
    exposure_times: ArrayLike | None = None,
    *,
    stops: int = 5,
    spacing_ev: float = 2.0,
    curve: CurveLike = "srgb",
    bits: int = 8,
    fill: float = 0.5,
    read_noise: float = 0.0,
    shot_noise: float = 0.0,
    shifts: ArrayLike | None = None,
    seed: int = 0,
) -> Bracket:
    """Photograph ``radiance`` ``(H, W, 3)`` at several exposures through ``curve``.

    Args:
        radiance: linear RGB scene, non-negative (relative or cd/m²).
        exposure_times: seconds per member; default ``stops`` times ``spacing_ev`` stops apart
            around 1 s.
        stops, spacing_ev: the default bracket (5 exposures 2 EV apart).
        curve: camera curve (:data:`CURVES` name or callable ``f(X, channel)``).
        bits: 8 (uint8) or 16 (uint16) code values.
        fill: sensor exposure of the middle member's 99th-percentile pixel (sets the scale
            ``k`` in ``X = k E t``; the returned ``radiance`` is ``k E``).
        read_noise: standard deviation of additive Gaussian noise in sensor exposure units.
        shot_noise: photon noise: variance ``shot_noise · X`` (Poisson-like, Gaussian).
        shifts: ``(N, 2)`` integer (dx, dy) translations of each member (camera shake): the
            member shows the scene moved ``dx`` px right and ``dy`` px down, edges repeat the
            border; ``None`` for none.
        seed: noise seed.
    """
    e = np.asarray(radiance, dtype=np.float64)
    if e.ndim != 3 or e.shape[-1] != 3:
        raise ValueError(f"radiance: expected an (H, W, 3) image, got shape {e.shape}")
    e = np.where(np.isfinite(e), np.maximum(e, 0.0), 0.0)
    if exposure_times is None:
        ev = (np.arange(stops) - (stops - 1) / 2) * spacing_ev
        times = np.exp2(ev)
    else:
        times = np.asarray(exposure_times, dtype=np.float64).reshape(-1)
    n = len(times)
    if bits not in (8, 16):
        raise ValueError(f"bits: expected 8 or 16, got {bits}")
    f = camera_curve(curve)
    t_mid = float(np.sort(times)[(n - 1) // 2])
    ref = np.percentile(e.mean(axis=-1), 99)
    k = fill / (ref * t_mid) if ref > 0 else 1.0
    e = e * k
    sh = np.zeros((n, 2), dtype=np.int64) if shifts is None else np.asarray(shifts, np.int64)
    if sh.shape != (n, 2):
        raise ValueError(f"shifts: expected ({n}, 2) integer (dx, dy), got shape {sh.shape}")
    rng = np.random.default_rng(seed)
    top = (1 << bits) - 1
    codes = np.empty((n, *e.shape), dtype=np.uint8 if bits == 8 else np.uint16)
    h, w = e.shape[:2]
    for j, t in enumerate(times):
        dx, dy = sh[j]
        rows = np.clip(np.arange(h) - dy, 0, h - 1)
        cols = np.clip(np.arange(w) - dx, 0, w - 1)
        x = e[rows][:, cols] * t
        if read_noise or shot_noise:
            sd = np.sqrt(read_noise**2 + shot_noise * x)
            x = x + sd * rng.standard_normal(x.shape)
        x = np.clip(x, 0.0, 1.0)
        y = np.stack([f(x[..., ch], ch) for ch in range(3)], axis=-1)
        codes[j] = np.clip(np.rint(y * top), 0, top).astype(codes.dtype)
    return Bracket(codes, times, e, sh, true_response(curve, top + 1))
