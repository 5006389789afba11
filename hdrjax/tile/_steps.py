"""Neighbourhood steps that can run on tiles: each declares its halo and maps one window.

A step is an equinox Module. :meth:`AbstractStep.halo` gives, for an image shape, how many
pixels beyond a tile (rows, columns) its result depends on; :meth:`AbstractStep.bind` fixes
what the whole image determines (image size, global statistics) and returns the step that is
then called on every window. A window's true image edges are the image's own, so each
step handles them with the whole-image function's own edge rule (see :mod:`._layout`).
"""

import abc
import functools
import math
from collections.abc import Callable, Sequence
from typing import Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .. import _check
from .._stats import Statistics
from ..filters import mean_filter, median_filter
from ..filters._api import check_passes, check_size
from ..operators._base import AbstractOperator, StatisticsSettings
from ..vision._fft import fft_size, kernel_spectrum
from ..vision._spencer1995 import Variant, apply_glare, glare_kernel, kernel_radius
from ..vision._view import ResolvedView, View, resolve_view

TILE_MODES = ("nearest", "reflect", "mirror")
"""Filter edge modes that tiles reproduce exactly (``"wrap"`` reads the opposite edge)."""


class AbstractStep(eqx.Module):
    """A neighbourhood operation with a known halo (see the module docstring)."""

    def statistics_settings(
        self,
    ) -> tuple[tuple[float, float, float], StatisticsSettings] | None:
        """``(weights, settings)`` of the whole-image statistics :meth:`bind` reads (a first
        pass over the tiles, :func:`hdrjax.tile.apply`), ``None`` when it reads none."""
        return None

    @property
    def needs_stats(self) -> bool:
        """Whether :meth:`bind` needs whole-image statistics (a first pass)."""
        return self.statistics_settings() is not None

    @abc.abstractmethod
    def halo(self, shape: tuple[int, ...]) -> tuple[int, int]:
        """Pixels (rows, columns) beyond a tile that its result depends on."""

    def bind(self, shape: tuple[int, ...], stats: Statistics | None) -> "AbstractStep":
        """The step for an image of ``shape`` with global ``stats`` (first pass) filled in."""
        del shape, stats
        return self

    @abc.abstractmethod
    def __call__(self, window: Array) -> Array:
        """Map one window (``(h, w)`` or ``(h, w, C)``) to a result of the same shape."""


def _check_mode(mode: str) -> str:
    if mode not in TILE_MODES:
        raise ValueError(
            f"mode: tiles reproduce the edge modes {', '.join(TILE_MODES)}, got {mode!r}"
            " ('wrap' needs the opposite image edge; run the whole image instead)"
        )
    return mode


def _check_planes(shape, channel_axis) -> None:
    """Filters see ``(H, W)`` planes with ``channel_axis=None``, else ``(H, W, C)``."""
    want = 2 if channel_axis is None else 3
    if len(shape) != want:
        what = "(H, W) with channel_axis=None" if want == 2 else "(H, W, C) with channel_axis=-1"
        raise ValueError(f"image: expected shape {what}, got {tuple(shape)}")


class _AbstractFilterStep(AbstractStep):
    """A k×k filter repeated ``passes`` times: halo ``passes · (size // 2)``, no statistics.

    Subclasses declare the fields ``size``, ``passes``, ``mode`` and ``channel_axis``.
    """

    size: eqx.AbstractVar[int]
    passes: eqx.AbstractVar[int]
    mode: eqx.AbstractVar[str]
    channel_axis: eqx.AbstractVar[int | None]

    def __check_init__(self):
        check_size(self.size)
        check_passes(self.passes)
        _check_mode(self.mode)

    def halo(self, shape):
        h = self.passes * (self.size // 2)
        return h, h

    def bind(self, shape, stats):
        _check_planes(shape, self.channel_axis)
        return self


class Median(_AbstractFilterStep):
    """:func:`hdrjax.filters.median_filter` on tiles; bit-identical to the whole image.

    Halo ``passes · (size // 2)``. Each window is filtered with the same function; its
    flat pixel positions (the luminance criterion's tie-break) are the image's shifted by a
    constant, so ties go to the same pixel as in the whole image.
    """

    size: int = eqx.field(static=True, default=5)
    criterion: Literal["luminance", "channels", "vector"] = eqx.field(
        static=True, default="luminance"
    )
    passes: int = eqx.field(static=True, default=1)
    mode: str = eqx.field(static=True, default="nearest")
    weights: tuple[float, float, float] | None = eqx.field(static=True, default=None)
    channel_axis: int | None = eqx.field(static=True, default=-1)

    def __call__(self, window):
        return median_filter(
            window,
            self.size,
            criterion=self.criterion,
            passes=self.passes,
            mode=self.mode,  # type: ignore[arg-type]
            weights=self.weights,
            channel_axis=self.channel_axis,
        )


class Mean(_AbstractFilterStep):
    """:func:`hdrjax.filters.mean_filter` on tiles; bit-identical to the whole image.

    Halo ``passes · (size // 2)``; every output pixel is the same pairwise sum of the same
    window values as in the whole-image filter.
    """

    size: int = eqx.field(static=True, default=5)
    passes: int = eqx.field(static=True, default=1)
    mode: str = eqx.field(static=True, default="nearest")
    channel_axis: int | None = eqx.field(static=True, default=-1)

    def __call__(self, window):
        return mean_filter(
            window,
            self.size,
            passes=self.passes,
            mode=self.mode,  # type: ignore[arg-type]
            channel_axis=self.channel_axis,
        )


@eqx.filter_jit
def _bind(op: AbstractOperator, stats: Statistics | None) -> AbstractOperator:
    """``op.bind(stats)`` as one compiled program (eagerly, each operation compiles apart)."""
    return op.bind(stats)


class Tonemap(AbstractStep):
    """A tone-mapping operator on tiles, its global parameters from the first pass.

    Any operator whose :meth:`~hdrjax.operators.AbstractOperator.halo` is finite: the
    pointwise ones (halo 0; they may run in place) and the neighbourhood ones that declare
    their reach (:class:`~hdrjax.operators.Reinhard2002Local`: the radius of its largest
    Gaussian, ``ceil(4 s_max / (2√2))``, 39 pixels for the default scales). Unset
    parameters come from the operator's own :meth:`~hdrjax.operators.AbstractOperator.bind`
    of the whole image's statistics, merged from the tiles' (:func:`hdrjax.tile.apply`'s
    first pass): the result is the whole-image operator bound to
    ``op.statistics(image)``, to float rounding (log sums added per tile; for Tumblin et
    al. 1999 the trimmed adaptation luminance is then the histogram estimate, as for any
    merged statistics). The local operator's normalised convolution zero-pads at the true
    image edges in the window as in the whole image; its FFTs differ in size, so the
    Gaussian responses agree to float rounding (about 1e-6 relative in float32), not bit
    for bit. Its per-pixel scale choice (first scale with activity ``|V_i| > ε``) is
    discontinuous: where an activity lies within that rounding of ``ε`` a tile may pick the
    neighbouring scale (4 of 262 144 pixels of data/cornell_box.exr, output differing by up
    to 0.03).
    """

    operator: AbstractOperator

    def __check_init__(self):
        op = self.operator
        if not isinstance(op, AbstractOperator):
            raise ValueError(f"operator: expected an hdrjax operator, got {type(op).__name__}")

    def statistics_settings(self):
        settings = self.operator.statistics_settings()
        if settings is None:
            return None
        return self.operator.weights_, settings

    def halo(self, shape):
        _check.shape(jax.ShapeDtypeStruct(tuple(shape), jnp.float32), "image", ndim=3)
        h = tuple(self.operator.halo(tuple(shape)))
        if len(h) != 2 or not all(math.isfinite(v) and v >= 0 for v in h):
            raise ValueError(
                f"operator: {self.operator.name} reads the whole image (halo {h}), so it cannot"
                " run on tiles; run the whole image instead"
            )
        return int(math.ceil(h[0])), int(math.ceil(h[1]))

    def bind(self, shape, stats):
        del shape
        if stats is not None and not isinstance(stats, Statistics):
            raise ValueError(
                f"stats: expected the merged Statistics {self.operator.name} binds"
                " (hdrjax.tile.operator_statistics(op, image) or op.statistics(image)), got"
                f" {type(stats).__name__}"
            )
        return Tonemap(_bind(self.operator, stats))

    def __call__(self, window):
        return self.operator(jnp.asarray(window))


@functools.lru_cache(maxsize=16)
def _window_spectrum(
    view: ResolvedView, variant: str, radius_deg: float, shape: tuple[int, int], dtype: str
) -> tuple[Array, tuple[int, int]]:
    """The whole-image glare kernel's spectrum on a window's FFT grid."""
    ry, rx = kernel_radius(view, radius_deg)
    size = fft_size(shape[0], shape[1], ry, rx)
    kernel = glare_kernel(view, variant, radius_deg=radius_deg)  # type: ignore[arg-type]
    cdt = np.complex128 if dtype == "float64" else np.complex64
    return jnp.asarray(kernel_spectrum(kernel, size).astype(cdt)), size


class Glare(AbstractStep):
    """Spencer et al. 1995 veiling glare (:func:`hdrjax.vision.glare`) on tiles.

    The full PSF reaches across the whole image (halo = image size), which tiles cannot
    shorten; ``radius_deg`` truncates it (:func:`hdrjax.vision.glare`'s own parameter:
    the light scattered further stays in its pixel). With it the halo is the kernel radius
    ``ceil(radius_deg / pixel_deg)`` and tiles reproduce ``glare(rgb, view,
    radius_deg=radius_deg)`` to float rounding (a different FFT size per window and a
    per-window normalisation: about 1e-6 of the brightest pixel's scattered light in
    float32). The kernel is that of the whole image's view (pixel size in degrees).
    """

    view: View | ResolvedView | float | None = eqx.field(static=True, default=None)
    variant: Variant = eqx.field(static=True, default="photopic")
    radius_deg: float | None = eqx.field(static=True, default=None)

    def _view(self, shape) -> ResolvedView:
        return resolve_view(self.view, shape[0], shape[1])

    def halo(self, shape):
        return kernel_radius(self._view(shape), self.radius_deg)

    def bind(self, shape, stats):
        del stats
        if len(shape) != 3 or shape[-1] != 3:
            raise ValueError(f"image: glare expects (H, W, 3) RGB, got shape {shape}")
        return Glare(self._view(shape), self.variant, self.radius_deg)

    def __call__(self, window):
        if not isinstance(self.view, ResolvedView):
            raise ValueError("Glare: bind the step to the image shape first (step.bind)")
        x = jnp.asarray(window)
        spec, size = _window_spectrum(
            self.view, self.variant, self.radius_deg, x.shape[:2], str(x.dtype)
        )
        return apply_glare(x, spec, size)


class Neighbourhood(AbstractStep):
    """Any function of a window with a known halo, e.g. a user's filter.

    ``fn(window)`` must return the window's shape and treat the window's edges as image
    edges (with the padding rule it wants at the true image edges); results equal the
    whole-image ``fn(image)`` wherever each output pixel depends only on inputs within
    ``radius`` pixels (rows, columns).
    """

    fn: Callable[[Array], Array] = eqx.field(static=True)
    radius: tuple[int, int] = eqx.field(static=True, converter=lambda r: _pair(r))

    def halo(self, shape):
        return self.radius

    def __call__(self, window):
        return self.fn(window)


def _pair(r: int | Sequence[int]) -> tuple[int, int]:
    t = (r, r) if isinstance(r, int) else tuple(r)
    if len(t) != 2 or any(isinstance(v, bool) or int(v) != v or v < 0 for v in t):
        raise ValueError(f"radius: expected one or two integers >= 0, got {r!r}")
    return int(t[0]), int(t[1])


__all__ = ["TILE_MODES", "AbstractStep", "Glare", "Mean", "Median", "Neighbourhood", "Tonemap"]
