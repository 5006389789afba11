"""Apply the human-vision effects a scene calls for: :func:`analyze`, :func:`simulate` and
the :class:`HumanVision` step.

Numeric contract: input is linear RGB in absolute units (cd/m²); the output is linear RGB in
cd/m² (world luminance; *display* luminance after the ``contrast`` effect), ready for a
tone-mapping operator (``hdrjax.tonemap``) or a linear display mapping.

Order (pcond's): ``acuity`` → ``glare`` → ``colour_loss``/``blue_shift`` → ``contrast``.
An effect that is not selected is not traced: the compiled function holds no operation of
it (tests/vision/test_simulate.py counts them in the lowered program).

Tone mapping: ``simulate(..., then=op)`` returns ``op`` applied to the result, the same image
as ``op(simulate(...)[0])``. For a global operator (a luminance curve) the analysis and the
tone mapping of the unmodified image run as one compiled program that reads the image once;
its image is returned when the scene calls for no effect (a daylight scene then costs about
one tone mapping), and discarded otherwise (the effects run, then ``op``).

Relative images: an array has no units, so :func:`simulate` and :func:`analyze` require
``scale`` (cd/m² per stored unit; 1.0 for an image already in cd/m²). A layered image from
``hdrjax.io.read`` in cd/m² (or W/sr/m², converted with Radiance's 179 lm/W) needs none; a
relative one needs ``scale`` or its ``white_luminance``.
"""

import dataclasses
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check, _repr
from .._colour import luminance
from .._photometry import LMIN, check_rgb, chroma_key, weights_of
from ..operators._base import AbstractLuminanceCurve, AbstractOperator, make_operator
from ..operators._call import clean_operator_call
from ._acuity import acuity_loss, max_levels
from ._contrast import DISPLAY_MAX, DISPLAY_RANGE, ContrastModel, contrast
from ._fovea import adaptation_luminance, pixel_stride
from ._jensen2001 import blue_shift
from ._pcond import colour_loss, veil
from ._report import (
    EFFECTS,
    SceneReport,
    analyze_rgb,
    fast_report,
    fast_statistics,
    masked_report,
)
from ._spencer1995 import Variant, apply_glare, glare_spectrum
from ._view import ResolvedView, View, as_view

GlareModel = Literal["spencer1995", "pcond"]
WHTEFFICACY = 179.0
"""lm/W: Radiance's luminous efficacy of white, converting W/(sr·m²) to cd/m²."""

_ALIASES = {
    "color_loss": "colour_loss",
    "colour": "colour_loss",
    "color": "colour_loss",
    "veil": "glare",
    "blueshift": "blue_shift",
}


def effect_name(name: str, arg: str = "effects") -> str:
    """Canonical effect name (case- and separator-insensitive; ``color`` = ``colour``);
    ``arg``: the caller's argument (or option) the name came from, for the message."""
    key = str(name).strip().lower().replace("-", "_").replace(" ", "_")
    key = _ALIASES.get(key, _ALIASES.get(key.replace("_", ""), key))
    if key not in EFFECTS:
        raise ValueError(f"{arg}: unknown effect {name!r}; valid: {', '.join(EFFECTS)}")
    return key


def _ordered(names: Iterable[str]) -> tuple[str, ...]:
    chosen = {effect_name(n) for n in names}
    return tuple(n for n in EFFECTS if n in chosen)


def select_effects(
    effects: "str | Iterable[str] | Mapping[str, bool]", report: SceneReport | None
) -> tuple[str, ...]:
    """Effect names from ``"auto"``, ``"all"``, ``"none"``, a set of names, or a mapping that
    forces effects on (``True``) or off (``False``) on top of the automatic choice."""
    if isinstance(effects, str):
        key = effects.strip().lower()
        if key == "auto":
            return _auto(report)
        if key == "all":
            return EFFECTS
        if key == "none":
            return ()
        return _ordered(e for e in key.split(",") if e.strip())
    if isinstance(effects, Mapping):
        forced = {effect_name(k): bool(v) for k, v in effects.items()}
        base = set(_auto(report))
        base |= {k for k, v in forced.items() if v}
        base -= {k for k, v in forced.items() if not v}
        return _ordered(base)
    return _ordered(effects)


def _check_names(effects: "str | Iterable[str] | Mapping[str, bool]") -> None:
    """Raise for an unknown effect name in any form of ``effects`` (the report not needed)."""
    if isinstance(effects, str):
        key = effects.strip().lower()
        names: Iterable[str] = () if key in ("auto", "all", "none") else key.split(",")
    else:
        names = effects  # a mapping's keys, or the names
    for name in names:
        if str(name).strip():
            effect_name(name)


def _auto(report: SceneReport | None) -> tuple[str, ...]:
    if report is None:
        raise ValueError("effects='auto' needs the scene report (analyze the image first)")
    return report.selected


class HumanVision(eqx.Module):
    """The selected human-vision effects as one step (a pytree; jit, vmap and grad go
    through it). Build it with :meth:`HumanVision.build` or get it from :func:`simulate`.

    Attributes:
        effects: the effects to apply (canonical names, application order).
        view: the resolved field of view; the step applies to images of this size.
        glare_spectrum: FFT of the Spencer kernel (``None`` without Spencer glare).
        glare_size: its FFT grid.
        glare_model: ``"spencer1995"`` (FFT convolution) or ``"pcond"`` (foveal veil).
        acuity_levels: MIP levels of the acuity blur (static).
        adaptation: global adaptation (cd/m²) for ``contrast``; ``None`` measures the input.
        contrast_model: ``"pcond"`` or ``"ward1994"``.
        display_max, display_range: the display, for ``contrast``.
        chromaticities: the image's primaries (``None``: Rec.709/D65).
    """

    __repr__ = _repr.fields_repr
    _repr_html_ = _repr.fields_html

    effects: tuple[str, ...] = eqx.field(static=True)
    view: ResolvedView = eqx.field(static=True)
    glare_spectrum: Array | None
    glare_size: tuple[int, int] | None = eqx.field(static=True)
    glare_model: str = eqx.field(static=True)
    acuity_levels: int = eqx.field(static=True)
    adaptation: Array | None
    contrast_model: str = eqx.field(static=True)
    display_max: float = eqx.field(static=True)
    display_range: float = eqx.field(static=True)
    chromaticities: tuple[float, ...] | None = eqx.field(static=True)

    @classmethod
    def build(
        cls,
        shape: Sequence[int],
        view: "View | ResolvedView | float | None" = None,
        effects: Iterable[str] = (),
        *,
        glare_model: GlareModel = "spencer1995",
        glare_variant: Variant = "photopic",
        glare_radius_deg: float | None = None,
        acuity_levels: int | None = None,
        adaptation: float | None = None,
        contrast_model: ContrastModel = "pcond",
        display_max: float = DISPLAY_MAX,
        display_range: float = DISPLAY_RANGE,
        chromaticities: Sequence[float] | None = None,
        dtype: Any = None,
    ) -> "HumanVision":
        """Prepare the effects for images of ``shape`` ``(H, W[, 3])``.

        Args:
            shape: image height and width (a trailing 3 is allowed).
            view: field of view (:class:`View`, horizontal degrees, or ``None``: pcond's 40°).
            effects: names from :data:`EFFECTS` (any order; applied in pcond's order).
            glare_model: Spencer et al. 1995 PSF convolution or pcond's foveal veil.
            glare_variant: Spencer PSF weights (photopic/mesopic/scotopic).
            glare_radius_deg: truncate the PSF (degrees); ``None``: the whole image.
            acuity_levels: acuity MIP levels; default: enough for any adaptation.
            adaptation: global adaptation in cd/m² for ``contrast`` (``None``: measured).
            contrast_model: ``"pcond"`` (combined TVI) or ``"ward1994"``.
            display_max: display maximum, cd/m²; display_range: its ``L_max/L_min``.
            chromaticities: the image's primaries.
            dtype: float dtype of the images (default: JAX's default float).
        """
        _check.image_size(shape)
        H, W = (int(v) for v in tuple(shape)[:2])
        if isinstance(view, ResolvedView):
            if (view.height, view.width) != (H, W):
                raise ValueError(f"view is for {view.height}×{view.width}, shape is {H}×{W}")
            rv = view
        else:
            rv = as_view(view).resolve(H, W)
        names = _ordered(effects)
        if glare_model not in ("spencer1995", "pcond"):
            raise ValueError(f"glare_model: expected 'spencer1995' or 'pcond', got {glare_model!r}")
        if contrast_model not in ("pcond", "ward1994"):
            raise ValueError(
                f"contrast_model: expected 'pcond' or 'ward1994', got {contrast_model!r}"
            )
        dtype = jnp.dtype(dtype if dtype is not None else jnp.result_type(float))
        spec, size = None, None
        if "glare" in names and glare_model == "spencer1995":
            spec, size = glare_spectrum(rv, glare_variant, radius_deg=glare_radius_deg, dtype=dtype)
        levels = max_levels(rv) if acuity_levels is None else int(acuity_levels)
        ch = chroma_key(chromaticities)  # validated now, not at trace time
        return cls(
            effects=names,
            view=rv,
            glare_spectrum=spec,
            glare_size=size,
            glare_model=glare_model,
            acuity_levels=levels,
            adaptation=None if adaptation is None else jnp.asarray(adaptation, dtype),
            contrast_model=contrast_model,
            display_max=float(display_max),
            display_range=float(display_range),
            chromaticities=ch,
        )

    @property
    def applied(self) -> tuple[str, ...]:
        """The effects that run: as :attr:`effects`, but ``blue_shift`` renders the colour
        loss when both are selected (applying both would count the rod signal twice)."""
        if "blue_shift" in self.effects:
            return tuple(e for e in self.effects if e != "colour_loss")
        return self.effects

    def __call__(self, rgb: Float[ArrayLike, "H W 3"]) -> Float[Array, "H W 3"]:
        """Apply the effects to one image in cd/m² (``jax.vmap`` for batches)."""
        rgb = check_rgb(rgb, image=True)
        if rgb.shape[:2] != (self.view.height, self.view.width):
            raise ValueError(
                f"rgb: shape {rgb.shape[:2]} does not match this step's "
                f"{self.view.height}×{self.view.width}"
            )
        return _apply(self, rgb) if self.effects else rgb

    def _apply(self, rgb: Array) -> Array:
        x = rgb
        ch = self.chromaticities
        for name in self.applied:
            if name == "acuity":
                x = acuity_loss(x, self.view, levels=self.acuity_levels, chromaticities=ch)
            elif name == "glare":
                if self.glare_model == "pcond":
                    x = veil(x, self.view)
                else:
                    assert self.glare_spectrum is not None and self.glare_size is not None
                    x = apply_glare(x, self.glare_spectrum, self.glare_size)
            elif name == "colour_loss":
                x = colour_loss(x, chromaticities=ch)
            elif name == "blue_shift":
                x = blue_shift(x, chromaticities=ch)
            elif name == "contrast":
                La = self.adaptation
                if La is None:
                    L = luminance(rgb, weights_of(ch))
                    La = adaptation_luminance(L, self.view.fovea_block)
                x = contrast(
                    x,
                    La,
                    model=self.contrast_model,  # type: ignore[arg-type]
                    display_max=self.display_max,
                    display_range=self.display_range,
                )
        return x


@eqx.filter_jit
def _apply(step: HumanVision, rgb: Array) -> Array:
    return step._apply(rgb)


def _unit_factor(unit: Any) -> float | None:
    """cd/m² per stored unit for absolute luminance units; ``None`` when unknown/relative."""
    if unit is None:
        return None
    u = str(unit).strip().lower().replace(" ", "").replace("²", "2").replace("^2", "2")
    u = u.replace("·", "").replace("*", "")
    if u in ("cd/m2", "nit", "nits", "candela/m2"):
        return 1.0
    if u in ("w/(srm2)", "w/sr/m2", "w/m2/sr", "w/(m2sr)"):
        return WHTEFFICACY
    if u in ("lx", "lux", "w/m2"):
        raise ValueError(
            f"image holds {unit} (illuminance or irradiance), not luminance; the vision "
            "effects need luminance in cd/m²"
        )
    return None


def absolute_rgb(
    image: Any, scale: float | None, chromaticities: Sequence[float] | None = None
) -> tuple[Array, tuple[float, ...] | None]:
    """RGB in cd/m² and its primaries from an array (with ``scale``) or a layered image.

    Raises:
        ValueError: if the scale of a relative image is not stated.
    """
    if scale is not None and not (float(scale) > 0 and np.isfinite(float(scale))):
        raise ValueError(f"scale: expected a finite number > 0 (cd/m² per unit), got {scale!r}")
    if hasattr(image, "rgb") and callable(image.rgb):
        # a layered image: its pixels in the working space (sRGB) unless primaries are
        # given, then in those
        rgb = image.rgb() if chromaticities is None else image.rgb(chromaticities)
        unit = getattr(image, "unit", None)
        factor = float(scale) if scale is not None else _unit_factor(unit)
        if factor is None:
            white = getattr(image, "white_luminance", None)
            if white is not None and float(white) > 0:
                factor = float(white)
        if factor is None:
            raise ValueError(
                f"image is in relative units (unit={unit!r}); pass scale= (cd/m² per unit) — "
                "the vision effects depend on absolute luminance and will not guess it"
            )
    else:
        if scale is None:
            raise ValueError(
                "an array carries no units: pass scale= (cd/m² per unit; 1.0 if the image is "
                "already in cd/m²) — the vision effects depend on absolute luminance"
            )
        rgb, factor = image, float(scale)
    rgb = check_rgb(rgb, "image", image=True)
    ch = chroma_key(chromaticities)
    if factor == 1.0:
        return rgb, ch
    return _to_cd(rgb, jnp.asarray(factor, rgb.dtype)), ch


@jax.jit
def _to_cd(rgb: Array, factor: Array) -> Array:
    """``rgb · factor``; finite values the factor takes past the float range saturate at
    the largest float (a stored 3.4e38 in W/sr/m² is beyond float32 in cd/m²), so finite
    pixels stay finite. One fused step; the other values keep their bits."""
    top = jnp.finfo(rgb.dtype).max
    y = rgb * factor
    return jnp.where(jnp.isfinite(rgb), jnp.clip(y, -top, top), y)


def analyze(
    image: Any,
    view: "View | float | None" = None,
    *,
    scale: float | None = None,
    chromaticities: Sequence[float] | None = None,
) -> SceneReport:
    """Report a scene's adaptation and which vision effects apply, and why (pcond's rules).

    Args:
        image: linear RGB ``(H, W, 3)`` array, or a layered image from ``hdrjax.io.read``.
        view: field of view (:class:`View`, horizontal degrees, or ``None``: 40° across the
            longer side as in pcond).
        scale: cd/m² per stored unit; required for arrays and relative images.
        chromaticities: the image's primaries (``None``: Rec.709/D65, or the file's).

    Returns:
        A :class:`SceneReport`: adaptation luminances (global and foveal), 5th percentile,
        range, and a :class:`Decision` with numbers and thresholds for every effect.

    Example:
        >>> import numpy as np
        >>> night = np.full((256, 512, 3), 0.05, np.float32)  # 0.05 cd/m², 40° wide
        >>> analyze(night, 40.0, scale=1.0).selected
        ('acuity', 'colour_loss', 'blue_shift', 'contrast')
    """
    rgb, ch = absolute_rgb(image, scale, chromaticities)
    rv = as_view(view).resolve(rgb.shape[0], rgb.shape[1])
    return analyze_rgb(rgb, rv, weights_of(ch))


def _operator(then: "AbstractOperator | str | None") -> AbstractOperator | None:
    if then is None or isinstance(then, AbstractOperator):
        return then
    if isinstance(then, str):
        return make_operator(then)
    raise ValueError(
        f"then: expected a tone-mapping operator (an hdrjax operator or a registered name "
        f"such as 'reinhard2002'), got {type(then).__name__}"
    )


def _may_select_nothing(effects: "str | tuple[str, ...] | Mapping[str, bool]") -> bool:
    """Whether ``effects`` can resolve to no effect (so the image may go straight to the
    tone mapping): ``"auto"``, ``"none"``, or overrides that force nothing on."""
    if isinstance(effects, str):
        key = effects.strip().lower()
        return key in ("auto", "none") or not any(e.strip() for e in key.split(","))
    if isinstance(effects, Mapping):
        return not any(bool(v) for v in effects.values())
    return not effects


@eqx.filter_jit
def _analyze_and_tonemap(
    op: AbstractOperator,
    rgb: Array,
    weights: tuple[float, float, float],
    block: tuple[int, int],
    stride: tuple[int, int],
) -> tuple:
    """The analysis statistics and ``op(rgb)`` in one program, for an image that turns out
    to be clean (the caller checks it from the statistics and discards the image
    otherwise). The tone mapping takes the operators' finite-image path; its luminance is
    the analysis's (the same expression, merged by XLA when the weights are the same), so
    the image is read for both at once."""
    L = luminance(rgb, weights)
    return (clean_operator_call(op, rgb), L, *fast_statistics(L, block, stride))


def simulate(
    image: Any,
    view: "View | float | None" = None,
    effects: "str | Iterable[str] | Mapping[str, bool]" = "auto",
    *,
    scale: float | None = None,
    chromaticities: Sequence[float] | None = None,
    glare_model: GlareModel = "spencer1995",
    glare_variant: "Variant | Literal['auto']" = "auto",
    glare_radius_deg: float | None = None,
    contrast_model: ContrastModel = "pcond",
    display_max: float = DISPLAY_MAX,
    display_range: float = DISPLAY_RANGE,
    then: "AbstractOperator | str | None" = None,
) -> tuple[Float[Array, "H W 3"], SceneReport]:
    """Simulate what a human observer sees: apply only the effects the scene calls for.

    Args:
        image: linear RGB ``(H, W, 3)`` array, or a layered image from ``hdrjax.io.read``.
        view: field of view (:class:`View`, horizontal degrees, or ``None``: pcond's 40°).
        effects: ``"auto"`` (the report's selection), ``"all"``, ``"none"``, a set of
            names from :data:`EFFECTS`, or a mapping forcing effects on/off on top of auto,
            e.g. ``{"glare": False}``.
        scale: cd/m² per stored unit; required for arrays and relative images.
        chromaticities: the image's primaries.
        glare_model: ``"spencer1995"`` PSF convolution (default) or ``"pcond"`` veil.
        glare_variant: PSF weights; ``"auto"`` picks them from the global adaptation.
        glare_radius_deg: truncate the PSF (degrees); ``None``: whole image (exact).
        contrast_model: ``"pcond"`` (combined TVI) or ``"ward1994"``.
        display_max: display maximum luminance, cd/m² (``contrast``).
        display_range: display ``L_max/L_min`` (``contrast``, pcond model).
        then: a tone-mapping operator (an ``hdrjax.operators`` instance or a registered
            name, as in ``hdrjax.tonemap``) applied to the result: the same image as
            ``op(simulate(...)[0])``, faster. When the scene calls for no effect (a
            daylight scene), the analysis and a global operator's tone mapping run as one
            compiled program that reads the image once for both; when it calls for some,
            that tone mapping is discarded (one extra global tone mapping on a scene whose
            effects cost far more).

    Returns:
        ``(rgb, report)``: RGB in cd/m² (display cd/m² after ``contrast``), or the
        operator's display-referred RGB with ``then``, and the :class:`SceneReport` (its
        5th percentile found on first use when the range decided the rules), whose
        ``selected`` names the effects applied (the rules' choice as ``effects`` overrode
        it; ``decisions`` keep the rules' verdicts). Not traceable itself (the report
        decides what to compile); use :meth:`HumanVision.build` under
        ``jax.jit``/``vmap``/``grad``.
    """
    rgb, ch = absolute_rgb(image, scale, chromaticities)
    if isinstance(rgb, jax.core.Tracer):
        raise ValueError(
            "simulate decides what to compile from concrete values; under jax.jit/vmap/grad "
            "use HumanVision.build(shape, view, effects)(rgb)"
        )
    op = _operator(then)
    if not isinstance(effects, str | Mapping):
        effects = tuple(effects)  # read once (it may be an iterator)
    _check_names(effects)  # before the analysis
    rv = as_view(view).resolve(rgb.shape[0], rgb.shape[1])
    weights = weights_of(ch)
    report = None
    if isinstance(op, AbstractLuminanceCurve) and _may_select_nothing(effects):
        block = rv.fovea_block
        shown, L, *stats = _analyze_and_tonemap(op, rgb, weights, block, pixel_stride(block))
        report = fast_report(rv, L, *stats, defer_p05=True)
        if report is not None and not select_effects(effects, report):
            # a clean image that calls for nothing: already mapped
            return shown, _applied(report, ())
        if report is None:
            report = masked_report(rv, L)
    if report is None:
        report = analyze_rgb(rgb, rv, weights, defer_p05=True)
    names = select_effects(effects, report)
    if not names:  # nothing selected: nothing traced, nothing computed
        return (rgb if op is None else op(rgb)), _applied(report, ())
    fov = report.adaptation_foveal
    fmin = float(np.min(fov)) if fov.size else LMIN
    step = HumanVision.build(
        rgb.shape,
        rv,
        names,
        glare_model=glare_model,
        glare_variant=report.glare_variant if glare_variant == "auto" else glare_variant,
        glare_radius_deg=glare_radius_deg,
        acuity_levels=max_levels(rv, max(fmin, LMIN)),
        adaptation=report.adaptation_global,
        contrast_model=contrast_model,
        display_max=display_max,
        display_range=display_range,
        chromaticities=ch,
        dtype=rgb.dtype,
    )
    out = step(rgb)
    return (out if op is None else op(out)), _applied(report, step.effects)


def _applied(report: SceneReport, names: tuple[str, ...]) -> SceneReport:
    """The report with ``selected`` = the effects the step was built with (``effects=`` may
    override the rules' choice; ``decisions`` keep the rules' verdicts)."""
    if report.selected == names:
        return report
    return dataclasses.replace(report, selected=names)


__all__ = [
    "EFFECTS",
    "HumanVision",
    "WHTEFFICACY",
    "absolute_rgb",
    "analyze",
    "effect_name",
    "select_effects",
    "simulate",
]
