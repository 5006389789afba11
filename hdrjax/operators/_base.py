"""Operator base class, parameter handling, the registry and the ``tonemap`` dispatcher.

Every operator is an equinox Module: array fields are parameters (``None`` meaning "measure
this image"), static fields are settings. Calling an operator on ``(..., H, W, 3)`` linear RGB
returns display-referred linear RGB (nominally [0, 1], not yet clipped or encoded; see
:mod:`hdrjax.display`). Leading batch axes are mapped with ``jax.vmap`` so statistics are
per frame and results do not depend on the batch shape; use :meth:`AbstractOperator.measure`
to share measured parameters across frames or tiles.

Bad pixels: a pixel with a NaN channel is NaN in the output (all channels; it never reaches
its neighbours or the statistics), a pixel whose luminance is +Inf is display white (1.0), and
one whose luminance is -Inf or ≤ 0 is black. Statistics use finite pixels only.
"""

import abc
import dataclasses
import functools
import inspect
import math
import re
import threading
from collections.abc import Callable
from typing import Any, ClassVar, NamedTuple, TypeVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._colour import REC709_WEIGHTS, luminance, luminance_weights
from .._photometry import chroma_key
from .._scale import ln_max
from .._stats import (
    DEFAULT_BINS,
    DEFAULT_DELTA,
    LuminanceStats,
    Statistics,
    mantissa_bits,
    summarise,
)

_Op = TypeVar("_Op", bound="AbstractOperator")


def param(x: ArrayLike | None) -> Array | None:
    """Field converter: numbers become arrays of the default float dtype (so ``jit`` traces
    them instead of recompiling per value); ``None`` stays ``None`` (measure the image)."""
    if x is None:
        return None
    x = jnp.asarray(x)
    if not jnp.issubdtype(x.dtype, jnp.floating):
        x = x.astype(jnp.result_type(float))
    return x


def weights_field(default: tuple[float, float, float] = REC709_WEIGHTS) -> Any:
    return parameter(
        default,
        help="luminance weights (R, G, B) of the image's primaries (the command line takes"
        " them from the file)",
        static=True,
        shape=(3,),
        converter=lambda w: tuple(float(v) for v in w),
    )


def chromaticities_field() -> Any:
    """``chromaticities``: the image's primaries, for operators that need more of them than
    the luminance weights (scotopic luminance, XYZ)."""
    return parameter(
        None,
        help="the image's primaries, OpenEXR's 8 numbers (the command line takes them from"
        " the file); None: Rec.709 with D65",
        range="[0, 1]",
        static=True,
        shape=(8,),
        converter=chroma_key,
    )


CHROMA = ("ratio", "ycbcr")
"""How :class:`AbstractLuminanceCurve` puts colour back (its ``chroma`` setting)."""


def chroma_field() -> Any:
    """``chroma``: how a luminance curve puts colour back (:class:`AbstractLuminanceCurve`)."""
    return parameter(
        "ratio",
        help="colour: ratio (RGB scaled by L_d / L_w, hue and saturation kept) or ycbcr (luma"
        " replaced by L_d, Cb and Cr kept in image units, as GPU shader versions do)",
        static=True,
        choices=CHROMA,
    )


def chroma_of(op: Any) -> str:
    """How an operator puts colour back: its ``chroma`` setting (:func:`chroma_field`)
    where it declares one, else ``"ratio"``."""
    return getattr(op, "chroma", "ratio")


POOLING = ("mean", "log_mean", "max", "min")
"""How an estimated parameter pools over frames (:class:`ParameterInfo`)."""

_META = "hdrjax"  # the field-metadata key holding a field's ParameterInfo
_INTERVAL = re.compile(r"^\s*([\[(])\s*([^,\s]+)\s*,\s*([^,\s]+)\s*([\])])\s*$")


@dataclasses.dataclass(frozen=True)
class ParameterInfo:
    """What an operator declares about one parameter (see :func:`parameter`).

    Attributes:
        name: the field name (the keyword of the constructor and of ``--set``).
        default: the default value; ``None`` for a parameter estimated from the image (or
            an alternative to another one); ``dataclasses.MISSING`` when required.
        help: one line for the user.
        unit: ``"cd/m²"``, ``"image units"`` (relative luminance), ``"EV"``, ``"s"``…;
            empty for a pure number.
        range: valid values ``(lo, hi)``, ``closed`` saying which ends are included;
            ``None`` for settings that are not numbers.
        closed: whether ``lo`` and ``hi`` themselves are valid.
        estimated: ``None`` means "measure this image".
        pooling: how the estimated values of several frames combine: ``"mean"`` and
            ``"log_mean"`` (pixel-weighted arithmetic and geometric means), ``"max"``,
            ``"min"``; ``None`` for a parameter that is not estimated.
        static: a setting fixed at compile time (not a pytree leaf: not differentiable).
        choices: the valid values of a setting that is a name.
        names: names a number parameter also takes in place of a number (``L_white="max"``),
            which the operator turns into a number or a setting when it is built.
        shape: the shape of an array parameter (``()``: a scalar; ``None``: any length).
    """

    name: str
    default: Any
    help: str
    unit: str = ""
    range: tuple[float, float] | None = None
    closed: tuple[bool, bool] = (True, True)
    estimated: bool = False
    pooling: str | None = None
    static: bool = False
    choices: tuple[str, ...] | None = None
    shape: tuple[int, ...] | None = ()
    names: tuple[str, ...] = ()

    @property
    def required(self) -> bool:
        return self.default is dataclasses.MISSING

    def range_text(self) -> str:
        """The range in interval notation, ``(0, inf)``, followed by the ``names`` it also
        takes (``(0, inf] or max | inf``); the choices ``a | b``; or ``""``."""
        if self.choices:
            return " | ".join(self.choices)
        if self.range is None:
            return ""
        lo, hi = (f"{v:g}" for v in self.range)
        text = f"{'[('[not self.closed[0]]}{lo}, {hi}{'])'[not self.closed[1]]}"
        return f"{text} or {' | '.join(self.names)}" if self.names else text

    def contains(self, value: Any) -> bool:
        """Whether a concrete value (a number, array or name) is valid."""
        if self.choices is not None:
            return value in self.choices
        if self.names and isinstance(value, str):
            return value in self.names
        if self.range is None:
            return True
        v = np.asarray(value, np.float64)
        lo, hi = self.range
        above = v >= lo if self.closed[0] else v > lo
        below = v <= hi if self.closed[1] else v < hi
        return bool(np.all(above & below))

    def check(self, value: Any, owner: str) -> None:
        """``ValueError`` naming the parameter and its range unless ``value`` is valid;
        ``None`` (estimate) and traced values pass."""
        if value is None or traced(value) or self.contains(value):
            return
        shown = value if isinstance(value, str) else np.asarray(value).tolist()
        what = "one of" if self.choices else "a value in"
        unit = f", {self.unit}" if self.unit else ""
        raise ValueError(
            f"{self.name}: expected {what} {self.range_text()} ({owner}{unit}), got {shown!r}"
        )


def _interval(text: str, where: str) -> tuple[tuple[float, float], tuple[bool, bool]]:
    m = _INTERVAL.match(text)
    try:
        assert m is not None
        lo, hi = float(m[2]), float(m[3])
        assert lo < hi
    except (AssertionError, ValueError):
        raise ValueError(
            f"range: expected an interval such as '(0, inf)' or '[0, 1]', got {text!r} ({where})"
        ) from None
    return (lo, hi), (m[1] == "[", m[4] == "]")


def parameter(
    default: Any = dataclasses.MISSING,
    *,
    help: str,
    unit: str = "",
    range: str | None = None,
    estimated: bool = False,
    pooling: str | None = None,
    static: bool = False,
    choices: tuple[str, ...] | None = None,
    shape: tuple[int, ...] | None = (),
    converter: Callable[[Any], Any] | None = None,
    names: tuple[str, ...] = (),
) -> Any:
    """An operator field with what the operator knows about it (:class:`ParameterInfo`).

    Array parameters (the default) go through :func:`param` (numbers become arrays of the
    default float dtype; ``None`` stays ``None``), so ``jit`` traces them and ``grad`` can
    differentiate them; ``static=True`` makes a setting. ``range`` is an interval,
    ``"(0, inf)"``, ``"[-8, 8]"``, checked by :func:`make_operator` and the command line
    (concrete values only). An ``estimated`` parameter (default ``None``: measured from
    the image) says how it pools over frames. ``names``: words a number parameter also
    takes (the operator's ``converter`` or ``__post_init__`` turns them into values).
    Read back with :func:`parameter_info`.

    >>> class Op(AbstractOperator):  # doctest: +SKIP
    ...     key: Array | None = parameter(None, help="the key", range="(0, inf)",
    ...                                   estimated=True, pooling="log_mean")
    """
    where = help.split(";")[0]
    if pooling is not None and pooling not in POOLING:
        raise ValueError(f"pooling: expected one of {', '.join(POOLING)}, got {pooling!r}")
    if estimated != (pooling is not None):
        raise ValueError(f"pooling: an estimated parameter needs one, others none ({where})")
    if estimated and default is not None:
        raise ValueError(f"default: an estimated parameter defaults to None ({where})")
    bounds, closed = _interval(range, where) if range is not None else (None, (True, True))
    info = ParameterInfo(
        name="",
        default=default,
        help=help,
        unit=unit,
        range=bounds,
        closed=closed,
        estimated=estimated,
        pooling=pooling,
        static=static,
        choices=tuple(choices) if choices is not None else None,
        shape=shape,
        names=tuple(names),
    )
    if not static and converter is None:
        converter = param
    kw: dict[str, Any] = {} if default is dataclasses.MISSING else {"default": default}
    return eqx.field(converter=converter, static=static, metadata={_META: info}, **kw)


def estimated(
    help: str,
    *,
    pooling: str,
    unit: str = "",
    range: str = "(0, inf)",
    shape: tuple[int, ...] | None = (),
    names: tuple[str, ...] = (),
    converter: Callable[[Any], Any] | None = None,
) -> Any:
    """A parameter estimated from the image: :func:`parameter` with default ``None``
    ("measure this image"), ``estimated=True`` and how the values of several frames pool
    (``"mean"``, ``"log_mean"``, ``"max"``, ``"min"``); positive by default."""
    return parameter(
        None,
        help=help,
        unit=unit,
        range=range,
        estimated=True,
        pooling=pooling,
        shape=shape,
        names=names,
        converter=converter,
    )


def as_float_image(rgb: ArrayLike, name: str = "rgb") -> Array:
    """Validate ``(..., H, W, 3)`` and promote to float32/float64 (float16/ints → float32).
    ``name``: the caller's argument name, which the messages start with."""
    _check.real(rgb, name)
    rgb = jnp.asarray(rgb)
    if rgb.ndim < 3 or rgb.shape[-1] != 3:
        raise ValueError(f"{name}: expected an image of shape (..., H, W, 3), got {rgb.shape}")
    _check.nonempty(rgb.shape, name)
    if not jnp.issubdtype(rgb.dtype, jnp.floating) or rgb.dtype in (jnp.float16, jnp.bfloat16):
        rgb = rgb.astype(jnp.result_type(float))
    return rgb


class Prepared(eqx.Module):
    """An image split into what operators compute on and what marks its bad pixels.

    ``clean`` images (every pixel finite, the common case) skip all masking: on XLA:CPU a
    ``where`` inside a reduction runs unvectorised, several times slower than the reduction.
    """

    rgb: Array  # non-finite pixels replaced by 0
    L: Array  # luminance of ``rgb``
    L_stats: Array  # luminance with NaN at non-finite pixels: statistics skip them
    has_nan: Array | None = None
    inf_sign: Array | None = None  # +1 where luminance is +Inf, -1 for -Inf, 0 otherwise
    clean: bool = eqx.field(static=True, default=False)
    stats: Statistics | None = None  # measured by :func:`dispatch` (``stats_key``)
    stats_key: tuple = eqx.field(static=True, default=())
    to_space: Array | None = None  # a 3×3 conversion the mapping applies to ``rgb``

    def valid(self) -> Array:
        """Boolean mask of the pixels statistics may use (finite ones)."""
        return jnp.ones(self.L.shape, bool) if self.clean else ~jnp.isnan(self.L_stats)


def prepare(rgb: Array, weights: tuple[float, float, float]) -> Prepared:
    """Mask NaN/Inf pixels (the slow path; :func:`dispatch` takes it only when needed)."""
    finite = jnp.all(jnp.isfinite(rgb), axis=-1)
    has_nan = jnp.any(jnp.isnan(rgb), axis=-1)
    safe = jnp.where(finite[..., None], rgb, 0.0)
    L = luminance(safe, weights)
    inf_l = luminance(jnp.where(jnp.isinf(rgb), jnp.sign(rgb), 0.0), weights)
    inf_sign = jnp.where(finite | has_nan, 0.0, jnp.sign(inf_l))
    return Prepared(safe, L, jnp.where(finite, L, jnp.nan), has_nan, inf_sign)


class StatisticsSettings(NamedTuple):
    """What an operator's :meth:`~AbstractOperator.bind` reads from statistics: the
    percentile ``method``, histogram ``bins``, the ``delta`` of the log-average and whether
    the per-channel sums are needed (``channels``). Statistics merge only with statistics
    measured with the same settings."""

    method: str = "histogram"
    bins: int = DEFAULT_BINS
    delta: float = DEFAULT_DELTA
    channels: bool = False

    @property
    def key(self) -> tuple[str, int, float]:
        return (self.method, int(self.bins), float(self.delta))


def _shared_luminance(rgb: Array, weights: tuple[float, float, float]) -> Array:
    """The luminance image that the statistics pass and the branches share (XLA would
    otherwise compute it twice, once per consumer's shape)."""
    L = luminance(rgb, weights)
    return jax.lax.optimization_barrier(L.reshape(-1)).reshape(L.shape)


def _decide(rgb: Array, weights: tuple[float, float, float], stats: Any):
    """The part of :func:`dispatch` before its branch: ``(L, finite, statistics, key)``."""
    if stats is None or StatisticsSettings(*stats).method != "histogram":
        # (the exact method sorts: only in the branch that needs it)
        L = luminance(rgb, weights)
        return L, jnp.isfinite(jnp.sum(L)), None, ()
    key = StatisticsSettings(*stats).key
    L = _shared_luminance(rgb, weights)
    finite, st = summarise(L, method=key[0], bins=key[1], delta=key[2], assume_finite=True)
    return L, finite, st, key


class _Branch(threading.local):
    """Set by :func:`_branch_jit` while it traces (in this thread): the branch
    :func:`dispatch` takes (``True``: clean) and the statistics measured for it, decided by
    a separate compiled pass."""

    def __init__(self) -> None:
        self.taken: list[tuple[bool, Any]] = []


_BRANCH = _Branch()


def dispatch(
    rgb: Array,
    weights: tuple[float, float, float],
    fn: Callable,
    fix: bool,
    stats: StatisticsSettings | tuple | None = None,
):
    """Run ``fn(prepared)`` on the clean fast path when every luminance is finite, else on
    the masked path; ``fix`` puts NaN/Inf pixels back afterwards.

    ``stats``: the :class:`StatisticsSettings` the operator will read
    (:func:`statistics_of`); then the statistics pass itself tells whether the image is
    finite, and the clean path reuses its result (the luminance is read once for both).
    Otherwise one plain sum decides.

    Traced code compiles both branches (``lax.cond``). An eager call of one image decides
    first, in a compiled pass of its own, and compiles only the branch it takes
    (:meth:`AbstractOperator.__call__`): about 60 % of the compile time for the first
    image of a size (:data:`DECIDE_FIRST_PIXELS`), as a clean image needs no masked path."""

    def clean(x, L, st, key):
        return fn(Prepared(x, L, L, clean=True, stats=st, stats_key=key))

    def dirty(x):
        p = prepare(x, weights)
        out = fn(p)
        return finish(p, out) if fix else out

    if _BRANCH.taken:
        take_clean, st = _BRANCH.taken.pop()
        if not take_clean:
            return dirty(rgb)
        if st is None:
            return clean(rgb, luminance(rgb, weights), None, ())
        key = StatisticsSettings(*stats).key if stats is not None else ()
        return clean(rgb, _shared_luminance(rgb, weights), st, key)  # as _decide
    L, finite, st, key = _decide(rgb, weights, stats)
    return jax.lax.cond(finite, lambda x, st: clean(x, L, st, key), lambda x, st: dirty(x), rgb, st)


@eqx.filter_jit
def _decide_jit(rgb: Array, weights: tuple[float, float, float], stats: Any):
    """``(finite, statistics)`` of :func:`_decide`, as its own compiled pass."""
    return _decide(rgb, weights, stats)[1:3]


@eqx.filter_jit
def _branch_jit(op: "AbstractOperator", rgb: Array, st: Any, take_clean: bool, measure: bool):
    """``op.measure(rgb)`` or ``op(rgb)`` compiled with only the branch ``take_clean``."""
    _BRANCH.taken.append((take_clean, st))
    try:
        return op.measure(rgb) if measure else op(rgb)
    finally:
        _BRANCH.taken.clear()


def _decided(op: "AbstractOperator", rgb: Array, measure: bool) -> Any:
    """:func:`_branch_jit` of the branch that :func:`_decide_jit` chooses for ``rgb``."""
    finite, st = _decide_jit(rgb, op.weights_, op.statistics_settings())
    take_clean = bool(finite)
    return _branch_jit(op, rgb, st if take_clean else None, take_clean, measure)


def _decides_first(rgb: Array) -> bool:
    return rgb.ndim == 3 and rgb.shape[0] * rgb.shape[1] <= DECIDE_FIRST_PIXELS


def finish(p: Prepared, out: Array) -> Array:
    """Put the bad pixels back: NaN stays NaN, +Inf luminance is white, -Inf is black."""
    bad = jnp.where(p.inf_sign > 0, 1.0, 0.0)[..., None]
    out = jnp.where((p.inf_sign != 0)[..., None], bad.astype(out.dtype), out)
    return jnp.where(p.has_nan[..., None], jnp.nan, out)


def luminance_floor(dtype) -> float:
    """Smallest luminance whose square is a normal float (1.1e-19 in float32)."""
    return math.sqrt(float(np.finfo(dtype).tiny)) * 10.0


def scale_by_luminance(
    rgb: Array, L: Array, curve: Callable[[Array], Array], *, per_channel: bool = True
) -> Array:
    """``C_out = C_in · L_d / L_w`` with ``L_d = curve(L_w)`` (colour ratios kept).

    Pixels with ``L_w ≤ 0`` are black. Below :func:`luminance_floor` the ratio is evaluated
    at the floor, which keeps gradients finite for luminances down to 1e-30 in float32.

    ``per_channel`` (default) evaluates the ratio on the luminance broadcast to the three
    channels, i.e. three times per pixel, with the same values: a per-pixel ratio is an
    expensive broadcast operand, which XLA:CPU materialises (a 64 MB image at 4096², plus
    its page faults) instead of fusing, while per channel, reading RGB and the luminance
    and writing the output is one fused loop (4096² RGB, Reinhard: ~100 against ~145 ms of
    CPU). Pass ``False`` for a curve that costs more than that buffer (a table lookup).
    """
    if per_channel:
        L = jnp.broadcast_to(L[..., None], rgb.shape)
    pos = L > 0
    Lc = jnp.maximum(jnp.where(pos, L, 1.0), luminance_floor(L.dtype))
    ratio = jnp.where(pos, curve(Lc) / Lc, 0.0)
    return rgb * (ratio if per_channel else ratio[..., None])


def replace_luminance(
    rgb: Array, L: Array, curve: Callable[[Array], Array], *, per_channel: bool = True
) -> Array:
    """``C_out = C_in + L_d − L_w`` with ``L_d = curve(max(L_w, 0))``: the pixel taken to
    YCbCr with its luminance weights as the luma weights (BT.601's or BT.709's matrix
    for their primaries), ``Y = L_w`` replaced by ``L_d``, ``Cb`` and ``Cr`` kept, and
    taken back to RGB.

    The inverse matrix gives ``R = Y + 2(1 − w_R) Cr``, ``B = Y + 2(1 − w_B) Cb`` and ``G``
    from ``Y = w·RGB``, with ``Cr`` and ``Cb`` proportional to ``R − Y`` and ``B − Y``, so
    for weights summing to 1 changing ``Y`` alone adds the same amount to R, G and B. The
    chroma stays in the input's units (it is not scaled with ``Y``); channels may leave
    [0, 1], negative ones included. ``per_channel``: as in :func:`scale_by_luminance`.
    """
    if per_channel:
        L = jnp.broadcast_to(L[..., None], rgb.shape)
    shift = curve(jnp.maximum(L, 0.0)) - L
    return rgb + (shift if per_channel else shift[..., None])


def safe_log(x: Array) -> Array:
    """``ln x`` for x > 0, 0 elsewhere, with finite gradients everywhere."""
    pos = x > 0
    return jnp.where(pos, jnp.log(jnp.where(pos, x, 1.0)), 0.0)


class AbstractOperator(eqx.Module):
    """A tone-mapping operator: linear RGB in, display-referred linear RGB out.

    Subclasses implement :meth:`_measure` (fill ``None`` parameters from image statistics)
    and :meth:`_apply` (map one prepared image with all parameters known).
    """

    name: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    """The paper (authors, year, title, venue) and its DOI where one exists."""
    scale_invariant: ClassVar[bool] = False
    """Whether ``op(k · rgb) == op(rgb)`` for every ``k > 0`` when the estimated parameters
    are measured (and ``delta``, where there is one, is 0): the operator works on relative
    luminance."""
    per_channel: ClassVar[bool] = False
    """Whether the curve maps R, G and B each by itself (no ``weights``); otherwise the
    operator maps luminance with the ``weights`` of the image's primaries."""
    default_fit_params: ClassVar[tuple[str, ...]] = ()
    """What ``hdrjax fit`` fits when no ``--param`` is given."""
    forward_mode: ClassVar[bool] = True
    """Whether forward-mode derivatives (``jax.jvp``) pass through the operator. False
    where its gradients are defined for reverse mode only (a custom VJP): fits then use a
    minimiser (BFGS) and reverse-mode Jacobians (:func:`hdrjax.fit.fit`)."""
    rounding: ClassVar[float] = 1e-6
    """Absolute error (display units) of float32 results from rounding alone: two
    evaluations that differ only in the order of operations (compiled against eager, merged
    statistics against the whole image's) agree to this."""
    frames_in_sequence: ClassVar[bool] = False
    """Whether a batch of frames is mapped one frame after another (``lax.map``) instead of
    together (``vmap``): for operators whose measurement iterates a data-dependent number of
    times (a while loop), where under ``vmap`` every frame iterates as long as the slowest
    and pays for all frames at each step."""
    only_feeds: ClassVar[dict[str, str]] = {}
    """Parameters whose only use is to estimate another one when that one is unset:
    ``{"L_max": "L_white"}`` says that once ``L_white`` is set, ``L_max`` does not change
    the output (so a fit need not measure it). Parameters not listed count as used."""

    def __check_init__(self):
        # every setting that is a name (compat, ceiling, look, chroma, …) is one of the
        # choices it declares: one check and one message for all operators
        for info in _named_settings(type(self)):
            info.check(getattr(self, info.name), self.name)

    def statistics_settings(self) -> StatisticsSettings | None:
        """The statistics :meth:`bind` reads (``None``, the default: none, e.g. when every
        parameter is given)."""
        return None

    def bind(self: _Op, stats: Statistics | None) -> _Op:
        """The operator with every unset (``None``) parameter computed from ``stats``
        (:meth:`statistics` of an image, or merged statistics of several frames, tiles or
        chunks): a pure function, differentiable in ``stats``. The default: nothing to
        fill."""
        del stats
        return self

    def _measure(self: _Op, p: Prepared) -> _Op:
        """:meth:`bind` to the statistics of a prepared image (reusing those
        :func:`dispatch` measured)."""
        return self.bind(statistics_of(p, self.statistics_settings()))

    @abc.abstractmethod
    def _apply(self, p: Prepared) -> Array:
        """Map one image (``(H, W, 3)``) whose parameters are all set."""

    @property
    def weights_(self) -> tuple[float, float, float]:
        return getattr(self, "weights", REC709_WEIGHTS)

    def statistics(self, rgb: Float[ArrayLike, "H W 3"]) -> Statistics | None:
        """Mergeable statistics of one image (``(H, W, 3)``) for :meth:`bind`: those of
        several frames, tiles or chunks combine with :meth:`Statistics.merge`, and
        ``op.bind(op.statistics(a).merge(op.statistics(b)))`` maps the two together as one
        image. ``None`` when the operator needs none."""
        rgb = as_float_image(rgb)
        if rgb.ndim != 3:
            raise ValueError(f"rgb: expected one image (H, W, 3), got shape {rgb.shape}")
        settings = self.statistics_settings()
        if settings is None:
            return None
        return _statistics_jit(rgb, self.weights_, StatisticsSettings(*settings))

    def measure(self: _Op, rgb: Float[ArrayLike, "H W 3"]) -> _Op:
        """The operator with every unset (``None``) parameter estimated from ``rgb``.

        Pass one image (``(H, W, 3)``); for a shared estimate over several frames, measure
        a representative frame or a mosaic of them.
        """
        rgb = as_float_image(rgb)
        if rgb.ndim != 3:
            raise ValueError(f"measure: expected one image (H, W, 3), got shape {rgb.shape}")
        if not self.unset():
            return self
        if not traced(self, rgb):
            return _measure_jit(self, rgb)
        return dispatch(
            rgb, self.weights_, self._measure, fix=False, stats=self.statistics_settings()
        )

    def __call__(self, rgb: Float[ArrayLike, "*batch H W 3"]) -> Float[Array, "*batch H W 3"]:
        rgb = as_float_image(rgb)
        if not traced(self, rgb):
            # called eagerly (a notebook, a script): run the compiled function, cached per
            # operator structure and image shape (eager lax.cond would recompile every call)
            return _apply_jit(self, rgb)
        if rgb.ndim > 3:
            if self.frames_in_sequence:
                return jax.lax.map(self.__call__, rgb)
            return jax.vmap(self.__call__)(rgb)
        run = lambda p: self._measure(p)._apply(p)  # noqa: E731
        return dispatch(rgb, self.weights_, run, fix=True, stats=self.statistics_settings())

    def for_primaries(
        self: _Op,
        weights: tuple[float, float, float] | None = None,
        chromaticities: tuple[float, ...] | None = None,
    ) -> _Op:
        """The operator for images in given primaries (a working space).

        Args:
            weights: luminance weights of the pixels (e.g. a file's photometric weights in
                the working space, :meth:`hdrjax.layers.LayeredImage.luminance_weights_in`);
                ``None``: those of ``chromaticities``. Set on operators that map luminance.
            chromaticities: the primaries and white (OpenEXR's 8-tuple; ``None``: Rec.709
                with D65). Set on operators whose colour model declares them (their
                ``chromaticities`` parameter).

        Per-channel operators come back as they are.
        """
        names = {f.name for f in dataclasses.fields(self)}
        changes: dict[str, Any] = {}
        if "chromaticities" in names:
            changes["chromaticities"] = chromaticities
        if "weights" in names:
            changes["weights"] = luminance_weights(chromaticities) if weights is None else weights
        return dataclasses.replace(self, **changes) if changes else self

    def unset(self) -> tuple[str, ...]:
        """Names of the parameters that will be measured from the image."""
        return tuple(
            f.name
            for f in dataclasses.fields(self)
            if not f.metadata.get("static", False) and getattr(self, f.name) is None
        )

    def unset_needed(self) -> tuple[str, ...]:
        """The unset parameters the output still depends on: :meth:`unset` less those that
        only estimate another parameter that is set (:attr:`only_feeds`; e.g. ``linear``
        with ``L_max`` set does not need ``ev100`` or the exposure settings)."""
        feeds = type(self).only_feeds
        return tuple(n for n in self.unset() if n not in feeds or getattr(self, feeds[n]) is None)

    def parameters(self) -> dict[str, Any]:
        """All fields as Python values (floats for scalar parameters), for printing."""
        out = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, jax.Array) and v.ndim == 0:
                v = float(v)
            out[f.name] = v
        return out

    def halo(self, shape: tuple[int, ...]) -> tuple[float, float]:
        """Pixels ``(rows, columns)`` a tile of an image of ``shape`` needs on each side to
        be mapped as in the whole image: 0 for pointwise operators (the default); a
        neighbourhood operator returns its reach."""
        del shape
        return 0, 0

    def __repr__(self) -> str:
        """``Reinhard2002(key=0.18, L_white=None, …)``: the values (with their units), not
        the array shapes equinox shows."""
        from .. import _repr

        units = {i.name: _repr.short_unit(i.unit) for i in parameter_info(self)}
        return _repr.call(self, units=units)

    def _repr_html_(self) -> str:
        """A notebook's view: each parameter's value, unit, range and meaning, and the
        paper."""
        from .. import _repr

        rows = []
        for info in parameter_info(self):
            v = getattr(self, info.name)
            shown = "measured from the image" if v is None and info.estimated else None
            rows.append(
                (info.name, shown or _repr.value(v, info.unit), info.range_text(), info.help)
            )
        head = ("parameter", "value", "valid", "meaning")
        title = f"{type(self).__name__} ({self.name})" if self.name else type(self).__name__
        return _repr.view(title, _repr.table(rows, head), note=self.reference)


def statistics_of(p: Prepared, settings: StatisticsSettings | tuple | None) -> Statistics | None:
    """Statistics of a prepared image's finite pixels (those :func:`dispatch` measured with
    the same settings are reused); ``channels``: with the per-channel sums."""
    if settings is None:
        return None
    settings = StatisticsSettings(*settings)
    method, bins, delta = settings.key
    if p.stats is not None and p.stats_key == settings.key:
        st = p.stats
    else:
        st = summarise(p.L_stats, delta=delta, method=method, bins=bins, assume_finite=p.clean)[1]  # type: ignore[arg-type]
    if settings.channels:
        st = eqx.tree_at(
            lambda s: s.channel_sum, st, jnp.sum(p.rgb, axis=(-3, -2)), is_leaf=lambda x: x is None
        )
    return st


def checked_statistics(op: "AbstractOperator", stats: Any) -> Statistics:
    """``stats`` if it is what ``op.bind`` reads (:meth:`AbstractOperator.statistics` with
    the operator's settings), else a ``ValueError`` naming what was expected."""
    settings = op.statistics_settings()
    if not isinstance(stats, Statistics):
        raise ValueError(
            f"stats: expected the Statistics of {op.name}.statistics(image), got"
            f" {type(stats).__name__}"
        )
    if settings is not None:
        s = StatisticsSettings(*settings)
        m = mantissa_bits(s.bins) if s.method == "histogram" else None
        if (stats.delta, stats.m) != (float(s.delta), m) or (
            s.channels and stats.channel_sum is None
        ):
            raise ValueError(
                f"stats: measured with other settings than {op.name}'s (delta {stats.delta},"
                f" histogram bits {stats.m}; expected delta {float(s.delta)}, bits {m}"
                f"{', channel sums' if s.channels else ''}): use {op.name}.statistics(image)"
            )
    return stats


def bound_stats(op: "AbstractOperator", stats: Any) -> LuminanceStats:
    """The luminance statistics (percentiles, log-averages, extrema) ``op.bind`` computes
    its parameters from (:func:`checked_statistics`)."""
    return checked_statistics(op, stats).luminance_stats()


def filled_with_first_valid(x: Array, valid: Array) -> Array:
    """``x`` (``(H, W)`` or ``(H, W, C)``) with its invalid pixels given the value of the
    first valid pixel (raster order): for whole-image filters and solves, whose every
    pixel reaches every other, so that a bad pixel brings in no value of its own (the
    caller's mapping puts the bad pixels back)."""
    first = jnp.argmax(valid.reshape(-1))
    pixels = x.reshape((-1,) + x.shape[valid.ndim :])
    v = valid.reshape(valid.shape + (1,) * (x.ndim - valid.ndim))
    return jnp.where(v, x, pixels[first])


def fill(op: _Op, **values: Any) -> _Op:
    """``op`` with the given parameters set (the one way operators bind measured values)."""
    names = tuple(values)
    return eqx.tree_at(
        lambda o: tuple(getattr(o, n) for n in names),
        op,
        tuple(jnp.asarray(values[n]) for n in names),
        is_leaf=lambda x: x is None,
    )


def rgb_statistics(
    rgb: Array, weights: tuple[float, float, float], settings: StatisticsSettings
) -> Statistics:
    """:func:`statistics_of` an image (``(H, W, 3)``, traced or not), without its luminance
    image (small, to merge or keep)."""

    def fn(p):
        return statistics_of(p, settings).without_source()

    return dispatch(rgb, weights, fn, fix=False, stats=settings)


@functools.partial(jax.jit, static_argnums=(1, 2))
def _statistics_jit(rgb: Array, weights, settings) -> Statistics:
    return rgb_statistics(rgb, weights, settings)


def stats_of(
    p: Prepared,
    *,
    method: str = "histogram",
    bins: int = DEFAULT_BINS,
    delta: float = DEFAULT_DELTA,
) -> LuminanceStats:
    """Luminance statistics of a prepared image (its finite pixels): percentiles,
    log-averages, extrema (:meth:`Statistics.luminance_stats`); unused ones are removed by
    XLA. ``delta`` is the offset inside the paper's log-average."""
    st = statistics_of(p, StatisticsSettings(method, int(bins), float(delta)))
    assert st is not None
    return st.luminance_stats()


# ----------------------------------------------------------------------------- registry

_REGISTRY: dict[str, type[AbstractOperator]] = {}
ENTRY_POINT_GROUP = "hdrjax.operators"
"""The entry-point group through which installed packages contribute operators."""
_entry_points_loaded = False


def _key(name: str) -> str:
    return re.sub(r"[\s_\-]", "", name.lower())


def _qualified(cls: type) -> str:
    return f"{cls.__module__}.{cls.__qualname__}"


def register(name: str) -> Callable[[type[_Op]], type[_Op]]:
    """Class decorator adding an operator to the registry under ``name`` (looked up case-
    and ``_``/``-`` insensitively), for the package's operators and plug-ins alike.

    Raises:
        ValueError: ``name`` is empty, the class is not an :class:`AbstractOperator`, or
            the name is taken by a different class (the same class defined again, as when
            its module is reloaded, replaces the old definition).
    """
    if not isinstance(name, str) or not _key(name):
        raise ValueError(f"name: expected an operator name such as 'reinhard2002', got {name!r}")

    def deco(cls: type[_Op]) -> type[_Op]:
        if not (isinstance(cls, type) and issubclass(cls, AbstractOperator)):
            raise ValueError(
                f"register({name!r}): expected a subclass of hdrjax.operators.AbstractOperator,"
                f" got {cls!r}"
            )
        old = _REGISTRY.get(_key(name))
        if old is not None and _qualified(old) != _qualified(cls):
            raise ValueError(
                f"name: {name!r} is already registered to {_qualified(old)}; register"
                f" {_qualified(cls)} under another name"
            )
        cls.name = name
        _REGISTRY[_key(name)] = cls
        return cls

    return deco


def _load_entry_points() -> None:
    """Import the operators installed packages declare in the entry-point group
    ``hdrjax.operators`` (once, on the registry's first use). An entry point names a module
    whose import registers its operators, or an operator class, registered under the entry
    point's name unless its module registered it. A plug-in that fails to load is skipped
    with one warning line naming it."""
    global _entry_points_loaded
    if _entry_points_loaded:
        return
    _entry_points_loaded = True  # first: a plug-in that lists the registry does not recurse
    import importlib.metadata
    import warnings

    for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        try:
            obj = ep.load()
            if isinstance(obj, type) and obj not in _REGISTRY.values():
                register(ep.name)(obj)
        except Exception as e:  # a broken plug-in must not break the package
            text = " ".join(str(e).split()) or type(e).__name__
            warnings.warn(
                f"hdrjax operator plug-in {ep.name!r} ({ep.value}) not loaded: {text}",
                RuntimeWarning,
                stacklevel=3,
            )


def operator_names() -> tuple[str, ...]:
    """Registered operator names, sorted (the package's and the plug-ins')."""
    _load_entry_points()
    return tuple(sorted(cls.name for cls in _REGISTRY.values()))


def get_operator(name: str) -> type[AbstractOperator]:
    """The operator class registered under ``name`` (case and ``_``/``-`` insensitive)."""
    _load_entry_points()
    try:
        return _REGISTRY[_key(name)]
    except KeyError:
        raise ValueError(
            f"method: unknown operator {name!r}; valid: {', '.join(operator_names())}"
        ) from None


def parameter_names(cls: type[AbstractOperator]) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(cls) if f.init)


def required_parameters(cls: type[AbstractOperator]) -> tuple[str, ...]:
    """The parameters an operator cannot estimate: those without a default (a table)."""
    return tuple(
        f.name
        for f in dataclasses.fields(cls)
        if f.init and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    )


@functools.cache
def _named_settings(cls: type[AbstractOperator]) -> tuple[ParameterInfo, ...]:
    """The parameters of ``cls`` declared with ``choices``."""
    return tuple(i for i in parameter_info(cls) if i.choices is not None)


def parameter_info(cls: type[AbstractOperator] | AbstractOperator) -> tuple[ParameterInfo, ...]:
    """What an operator (class or instance) declares about each of its parameters, in
    constructor order: help, unit, default, range, whether estimated, how it pools.

    A field declared without :func:`parameter` (a plug-in's plain ``eqx.field``) gets its
    help from the docstring's ``Attributes:`` section, no range, and the shape of its
    default when that is a number or a vector (``--set`` then takes it).

    >>> [p.name for p in parameter_info(get_operator("reinhard2002"))][:3]
    ['key', 'L_white', 'log_average']
    """
    out = []
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        info = f.metadata.get(_META)
        if info is None:
            default = f.default
            if default is dataclasses.MISSING and f.default_factory is not dataclasses.MISSING:
                default = f.default_factory()
            info = ParameterInfo(
                name="",
                default=default,
                help=_docstring_help(cls, f.name),
                static=bool(f.metadata.get("static", False)),
                shape=_shape_of(default),
            )
        out.append(dataclasses.replace(info, name=f.name))
    return tuple(out)


def _shape_of(default: Any) -> tuple[int, ...] | None:
    """The shape of a plain field's default: ``()`` for a number, ``(n,)`` for a vector
    array; ``None`` (unknown) otherwise, tuples (settings such as ``weights``) included."""
    if isinstance(default, bool) or default is None or isinstance(default, (tuple, str)):
        return None
    shape = np.shape(default) if isinstance(default, (int, float, np.ndarray, jax.Array)) else None
    return shape if shape is not None and len(shape) <= 1 else None


def parameter_help(cls: type[AbstractOperator], name: str) -> str:
    """The help text of parameter ``name`` (empty when it has none)."""
    for info in parameter_info(cls):
        if info.name == name:
            return info.help
    return ""


def _docstring_help(cls: type[AbstractOperator] | AbstractOperator, name: str) -> str:
    """The description of parameter ``name`` in the ``Attributes:`` section of the
    operator's docstring, on one line (empty when it has none)."""
    doc = inspect.cleandoc(cls.__doc__ or "")
    m = re.search(r"^Attributes:\n((?:[ \t]+.*\n?|\n)*)", doc, re.M)
    if m is None:
        return ""
    entry = re.search(
        rf"^([ \t]+)(?:\w+, )*{re.escape(name)}(?:, \w+)*(?: \(.*?\))?:(.*(?:\n\1[ \t]+.*)*)",
        m[1],
        re.M,
    )
    return " ".join(entry[2].split()).rstrip(".") if entry else ""


def make_operator(method: str, **params: Any) -> AbstractOperator:
    """Instantiate a registered operator.

    Raises:
        ValueError: an unknown ``method`` or parameter (the message lists the valid ones),
            a missing required parameter (named, with what it expects), or a concrete
            value outside the parameter's range (named, with the range; traced values
            are not checked).
    """
    cls = get_operator(method)
    valid = parameter_names(cls)
    bad = sorted(set(params) - set(valid))
    if bad:
        raise ValueError(
            f"{bad[0]}: not a parameter of {cls.name}; valid: {', '.join(valid)}"
            if len(bad) == 1
            else f"{', '.join(bad)}: not parameters of {cls.name}; valid: {', '.join(valid)}"
        )
    for name in required_parameters(cls):
        if params.get(name) is None:
            what = parameter_help(cls, name).split("; ")[0] or "a value"
            raise ValueError(
                f"{name}: expected {what} (the {cls.name} operator needs it: it cannot be"
                " estimated from the image), got none"
            )
    for info in parameter_info(cls):
        if info.name in params:
            info.check(params[info.name], cls.name)
    return cls(**params)


DECIDE_FIRST_PIXELS = 1 << 20
"""Largest image (pixels) whose eager call decides clean or masked in a pass of its own.

The decision's compiled pass and the branch taken compile in about 60 % of the time of the
whole function (both branches under ``lax.cond``): reinhard2002 1.12 s against 1.62 s for
the first 64×96 image, drago2003 0.44 against 0.66, mantiuk2008 2.55 against 4.16. The
separate pass reads the image once more: at 4096² reinhard2002 took 162 ms a call against
112 ms, so larger images, whose calls cost more than their compile, run the whole
function."""


def _apply_jit(op: AbstractOperator, rgb: Array) -> Array:
    """``op(rgb)`` compiled, called eagerly. One image of up to
    :data:`DECIDE_FIRST_PIXELS` decides first whether it is clean, in a compiled pass of
    its own, and compiles only the branch it takes (:func:`dispatch`); larger images,
    batches and operators with a call of their own compile the whole function."""
    if traced(op, rgb):
        return op(rgb)
    if _decides_first(rgb) and type(op).__call__ is AbstractOperator.__call__:
        return _decided(op, rgb, measure=False)
    return _apply_whole_jit(op, rgb)


@eqx.filter_jit
def _apply_whole_jit(op: AbstractOperator, rgb: Array) -> Array:
    return op(rgb)


def _measure_jit(op: AbstractOperator, rgb: Array) -> AbstractOperator:
    """``op.measure(rgb)`` compiled, called eagerly; as :func:`_apply_jit`, an image of up
    to :data:`DECIDE_FIRST_PIXELS` compiles only the branch it takes."""
    if traced(op, rgb):
        return op.measure(rgb)
    if _decides_first(rgb) and type(op).measure is AbstractOperator.measure and op.unset():
        return _decided(op, rgb, measure=True)
    return _measure_whole_jit(op, rgb)


@eqx.filter_jit
def _measure_whole_jit(op: AbstractOperator, rgb: Array) -> AbstractOperator:
    return op.measure(rgb)


def measure_in_space(op: _Op, rgb: Array, matrix: np.ndarray | None) -> _Op:
    """``op.measure(convert(rgb, matrix))`` compiled: the operator measured on pixels
    converted into its working space (:func:`hdrjax.spaces.convert`; ``None``: as they are).

    Statistics of luminance alone need no conversion: the luminance of the converted pixels
    is that of ``rgb`` with the weights ``w M`` (a 3×3 matrix is linear), so the pixels are
    read once, as they are. Operators that also read channel sums, or that have no
    ``weights``, measure the converted pixels.
    """
    if matrix is None or not op.unset():
        return _measure_jit(op, rgb) if matrix is None else op
    if _luminance_only(op):
        w = tuple(float(v) for v in np.asarray(op.weights_, np.float64) @ matrix)
        # weights: a field of the luminance operators (checked above), not of the base class
        measured = _measure_jit(dataclasses.replace(op, weights=w), rgb)  # type: ignore[call-arg]
        return dataclasses.replace(measured, weights=op.weights_)  # type: ignore[call-arg]
    return _measure_converted_jit(op, rgb, matrix)


def apply_in_space(op: "AbstractOperator", rgb: Array, matrix: np.ndarray | None) -> Array:
    """``op(convert(rgb, matrix))`` compiled, for one image ``(H, W, 3)``.

    An operator that scales each pixel by a function of its luminance
    (:class:`AbstractLuminanceCurve`) commutes with the matrix when its luminance is taken
    with the weights ``w M``: the pixels are mapped as they are and converted on the way
    out, in the mapping's one fused loop. Bad pixels keep the working space's rules (NaN
    stays NaN, +Inf luminance is white, −Inf black), their luminance taken as the file's.
    Other operators map the converted pixels."""
    if matrix is None:
        return _apply_jit(op, rgb)
    if maps_luminance_ratio(op) and np.ndim(rgb) == 3:
        w = tuple(float(v) for v in np.asarray(op.weights_, np.float64) @ matrix)
        return _apply_converted_jit(op, w, rgb, matrix)
    return _convert_apply_jit(op, rgb, matrix)


def maps_luminance_ratio(op: "AbstractOperator") -> bool:
    """Whether ``op`` multiplies each pixel by a function of its luminance and of
    luminance statistics alone (:class:`AbstractLuminanceCurve`'s own mapping with
    ``chroma="ratio"``), so that it commutes with a colour matrix whose luminance weights
    it is given."""
    curve_mapping = getattr(type(op), "_apply", None) is AbstractLuminanceCurve._apply
    return (
        isinstance(op, AbstractLuminanceCurve)
        and curve_mapping
        and chroma_of(op) == "ratio"
        and _luminance_only(op)
    )


def _luminance_only(op: "AbstractOperator") -> bool:
    settings = op.statistics_settings()
    has_weights = "weights" in {f.name for f in dataclasses.fields(op)}
    return has_weights and (settings is None or not StatisticsSettings(*settings).channels)


def _converted(rgb: Array, matrix: Any, saturate: bool = True) -> Array:
    from ..spaces import convert

    return convert(rgb, matrix, saturate=saturate)


@eqx.filter_jit
def _measure_converted_jit(op: AbstractOperator, rgb: Array, matrix: Array) -> AbstractOperator:
    return op.measure(_converted(rgb, matrix))


@eqx.filter_jit
def _convert_apply_jit(op: AbstractOperator, rgb: Array, matrix: Array) -> Array:
    return op(_converted(rgb, matrix))


@eqx.filter_jit
def _apply_converted_jit(
    op: AbstractOperator, native_weights: tuple, rgb: Array, matrix: Array
) -> Array:
    # AbstractOperator.__call__'s traced path on the file's pixels and luminance, whose
    # mapping multiplies the converted pixels by its ratio: the conversion is part of the
    # mapping's one loop (converting its output instead reads each output three times,
    # and the curve is evaluated again for each)
    native = dataclasses.replace(op, weights=native_weights)  # type: ignore[call-arg]

    def run(p: Prepared) -> Array:
        return native._measure(p)._apply(dataclasses.replace(p, to_space=matrix))

    rgb = as_float_image(rgb)
    return dispatch(rgb, native_weights, run, fix=True, stats=native.statistics_settings())


def traced(*trees: Any) -> bool:
    """Whether any array in ``trees`` is a tracer (we are inside jit/vmap/grad)."""
    return any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(trees))


def tonemap(
    rgb: Float[ArrayLike, "*batch H W 3"], method: str = "reinhard2002", **params: Any
) -> Float[Array, "*batch H W 3"]:
    """Tone-map linear RGB with a registered operator (jit-compiled, differentiable).

    Args:
        rgb: linear-light RGB, channels last, ``(..., H, W, 3)``; relative or cd/m²
            (operators that need absolute units say so).
        method: registry name, case- and separator-insensitive (see :func:`operator_names`).
        **params: the operator's parameters; ``None`` or omitted means "estimate from the
            image" where the operator supports it.

    Returns:
        Display-referred linear RGB, nominally in [0, 1]; encode with
        :func:`hdrjax.display.encode`.

    Raises:
        ValueError: unknown ``method`` or parameter (the message lists the valid ones), or an
            image that is not ``(..., H, W, 3)``.

    >>> import jax.numpy as jnp, hdrjax
    >>> out = hdrjax.tonemap(jnp.ones((2, 2, 3)), method="linear", L_max=2.0)
    >>> float(out[0, 0, 0])
    0.5
    """
    op = make_operator(method, **params)
    return _apply_jit(op, as_float_image(rgb))


__all__ = [
    "CHROMA",
    "ENTRY_POINT_GROUP",
    "AbstractOperator",
    "ParameterInfo",
    "Prepared",
    "StatisticsSettings",
    "apply_in_space",
    "bound_stats",
    "chroma_field",
    "chroma_of",
    "count_valid",
    "dispatch",
    "estimated",
    "fill",
    "finish",
    "get_operator",
    "make_operator",
    "measure_in_space",
    "operator_names",
    "param",
    "parameter",
    "parameter_info",
    "prepare",
    "register",
    "replace_luminance",
    "safe_log",
    "scale_by_luminance",
    "stats_of",
    "tonemap",
    "weights_field",
]


def max_luminance(st: LuminanceStats) -> Array:
    """Largest finite luminance (1 when no pixel is positive, so it can divide)."""
    return jnp.where(st.max > 0, st.max, 1.0)


def count_valid(p: Prepared) -> Array:
    """Number of finite pixels (at least 1, so it can divide)."""
    return jnp.asarray(p.L.size) if p.clean else jnp.maximum(jnp.sum(p.valid()), 1)


def log_average(p: Prepared, eps: float) -> Array:
    """``exp(mean(ln(max(L, 0) + eps)))`` over the finite pixels."""
    terms = jnp.log(jnp.maximum(p.L, 0.0) + eps)
    if not p.clean:
        terms = jnp.where(p.valid(), terms, 0.0)
    # a mean of logarithms is at most ln(max), but exp of its rounding may overflow
    return jnp.exp(jnp.minimum(jnp.sum(terms) / count_valid(p), ln_max(p.L.dtype)))


class AbstractLuminanceCurve(AbstractOperator):
    """An operator that maps luminance through a curve and keeps colour ratios."""

    cheap_curve: ClassVar[bool] = True
    """Whether :meth:`_curve` is cheap enough to evaluate once per channel (a few
    arithmetic operations), which fuses the mapping into one loop (:func:`scale_by_luminance`)."""

    @abc.abstractmethod
    def _curve(self, L: Array) -> Array:
        """Display luminance of world luminance ``L ≥ 0`` (parameters all set)."""

    def _apply(self, p: Prepared) -> Array:
        # when dispatch's statistics pass was the luminance image's only other reader, the
        # mapping's fused loop recomputes the luminance from RGB rather than read it back
        # (4096² Reinhard: ~8 ms less CPU); elsewhere that image is read anyway
        fresh = p.clean and p.stats is not None and self.cheap_curve
        L = luminance(p.rgb, self.weights_) if fresh else p.L
        # pixels converted to another space here (apply_in_space) keep their luminance
        if p.to_space is not None:  # p.rgb is finite here: clamping keeps it so
            top = jnp.finfo(p.rgb.dtype).max
            rgb = jnp.clip(_converted(p.rgb, p.to_space, saturate=False), -top, top)
        else:
            rgb = p.rgb
        if chroma_of(self) == "ycbcr":
            return replace_luminance(rgb, L, self._curve, per_channel=self.cheap_curve)
        return scale_by_luminance(rgb, L, self._curve, per_channel=self.cheap_curve)

    def curve(self, L: ArrayLike) -> Array:
        """The luminance curve alone, for plotting or inspection (parameters must be set)."""
        missing = self.unset_needed()
        if missing:
            raise ValueError(
                f"{self.name}: measure an image first; unset parameters: {', '.join(missing)}"
            )
        return self._curve(jnp.maximum(jnp.asarray(L, jnp.result_type(float)), 0.0))
