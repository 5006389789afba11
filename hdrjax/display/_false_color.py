"""False colour: physical values shown as colours, with a legend.

Birukov et al., GraphiCon 2022, sections 2 and 3.1: luminance, illuminance, the
calculation-error layer and the ray-hits layer are shown in false colour, with user control
of the colours and of the values they stand for.

Numeric contract: input is one quantity per pixel, ``(..., H, W)``, in any unit (cd/m², lx,
relative error, rays); output is **sRGB-encoded** RGB in [0, 1], ``(..., H, W, 3)`` — colour
scales are defined in sRGB, so write it with :func:`hdrjax.io.write_display` directly, do
not pass it through :func:`hdrjax.display.encode` again.

Mapping. Values in ``[vmin, vmax]`` are placed on the scale linearly or, with ``log=True``,
linearly in ``ln v``, and take the colour scale's colour there (a matplotlib colormap by
name, or a list of colours interpolated in sRGB). With ``levels`` and ``bands=True`` the
range is cut into bands between consecutive levels, one flat colour each (colours evenly
spaced along the scale). ``isolines`` draws one-pixel lines where the value crosses each
given level (a pixel is on the line when it and its right or lower neighbour lie on
different sides of the level).

Special values, each with its own colour (defaults below; all can be changed): below
``vmin`` → ``under`` (also zero and negative values on a log scale), above ``vmax`` →
``over``, NaN → ``nan``, +Inf → ``posinf``, −Inf → ``neginf``. Nothing raises on data.

The range, when not given, is the finite values' minimum and maximum (positive ones for a
log scale) or, with ``percentiles=(lo, hi)``, those percentiles of the finite positive values
from :func:`hdrjax.stats.percentile` (histogram method; the quantities shown this way are
non-negative).
"""

import dataclasses
import functools
from collections.abc import Sequence
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._stats import percentile

UNDER = "black"
"""Default colour of values below the range (and of values ≤ 0 on a log scale)."""
OVER = "white"
"""Default colour of values above the range."""
NAN = "magenta"
"""Default colour of NaN."""
POSINF = "cyan"
"""Default colour of +Inf."""
NEGINF = "navy"
"""Default colour of −Inf."""
ISOLINE = "black"
"""Default colour of iso-lines."""
LUT_SIZE = 256


def _rgb_of(color: Any) -> tuple[float, float, float]:
    """A matplotlib colour (name, hex, RGB tuple) as sRGB floats in [0, 1]."""
    from matplotlib.colors import to_rgb

    try:
        return tuple(float(c) for c in to_rgb(color))
    except ValueError:
        raise ValueError(f"not a colour: {color!r}") from None


def _lut(cmap: Any, n: int = LUT_SIZE) -> np.ndarray:
    """(n, 3) sRGB table of a colormap name, a matplotlib Colormap or a list of colours."""
    import matplotlib
    from matplotlib.colors import Colormap, LinearSegmentedColormap

    if isinstance(cmap, str):
        try:
            cm = matplotlib.colormaps[cmap]
        except KeyError:
            raise ValueError(
                f"cmap: unknown colormap {cmap!r} (any matplotlib name, e.g. viridis, "
                "inferno, turbo, jet; or a list of colours)"
            ) from None
    elif isinstance(cmap, Colormap):
        cm = cmap
    else:
        colors = [_rgb_of(c) for c in cmap]
        if len(colors) < 2:
            raise ValueError("cmap: a list of colours needs at least two")
        cm = LinearSegmentedColormap.from_list("user", colors, N=n)
    return np.asarray(cm(np.linspace(0.0, 1.0, n))[:, :3], np.float32)


@dataclasses.dataclass(frozen=True)
class FalseColorScale:
    """A resolved false-colour mapping: range, scale, colours, bands, iso-lines, labels.

    Build one with :func:`false_color_scale` (or get it from :func:`false_color`); call it
    on values to colour them, ask it for a :meth:`legend` figure, or :meth:`composite` an
    image with its legend.
    """

    vmin: float
    vmax: float
    log: bool
    lut: np.ndarray  # (n, 3) sRGB
    levels: tuple[float, ...] | None
    bands: bool
    isolines: tuple[float, ...]
    under: tuple[float, float, float]
    over: tuple[float, float, float]
    nan: tuple[float, float, float]
    posinf: tuple[float, float, float]
    neginf: tuple[float, float, float]
    isoline_color: tuple[float, float, float]
    name: str | None = None
    unit: str | None = None
    ticks: tuple[float, ...] | None = None

    @property
    def band_colors(self) -> np.ndarray:
        """(n_bands, 3) flat colours of the bands (evenly spaced along the scale)."""
        nb = len(self.levels) - 1
        x = (np.arange(nb) + 0.5) / nb * (len(self.lut) - 1)  # the scale at the band centres
        grid = np.arange(len(self.lut))
        cols = [np.interp(x, grid, self.lut[:, c]) for c in range(3)]
        return np.stack(cols, axis=-1).astype(np.float32)

    @property
    def label(self) -> str:
        name = self.name or "value"
        return f"{name} [{self.unit}]" if self.unit else name

    def __call__(self, values: Float[ArrayLike, "*batch H W"]) -> Float[Array, "*batch H W 3"]:
        """Colour ``values`` (``(..., H, W)``) → sRGB ``(..., H, W, 3)`` in [0, 1]."""
        v = jnp.asarray(values)
        if not jnp.issubdtype(v.dtype, jnp.floating) or v.dtype in (jnp.float16, jnp.bfloat16):
            v = v.astype(jnp.result_type(float))
        if v.ndim < 2:
            raise ValueError(f"values: expected (..., H, W), got shape {v.shape}")
        bands = self.bands and self.levels is not None
        table = self.band_colors if bands else self.lut
        special = np.array([self.under, self.over, self.nan, self.posinf, self.neginf])
        return _colorize(
            v,
            jnp.asarray(table, v.dtype),
            jnp.asarray(special, v.dtype),
            jnp.asarray(self.levels if bands else (), v.dtype),
            jnp.asarray(self.isolines, v.dtype),
            jnp.asarray(self.isoline_color, v.dtype),
            jnp.asarray([self.vmin, self.vmax], v.dtype),
            log=self.log,
            bands=bands,
        )

    def legend(
        self,
        *,
        height: int = 400,
        width: int | None = None,
        dpi: int = 100,
        specials: Sequence[str] = ("nan", "posinf", "neginf"),
    ):
        """A matplotlib Figure with the colour bar (label with name and unit, ticks at
        :attr:`ticks` when given, end triangles for the under/over colours) and patches for
        the ``specials`` (any of ``"nan"``, ``"posinf"``, ``"neginf"``).

        Args:
            height, width: figure size in pixels (width default: about 0.4 × height,
                at least 150).
            dpi: resolution used to convert pixels to inches.
        """
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm, Normalize
        from matplotlib.figure import Figure
        from matplotlib.patches import Patch

        width = width or max(150, int(0.4 * height))
        fig = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
        bands = self.bands and self.levels is not None
        cmap = ListedColormap(self.band_colors if bands else self.lut).with_extremes(
            under=self.under, over=self.over
        )
        if bands:
            norm = BoundaryNorm(self.levels, cmap.N)
        elif self.log:
            norm = LogNorm(self.vmin, self.vmax)
        else:
            norm = Normalize(self.vmin, self.vmax)
        names = {
            "nan": ("NaN", self.nan),
            "posinf": ("+Inf", self.posinf),
            "neginf": ("−Inf", self.neginf),
        }
        handles = [
            Patch(facecolor=names[s][1], edgecolor="0.3", label=names[s][0]) for s in specials
        ]
        bottom = 0.06 + 0.045 * len(handles) * (400 / max(height, 100))
        ax = fig.add_axes((0.12, min(bottom, 0.5), 0.16, 0.9 - min(bottom, 0.5)))
        cbar = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), cax=ax, extend="both")
        cbar.set_label(self.label)
        if self.ticks is not None:
            cbar.set_ticks(list(self.ticks))
            cbar.set_ticklabels([f"{t:g}" for t in self.ticks])
        elif bands:
            cbar.set_ticks(list(self.levels))
            cbar.set_ticklabels([f"{t:g}" for t in self.levels])
        if handles:
            fig.legend(
                handles=handles,
                loc="lower left",
                fontsize="small",
                frameon=False,
                borderaxespad=0.2,
            )
        return fig

    def composite(self, image: ArrayLike, *, legend_width: int | None = None, **legend_kw):
        """The image with its legend on the right, as one ``(H', W + w, 3)`` float array
        (sRGB, [0, 1]; the legend is rendered at the image's height, at least 300 px; a
        shorter image is padded with white below)."""
        img = np.asarray(image, np.float32)
        if img.ndim != 3 or img.shape[-1] != 3:
            raise ValueError(f"image: expected (H, W, 3), got shape {img.shape}")
        h = max(img.shape[0], 300)
        leg = render_figure(self.legend(height=h, width=legend_width, **legend_kw))[:h]
        if leg.shape[0] < h:
            leg = np.pad(leg, ((0, h - leg.shape[0]), (0, 0), (0, 0)), constant_values=1.0)
        if img.shape[0] < h:
            img = np.pad(img, ((0, h - img.shape[0]), (0, 0), (0, 0)), constant_values=1.0)
        return np.concatenate([img, leg], axis=1)


def render_figure(fig) -> np.ndarray:
    """A matplotlib Figure as an (H, W, 3) float sRGB array in [0, 1] (Agg, no pyplot)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].astype(np.float32) / 255.0


@functools.partial(jax.jit, static_argnames=("log", "bands"))
def _colorize(v, table, special, levels, isolines, iso_color, vrange, *, log, bands):
    vmin, vmax = vrange[0], vrange[1]
    finite = jnp.isfinite(v)
    if log:
        pos = finite & (v > 0)
        lv = jnp.log(jnp.where(pos, v, 1.0))
        t = (lv - jnp.log(vmin)) / (jnp.log(vmax) - jnp.log(vmin))
        below = finite & ~pos | (pos & (v < vmin))
    else:
        t = (jnp.where(finite, v, 0.0) - vmin) / (vmax - vmin)
        below = finite & (v < vmin)
    above = finite & (v > vmax)
    if bands:
        j = jnp.searchsorted(levels, jnp.where(finite, v, 0.0), side="right") - 1
        j = jnp.clip(j, 0, table.shape[0] - 1)  # v == levels[-1] joins the top band
        rgb = table[j]
    else:
        x = jnp.clip(t, 0.0, 1.0) * (table.shape[0] - 1)
        i0 = jnp.clip(jnp.floor(x).astype(jnp.int32), 0, table.shape[0] - 2)
        f = (x - i0)[..., None]
        rgb = table[i0] * (1 - f) + table[i0 + 1] * f
    cases = [below, above, jnp.isnan(v), v == jnp.inf, v == -jnp.inf]
    for case, color in zip(cases, special, strict=True):
        rgb = jnp.where(case[..., None], color, rgb)
    for k in range(isolines.shape[0]):
        side = v >= isolines[k]
        ok = ~jnp.isnan(v)
        right = (side[..., :, :-1] != side[..., :, 1:]) & ok[..., :, :-1] & ok[..., :, 1:]
        down = (side[..., :-1, :] != side[..., 1:, :]) & ok[..., :-1, :] & ok[..., 1:, :]
        line = jnp.zeros(v.shape, bool)
        line = line.at[..., :, :-1].set(right)
        line = line.at[..., :-1, :].set(line[..., :-1, :] | down)
        rgb = jnp.where(line[..., None], iso_color, rgb)
    return rgb


@functools.partial(jax.jit, static_argnums=(1, 2))
def _data_range(v: Array, log: bool, percentiles) -> tuple[Array, Array]:
    if percentiles is not None:
        (lo, hi), _ = percentile(v, jnp.asarray(percentiles, jnp.float32))
        return lo, hi
    finite = jnp.isfinite(v)
    # subnormals count as 0: XLA:CPU flushes them, so their logs would be -inf
    use = finite & (v >= jnp.finfo(v.dtype).tiny) if log else finite
    return jnp.min(jnp.where(use, v, jnp.inf)), jnp.max(jnp.where(use, v, -jnp.inf))


def _auto_range(v, log: bool, percentiles) -> tuple[float, float]:
    """Range from the data: min/max (positive for log) or percentiles; never degenerate."""
    v = jnp.asarray(v)
    if not jnp.issubdtype(v.dtype, jnp.floating):
        v = v.astype(jnp.result_type(float))
    lo, hi = (float(t) for t in _data_range(v, log, percentiles)) if v.size else (np.nan,) * 2
    if not (np.isfinite(lo) and np.isfinite(hi)):  # no usable value (or no value at all)
        return (1.0, 10.0) if log else (0.0, 1.0)
    if hi <= lo:
        if log:
            return lo / 2.0, lo * 2.0
        pad = abs(lo) * 0.5 if lo != 0 else 0.5
        return lo - pad, lo + pad
    return lo, hi


def _floats(name: str, xs) -> tuple[float, ...] | None:
    if xs is None:
        return None
    out = tuple(float(x) for x in np.atleast_1d(np.asarray(xs, np.float64)))
    if not all(np.isfinite(out)):
        raise ValueError(f"{name}: expected finite numbers, got {xs!r}")
    return out


def false_color_scale(
    values: ArrayLike | None = None,
    *,
    cmap: Any = "viridis",
    vmin: float | None = None,
    vmax: float | None = None,
    percentiles: tuple[float, float] | None = None,
    log: bool = False,
    levels: Sequence[float] | None = None,
    bands: bool = False,
    isolines: Sequence[float] | None = None,
    name: str | None = None,
    unit: str | None = None,
    ticks: Sequence[float] | None = None,
    under: Any = UNDER,
    over: Any = OVER,
    nan: Any = NAN,
    posinf: Any = POSINF,
    neginf: Any = NEGINF,
    isoline_color: Any = ISOLINE,
) -> FalseColorScale:
    """Resolve a false-colour mapping; see :func:`false_color` for the arguments.

    ``values`` is needed only when ``vmin``/``vmax`` are to be taken from the data.

    Raises:
        ValueError: bad arguments (unknown colormap or colour, ``vmin ≥ vmax``, a
            non-positive range on a log scale, fewer than two or unsorted band levels).
    """
    levels_t = _floats("levels", levels)
    if bands:
        if levels_t is None or len(levels_t) < 2:
            raise ValueError("bands=True needs at least two levels")
        if any(b <= a for a, b in zip(levels_t, levels_t[1:], strict=False)):
            raise ValueError(f"levels: expected increasing values, got {levels_t}")
        if log and levels_t[0] <= 0:
            raise ValueError(f"levels: a log scale needs levels > 0, got {levels_t}")
        vmin, vmax = levels_t[0], levels_t[-1]
    if percentiles is not None:
        p = _floats("percentiles", percentiles)
        if len(p) != 2 or not 0 <= p[0] < p[1] <= 100:
            raise ValueError(f"percentiles: expected (lo, hi) with 0 <= lo < hi <= 100, got {p}")
        percentiles = p
    if vmin is None or vmax is None:
        if values is None:
            raise ValueError("vmin and vmax are needed when no values are given")
        lo, hi = _auto_range(values, log, percentiles)
        vmin = lo if vmin is None else vmin
        vmax = hi if vmax is None else vmax
    vmin, vmax = float(vmin), float(vmax)
    if not (np.isfinite(vmin) and np.isfinite(vmax) and vmin < vmax):
        raise ValueError(f"range: expected finite vmin < vmax, got {vmin}:{vmax}")
    if log and vmin <= 0:
        raise ValueError(f"range: a log scale needs vmin > 0, got {vmin}")
    return FalseColorScale(
        vmin=vmin,
        vmax=vmax,
        log=bool(log),
        lut=_lut(cmap),
        levels=levels_t,
        bands=bool(bands),
        isolines=_floats("isolines", isolines) or (),
        under=_rgb_of(under),
        over=_rgb_of(over),
        nan=_rgb_of(nan),
        posinf=_rgb_of(posinf),
        neginf=_rgb_of(neginf),
        isoline_color=_rgb_of(isoline_color),
        name=name,
        unit=unit,
        ticks=_floats("ticks", ticks),
    )


class FalseColor(NamedTuple):
    """What :func:`false_color` returns."""

    image: Array
    """sRGB in [0, 1], ``(..., H, W, 3)``."""
    legend: Any
    """A matplotlib Figure (``None`` with ``legend=False``); save it with ``savefig``."""
    scale: FalseColorScale
    """The resolved mapping: apply it to other images, or :meth:`~FalseColorScale.composite`."""
    specials: tuple[str, ...] = ()
    """Which of ``"nan"``, ``"posinf"``, ``"neginf"`` occur in the values (legend patches)."""

    def composite(self, **legend_kw) -> np.ndarray:
        """One ``(H', W + w, 3)`` sRGB array: the image (a single one) with its legend."""
        legend_kw.setdefault("specials", self.specials)
        return self.scale.composite(self.image, **legend_kw)


def false_color(
    values: Float[ArrayLike, "*batch H W"], *, legend: bool = True, **options: Any
) -> FalseColor:
    """Show a physical quantity in false colour and make its legend.

    Args:
        values: the quantity per pixel, ``(..., H, W)``: luminance (cd/m²), illuminance (lx),
            an error or ray-hits layer, ...
        cmap: a matplotlib colormap name (``"viridis"``, ``"turbo"``, ``"jet"``...), a
            matplotlib Colormap, or a list of colours (names, ``"#rrggbb"`` or RGB tuples in
            [0, 1]) interpolated in sRGB.
        vmin, vmax: the range, in the values' unit. Missing ends come from the data: the
            finite minimum/maximum (positive ones on a log scale) or ``percentiles``.
        percentiles: ``(lo, hi)`` in [0, 100] for the automatic range (e.g. ``(1, 99)``).
        log: logarithmic scale (values ≤ 0 get the ``under`` colour).
        levels: band edges for ``bands=True`` (increasing; they set the range).
        bands: flat colour bands between consecutive ``levels`` instead of a gradient.
        isolines: values at which to draw one-pixel iso-lines in ``isoline_color``.
        name, unit: the quantity's name and unit for the legend label (``"luminance"``,
            ``"cd/m²"``).
        ticks: legend tick values (default: matplotlib's, or the levels for bands).
        under, over, nan, posinf, neginf, isoline_color: colours of values below/above the
            range, NaN, +Inf, −Inf and the iso-lines (any matplotlib colour).
        legend: build the legend figure.

    All options but ``legend`` are keyword arguments of :func:`false_color_scale`, which
    resolves them (a misspelt name raises ``TypeError``).

    Returns:
        ``FalseColor(image, legend, scale)``: sRGB ``(..., H, W, 3)`` in [0, 1], the legend
        Figure (with NaN/±Inf patches only for those present in ``values``), the resolved
        :class:`FalseColorScale`, and which special values occur. ``.composite()`` puts the
        image and its legend side by side in one array (for one PNG).

    Raises:
        ValueError: bad arguments only (see :func:`false_color_scale`); never on the data.

    Example:
        >>> import numpy as np
        >>> L = np.array([[0.5, 10.0, 200.0], [np.nan, np.inf, 1e4]], np.float32)
        >>> fc = false_color(L, vmin=1, vmax=1000, log=True, cmap=["blue", "red"], legend=False)
        >>> fc.image[0, 0].tolist()  # below the range
        [0.0, 0.0, 0.0]
        >>> [round(c, 3) for c in fc.image[0, 2].tolist()]  # ln 200 / ln 1000 of the way to red
        [0.767, 0.0, 0.233]
        >>> fc.image[1].tolist()  # NaN, +Inf, above the range
        [[1.0, 0.0, 1.0], [0.0, 1.0, 1.0], [1.0, 1.0, 1.0]]
    """
    _check.real(values, "values")
    _check.nonempty(np.shape(values), "values", "(..., H, W)", (-2, -1))
    scale = false_color_scale(values, **options)
    image = scale(values)
    v = jnp.asarray(values)
    found = (jnp.any(jnp.isnan(v)), jnp.any(v == jnp.inf), jnp.any(v == -jnp.inf))
    present = tuple(s for s, hit in zip(("nan", "posinf", "neginf"), found, strict=True) if hit)
    fig = scale.legend(specials=present) if legend else None
    return FalseColor(image, fig, scale, present)
