"""The conformance table: every public function that takes an image or a field of values,
as a :class:`Case` the generic tests in ``test_images.py`` run over the hard-value families,
dtypes and shapes.

A case is ``fn(x)`` of one linear, *relative* RGB image ``x`` of shape ``(H, W, 3)`` (the
vision cases scale it to cd/m² themselves). Registries are expanded here, so a newly
registered filter mode, median criterion, vision effect or light detector is a new case
without anyone adding it; operators have their own registry-driven suite in
``tests/operators/test_conformance.py``.

Policies the generic tests check (the numeric contract every module docstring states):

- **dtype**: float32 in → float32 out; float64 in (x64 on) → float64 out; float16 (and
  bfloat16) inputs are *computed in* JAX's default float and returned in it (float32, or
  float64 with x64): half floats are a storage format (EXR ``half``), too narrow for
  log-averages and sums over an image.
- **finite where finite**: a pixel whose input is finite gets a finite output, unless a
  non-finite input pixel is within its documented *reach*:

  - ``"pixel"``: non-finite pixels are passed through or replaced per pixel, never spread.
  - ``"linear"``: a linear filter or resampler (mean filter, bilinear panorama resampling)
    lets a NaN/Inf reach exactly the outputs whose weights touch it — checked by applying
    the same function to the indicator image of the bad pixels.
  - ``"window"``: the median filter's window (``size``): a NaN stays in its window.
  - ``"stat"``: the outputs are statistics, from which non-finite pixels are excluded, so
    they are finite whatever the input.

- **documented non-finite outputs** are listed per case in ``nonfinite_ok`` (e.g. the
  percentiles of an image without a positive pixel are NaN; a map without light has
  threshold ``inf``).
"""

import dataclasses
import inspect
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import hdrjax
import hdrjax.display as hd
import hdrjax.filters as hf
import hdrjax.lights as hl
import hdrjax.panorama as hp
import hdrjax.targets as ht
import hdrjax.vision as hv
from hdrjax import stats

SCALE = 100.0
"""cd/m² per unit for the vision cases: the families then span scotopic to photopic."""


@dataclasses.dataclass(frozen=True)
class Case:
    fn: Callable
    covers: tuple[str, ...]
    """Public names (``module.name``) this case exercises."""
    reach: str = "pixel"
    """How far a non-finite input pixel may reach: pixel, linear, window or stat."""
    size: int = 1
    """Window size for ``reach="window"``."""
    jit: bool = True
    """Traceable (jit/vmap/grad); False for the NumPy-side functions."""
    grad: bool = True
    """Differentiable with respect to the image (and its Module's parameters)."""
    batch: bool = False
    """Accepts leading batch axes ``(..., H, W, 3)`` itself."""
    out_range: tuple[float, float] | None = None
    """Documented range of the finite outputs."""
    nonfinite_ok: Callable[[np.ndarray], bool] | None = None
    """Predicate on the input image: True where the case's documentation allows non-finite
    outputs for it (e.g. percentiles of an image without light are NaN)."""
    dtypes: tuple[str, ...] = ("float16", "float32", "float64")
    """Input dtypes of the family test (slow compiles: fewer)."""
    module: Callable | None = None
    """For Module cases: ``module(x) -> eqx.Module`` whose array fields are parameters."""


def no_light(img, lo=0.0, hi=np.inf):
    """No pixel has a finite luminance in ``(lo, hi)`` (and above the smallest normal)."""
    with np.errstate(invalid="ignore", over="ignore"):  # inf - inf in the NaN/Inf family
        L = np.asarray(img, np.float64) @ np.array([0.2126, 0.7152, 0.0722])
    ok = np.isfinite(L) & (L > max(lo, np.finfo(np.float32).tiny)) & (L < hi)
    return not ok.any()


def _cd(x):
    """cd/m² for the vision cases: half floats are promoted first (as the library does), so
    the scaling itself does not overflow float16."""
    if x.dtype == jnp.float16:
        x = x.astype(jnp.result_type(float))
    return x * SCALE


def _module_case(make, **kw):
    """A Module applied to the image; ``make(x)`` builds it for the image's shape."""
    return Case(fn=lambda x: make(x)(x), module=make, **kw)


def _float_leaves(out):
    return [
        np.asarray(v)
        for v in jax.tree_util.tree_leaves(out)
        if hasattr(v, "dtype") and jnp.issubdtype(v.dtype, jnp.floating)
    ]


def _cube(x):
    """Six square faces from an image (the cube-map inputs)."""
    s = min(x.shape[0], x.shape[1])
    f = x[:s, :s]
    return jnp.stack([f, f[::-1], f[:, ::-1], jnp.swapaxes(f, 0, 1), f[::-1, ::-1], f])


def _dirs(n=7):
    """Directions on and between the axes and poles (equirect sampling points)."""
    d = np.array(
        [[0, 0, -1], [1, 0, 0], [0, 1, 0], [0, -1, 0], [-1, 0, 0], [0, 0, 1], [1, 1, 1]],
        np.float32,
    )[:n]
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


_Q = np.array([1.0, 5.0, 50.0, 95.0, 99.0])

CASES: dict[str, Case] = {
    # --- colour ------------------------------------------------------------------------
    "luminance": Case(lambda x: hdrjax.luminance(x), ("hdrjax.luminance",), batch=True),
    # --- display -----------------------------------------------------------------------
    "desaturate_highlights": Case(
        lambda x: hdrjax.desaturate_highlights(x),
        ("hdrjax.desaturate_highlights", "hdrjax.display.desaturate_highlights"),
        batch=True,
    ),
    "DesaturateHighlights": _module_case(
        lambda x: hd.DesaturateHighlights(threshold=jnp.asarray(2.0, x.dtype)),
        covers=("hdrjax.display.DesaturateHighlights",),
        batch=True,
    ),
    "highlight_threshold": Case(
        lambda x: hd.highlight_threshold(x),
        ("hdrjax.display.highlight_threshold",),
        reach="stat",
        grad=False,  # a histogram percentile: a constant for jax.grad (documented)
        batch=True,
    ),
    "encode_srgb": Case(
        lambda x: hd.encode(x), ("hdrjax.display.encode",), batch=True, out_range=(0, 1)
    ),
    "encode_gamma": Case(
        lambda x: hd.encode(x, "gamma"), ("hdrjax.display.encode",), batch=True, out_range=(0, 1)
    ),
    "gamma_encode": Case(
        lambda x: hd.gamma_encode(jnp.maximum(x, 0)), ("hdrjax.display.gamma_encode",), batch=True
    ),
    "srgb_encode": Case(lambda x: hd.srgb_encode(x), ("hdrjax.display.srgb_encode",), batch=True),
    "srgb_decode": Case(lambda x: hd.srgb_decode(x), ("hdrjax.display.srgb_decode",), batch=True),
    "quantize": Case(
        lambda x: hd.quantize(np.asarray(hd.encode(x)), 16).astype(np.float32) / 65535,
        ("hdrjax.display.quantize",),
        jit=False,
        grad=False,
        batch=True,
        out_range=(0, 1),
    ),
    "false_color": Case(
        # NaN/±Inf get their own colours: the image is finite everywhere, in [0, 1]
        lambda x: hd.false_color(np.asarray(hdrjax.luminance(x)), legend=False, log=True).image,
        ("hdrjax.false_color", "hdrjax.display.false_color", "hdrjax.display.false_color_scale"),
        reach="stat",
        jit=False,
        grad=False,
        batch=False,  # one scale (one legend) for a whole batch, by design
        out_range=(0, 1),
    ),
    # --- statistics --------------------------------------------------------------------
    "stats.measure": Case(
        lambda x: stats.measure(hdrjax.luminance(x)),
        ("hdrjax.stats.measure", "hdrjax.stats.LuminanceStats"),
        reach="stat",
    ),
    "stats.measure_exact": Case(
        lambda x: stats.measure(hdrjax.luminance(x), method="exact"),
        ("hdrjax.stats.measure",),
        reach="stat",
    ),
    "stats.percentile": Case(
        lambda x: stats.percentile(hdrjax.luminance(x), jnp.asarray(_Q, x.dtype))[0],
        ("hdrjax.stats.percentile",),
        reach="stat",
        grad=False,
        nonfinite_ok=no_light,  # documented: NaN when no pixel is finite and positive
    ),
    "stats.percentile_exact": Case(
        lambda x: stats.percentile(hdrjax.luminance(x), jnp.asarray(_Q, x.dtype), method="exact")[
            0
        ],
        ("hdrjax.stats.percentile",),
        reach="stat",
        nonfinite_ok=no_light,
    ),
    # --- vision: the formulas, applied per value (luminance in cd/m²) --------------------
    **{
        f"vision.{f.__name__}": Case(
            lambda x, f=f: f(jnp.abs(_cd(x))), (f"hdrjax.vision.{f.__name__}",)
        )
        for f in (
            hv.acuity,
            hv.tvi,
            hv.tvi_photopic,
            hv.tvi_scotopic,
            hv.mesopic_weight,
            hv.blue_shift_weight,
            hv.contrast_scale,
            hv.spencer1995_psf,  # angles in degrees
        )
    },
    "vision.contrast_scale_ward1994": Case(
        lambda x: hv.contrast_scale(jnp.abs(_cd(x)), model="ward1994"),
        ("hdrjax.vision.contrast_scale",),
    ),
    "vision.ward1994_scale": Case(
        lambda x: hv.ward1994_scale(jnp.abs(_cd(x)), 50.0), ("hdrjax.vision.ward1994_scale",)
    ),
    "vision.fechner": Case(
        # brightness of the scene, then back: the inverse pair on the same values
        lambda x: hv.fechner_luminance(hv.fechner_brightness(jnp.abs(_cd(x)), 10.0), 10.0),
        ("hdrjax.vision.fechner_brightness", "hdrjax.vision.fechner_luminance"),
    ),
    "vision.scotopic_luminance": Case(
        lambda x: hv.scotopic_luminance(_cd(x)), ("hdrjax.vision.scotopic_luminance",)
    ),
    "vision.blue_shift": Case(lambda x: hv.blue_shift(_cd(x)), ("hdrjax.vision.blue_shift",)),
    "vision.colour_loss": Case(lambda x: hv.colour_loss(_cd(x)), ("hdrjax.vision.colour_loss",)),
    "vision.contrast": Case(lambda x: hv.contrast(_cd(x), 10.0), ("hdrjax.vision.contrast",)),
    # --- vision: spatial effects on one image --------------------------------------------
    "vision.sample_spacing": Case(
        # a dim scene seen through a 0.5° field: the eye's sample spacing exceeds one pixel,
        # so it depends on the image (it is clamped to 1 pixel in daylight or a wide view)
        lambda x: hv.sample_spacing(_cd(x) * 1e-4, 0.5),
        ("hdrjax.vision.sample_spacing",),
        reach="stat",
    ),
    "vision.acuity_loss": Case(lambda x: hv.acuity_loss(_cd(x)), ("hdrjax.vision.acuity_loss",)),
    "vision.glare": Case(lambda x: hv.glare(_cd(x), 30.0), ("hdrjax.vision.glare",)),
    "vision.veil": Case(lambda x: hv.veil(_cd(x)), ("hdrjax.vision.veil",)),
    "vision.perceptual_reproduction": Case(
        lambda x: hv.perceptual_reproduction(_cd(x)),
        ("hdrjax.vision.perceptual_reproduction",),
    ),
    "vision.Budak2005": _module_case(
        lambda x: hv.Budak2005(adaptation=jnp.asarray(10.0, x.dtype)),
        covers=("hdrjax.vision.Budak2005", "hdrjax.vision.ConeOpponentSpace"),
    ),
    "vision.analyze": Case(
        lambda x: _report_numbers(hv.analyze(np.asarray(x), scale=SCALE)),
        ("hdrjax.vision.analyze", "hdrjax.vision.SceneReport", "hdrjax.vision.Decision"),
        reach="stat",
        # documented: NaN statistics when no pixel lies in pcond's (1e-7, 1e5) cd/m²
        nonfinite_ok=lambda img: no_light(img * SCALE, 1e-7, 1e5),
        jit=False,
        grad=False,
    ),
    # --- lights ----------------------------------------------------------------------------
    "lights.display_image": Case(
        lambda x: hl.display_image(np.asarray(x)),
        ("hdrjax.lights.display_image",),
        jit=False,
        grad=False,
        out_range=(0, 1),
        reach="stat",  # documented: non-finite pixels are shown black
    ),
    "lights.cubemap_equirect": Case(
        lambda x: hl.cubemap_equirect(_cube(x), height=8),
        ("hdrjax.lights.cubemap_equirect",),
        reach="linear",
        batch=False,
    ),
    # --- panorama: bilinear resampling ------------------------------------------------------
    "panorama.equirect_to_cubemap": Case(
        lambda x: hp.equirect_to_cubemap(x, 4),
        ("hdrjax.panorama.equirect_to_cubemap",),
        reach="linear",
    ),
    "panorama.cubemap_to_equirect": Case(
        lambda x: hp.cubemap_to_equirect(_cube(x), 8),
        ("hdrjax.panorama.cubemap_to_equirect",),
        reach="linear",
    ),
    "panorama.equirect_to_fisheye": Case(
        lambda x: hp.equirect_to_fisheye(x, 8),
        ("hdrjax.panorama.equirect_to_fisheye",),
        reach="linear",
    ),
    "panorama.fisheye_to_equirect": Case(
        lambda x: hp.fisheye_to_equirect(x, 8),
        ("hdrjax.panorama.fisheye_to_equirect",),
        reach="linear",
    ),
    "panorama.polar_to_cartesian": Case(
        lambda x: hp.polar_to_cartesian(x, 8),
        ("hdrjax.panorama.polar_to_cartesian",),
        reach="linear",
    ),
    "panorama.sample_equirect": Case(
        lambda x: hp.sample_equirect(x, jnp.asarray(_dirs(), x.dtype)),
        ("hdrjax.panorama.sample_equirect",),
        reach="linear",
    ),
    "panorama.sample_bilinear": Case(
        lambda x: hp.sample_bilinear(
            x,
            jnp.asarray([0.0, 0.3, x.shape[1] - 1.0], x.dtype),
            jnp.asarray([0.0, x.shape[0] / 2, x.shape[0] - 1.0], x.dtype),
        ),
        ("hdrjax.panorama.sample_bilinear",),
        reach="linear",
    ),
}

# NumPy-side cases return NumPy/Python numbers (no dtype contract to check): float16 (the
# promotion) and float32 suffice
for _c in list(CASES):
    if not CASES[_c].jit and "simulate" not in _c:
        CASES[_c] = dataclasses.replace(CASES[_c], dtypes=("float16", "float32"))

# the operators' automatic estimates as functions: every public function of hdrjax.estimate
for _name in hdrjax.estimate.__all__:
    _f = getattr(hdrjax.estimate, _name)
    if inspect.isfunction(_f):
        CASES[f"estimate.{_name}"] = Case(
            lambda x, f=_f: f(x),
            (f"hdrjax.estimate.{_name}", "hdrjax.estimate.Estimate"),
            reach="stat",
            grad=False,  # histogram percentiles inside: constants for jax.grad (documented)
        )

# --- registries ------------------------------------------------------------------------------
for _mode in hf.MODES:
    CASES[f"filters.mean_filter[{_mode}]"] = Case(
        (lambda m: lambda x: hf.mean_filter(x, 3, mode=m))(_mode),
        ("hdrjax.mean_filter", "hdrjax.filters.mean_filter"),
        reach="linear",
        batch=True,
    )
# every criterion, and every edge mode (the modes' padding is shared with the mean filter:
# one criterion per mode keeps the count down)
for _i, _crit in enumerate(hf.CRITERIA):
    for _mode in hf.MODES if _i == 0 else ("nearest",):
        CASES[f"filters.median_filter[{_crit},{_mode}]"] = Case(
            (lambda c, m: lambda x: hf.median_filter(x, 3, criterion=c, mode=m))(_crit, _mode),
            ("hdrjax.median_filter", "hdrjax.filters.median_filter"),
            reach="window",
            size=3,
            batch=True,
        )

for _effect in hv.EFFECTS:
    CASES[f"vision.HumanVision[{_effect}]"] = _module_case(
        (lambda e: lambda x: hv.HumanVision.build(x.shape, 30.0, (e,), dtype=x.dtype))(_effect),
        covers=("hdrjax.vision.HumanVision", "hdrjax.vision.View", "hdrjax.vision.ResolvedView"),
    )
    CASES[f"vision.simulate[{_effect}]"] = Case(
        (lambda e: lambda x: hv.simulate(np.asarray(x), 30.0, {e}, scale=SCALE)[0])(_effect),
        ("hdrjax.vision.simulate",),
        jit=False,  # documented: decides what to compile from concrete values
        grad=False,
        dtypes=("float32",),  # runs HumanVision, whose dtypes the case above checks
    )

# light detectors: every public function of hdrjax.lights that returns a light set
DETECTORS = sorted(
    n
    for n in dir(hl)
    if not n.startswith("_")
    and inspect.isfunction(getattr(hl, n))
    and inspect.signature(getattr(hl, n)).return_annotation in (hl.Lights, hl.MedianCutLights)
)
_DETECT_ARGS = {
    "detect": lambda x: hl.detect(x, width=16),
    "detect_image": lambda x: hl.detect_image(x, width=16),
    "detect_cubemap": lambda x: hl.detect_cubemap(_cube(x), height=8, width=16),
    "median_cut": lambda x: hl.median_cut(x, n_lights=4, width=16),
}


def _without_inf_threshold(res):
    """Documented: ``threshold`` is +inf when the map has no light to find; every other
    output (and a NaN threshold) must be finite."""
    t = getattr(res, "threshold", None)
    if t is None:
        return res
    return eqx.tree_at(lambda r: r.threshold, res, jnp.where(jnp.isposinf(t), 0.0, t))


for _name in DETECTORS:
    CASES[f"lights.{_name}"] = Case(
        # a KeyError here: a new detector needs its arguments in _DETECT_ARGS
        lambda x, f=_DETECT_ARGS[_name]: _without_inf_threshold(f(x)),
        (f"hdrjax.lights.{_name}", "hdrjax.lights.Lights", "hdrjax.lights.MedianCutLights"),
        reach="stat",
        grad=False,  # detections are discrete: positions and counts
        # batches: median_cut here; detect/detect_image in tests/lights/test_detect.py
        # (slow compiles); detect_cubemap: the test's _cube makes one set of faces
        batch=_name == "median_cut",
        dtypes=("float32",),  # slow to compile; dtypes: tests/lights
    )

# targets: every concrete target class, on a display image (clipped to [0, 1] by the target)
_TARGETS = {
    "MeanLuminance": lambda: ht.MeanLuminance(0.18),
    "Percentiles": lambda: ht.Percentiles([10.0, 50.0, 90.0], [0.05, 0.2, 0.8]),
    "ClippedFraction": lambda: ht.ClippedFraction(0.01),
    "Histogram": lambda: ht.Histogram(np.full(8, 1 / 8)),
    "Scaled": lambda: 2.0 * ht.MeanLuminance(0.18),
    "Combined": lambda: ht.MeanLuminance(0.18) + ht.ClippedFraction(0.01),
}
TARGET_CLASSES = sorted(
    n
    for n in dir(ht)
    if not n.startswith("_")
    and inspect.isclass(getattr(ht, n))
    and issubclass(getattr(ht, n), ht.AbstractTarget)
    and not inspect.isabstract(getattr(ht, n))
    and not n.startswith("Abstract")
)
for _name in TARGET_CLASSES:
    if _name == "Reference":
        _make = (lambda: lambda x: ht.Reference(jnp.full(x.shape, 0.5, x.dtype)))()
    else:
        _make = (lambda m: lambda x: m())(_TARGETS[_name])  # KeyError: add the new target
    CASES[f"targets.{_name}"] = Case(
        # targets take display images: x / (1 + |x|) puts every family in (-1, 1)
        lambda x, mk=_make: mk(x).residuals(x / (1 + jnp.abs(x))),
        (f"hdrjax.targets.{_name}", "hdrjax.targets.AbstractTarget"),
        reach="stat",
        # documented: percentiles of the positive display luminance; an all-black display
        # has none (NaN statistics)
        nonfinite_ok=no_light if _name == "Percentiles" else None,
    )


def _report_numbers(report):
    """The numbers of a SceneReport (global statistics: finite with bad pixels excluded)."""
    vals = [
        report.adaptation_global,
        report.adaptation_centre,
        report.luminance_p05,
        report.luminance_min,
        report.luminance_max,
        report.dynamic_range,
    ]
    vals += [d.value for d in report.decisions.values()]
    return np.concatenate(
        [np.ravel(np.asarray(vals, np.float64)), np.ravel(report.adaptation_foveal)]
    )


def covered_names() -> set[str]:
    return {n for c in CASES.values() for n in c.covers}


def float_leaves(out):
    return _float_leaves(out)


def parameters(module):
    """The inexact-array fields of an equinox Module and the rest."""
    return eqx.partition(module, eqx.is_inexact_array)
