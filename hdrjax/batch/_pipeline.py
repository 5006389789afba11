"""``Pipeline``: what happens to every frame of a batch, described once.

Numeric contract: a frame is linear RGB ``(H, W, 3)`` as read from its file (relative or
cd/m²), in the file's primaries. The pipeline converts it into the working space
(``space``, sRGB by default; :mod:`hdrjax.spaces`), multiplies it by ``scale``, runs the
optional ``steps`` in order (median/mean filter, highlight desaturation, human-vision
simulation; all on scene-referred linear RGB), tone-maps it with ``operator`` and, for
display formats, clips to [0, 1], applies the transfer function and rounds to ``bits``-bit
code values on the device (``round(clip(v, 0, 1) · (2^bits − 1))``, ties to even). HDR
formats (``exr``, ``hdr``, ``pfm``) receive the operator's display-referred *linear* float32 output.

The pipeline is an equinox Module: the operator's parameters and the colour conversion
``matrix`` are its array leaves (traced by ``jit``), everything else is static. Steps are
:class:`Step` records (a kind and keyword options), so a pipeline pickles and travels to
Dask workers.
"""

import dataclasses
import inspect
from collections.abc import Callable, Mapping
from typing import Any, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, UInt

from .. import _check, _repr
from ..io._display import DEFAULT_COMPRESSION
from ..operators._base import AbstractOperator, as_float_image, make_operator
from ..operators._call import clean_operator_call
from ..operators._time import has_time_course

DISPLAY_FORMATS = ("png", "tif", "jpg")
"""Encoded outputs (8 or 16 bit code values; JPEG 8 bit only)."""
HDR_FORMATS = ("exr", "hdr", "pfm")
"""Linear float outputs (the operator's display-referred linear RGB)."""
STEP_KINDS = ("median", "mean", "desaturate", "vision")


def _step_function(kind: str) -> Callable:
    from .. import display, filters

    if kind == "median":
        return filters.median_filter
    if kind == "mean":
        return filters.mean_filter
    if kind == "desaturate":
        return display.desaturate_highlights
    from ..vision._simulate import HumanVision

    return HumanVision.build


@dataclasses.dataclass(frozen=True)
class Step:
    """One processing step before tone mapping: a kind and its keyword options.

    Kinds and the function the options go to:

    - ``"median"``: :func:`hdrjax.filters.median_filter` (e.g. ``size=3``);
    - ``"mean"``: :func:`hdrjax.filters.mean_filter`;
    - ``"desaturate"``: :func:`hdrjax.display.desaturate_highlights` (``threshold=None``:
      automatic, per frame);
    - ``"vision"``: :meth:`hdrjax.vision.HumanVision.build` (``effects=(...)``, ``view``,
      ...; the shape comes from the frame). The input must be in cd/m²: set the pipeline's
      ``scale``.

    Options are checked against the function's signature when the step is made, so a
    misspelt option raises instead of being ignored.
    """

    kind: str
    options: tuple[tuple[str, Any], ...] = ()

    def __post_init__(self) -> None:
        if self.kind not in STEP_KINDS:
            raise ValueError(f"step: unknown kind {self.kind!r}; valid: {', '.join(STEP_KINDS)}")
        names = set(inspect.signature(_step_function(self.kind)).parameters)
        names -= {"image", "rgb", "shape"}  # the frame itself
        bad = sorted(k for k, _ in self.options if k not in names)
        if bad:
            raise ValueError(
                f"step {self.kind!r}: unknown option(s) {', '.join(bad)}; "
                f"valid: {', '.join(sorted(names))}"
            )
        # lists become tuples so that the step stays hashable (it is a static jit argument)
        fixed = tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in self.options)
        object.__setattr__(self, "options", fixed)

    def __call__(self, rgb: Array) -> Array:
        """Apply the step to one frame ``(H, W, 3)``."""
        fn = _step_function(self.kind)
        opts = dict(self.options)
        if self.kind == "vision":
            return fn(rgb.shape[:2], **opts)(rgb)
        return fn(rgb, **opts)


def step(kind: str, **options: Any) -> Step:
    """Shorthand for :class:`Step`: ``step("median", size=3)``."""
    return Step(kind, tuple(sorted(options.items())))


def _as_operator(op: AbstractOperator | str) -> AbstractOperator:
    if isinstance(op, str):
        return make_operator(op)
    if not isinstance(op, AbstractOperator):
        raise TypeError(f"operator: expected an operator or a method name, got {type(op).__name__}")
    return op


def _as_steps(steps: Any) -> tuple[Step, ...]:
    out = []
    for s in steps:
        if isinstance(s, Step):
            out.append(s)
        elif isinstance(s, str):
            out.append(Step(s))
        elif isinstance(s, tuple) and len(s) == 2 and isinstance(s[1], Mapping):
            out.append(step(s[0], **s[1]))
        else:
            raise TypeError(f"steps: expected Step, a kind, or (kind, options); got {s!r}")
    return tuple(out)


class Pipeline(eqx.Module):
    """Read → scale → steps → tone map → encode → write, for every frame of a batch.

    Attributes:
        operator: a tone-mapping operator, or a registry name (``"reinhard2002"``);
            ``None`` parameters are measured (per frame, shared over the sequence or
            smoothed over time: see :func:`hdrjax.batch.run`).
        steps: :class:`Step` records (or ``(kind, {options})`` pairs) applied in order
            before tone mapping.
        format: output type: ``"png"``, ``"tif"``, ``"jpg"`` (encoded) or ``"exr"``,
            ``"hdr"``, ``"pfm"`` (display-referred linear float).
        bits: 8 or 16 bits per channel for ``png``/``tif``.
        compression: zlib level of ``png``/``tif`` outputs, 0–9 (default 1, OpenCV's:
            Sub-filtered PNG rows with run-length matching, 15 ms for a 1024×512 frame;
            level 6 is ~8× slower for ~1 % smaller PNGs; see
            :data:`hdrjax.io.DEFAULT_COMPRESSION`).
        transfer: ``"srgb"``, ``"gamma"`` or ``"linear"`` encoding for display formats.
        gamma: exponent for ``transfer="gamma"``.
        display: a display name (:func:`hdrjax.display.get_display`: ``"Display P3"``,
            ``"ITU-R BT.2100 PQ"``...) instead of ``transfer``: outputs are converted from
            ``space`` to its primaries, gamut-mapped (``gamut``) and tagged for it.
        gamut: the gamut method with a ``display`` (``None``: the encoder's default).
        scale: factor applied to each frame first (e.g. to cd/m²).
        space: the working space frames are converted into (a :mod:`hdrjax.spaces` name;
            ``"sRGB"``: BT.709 primaries, D65).
        cat: chromatic adaptation between different whites (``"CAT02"``).
        matrix: the conversion of the current frames' primaries into ``space`` (set by
            :meth:`for_source`; ``None``: the identity).
        vectorize: how a compiled batch goes over its frames: ``"vmap"`` (all frames at
            once, vectorised across frames), ``"map"`` (``lax.map``: one frame after the
            other inside the one compiled call; each frame's intermediates stay in cache) or
            ``"auto"``: ``"map"`` on CPU, where it measured 1.3–2× faster than ``"vmap"`` for
            1024×512 frames in batches of 8, and ``"vmap"`` on GPU/TPU. Frames with bad
            pixels always go through ``lax.map`` (their operators branch on the data, and
            under ``vmap`` both branches would run for every frame).

    >>> p = Pipeline("reinhard2002", format="png")
    >>> p.extension
    '.png'
    """

    __repr__ = _repr.fields_repr
    _repr_html_ = _repr.fields_html

    operator: AbstractOperator = eqx.field(converter=_as_operator)
    steps: tuple[Step, ...] = eqx.field(static=True, default=(), converter=_as_steps)
    format: Literal["png", "tif", "jpg", "exr", "hdr", "pfm"] = eqx.field(
        static=True, default="png"
    )
    bits: int = eqx.field(static=True, default=8)
    compression: int = eqx.field(static=True, default=DEFAULT_COMPRESSION)
    transfer: Literal["srgb", "gamma", "linear"] = eqx.field(static=True, default="srgb")
    gamma: float = eqx.field(static=True, default=2.2)
    display: str | None = eqx.field(static=True, default=None)
    gamut: str | None = eqx.field(static=True, default=None)
    scale: float = eqx.field(static=True, default=1.0)
    vectorize: Literal["auto", "map", "vmap"] = eqx.field(static=True, default="auto")
    space: str = eqx.field(static=True, default="sRGB")
    cat: str = eqx.field(static=True, default="CAT02")
    matrix: Float[Array, "3 3"] | None = None

    def __check_init__(self) -> None:
        from .. import spaces

        spaces.space(self.space)  # raise ValueError for unknown names, here
        spaces.check_cat(self.cat)
        if self.format not in DISPLAY_FORMATS + HDR_FORMATS:
            raise ValueError(
                f"format: expected one of {', '.join(DISPLAY_FORMATS + HDR_FORMATS)}, "
                f"got {self.format!r}"
            )
        if self.bits not in (8, 16):
            raise ValueError(f"bits: expected 8 or 16, got {self.bits!r}")
        if isinstance(self.compression, bool) or self.compression not in range(10):
            raise ValueError(f"compression: expected a zlib level 0..9, got {self.compression!r}")
        if self.format == "jpg" and self.bits != 8:
            raise ValueError("bits: JPEG holds 8 bits per channel; use png or tif for 16")
        if self.transfer not in ("srgb", "gamma", "linear"):
            raise ValueError(
                f"transfer: expected 'srgb', 'gamma' or 'linear', got {self.transfer!r}"
            )
        if self.vectorize not in ("auto", "map", "vmap"):
            raise ValueError(f"vectorize: expected 'auto', 'map' or 'vmap', got {self.vectorize!r}")
        if self.display is not None:
            from ..display import get_display

            disp = get_display(self.display, self.gamma)  # ValueError for unknown names
            if disp.hdr and self.encoded and self.bits != 16:
                raise ValueError(f"bits: {disp.name} needs 16 bits per channel, got {self.bits}")
        if not (self.gamma > 0 and self.scale > 0):
            raise ValueError(f"gamma and scale must be > 0, got {self.gamma!r}, {self.scale!r}")

    @property
    def extension(self) -> str:
        """File extension of the outputs, with the dot."""
        return "." + self.format

    @property
    def output_display(self):
        """The :class:`hdrjax.display.Display` outputs are encoded and tagged for."""
        from ..display import get_display

        name = self.display or {"srgb": "sRGB"}.get(self.transfer, self.transfer)
        return get_display(name, self.gamma)

    @property
    def encoded(self) -> bool:
        """Whether outputs are display-encoded code values (png/tif/jpg)."""
        return self.format in DISPLAY_FORMATS

    def for_source(self, source: tuple[float, ...] | None) -> "Pipeline":
        """The pipeline for frames in these primaries (OpenEXR's chromaticities, ``None``
        for Rec.709/D65): their conversion into the working space, and the operator's
        luminance weights (the files' own luminance, see
        :func:`hdrjax.spaces.luminance_weights_in`) and primaries."""
        from .. import spaces

        target = spaces.space(self.space)
        m = spaces.conversion_matrix(source, target, cat=self.cat)
        weights = spaces.luminance_weights_in(source, target, cat=self.cat)
        op = self.operator.for_primaries(
            weights, None if target.is_rec709 else target.chromaticities
        )
        matrix = None if spaces.is_identity(m) else jnp.asarray(m, jnp.float32)
        return dataclasses.replace(self, operator=op, matrix=matrix)

    def prepare(self, rgb: Float[Array, "H W 3"]) -> Float[Array, "H W 3"]:
        """Scale and run the steps: the image the operator measures and maps."""
        x = as_float_image(rgb)
        if self.matrix is not None:
            from ..spaces import convert

            x = convert(x, self.matrix)
        if self.scale != 1.0:
            x = x * jnp.asarray(self.scale, x.dtype)
        for s in self.steps:
            x = s(x)
        return x

    def prepare_batch(self, frames: Float[Array, "B H W 3"]) -> Float[Array, "B H W 3"]:
        """:meth:`prepare` on each frame of a batch. The steps run frame after frame
        (``lax.map``): each is a large vectorised computation of its own, and the filters
        are written for one image at a time."""
        if not self.steps:
            return jax.vmap(self.prepare)(frames)
        return jax.lax.map(self.prepare, frames)

    def finish(self, mapped: Float[Array, "H W 3"]) -> Array:
        """Encode an operator output for the file: code values, or float32 linear RGB."""
        if not self.encoded:
            return mapped.astype(jnp.float32)
        from ..display import encode

        if self.display is None:
            enc = encode(mapped, self.transfer, gamma=self.gamma)
        else:
            enc = encode(mapped, display=self.display, space=self.space, gamut=self.gamut)
        top = (1 << self.bits) - 1
        code = jnp.round(enc * top)  # encode clips to [0, 1] and maps NaN to 0
        return code.astype(jnp.uint8 if self.bits == 8 else jnp.uint16)

    def __call__(
        self, rgb: Float[Array, "H W 3"], operator: AbstractOperator | None = None
    ) -> Float[Array, "H W 3"] | UInt[Array, "H W 3"]:
        """One frame through the whole pipeline (``operator`` overrides the pipeline's,
        e.g. with parameters fixed for the sequence)."""
        op = self.operator if operator is None else operator
        return self.finish(op(self.prepare(rgb)))


def frame_is_clean(rgb: np.ndarray) -> bool:
    """Whether a frame can take the unmasked path: every value finite and below 1e30 in
    magnitude (so that sums of its luminance stay finite, the operators' own criterion)."""
    return bool(rgb.size) and bool(max(float(rgb.max()), -float(rgb.min())) < CLEAN_LIMIT)


CLEAN_LIMIT = 1e30


def map_frames(pipeline: "Pipeline", fn: Callable, args: Any, clean: bool) -> Any:
    """``fn`` over the leading (frame) axis of ``args``, as ``pipeline.vectorize`` says
    (``vmap`` only for clean frames: see :class:`Pipeline`)."""
    mode = pipeline.vectorize
    if mode == "auto":
        mode = "map" if jax.default_backend() == "cpu" else "vmap"
    return jax.vmap(fn)(args) if clean and mode == "vmap" else jax.lax.map(fn, args)


@eqx.filter_jit
def render_batch(
    pipeline: Pipeline,
    operators: AbstractOperator | None,
    frames: Float[Array, "B H W 3"],
    clean: bool = False,
) -> Array:
    """The pipeline on a batch of equal-shape frames, compiled once per shape.

    ``operators`` is ``None`` (each frame measured by itself) or an operator whose array
    leaves carry a leading frame axis (parameters fixed per frame). ``clean=True`` promises
    that every pixel of every frame is finite (:func:`frame_is_clean`): the operators' unmasked
    path is then used directly (the same result, without the check that selects it).
    """
    _check.shape(frames, "frames", ndim=4)
    x = pipeline.prepare_batch(frames)
    ops = pipeline.operator if operators is None else operators

    def one(args):
        op, f = args
        return pipeline.finish(clean_operator_call(op, f) if clean else op(f))

    if operators is None:
        return map_frames(pipeline, lambda f: one((ops, f)), x, clean)
    return map_frames(pipeline, one, (ops, x), clean)


@eqx.filter_jit
def render_sequence_batch(
    pipeline: Pipeline,
    frames: Float[Array, "B H W 3"],
    count: Array,
    fps: float,
    state: Any,
) -> tuple[Array, Any]:
    """Consecutive frames of a video through the pipeline with the operator's time course
    (:meth:`~hdrjax.operators.AbstractTimeDependentOperator.sequence`), compiled once per
    shape.

    ``state``: the observer's state after the previous frame (``None``: adapted to the
    first frame of this batch). ``count``: how many of the frames are real (the others
    pad the batch to its compiled size). Returns the outputs and the state after the last
    real frame, to carry to the next batch: a video mapped batch after batch equals one
    scan over all its frames.
    """
    _check.shape(frames, "frames", ndim=4)
    op = pipeline.operator
    if not has_time_course(op):
        raise ValueError(f"fps: {op.name} has no time course")
    x = pipeline.prepare_batch(frames)
    mapped, states = op.sequence(x, fps, initial=state)
    after = jax.tree.map(lambda v: jax.lax.dynamic_index_in_dim(v, count - 1, 0, False), states)
    return jax.vmap(pipeline.finish)(mapped), after


__all__ = [
    "DISPLAY_FORMATS",
    "HDR_FORMATS",
    "Pipeline",
    "Step",
    "frame_is_clean",
    "render_batch",
    "render_sequence_batch",
    "step",
]
