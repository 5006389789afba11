"""Parameter studies: an operator evaluated over a grid of parameter values in one call.

Numeric contract: ``image`` is linear RGB ``(H, W, 3)`` as the operator expects it (relative
or cd/m²); grid values are in the operator's own units. Grid point ``g`` is the operator with
the swept parameters set to ``g`` and its other unset (``None``) parameters filled by
``operator.measure(image)`` on the *full-resolution* image with those values set (as
:func:`hdrjax.tonemap` would measure them, so e.g. ``reinhard2002``'s automatic ``L_white``
follows a swept ``key``), then applied to the image box-filtered to at most ``max_size``
pixels on its long side (:func:`hdrjax.fit.downscale`, the same reduction
:func:`hdrjax.fit.fit` uses). The statistics of that display image are those of
:mod:`hdrjax.targets`, so a sweep shows the landscape a fit walks:

- ``mean``: :class:`~hdrjax.targets.MeanLuminance`, ``mean(L_d)`` with
  ``L_d = luminance(clip(display, 0, 1))``;
- ``p1``, ``p50``, ``p99``: :class:`~hdrjax.targets.Percentiles`, exact percentiles of the
  pixels with ``L_d > 0`` (linear interpolation, as ``numpy.percentile``);
- ``clipped``: :class:`~hdrjax.targets.ClippedFraction`, the *soft* fraction of pixels with a
  channel at display white, ``mean(σ((max_c rgb_c − 1) / 0.01))``.

With a ``target`` the sweep also returns its loss ``Σ r²`` (``r = target.residuals``), the
quantity :func:`hdrjax.fit.fit` minimises; a target that takes the source image
(:class:`hdrjax.targets.TMQI`) gets the box-filtered input the operator was applied to.

The whole grid (the outer product of the value lists) is evaluated in one jit-compiled
``jax.vmap`` over the flattened grid; image statistics that do not depend on the swept
parameters stay unbatched under ``vmap`` and are computed once. Memory grows as
``grid points × downscaled pixels``; ``batch_size`` evaluates the grid in vmapped chunks
(``jax.lax.map``) when that is too much.
"""

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ._progress import compiled_progress, tick, wait_ready
from .fit import downscale
from .operators import make_operator, parameter_info
from .operators._base import AbstractOperator, as_float_image
from .targets import AbstractTarget, ClippedFraction, MeanLuminance, Percentiles

STAT_NAMES: tuple[str, ...] = ("mean", "p1", "p50", "p99", "clipped")
"""Names of the default statistics, in the order of the last axis of ``statistics``."""


def _default_statistics() -> AbstractTarget:
    """The targets behind :data:`STAT_NAMES` (values unused; built on use, not at import, so
    that importing hdrjax creates no arrays)."""
    return MeanLuminance(0.0) + Percentiles((1.0, 50.0, 99.0), (0.0,) * 3) + ClippedFraction(0.0)


class SweepResult(eqx.Module):
    """The statistics of an operator over a parameter grid (see :func:`sweep`).

    Attributes:
        axes: the grid values of each swept parameter, in the order of ``params``.
        statistics: shape ``(*grid_shape, len(stat_names))``; ``statistics[i, j, k]`` is
            statistic ``k`` at ``params[0] = axes[0][i]``, ``params[1] = axes[1][j]``.
        loss: the target's loss ``Σ r²`` over the grid, shape ``grid_shape`` (``None``
            without a target).
        operator: the operator that was swept (the swept fields as given, not the grid's).
        params: the swept parameter names (one grid axis each).
        stat_names: the names of the statistics (:data:`STAT_NAMES`).
    """

    axes: tuple[Array, ...]
    statistics: Float[Array, "*grid n"]
    loss: Float[Array, "*grid"] | None
    operator: AbstractOperator
    params: tuple[str, ...] = eqx.field(static=True)
    stat_names: tuple[str, ...] = eqx.field(static=True, default=STAT_NAMES)

    @property
    def shape(self) -> tuple[int, ...]:
        """The grid shape, ``tuple(len(a) for a in axes)``."""
        return tuple(int(a.shape[0]) for a in self.axes)

    @property
    def grid(self) -> dict[str, Array]:
        """``{name: values}`` of the swept parameters."""
        return dict(zip(self.params, self.axes, strict=True))

    def stat(self, name: str) -> Float[Array, "*grid"]:
        """One statistic over the grid (``"loss"`` for the target's loss)."""
        if name == "loss":
            if self.loss is None:
                raise ValueError("stat: 'loss' needs a sweep with a target")
            return self.loss
        if name not in self.stat_names:
            valid = list(self.stat_names) + (["loss"] if self.loss is not None else [])
            raise ValueError(f"stat: unknown statistic {name!r}; valid: {', '.join(valid)}")
        return self.statistics[..., self.stat_names.index(name)]

    def _best(self) -> list[Array]:
        """The swept values at the least-loss grid point (NaN losses ignored)."""
        i = np.unravel_index(int(np.nanargmin(np.asarray(self.stat("loss")))), self.shape)
        return [a[k] for a, k in zip(self.axes, i, strict=True)]

    def argmin(self) -> dict[str, float]:
        """The grid point of least loss, ``{name: value}`` (needs a target)."""
        return {n: float(v) for n, v in zip(self.params, self._best(), strict=True)}

    def best_operator(self) -> AbstractOperator:
        """The swept operator with the parameters of the least-loss grid point set (its other
        ``None`` parameters still unset): a starting point for :func:`hdrjax.fit.fit`."""
        return _with(self.operator, self.params, self._best())

    def select(self, **indices: int) -> "SweepResult":
        """The sub-grid with the named parameters fixed at the given grid *indices*
        (e.g. ``res.select(key=3)`` to plot a slice of a 3-parameter sweep)."""
        bad = sorted(set(indices) - set(self.params))
        if bad:
            raise ValueError(f"select: {bad} are not swept parameters {list(self.params)}")
        idx = tuple(int(indices[n]) if n in indices else slice(None) for n in self.params)
        for n, a, i in zip(self.params, self.axes, idx, strict=True):
            if isinstance(i, int) and not -a.shape[0] <= i < a.shape[0]:
                raise ValueError(f"select: {n}={i} is outside the grid of {a.shape[0]} values")
        keep = [k for k, n in enumerate(self.params) if n not in indices]
        return SweepResult(
            axes=tuple(self.axes[k] for k in keep),
            statistics=self.statistics[idx],
            loss=None if self.loss is None else self.loss[idx],
            operator=self.operator,
            params=tuple(self.params[k] for k in keep),
            stat_names=self.stat_names,
        )

    def _ranges(self) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
        """Text of each swept parameter's values and of each statistic's range over the
        grid (with the least-loss point when there is a loss)."""
        from . import _repr

        units = {i.name: _repr.short_unit(i.unit) for i in parameter_info(self.operator)}
        swept = [
            (
                n,
                f"{a.shape[0]} values, {_repr.value(np.min(a))} to {_repr.value(np.max(a))}"
                + (f" {units[n]}" if units.get(n) else ""),
            )
            for n, a in self.grid.items()
        ]
        names = list(self.stat_names) + (["loss"] if self.loss is not None else [])
        stats = []
        for n in names:
            s = np.asarray(self.stat(n))
            ok = s[np.isfinite(s)]
            text = f"{_repr.value(ok.min())} to {_repr.value(ok.max())}" if ok.size else "NaN"
            stats.append((n, text))
        if self.loss is not None and np.isfinite(np.asarray(self.loss)).any():
            best = ", ".join(f"{k}={_repr.value(v)}" for k, v in self.argmin().items())
            stats.append(("least loss at", best))
        return swept, stats

    def __repr__(self) -> str:
        """``SweepResult(reinhard2002 over key: 8 values, 0.05 to 0.5; mean 0.1 to 0.4, …)``."""
        from . import _repr

        if not _repr.concrete(self.statistics):
            return f"SweepResult({self.operator.name} over {', '.join(self.params)}; traced)"
        swept, stats = self._ranges()
        over = "; ".join(f"{n}: {t}" for n, t in swept)
        return (
            f"SweepResult({self.operator.name} over {over}; "
            + ", ".join(f"{n} {t}" for n, t in stats)
            + ")"
        )

    def _repr_html_(self) -> str:
        """A notebook's view: the swept values, each statistic's range over the grid (and
        the least-loss point), and for a 1-D grid of at most 16 points every value."""
        from . import _repr

        if not _repr.concrete(self.statistics):
            return _repr.preformatted(repr(self))
        swept, stats = self._ranges()
        body = _repr.table(swept, ("swept", "values")) + _repr.table(stats, ("statistic", "range"))
        if len(self.params) == 1 and self.shape[0] <= 16:
            names = list(self.stat_names) + (["loss"] if self.loss is not None else [])
            cols = [np.asarray(self.stat(n)) for n in names]
            rows = [
                [_repr.value(a)] + [_repr.value(c[i]) for c in cols]
                for i, a in enumerate(np.asarray(self.axes[0]))
            ]
            body += _repr.table(rows, [self.params[0], *names])
        title = f"SweepResult: {type(self.operator).__name__} ({self.operator.name})"
        return _repr.view(title, body, note=f"operator: {self.operator!r}")


def _with(op: AbstractOperator, names: tuple[str, ...], values: Sequence[Array]):
    return eqx.tree_at(
        lambda o: tuple(getattr(o, n) for n in names),
        op,
        tuple(values),
        is_leaf=lambda x: x is None,
    )


@eqx.filter_jit
def _sweep_jit(op, image, names, flat, target, max_size, batch_size, ticks=False):
    small = downscale(image, max_size)
    stats = _default_statistics()

    def one(values):
        if ticks:  # once per grid point (vmap and lax.map call it per element)
            tick(values[0])
        o = _with(op, names, values).measure(image)
        out = o(small)
        s = stats.statistics(out)
        if target is None:
            return s, None
        r = target.residuals_for(out, small)
        return s, jnp.sum(r * r)

    if batch_size is None:
        return jax.vmap(one)(flat)
    return jax.lax.map(one, flat, batch_size=batch_size)


def _grid_values(op: AbstractOperator, grid: Any) -> dict[str, np.ndarray]:
    valid = sorted(
        f.name for f in dataclasses.fields(op) if f.init and not f.metadata.get("static", False)
    )
    if not isinstance(grid, Mapping) or not grid:
        raise ValueError(
            f"grid: expected a non-empty dict {{parameter: 1-D values}} of {op.name} "
            f"parameters ({', '.join(valid)}), got {grid!r}"
        )
    bad = [n for n in grid if n not in valid]
    if bad:
        raise ValueError(f"grid: {bad} are not parameters of {op.name}; valid: {', '.join(valid)}")
    out = {}
    for n, v in grid.items():
        try:
            a = np.asarray(v, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"grid[{n!r}]: expected 1-D numeric values, got {v!r}") from None
        if a.ndim != 1:
            raise ValueError(f"grid[{n!r}]: expected 1-D values, got shape {a.shape}")
        if a.size == 0:
            raise ValueError(f"grid[{n!r}]: no values (empty array)")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"grid[{n!r}]: values must be finite, got {a.tolist()}")
        out[n] = a
    return out


def sweep(
    operator: AbstractOperator | str,
    image: Float[ArrayLike, "H W 3"],
    grid: Mapping[str, Float[ArrayLike, " n"]],
    target: AbstractTarget | None = None,
    *,
    max_size: int | None = 64,
    batch_size: int | None = None,
    progress: bool = True,
) -> SweepResult:
    """Evaluate ``operator`` at every point of ``grid`` and measure the display statistics.

    Where a person watches (a terminal or a Jupyter notebook; never in a pipe, a log or
    inside an enclosing ``jit``) and ``progress`` is true, a bar counts the grid points
    evaluated, for sweeps that last over a second (with ``batch_size``, it advances batch
    by batch); the call then returns when the sweep is done.

    Args:
        operator: an operator instance (parameters not in ``grid`` keep their values; ``None``
            ones are measured, see the module docstring) or a registered name.
        image: linear RGB ``(H, W, 3)``.
        grid: ``{parameter: 1-D values}``; one grid axis per entry, in this order (the full
            outer product for two or more). Only scalar array parameters can be swept.
        target: an :mod:`hdrjax.targets` target whose loss ``Σ r²`` is also returned.
        max_size: evaluate on the image box-filtered to this long side (``None``: full size).
        batch_size: evaluate this many grid points at a time (``None``: all at once).

    Returns:
        A :class:`SweepResult`; ``statistics`` has shape ``(*grid_shape, 5)``
        (:data:`STAT_NAMES`).

    Raises:
        ValueError: an unknown or non-scalar parameter name (the message lists the valid
            ones), empty, non-1-D or non-finite grid values, or a malformed image.

    >>> import jax.numpy as jnp
    >>> img = jnp.exp(jnp.linspace(-3.0, 3.0, 48)).reshape(4, 4, 3)
    >>> res = sweep("linear", img, {"L_max": [1.0, 10.0, 100.0]})
    >>> res.statistics.shape, res.stat_names[0]
    ((3, 5), 'mean')
    """
    op = make_operator(operator) if isinstance(operator, str) else operator
    if not isinstance(op, AbstractOperator):
        raise ValueError(f"operator: expected an operator or a registered name, got {op!r}")
    if target is not None and not isinstance(target, AbstractTarget):
        raise ValueError(f"target: expected an hdrjax.targets target or None, got {target!r}")
    if max_size is not None and not int(max_size) >= 1:
        raise ValueError(f"max_size: expected an integer >= 1 or None, got {max_size!r}")
    if batch_size is not None and not int(batch_size) >= 1:
        raise ValueError(f"batch_size: expected an integer >= 1 or None, got {batch_size!r}")
    values = _grid_values(op, grid)
    image = as_float_image(image, "image")
    if image.ndim != 3:
        raise ValueError(f"image: expected one image (H, W, 3), got {image.shape}")
    names = tuple(values)
    measured = eqx.filter_eval_shape(lambda o, x: o.measure(x), op, image)
    for n in names:
        shape = getattr(measured, n).shape
        if shape != ():
            raise ValueError(f"grid[{n!r}]: {op.name}.{n} has shape {shape}; only scalars sweep")
    dtype = jnp.result_type(float)
    axes = tuple(jnp.asarray(values[n], dtype) for n in names)
    mesh = jnp.meshgrid(*axes, indexing="ij")
    flat = tuple(m.reshape(-1) for m in mesh)
    show = progress and not isinstance(image, jax.core.Tracer)
    points = int(flat[0].shape[0])
    with compiled_progress(show, total=points, unit="point", desc=f"sweep {op.name}") as ticks:
        stats, loss = _sweep_jit(
            op,
            image,
            names,
            flat,
            target,
            None if max_size is None else int(max_size),
            None if batch_size is None else int(batch_size),
            ticks,
        )
        if ticks:
            wait_ready((stats, loss))
    shape = tuple(a.shape[0] for a in axes)
    return SweepResult(
        axes=axes,
        statistics=stats.reshape(*shape, stats.shape[-1]),
        loss=None if loss is None else loss.reshape(shape),
        operator=op,
        params=names,
    )


# ----------------------------------------------------------------------------- plotting


def _is_log(v: np.ndarray) -> bool:
    """Positive values spaced evenly in ``ln`` (not linearly), or two spanning a decade."""
    if v.size < 2 or np.any(v <= 0):
        return False
    if v.size == 2:
        return bool(max(v) / min(v) >= 10.0)
    dl, d = np.diff(np.log(v)), np.diff(v)
    even_log = np.allclose(dl, dl[0], rtol=1e-3, atol=0.0)
    even_lin = np.allclose(d, d[0], rtol=1e-3, atol=0.0)
    return bool(even_log and not even_lin)


def _edges(v: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around the grid values (midpoints; geometric midpoints on a log axis)."""
    x = np.log(v) if log else v.astype(np.float64)
    if x.size == 1:  # one value: a cell of ±half its size (±0.5 in ln on a log axis)
        h = 0.5 if log else 0.5 * (abs(x[0]) or 1.0)
        e = np.array([x[0] - h, x[0] + h])
    else:
        mid = 0.5 * (x[1:] + x[:-1])
        e = np.concatenate([[2 * x[0] - mid[0]], mid, [2 * x[-1] - mid[-1]]])
    return np.exp(e) if log else e


def plot_sweep(
    result: SweepResult,
    stat: str | Sequence[str] | None = None,
    ax: Any = None,
    *,
    log: bool | Sequence[bool] | None = None,
    cmap: str = "viridis",
    norm: str | None = None,
) -> Any:
    """Draw a sweep with matplotlib; returns the Axes drawn into.

    Two parameters: a heat map (``pcolormesh``) of one statistic, ``params[0]`` on x and
    ``params[1]`` on y, with a labelled colour bar; a stat of ``None`` draws the loss when
    there is one, else ``"mean"``. One parameter: one curve per statistic (``None``: all of
    :data:`STAT_NAMES`, display units on the left axis) and, with a target, the loss on a
    twin right axis. The grid point of least loss is marked (a white star on heat maps, a
    dot on the loss curve) when the sweep has a loss. Sweeps of three or more parameters
    are plotted through :meth:`SweepResult.select`.

    Args:
        result: from :func:`sweep`.
        stat: a statistic name (``"loss"`` included), or several for a 1-parameter sweep.
        ax: Axes to draw into (a new figure when ``None``).
        log: log scale per parameter axis; ``None`` chooses log for positive log-spaced
            values.
        cmap: colour map of the heat map.
        norm: its colour scale (``"linear"``, ``"log"``, …); ``None``: log for a loss
            spanning more than two decades, else linear.
    """
    import matplotlib.pyplot as plt

    k = len(result.params)
    if k not in (1, 2):
        raise ValueError(
            f"plot_sweep: draws 1 or 2 parameters, the sweep has {k} ({list(result.params)}); "
            "fix the others with result.select(name=index)"
        )
    order = [np.argsort(np.asarray(a)) for a in result.axes]  # cells need increasing edges
    axes = [np.asarray(a, np.float64)[o] for a, o in zip(result.axes, order, strict=True)]
    if log is None:
        logs = [_is_log(a) for a in axes]
    elif isinstance(log, bool):
        logs = [log] * k
    else:
        logs = [bool(v) for v in log]
        if len(logs) != k:
            raise ValueError(f"log: expected {k} values (one per parameter), got {len(logs)}")
    for a, lg, n in zip(axes, logs, result.params, strict=True):
        if lg and np.any(a <= 0):
            raise ValueError(f"log: {n} has values <= 0 and cannot use a log axis")
    has_loss = result.loss is not None
    name = result.operator.name
    c, stats, values = np.empty((0, 0)), [], {}
    if k == 2:
        if stat is None:
            stat = "loss" if has_loss else "mean"
        if not isinstance(stat, str):
            raise ValueError("stat: a heat map shows one statistic; pass its name")
        c = np.asarray(result.stat(stat), np.float64)[np.ix_(*order)]
    else:
        if stat is None:
            stats = list(result.stat_names)
        else:
            stats = [stat] if isinstance(stat, str) else list(stat)
        values = {s: np.asarray(result.stat(s), np.float64)[order[0]] for s in stats}
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4.5) if k == 2 else (6, 4), layout="constrained")

    if k == 2:
        if norm is None and stat == "loss" and np.all(c > 0) and c.max() > 100 * c.min():
            norm = "log"  # losses span decades: a linear scale hides the minimum
        mesh = ax.pcolormesh(
            _edges(axes[0], logs[0]),
            _edges(axes[1], logs[1]),
            c.T,
            cmap=cmap,
            norm=norm,
            shading="flat",
        )
        ax.figure.colorbar(mesh, ax=ax, label=stat)
        if logs[0]:
            ax.set_xscale("log")
        if logs[1]:
            ax.set_yscale("log")
        ax.set_xlabel(result.params[0])
        ax.set_ylabel(result.params[1])
        ax.set_title(f"{name}: {stat}")
        if has_loss:
            best = result.argmin()
            ax.plot(
                best[result.params[0]],
                best[result.params[1]],
                "*",
                color="white",
                mec="black",
                ms=14,
                label=f"min loss {float(np.nanmin(np.asarray(result.loss))):.3g}",
            )
            ax.legend(loc="best", fontsize="small")
        return ax

    x = axes[0]
    for s in stats:
        if s != "loss":
            ax.plot(x, values[s], marker=".", label=s)
    if logs[0]:
        ax.set_xscale("log")
    ax.set_xlabel(result.params[0])
    ax.set_ylabel("display luminance / fraction")
    ax.set_title(f"{name}: sweep of {result.params[0]}")
    lax = ax
    if has_loss and (stat is None or "loss" in stats):
        lax = ax if all(s == "loss" for s in stats) else ax.twinx()
        loss = np.asarray(result.loss, np.float64)[order[0]]
        lax.plot(x, loss, "--", color="black", label="loss")
        best = int(np.nanargmin(loss))
        lax.plot(x[best], loss[best], "o", color="red", label=f"min loss {loss[best]:.3g}")
        lax.set_ylabel("loss")
        if lax is not ax:
            lax.set_yscale("log" if np.all(loss > 0) else "linear")
    handles, labels = ax.get_legend_handles_labels()
    if lax is not ax:
        h2, l2 = lax.get_legend_handles_labels()
        handles, labels = handles + h2, labels + l2
    if handles:
        ax.legend(handles, labels, loc="best", fontsize="small")
    return ax


__all__ = ["STAT_NAMES", "SweepResult", "plot_sweep", "sweep"]
