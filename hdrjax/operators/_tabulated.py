"""Tabulated operator: a user-edited table of (world luminance → display value) pairs.

Birukov et al. 2022's third operator ("a table of values edited by the user"). The table is
interpolated in ``log10`` of world luminance with a monotone piecewise-cubic Hermite curve
(PCHIP, Fritsch & Carlson 1980, https://doi.org/10.1137/0717021 — the same slopes as
``scipy.interpolate.PchipInterpolator``) or piecewise-linearly (``interpolation="linear"``);
both preserve the table's monotonicity. Below the first entry the display value falls
linearly in luminance to 0 at ``L = 0``; above the last it stays at the last value.

Files: CSV with a header line ``luminance,display`` (``#`` comments allowed) or JSON
``{"luminance": [...], "display": [...]}``; luminance in image units (cd/m² for absolute
images), display values nominally in [0, 1].
"""

import csv
import io
import json
import os
import tempfile
from typing import ClassVar, Literal

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._interp import take
from ._base import AbstractLuminanceCurve, Prepared, parameter, register, weights_field


def _knots(x: ArrayLike) -> Array:
    x = jnp.asarray(x)
    if not jnp.issubdtype(x.dtype, jnp.floating):
        x = x.astype(jnp.result_type(float))
    return x


def validate_table(luminance: ArrayLike, display: ArrayLike, source: str = "table") -> None:
    """Raise ``ValueError`` (naming ``source``) unless the table is usable."""
    lum = np.asarray(luminance, dtype=np.float64).reshape(-1)
    dis = np.asarray(display, dtype=np.float64).reshape(-1)
    if lum.size == 0:
        raise ValueError(f"{source}: the table is empty; expected at least 2 rows")
    if lum.shape != dis.shape:
        raise ValueError(f"{source}: {lum.size} luminance values but {dis.size} display values")
    if lum.size < 2:
        raise ValueError(f"{source}: expected at least 2 rows, got {lum.size}")
    if not (np.all(np.isfinite(lum)) and np.all(np.isfinite(dis))):
        raise ValueError(f"{source}: table values must be finite numbers")
    if np.any(lum <= 0):
        raise ValueError(f"{source}: luminance values must be > 0 (interpolation is in log L)")
    bad = np.nonzero(np.diff(lum) <= 0)[0]
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"{source}: luminance must increase strictly; row {i + 2} ({lum[i + 1]:g}) is not"
            f" above row {i + 1} ({lum[i]:g})"
        )
    bad = np.nonzero(np.diff(dis) < 0)[0]
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"{source}: display values must not decrease (non-monotone table); row {i + 2}"
            f" ({dis[i + 1]:g}) is below row {i + 1} ({dis[i]:g})"
        )


def pchip_slopes(x: Array, y: Array) -> Array:
    """Fritsch–Carlson slopes, as ``scipy.interpolate.PchipInterpolator``."""
    h = jnp.diff(x)
    d = jnp.diff(y) / h
    if x.shape[0] == 2:
        return jnp.stack([d[0], d[0]])
    w1 = 2 * h[1:] + h[:-1]
    w2 = h[1:] + 2 * h[:-1]
    same = (jnp.sign(d[:-1]) * jnp.sign(d[1:])) > 0
    d0s = jnp.where(same, d[:-1], 1.0)
    d1s = jnp.where(same, d[1:], 1.0)
    inner = jnp.where(same, (w1 + w2) / (w1 / d0s + w2 / d1s), 0.0)

    def edge(h0, h1, m0, m1):
        e = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
        e = jnp.where(jnp.sign(e) != jnp.sign(m0), 0.0, e)
        return jnp.where((jnp.sign(m0) != jnp.sign(m1)) & (jnp.abs(e) > jnp.abs(3 * m0)), 3 * m0, e)

    first = edge(h[0], h[1], d[0], d[1])
    last = edge(h[-1], h[-2], d[-1], d[-2])
    return jnp.concatenate([first[None], inner, last[None]])


def interpolate(L: Array, luminance: Array, display: Array, method: str = "pchip") -> Array:
    """Display value of world luminance ``L ≥ 0`` from the table (see module docstring)."""
    x = jnp.log10(luminance)
    y = display
    pos = L > 0
    t = jnp.log10(jnp.where(pos, L, luminance[0]))
    tc = jnp.clip(t, x[0], x[-1])
    k = jnp.clip(jnp.searchsorted(x, tc, side="right", method="compare_all") - 1, 0, x.shape[0] - 2)
    x0, x1, y0, y1 = take(x, k), take(x, k + 1), take(y, k), take(y, k + 1)
    h = x1 - x0
    s = (tc - x0) / h
    if method == "linear":
        v = y0 + s * (y1 - y0)
    else:
        m = pchip_slopes(x, y)
        m0, m1 = take(m, k), take(m, k + 1)
        s2, s3 = s * s, s * s * s
        v = (
            (2 * s3 - 3 * s2 + 1) * y0
            + (s3 - 2 * s2 + s) * h * m0
            + (-2 * s3 + 3 * s2) * y1
            + (s3 - s2) * h * m1
        )
    below = L < luminance[0]
    ramp = y[0] * jnp.maximum(L, 0.0) / luminance[0]
    return jnp.where(below, ramp, v)


@register("tabulated")
class Tabulated(AbstractLuminanceCurve):
    """Tone curve given by a table of (world luminance, display value) pairs.

    Attributes:
        luminance: table luminances, strictly increasing, > 0 (image units).
        display: display values, non-decreasing (nominally [0, 1]); differentiable, so the
            knots can be fitted.
        interpolation: ``"pchip"`` (monotone cubic in log L) or ``"linear"`` (in log L).
    """

    reference: ClassVar[str] = (
        "Fritsch, Carlson 1980, Monotone piecewise cubic interpolation, SIAM J. Numer. Anal."
        " 17(2), https://doi.org/10.1137/0717021"
    )

    luminance: Float[Array, " K"] = parameter(
        help="table luminances, strictly increasing, > 0; a CSV/JSON file on the command"
        " line (--table)",
        unit="image units",
        range="(0, inf)",
        shape=None,
        converter=_knots,
    )
    display: Float[Array, " K"] = parameter(
        help="display values, non-decreasing (nominally [0, 1]); differentiable, so the"
        " knots can be fitted",
        unit="display units",
        range="[0, inf)",
        shape=None,
        converter=_knots,
    )
    interpolation: Literal["pchip", "linear"] = parameter(
        "pchip",
        help="pchip (monotone cubic in log L) or linear (in log L)",
        static=True,
        choices=("pchip", "linear"),
    )
    weights: tuple[float, float, float] = weights_field()

    def __check_init__(self):
        if self.luminance.ndim != 1 or self.display.ndim != 1:
            raise ValueError("tabulated: luminance and display must be 1-D tables")
        try:
            lum, dis = np.asarray(self.luminance), np.asarray(self.display)
        except Exception:  # traced values (fitting): checked by the caller's data
            return
        validate_table(lum, dis)

    cheap_curve: ClassVar[bool] = False  # a table lookup: once per pixel, not per channel

    def _measure(self, p: Prepared) -> "Tabulated":
        return self

    def _curve(self, L: Array) -> Array:
        return interpolate(L, self.luminance, self.display, self.interpolation)

    @classmethod
    def from_file(cls, path: str | os.PathLike, **kwargs) -> "Tabulated":
        """Read a CSV or JSON table (module docstring); errors name the file."""
        path = os.fspath(path)
        name = os.path.basename(path)
        try:
            with open(path, encoding="utf-8") as f:
                text = f.read()
        except OSError as e:
            raise ValueError(f"{name}: cannot read table: {e.strerror}") from None
        lum, dis = parse_table(text, name, json_format=path.lower().endswith(".json"))
        validate_table(lum, dis, name)
        return cls(lum, dis, **kwargs)

    def to_file(self, path: str | os.PathLike) -> None:
        """Write the table as CSV (or JSON for ``.json``), atomically."""
        path = os.fspath(path)
        lum = np.asarray(self.luminance, np.float64).tolist()
        dis = np.asarray(self.display, np.float64).tolist()
        if path.lower().endswith(".json"):
            text = json.dumps({"luminance": lum, "display": dis}, indent=2) + "\n"
        else:
            rows = "".join(f"{a!r},{b!r}\n" for a, b in zip(lum, dis, strict=True))
            text = "# hdrjax tabulated tone curve: world luminance -> display value\n"
            text += "luminance,display\n" + rows
        folder = os.path.dirname(os.path.abspath(path))
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-", suffix=".table")
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(text)
            os.replace(tmp, path)
        except BaseException:
            os.unlink(tmp)
            raise


def parse_table(text: str, name: str, *, json_format: bool) -> tuple[np.ndarray, np.ndarray]:
    """Parse a table file's text into (luminance, display) arrays."""
    if json_format:
        try:
            obj = json.loads(text)
            if isinstance(obj, dict):
                lum, dis = obj["luminance"], obj["display"]
            else:
                lum, dis = zip(*obj, strict=True) if obj else ([], [])
            return np.asarray(lum, np.float64), np.asarray(dis, np.float64)
        except (ValueError, KeyError, TypeError) as e:
            raise ValueError(
                f'{name}: expected JSON {{"luminance": [...], "display": [...]}}'
                f" or a list of [luminance, display] pairs ({e})"
            ) from None
    lum, dis = [], []
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    for i, row in enumerate(csv.reader(io.StringIO("\n".join(lines)))):
        if i == 0 and row and not _is_number(row[0]):
            continue  # header
        if len(row) != 2:
            raise ValueError(f"{name}: line {i + 1}: expected 'luminance,display', got {row}")
        try:
            lum.append(float(row[0]))
            dis.append(float(row[1]))
        except ValueError:
            raise ValueError(f"{name}: line {i + 1}: not numbers: {row}") from None
    return np.asarray(lum, np.float64), np.asarray(dis, np.float64)


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


__all__ = ["Tabulated", "interpolate", "parse_table", "pchip_slopes", "validate_table"]
