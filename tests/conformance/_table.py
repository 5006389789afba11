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

Bad input (``test_bad_input.py``, policy in ``hdrjax/_check.py``): every case is fed each
form of :data:`BAD_INPUTS` (wrong rank, wrong channel count, integer/bool/complex dtype, no
rows or no columns) and must raise a one-line ``ValueError`` naming the argument and the
expected form — unless the case declares the form in ``accepts`` with its reason and a
reference for the result.
Integer and bool images are promoted to float by policy (:data:`PROMOTED`): the result must
equal the result for the same values as float32. ``params`` lists out-of-range parameters
(argument name, call) that must raise a ``ValueError`` naming that argument.
"""

import dataclasses
import inspect
from collections.abc import Callable, Mapping

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import hdrjax
import hdrjax.batch as hb
import hdrjax.display as hd
import hdrjax.filters as hf
import hdrjax.lights as hl
import hdrjax.merge as hmerge
import hdrjax.metrics as hm
import hdrjax.panorama as hp
import hdrjax.targets as ht
import hdrjax.tile as htile
import hdrjax.vision as hv
from hdrjax import stats

XYZ = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1 / 3, 1 / 3)
"""CIE XYZ stored as RGB (OpenEXR's chromaticities): converted, it leaves the RGB gamut."""
BANDS = (400.0, 460.0, 520.0, 580.0, 640.0, 700.0)
"""Wavelengths (nm) of the spectral case."""

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
    accepts: Mapping[str, tuple[str, Callable]] = dataclasses.field(default_factory=dict)
    """Bad-input forms (keys of :data:`BAD_INPUTS`) the case accepts by design, each as
    ``(reason, reference)``; ``reference(fn, good, kind)`` gives the expected output for
    ``BAD_INPUTS[kind](good)``."""
    params: tuple[tuple[str, Callable], ...] = ()
    """Out-of-range parameters: ``(argument name, fn(x) calling the case with it)``; each
    must raise a ValueError naming the argument."""
    equals: tuple[Callable, float, float] | None = None
    """``(whole, rtol, atol)``: another way of computing ``whole(x)`` (tiles, a batch
    pipeline) — its outputs must equal ``whole``'s on every hard family
    (``test_equivalence.py``): NaN where ``whole`` has NaN, finite values within
    ``rtol``/``atol`` (atol relative to the largest finite output)."""


def no_light(img, lo=0.0, hi=np.inf):
    """No pixel has a finite luminance in ``(lo, hi)`` (and above the smallest normal)."""
    with np.errstate(invalid="ignore", over="ignore"):  # inf - inf in the NaN/Inf family
        L = np.asarray(img, np.float64) @ np.array([0.2126, 0.7152, 0.0722])
    ok = np.isfinite(L) & (L > max(lo, np.finfo(np.float32).tiny)) & (L < hi)
    return not ok.any()


def _cd(x):
    """cd/m² for the vision cases: half floats are promoted first (as the library does), so
    the scaling itself does not overflow float16; finite values that the scaling would
    take beyond the float range (the largest-scale families) saturate at its largest
    finite value, so the function sees a finite pixel where the family has one."""
    if x.dtype == jnp.float16:
        x = x.astype(jnp.result_type(float))
    if not jnp.issubdtype(x.dtype, jnp.floating):  # bad-input forms reach the function
        return x * SCALE
    y = x * SCALE
    big = jnp.sign(x) * jnp.finfo(x.dtype).max
    return jnp.where(jnp.isinf(y) & jnp.isfinite(x), big, y)


# --- bad input (test_bad_input.py) ------------------------------------------------------
BAD_INPUTS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    # wrong rank: one channel plane (H, W) and one row (W,) of a good (H, W, 3) image
    "rank2": lambda g: g[..., 0],
    "rank1": lambda g: g[0, :, 0],
    # wrong channel count: RGBA-like (red repeated as the 4th channel), and one channel
    "channels4": lambda g: np.concatenate([g, g[..., :1]], axis=-1),
    "channels1": lambda g: g[..., :1],
    # wrong dtype
    "int": lambda g: np.round(g).astype(np.int32),
    "bool": lambda g: g > 1.0,
    "complex": lambda g: g.astype(np.complex64),
    # empty: no rows (0, W, 3), no columns (H, 0, 3) — policy of hdrjax/_check.py
    "empty_rows": lambda g: g[:0],
    "empty_cols": lambda g: g[:, :0],
}
EMPTY_FORMS = ("empty_rows", "empty_cols")

PROMOTED = {
    "int": "integer images are promoted to the default float, as NumPy ufuncs do",
    "bool": "bool images (masks) are promoted to the default float (0.0 and 1.0)",
}
"""Dtype forms every case accepts (policy of hdrjax/_check.py): the result must equal the
result for the same values as float32."""


def channels_of(out, kind):
    """The part of an output for the good image that the bad form of ``kind`` must give,
    for functions that act on each value or each channel on its own."""
    if kind == "rank2":
        return out[..., 0]
    if kind == "rank1":
        return out[0, :, 0]
    if kind == "channels1":
        return out[..., :1]
    if kind == "channels4":
        return np.concatenate([out, out[..., :1]], axis=-1)
    if kind == "empty_rows":
        return out[:0]
    if kind == "empty_cols":
        return out[:, :0]
    raise KeyError(kind)


def per_value(fn, good, kind):
    """Reference for elementwise / per-channel functions: the same values' outputs."""
    return [channels_of(np.asarray(v), kind) for v in _float_leaves(fn(good))]


def grey(fn, good, kind):
    """Reference for one channel: the RGB image with that channel in R, G and B (its
    luminance is the channel; a vector median of grey pixels is the scalar median)."""
    assert kind == "channels1"
    rgb = np.repeat(good[..., :1], 3, axis=-1)
    return [np.asarray(v)[..., :1] for v in _float_leaves(fn(rgb))]


def vector_median_nearest(img, size=3):
    """NumPy vector median (the window pixel with the least summed Euclidean distance to the
    window's pixels; first in row-major window order on ties), edges replicated."""
    r = size // 2
    pad = np.pad(img, ((r, r), (r, r), (0, 0)), mode="edge").astype(np.float64)
    out = np.empty(img.shape, np.float64)
    for i in range(img.shape[0]):
        for j in range(img.shape[1]):
            w = pad[i : i + size, j : j + size].reshape(-1, img.shape[-1])
            d = np.sqrt(((w[:, None] - w[None]) ** 2).sum(-1)).sum(1)
            out[i, j] = w[np.argmin(d)]
    return out


SAME_PATH = None
"""A reference of ``None``: the form takes the code path whose values another form or case
checks; the test compares output shapes and dtypes (``jax.eval_shape``, no compile)."""

EMPTY_PER_PIXEL = {
    k: (
        "a function of each pixel (or value) takes an empty array, as NumPy ufuncs do: an"
        " empty result, whose shape and dtype are all there is to check",
        SAME_PATH,
    )
    for k in EMPTY_FORMS
}
ELEMENTWISE = {
    "rank2": ("a formula applied to each value: any shape", per_value),
    "channels4": ("a formula applied to each value: any shape", per_value),
    "rank1": ("a formula applied to each value: any shape (values: rank2)", SAME_PATH),
    "channels1": ("a formula applied to each value: any shape (values: rank2)", SAME_PATH),
    **EMPTY_PER_PIXEL,
}
PER_CHANNEL = {
    k: ("filters act on each channel: any channel count C (channels last)", per_value)
    for k in ("channels4", "channels1")
}
PER_CHANNEL_SAME = {
    k: ("the edge modes share the channel loop (values: mode nearest)", SAME_PATH)
    for k in ("channels4", "channels1")
}
RESAMPLE = {
    "channels4": ("resampling interpolates each channel: any channel count C", per_value),
    "channels1": ("resampling interpolates each channel (values: channels4)", SAME_PATH),
}


def _nan_like(fn, good, kind):
    """Reference for statistics of an empty pool: NaN in the shapes and dtypes of the
    outputs for the good image (traced by ``jax.eval_shape``, not compiled)."""
    out = jax.eval_shape(fn, jax.ShapeDtypeStruct(good.shape, good.dtype))
    return [np.full(v.shape, np.nan, v.dtype) for v in jax.tree_util.tree_leaves(out)]


def _abs(x):
    """``|x|`` for real inputs; other dtypes reach the function unchanged (bad-input test)."""
    return jnp.abs(x) if not jnp.iscomplexobj(x) else x


def _fdt(x):
    """The image's float dtype for parameters; float32 for the bad dtypes of the bad-input
    test (which must reach the function, not fail in the case's own parameters)."""
    return x.dtype if jnp.issubdtype(x.dtype, jnp.floating) else jnp.float32


def _bilinear(x):
    """Samples at a corner, between pixels and at the far edge (any input rank, for the
    bad-input test; coordinates in the image's float dtype, float32 for other dtypes)."""
    h, w = (tuple(x.shape[:2]) + (1, 1))[:2]
    dt = _fdt(x)
    xs = jnp.asarray([0.0, 0.3, w - 1.0], dt)
    return hp.sample_bilinear(x, xs, jnp.asarray([0.0, h / 2, h - 1.0], dt))


def _display_case(**kw):
    """An encoding for a display (:func:`hdrjax.display.encode` with ``kw``): per pixel,
    outputs in [0, 1]."""
    return Case(
        lambda x: hd.encode(x, **kw),
        ("hdrjax.display.encode",),
        batch=True,
        out_range=(0, 1),
        accepts=EMPTY_PER_PIXEL,
    )


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
    """Six square faces from an image (the cube-map inputs); an input of rank < 2 (the
    bad-input test) is stacked as it is."""
    if x.ndim < 2:
        return jnp.stack([x] * 6)
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
        lambda x: hd.DesaturateHighlights(threshold=jnp.asarray(2.0, _fdt(x))),
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
    "encode_p3": _display_case(display="Display P3"),
    "encode_pq": _display_case(display="PQ", space="ACEScg", gamut="compress"),
    "encode_pq_scene": Case(
        # the source peak is the image's largest finite value: a statistic
        lambda x: hd.encode(x, display="PQ", scene_referred=True),
        ("hdrjax.display.encode",),
        reach="stat",
        out_range=(0, 1),
    ),
    "encode_bt2020": _display_case(display="ITU-R BT.2020", space="CIE XYZ"),
    "encode_hlg": _display_case(display="HLG"),
    "gamut_map": Case(
        lambda x: hd.gamut_map(x - 0.25 * jnp.mean(x, axis=-1, keepdims=True)),
        ("hdrjax.display.gamut_map",),
        batch=True,
        out_range=(0, 1),
        accepts=EMPTY_PER_PIXEL,
    ),
    "bt2390_eetf": Case(
        lambda x: hd.bt2390_eetf(x, source_peak=4000.0),
        ("hdrjax.display.bt2390_eetf",),
        batch=True,
        accepts=ELEMENTWISE,
    ),
    "gamma_encode": Case(
        lambda x: hd.gamma_encode(jnp.maximum(x, 0)), ("hdrjax.display.gamma_encode",), batch=True
    ),
    "srgb_encode": Case(lambda x: hd.srgb_encode(x), ("hdrjax.display.srgb_encode",), batch=True),
    "srgb_decode": Case(lambda x: hd.srgb_decode(x), ("hdrjax.display.srgb_decode",), batch=True),
    "spaces.convert": Case(
        lambda x: hdrjax.spaces.convert(x, hdrjax.spaces.conversion_matrix(XYZ, "ACEScg")),
        ("hdrjax.spaces.convert",),
        batch=True,
        accepts=EMPTY_PER_PIXEL,
    ),
    "spaces.convert_to": Case(
        lambda x: hdrjax.spaces.convert_to(x, "ACEScg"),
        ("hdrjax.spaces.convert_to",),
        batch=True,
        accepts=EMPTY_PER_PIXEL,
    ),
    "spectral.spectral_to_xyz": Case(
        # the three channels as six bands of a spectrum (Sprague needs six)
        lambda x: hdrjax.spectral.spectral_to_xyz(jnp.concatenate([x, x[..., ::-1]], -1), BANDS),
        ("hdrjax.spectral.spectral_to_xyz",),
        batch=True,
        accepts=EMPTY_PER_PIXEL,
    ),
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
        lambda x: stats.percentile(hdrjax.luminance(x), jnp.asarray(_Q, _fdt(x)))[0],
        ("hdrjax.stats.percentile",),
        reach="stat",
        grad=False,
        nonfinite_ok=no_light,  # documented: NaN when no pixel is finite and positive
    ),
    "stats.percentile_exact": Case(
        lambda x: stats.percentile(hdrjax.luminance(x), jnp.asarray(_Q, _fdt(x)), method="exact")[
            0
        ],
        ("hdrjax.stats.percentile",),
        reach="stat",
        nonfinite_ok=no_light,
    ),
    # --- vision: the formulas, applied per value (luminance in cd/m²) --------------------
    **{
        f"vision.{f.__name__}": Case(
            lambda x, f=f: f(_abs(_cd(x))),
            (f"hdrjax.vision.{f.__name__}",),
            accepts=ELEMENTWISE,
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
        lambda x: hv.contrast_scale(_abs(_cd(x)), model="ward1994"),
        ("hdrjax.vision.contrast_scale",),
    ),
    "vision.ward1994_scale": Case(
        lambda x: hv.ward1994_scale(_abs(_cd(x)), 50.0), ("hdrjax.vision.ward1994_scale",)
    ),
    "vision.fechner": Case(
        # brightness of the scene, then back: the inverse pair on the same values
        lambda x: hv.fechner_luminance(hv.fechner_brightness(_abs(_cd(x)), 10.0), 10.0),
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
        lambda x: hv.Budak2005(adaptation=jnp.asarray(10.0, _fdt(x))),
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
    "panorama.equirect_to_perspective": Case(
        lambda x: hp.equirect_to_perspective(x, 6, 8, fov_deg=100.0, yaw_deg=30.0, pitch_deg=20.0),
        ("hdrjax.panorama.equirect_to_perspective",),
        reach="linear",
    ),
    "panorama.polar_to_cartesian": Case(
        lambda x: hp.polar_to_cartesian(x, 8),
        ("hdrjax.panorama.polar_to_cartesian",),
        reach="linear",
    ),
    "panorama.sample_equirect": Case(
        lambda x: hp.sample_equirect(x, jnp.asarray(_dirs(), _fdt(x))),
        ("hdrjax.panorama.sample_equirect",),
        reach="linear",
    ),
    "panorama.sample_bilinear": Case(
        _bilinear,
        ("hdrjax.panorama.sample_bilinear",),
        reach="linear",
    ),
}

# NumPy-side cases return NumPy/Python numbers (no dtype contract to check): float16 (the
# promotion) and float32 suffice
for _c in list(CASES):
    if not CASES[_c].jit and "simulate" not in _c:
        CASES[_c] = dataclasses.replace(CASES[_c], dtypes=("float16", "float32"))

# --- metrics: an image against a fixed reference (a statistic: bad pixels are left out) ------
_GREY = 47.0
"""cd/m² of the metrics' constant reference (0.47 relative): no family equals it."""


def no_finite(img):
    """No pixel is finite in all three channels (documented: NaN, no pixel to compare)."""
    return not np.all(np.isfinite(np.asarray(img, np.float64)), axis=-1).any()


CASES["metrics.pu21_encode"] = Case(
    lambda x: hm.pu21_encode(_abs(_cd(x))), ("hdrjax.metrics.pu21_encode",), accepts=ELEMENTWISE
)
for _f in (hm.pu_psnr, hm.pu_ssim, hm.log_psnr):
    CASES[f"metrics.{_f.__name__}"] = Case(
        lambda x, f=_f: f(_cd(x), jnp.full(jnp.shape(x), _GREY, _fdt(x))),
        (f"hdrjax.metrics.{_f.__name__}",),
        reach="stat",
        batch=True,
        nonfinite_ok=no_finite,
        out_range=(-1.0, 1.0) if _f is hm.pu_ssim else None,
    )
CASES["metrics.mpsnr"] = Case(
    lambda x: hm.mpsnr(_cd(x), jnp.full(jnp.shape(x), _GREY, _fdt(x))),
    ("hdrjax.metrics.mpsnr",),
    reach="stat",
    batch=True,
    nonfinite_ok=no_finite,
    grad=False,  # 8-bit renditions: piecewise constant, gradient 0 (documented)
)
CASES["metrics.delta_e_itp"] = Case(
    # against saturated red: far from every family, so that float32 rounding of ICtCp
    # (about 2e-3 ΔE_ITP, documented) stays within the jit == eager tolerance
    lambda x: hm.delta_e_itp(_cd(x), jnp.zeros(jnp.shape(x), _fdt(x)).at[..., 0].set(_GREY)),
    ("hdrjax.metrics.delta_e_itp",),
    batch=True,
    accepts=EMPTY_PER_PIXEL,
)
CASES["metrics.tmqi"] = Case(
    # the LDR image: x / (1 + |x|), display-like values; NaN/Inf pixels are set to 0
    lambda x: hm.tmqi(x, x / (1 + jnp.abs(x))),
    ("hdrjax.metrics.tmqi", "hdrjax.metrics.TMQIScore"),
    reach="stat",
    batch=True,
    out_range=(0.0, 1.0),
)
# an HDR image from a bracket, to cd/m²: by the exposure settings (a scale, per pixel) and
# by a measured illuminance (a scale from the whole map's upper hemisphere)
CASES["merge.calibrate"] = Case(
    lambda x: hmerge.calibrate(x, f_number=8.0, iso=100.0),
    ("hdrjax.merge.calibrate",),
    batch=True,
    accepts=EMPTY_PER_PIXEL,
)
CASES["merge.calibrate_illuminance"] = Case(
    lambda x: hmerge.calibrate_illuminance(x, 20000.0),
    ("hdrjax.merge.calibrate_illuminance",),
)
CASES["metrics.contrast_distortion"] = Case(
    # the rendition: x / (1 + |x|) as display values; NaN/Inf pixels are left out
    lambda x: hm.contrast_distortion(_cd(x), x / (1 + jnp.abs(x))),
    ("hdrjax.metrics.contrast_distortion",),
    reach="stat",
    batch=True,
    out_range=(0.0, float("inf")),
)

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
        (lambda e: lambda x: hv.HumanVision.build(x.shape, 30.0, (e,), dtype=_fdt(x)))(_effect),
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
    "TMQI": lambda: ht.TMQI(),
    "Naturalness": lambda: ht.Naturalness(),
}
_METRIC_TARGETS = {"TMQI": (0.0, 1.0), "Naturalness": (0.0, 1.0), "PUSSIM": (0.0, 2.0)}
"""Targets ``weight · (1 − metric)``: their residuals' range (TMQI's Q, N in [0, 1]; SSIM
in [−1, 1])."""
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
        _make = (lambda: lambda x: ht.Reference(jnp.full(x.shape, 0.5, _fdt(x))))()
    elif _name == "PUSSIM":  # a grey reference rendition in cd/m²
        _make = (lambda: lambda x: ht.PUSSIM(jnp.full(x.shape, _GREY, _fdt(x))))()
    else:
        _make = (lambda m: lambda x: m())(_TARGETS[_name])  # KeyError: add the new target
    CASES[f"targets.{_name}"] = Case(
        # targets take display images: x / (1 + |x|) puts every family in (-1, 1); x is
        # the source image of the targets that take one (TMQI)
        lambda x, mk=_make: mk(x).residuals_for(x / (1 + jnp.abs(x)), x),
        (f"hdrjax.targets.{_name}", "hdrjax.targets.AbstractTarget"),
        reach="stat",
        # documented: percentiles of the positive display luminance; an all-black display
        # has none (NaN statistics)
        nonfinite_ok=no_light if _name == "Percentiles" else None,
        out_range=_METRIC_TARGETS.get(_name),
    )


# --- tiles: hdrjax.tile.apply of every step equals the whole-image function ---------------
_TILE = (4, 4)
"""Tiles of the 8×8 family images: four tiles, each read with its step's halo."""
_REINHARD = hdrjax.operators.Reinhard2002()


def _reinhard(x):
    """The whole-image reference, compiled once (``hdrjax.tonemap`` is jit-compiled)."""
    return hdrjax.tonemap(x, "reinhard2002")


_measure = jax.jit(lambda x: stats.measure(hdrjax.luminance(x)))
_measure_plane = jax.jit(stats.measure)
TILE_STEPS: dict[str, tuple[Callable, Callable, str, float]] = {
    # name: (step, whole-image function, reach, rtol); the filters are bit-identical
    "Mean": (lambda: htile.Mean(3), lambda x: hf.mean_filter(x, 3), "linear", 0.0),
    "Median": (lambda: htile.Median(3), lambda x: hf.median_filter(x, 3), "window", 0.0),
    "Neighbourhood": (
        lambda: htile.Neighbourhood(lambda w: hf.mean_filter(w, 3, mode="reflect"), 1),
        lambda x: hf.mean_filter(x, 3, mode="reflect"),
        "linear",
        0.0,
    ),
    # the key and log-average from the tiled first pass: equal to float32 rounding
    "Tonemap": (lambda: htile.Tonemap(_REINHARD), _reinhard, "pixel", 1e-5),
    # a truncated PSF (halo 1 pixel at 3.75°/pixel): another FFT size per window
    "Glare": (
        lambda: htile.Glare(30.0, radius_deg=1.5),
        lambda x: hv.glare(x, 30.0, radius_deg=1.5),
        "pixel",
        1e-5,
    ),
}
_missing_steps = sorted(
    n
    for n in htile.__all__
    if inspect.isclass(getattr(htile, n))
    and issubclass(getattr(htile, n), htile.AbstractStep)
    and not inspect.isabstract(getattr(htile, n))
    and n not in TILE_STEPS
    and n != "AbstractStep"
)
assert not _missing_steps, f"new tile steps need an entry in TILE_STEPS: {_missing_steps}"
for _name, (_step, _whole, _reach, _rtol) in TILE_STEPS.items():
    CASES[f"tile.apply[{_name}]"] = Case(
        (lambda st: lambda x: htile.apply(st(), np.asarray(x), tile=_TILE))(_step),
        ("hdrjax.tile.apply", f"hdrjax.tile.{_name}", "hdrjax.tile.AbstractStep"),
        reach=_reach,
        size=3,
        jit=False,  # NumPy side: windows are copied out of (memory-mapped) arrays
        grad=False,
        dtypes=("float32",),  # the steps' dtypes: their whole-image cases
        equals=(_whole, _rtol, 1e-6),
    )
CASES["tile.statistics"] = Case(
    lambda x: htile.statistics(np.asarray(x), tile=_TILE),
    ("hdrjax.tile.statistics",),
    reach="stat",
    jit=False,
    grad=False,
    dtypes=("float32",),
    equals=(_measure, 1e-5, 1e-6),
)

# --- chunks: the pixels of any image in fixed-shape chunks equal the whole-image operator ---
_CHUNK = (3, 5)
"""Chunks of 15 pixels: the 8×8 family images in five chunks, the last one padded."""
CASES["tile.tonemap_chunked"] = Case(
    lambda x: htile.tonemap_chunked(_REINHARD, np.asarray(x), chunk=_CHUNK)[1],
    (
        "hdrjax.tile.tonemap_chunked",
        "hdrjax.tile.measure_chunked",
        "hdrjax.tile.statistics_chunked",
        "hdrjax.tile.map_chunked",
        "hdrjax.tile.bind_compiled",
        "hdrjax.tile.chunkable",
    ),
    jit=False,  # NumPy side: chunks are copied out of the image
    grad=False,  # the operator's gradients are its own cases
    equals=(_reinhard, 2e-5, 1e-6),
)

# --- batch: the frame pipeline on arrays equals the operator ---------------------------------
_PIPELINE = hb.Pipeline("reinhard2002", format="exr")  # float32 linear output, no encoding
CASES["batch.render_batch"] = Case(
    lambda x: hb.render_batch(_PIPELINE, None, x[None])[0],
    ("hdrjax.batch.render_batch", "hdrjax.batch.Pipeline"),
    jit=False,  # compiled by itself (filter_jit) and takes the batch axis itself
    grad=False,  # a file pipeline (its operator's gradients: tests/operators)
    dtypes=("float32",),  # writes float32 files whatever the input (documented)
    equals=(_reinhard, 1e-6, 1e-7),
)


# --- time-dependent adaptation: three frames (the image, half and a quarter as bright) -----
def _pattanaik_sequence(x):
    x = _cd(x)
    frames = jnp.stack([x, x * 0.5, x * 0.25])
    out = hdrjax.operators.pattanaik2000_sequence(frames, fps=16.0)[0]
    return jnp.moveaxis(out, 0, -2)  # (H, W, frame, channel): per-pixel, as the checks read


CASES["operators.pattanaik2000_sequence"] = Case(
    _pattanaik_sequence,
    ("hdrjax.operators.pattanaik2000_sequence", "hdrjax.operators.AdaptationState"),
)


def _vanhateren_sequence(x):
    x = _cd(x)
    frames = jnp.stack([x, x * 0.5, x * 0.25])
    out = hdrjax.operators.vanhateren2006_sequence(frames, fps=16.0, max_step=4.0)[0]
    return jnp.moveaxis(out, 0, -2)  # (H, W, frame, channel): per-pixel, as the checks read


CASES["operators.vanhateren2006_sequence"] = Case(
    _vanhateren_sequence,
    (
        "hdrjax.operators.vanhateren2006_sequence",
        "hdrjax.operators.ConeState",
        "hdrjax.operators.AbstractTimeDependentOperator",
        "hdrjax.operators.time_dependent_names",
    ),
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


# --- bad input: accepted forms and out-of-range parameters (test_bad_input.py) ---------------
_ELEMENTWISE_CASES = [
    "encode_srgb",
    "encode_gamma",
    "gamma_encode",
    "srgb_encode",
    "srgb_decode",
    "quantize",
    "vision.contrast_scale_ward1994",
    "vision.ward1994_scale",
    "vision.fechner",
] + [n for n in CASES if CASES[n].accepts is ELEMENTWISE]
_PARAMS: dict[str, tuple[tuple[str, Callable], ...]] = {
    "luminance": (("weights", lambda x: hdrjax.luminance(x, weights=(1.0, 2.0))),),
    "desaturate_highlights": (
        ("threshold", lambda x: hdrjax.desaturate_highlights(x, -1.0)),
        ("method", lambda x: hdrjax.desaturate_highlights(x, method="median")),
        ("bins", lambda x: hdrjax.desaturate_highlights(x, bins=0)),
    ),
    "DesaturateHighlights": (("bins", lambda x: hd.DesaturateHighlights(bins=0)(x)),),
    "highlight_threshold": (
        ("bins", lambda x: hd.highlight_threshold(x, bins=1)),
        ("weights", lambda x: hd.highlight_threshold(x, weights=(0.3, 0.7))),
    ),
    "encode_srgb": (("transfer", lambda x: hd.encode(x, "pq")),),
    "encode_gamma": (("gamma", lambda x: hd.encode(x, "gamma", gamma=0.0)),),
    "gamma_encode": (("gamma", lambda x: hd.gamma_encode(x, -2.2)),),
    "quantize": (("bits", lambda x: hd.quantize(np.clip(x, 0, 1), 12)),),
    "stats.measure": (
        ("bins", lambda x: stats.measure(hdrjax.luminance(x), bins=0)),
        ("method", lambda x: stats.measure(hdrjax.luminance(x), method="median")),
        ("delta", lambda x: stats.measure(hdrjax.luminance(x), delta=-1e-6)),
    ),
    "stats.percentile": (
        ("q", lambda x: stats.percentile(hdrjax.luminance(x), 150.0)),
        ("q", lambda x: stats.percentile(hdrjax.luminance(x), jnp.asarray([-1.0, 50.0]))),
        ("bins", lambda x: stats.percentile(hdrjax.luminance(x), 50.0, bins=0)),
    ),
    "vision.contrast_scale": (("model", lambda x: hv.contrast_scale(x, model="ward")),),
    "vision.contrast": (
        ("display_max", lambda x: hv.contrast(_cd(x), 10.0, display_max=-1.0)),
        ("model", lambda x: hv.contrast(_cd(x), 10.0, model="ward")),
    ),
    # a view given as a number is its horizontal field of view: the message names view
    "vision.sample_spacing": (("view", lambda x: hv.sample_spacing(_cd(x), -0.5)),),
    "vision.acuity_loss": (
        ("view", lambda x: hv.acuity_loss(_cd(x), 0.0)),
        ("levels", lambda x: hv.acuity_loss(_cd(x), 30.0, levels=-1)),
    ),
    "vision.glare": (
        ("view", lambda x: hv.glare(_cd(x), -30.0)),
        ("radius_deg", lambda x: hv.glare(_cd(x), 30.0, radius_deg=-1.0)),
        ("variant", lambda x: hv.glare(_cd(x), 30.0, variant="daylight")),
    ),
    "vision.veil": (("view", lambda x: hv.veil(_cd(x), -30.0)),),
    "vision.perceptual_reproduction": (
        ("display_max", lambda x: hv.perceptual_reproduction(_cd(x), display_max=-1.0)),
        ("gamma", lambda x: hv.perceptual_reproduction(_cd(x), gamma=0.0)),
    ),
    "vision.Budak2005": (("display_max", lambda x: hv.Budak2005(display_max=0.0)(_cd(x))),),
    "vision.analyze": (("scale", lambda x: hv.analyze(np.asarray(x), scale=-1.0)),),
    "lights.display_image": (("method", lambda x: hl.display_image(np.asarray(x), "nope")),),
    "lights.cubemap_equirect": (("height", lambda x: hl.cubemap_equirect(_cube(x), height=0)),),
    "lights.detect": (
        ("width", lambda x: hl.detect(x, width=0)),
        ("max_lights", lambda x: hl.detect(x, width=16, max_lights=0)),
    ),
    "lights.detect_image": (("width", lambda x: hl.detect_image(x, width=-16)),),
    "lights.detect_cubemap": (
        ("height", lambda x: hl.detect_cubemap(_cube(x), height=0, width=16)),
    ),
    "lights.median_cut": (
        ("n_lights", lambda x: hl.median_cut(x, n_lights=0, width=16)),
        ("width", lambda x: hl.median_cut(x, n_lights=4, width=0)),
    ),
    "panorama.equirect_to_cubemap": (("size", lambda x: hp.equirect_to_cubemap(x, 0)),),
    "panorama.cubemap_to_equirect": (("height", lambda x: hp.cubemap_to_equirect(_cube(x), 0)),),
    "panorama.equirect_to_fisheye": (
        ("size", lambda x: hp.equirect_to_fisheye(x, -8)),
        ("fov_deg", lambda x: hp.equirect_to_fisheye(x, 8, fov_deg=0.0)),
    ),
    "panorama.fisheye_to_equirect": (
        ("height", lambda x: hp.fisheye_to_equirect(x, 0)),
        ("fov_deg", lambda x: hp.fisheye_to_equirect(x, 8, fov_deg=-180.0)),
    ),
    "panorama.equirect_to_perspective": (
        ("height", lambda x: hp.equirect_to_perspective(x, 0, 8)),
        ("fov_deg", lambda x: hp.equirect_to_perspective(x, 6, 8, fov_deg=180.0)),
        ("yaw_deg", lambda x: hp.equirect_to_perspective(x, 6, 8, yaw_deg=float("inf"))),
    ),
    "panorama.polar_to_cartesian": (
        ("size", lambda x: hp.polar_to_cartesian(x, 0)),
        ("theta_max_deg", lambda x: hp.polar_to_cartesian(x, 8, theta_max_deg=0.0)),
    ),
    "panorama.sample_equirect": (("d", lambda x: hp.sample_equirect(x, jnp.ones((4, 2)))),),
    "estimate.log_average": (("delta", lambda x: hdrjax.estimate.log_average(x, delta=-1.0)),),
    "estimate.jgt_white": (("key", lambda x: hdrjax.estimate.jgt_white(x, key=-0.18)),),
    "estimate.jgt_key": (("bins", lambda x: hdrjax.estimate.jgt_key(x, bins=-1)),),
    "estimate.adaptation_luminance": (
        ("bins", lambda x: hdrjax.estimate.adaptation_luminance(x, bins=0)),
    ),
    "estimate.desaturation_threshold": (
        ("method", lambda x: hdrjax.estimate.desaturation_threshold(x, method="median")),
    ),
    "targets.Percentiles": (
        ("q", lambda x: ht.Percentiles([10.0, 50.0], [0.5]).residuals(x)),
        ("q", lambda x: ht.Percentiles([50.0, 150.0], [0.5, 0.9]).residuals(x)),
    ),
    "targets.ClippedFraction": (
        ("value", lambda x: ht.ClippedFraction(1.5).residuals(x)),
        ("softness", lambda x: ht.ClippedFraction(0.01, softness=0.0).residuals(x)),
    ),
    "targets.MeanLuminance": (("value", lambda x: ht.MeanLuminance(-0.2).residuals(x)),),
    "targets.Reference": (("space", lambda x: ht.Reference(x, space="rgb").residuals(x)),),
    "targets.TMQI": (
        ("source", lambda x: ht.TMQI().residuals(x)),
        ("gamma", lambda x: ht.TMQI(gamma=0.0).residuals(x, source=x)),
    ),
    "targets.Naturalness": (("gamma", lambda x: ht.Naturalness(gamma=-2.2).residuals(x)),),
    "targets.PUSSIM": (
        ("black", lambda x: ht.PUSSIM(x, black=200.0).residuals(x)),
        ("params", lambda x: ht.PUSSIM(x, params="pu08").residuals(x)),
        ("display", lambda x: ht.PUSSIM(x[:-1]).residuals(x)),
    ),
}
_PARAMS["metrics.pu21_encode"] = (("params", lambda x: hm.pu21_encode(x, params="pu08")),)
_PARAMS["metrics.pu_psnr"] = (("params", lambda x: hm.pu_psnr(x, x, params="pu08")),)
_PARAMS["metrics.pu_ssim"] = (("params", lambda x: hm.pu_ssim(x, x, params="PU21")),)
_PARAMS["metrics.log_psnr"] = (("floor", lambda x: hm.log_psnr(x, x, floor=-1e-5)),)
_PARAMS["metrics.mpsnr"] = (("span", lambda x: hm.mpsnr(x, x, span=0)),)
_PARAMS["metrics.tmqi"] = (("ldr", lambda x: hm.tmqi(x, x[..., :-1, :])),)
_PARAMS["metrics.delta_e_itp"] = (("b", lambda x: hm.delta_e_itp(x, x[:1])),)
_PARAMS["metrics.contrast_distortion"] = (
    ("ldr", lambda x: hm.contrast_distortion(x, x[..., :-1, :])),
    ("display", lambda x: hm.contrast_distortion(x, x, display="oled")),
    ("visual_model", lambda x: hm.contrast_distortion(x, x, visual_model="csf,masking")),
)
for _n in CASES:
    if _n.startswith("filters."):
        f = hf.mean_filter if "mean" in _n else hf.median_filter
        _PARAMS[_n] = (
            ("size", lambda x, f=f: f(x, -1)),
            ("size", lambda x, f=f: f(x, 4)),
            ("mode", lambda x, f=f: f(x, 3, mode="constant")),
        )
        if "median" in _n:
            _PARAMS[_n] += (("criterion", lambda x: hf.median_filter(x, 3, criterion="rank")),)
    elif _n.startswith("vision.HumanVision["):
        _PARAMS[_n] = (
            ("view", lambda x: hv.HumanVision.build(x.shape, -30.0, ("glare",))),
            ("effects", lambda x: hv.HumanVision.build(x.shape, 30.0, ("glow",))),
        )
    elif _n.startswith("vision.simulate["):
        _PARAMS[_n] = (
            ("scale", lambda x: hv.simulate(np.asarray(x), 30.0, {"glare"}, scale=-1.0)),
        )

_ACCEPTS: dict[str, Mapping[str, tuple[str, Callable]]] = {
    **{n: ELEMENTWISE for n in _ELEMENTWISE_CASES},
    **{n: RESAMPLE for n in CASES if n.startswith("panorama.")},
    # per-pixel functions of (..., 3) (their adaptation given, not measured): empty in,
    # empty out; every other image function rejects an empty H or W
    **{
        n: EMPTY_PER_PIXEL
        for n in (
            "luminance",
            "vision.scotopic_luminance",
            "vision.blue_shift",
            "vision.colour_loss",
            "vision.contrast",
        )
    },
    # percentiles of a pooled set: an empty pool has no value that qualifies (documented NaN)
    **{
        n: {
            k: (
                "percentiles of no value are NaN, as documented for no qualifying pixel",
                _nan_like,
            )
            for k in EMPTY_FORMS
        }
        for n in ("stats.percentile", "stats.percentile_exact")
    },
}
for _n in CASES:
    if _n in ("filters.mean_filter[nearest]", "filters.median_filter[channels,nearest]"):
        _ACCEPTS[_n] = PER_CHANNEL
    elif _n.startswith("filters.mean_filter"):
        _ACCEPTS[_n] = PER_CHANNEL_SAME
    elif _n == "filters.median_filter[luminance,nearest]":
        _ACCEPTS[_n] = {"channels1": ("one channel is its own luminance", grey)}
    elif _n.startswith("filters.median_filter[luminance"):
        _ACCEPTS[_n] = {
            "channels1": ("one channel is its own luminance (values: nearest)", SAME_PATH)
        }
    elif _n.startswith("filters.median_filter[vector"):
        _ACCEPTS[_n] = {
            "channels1": ("the vector median of one channel is its median", grey),
            "channels4": (
                "the vector median takes any channel count",
                lambda fn, good, kind: [vector_median_nearest(BAD_INPUTS[kind](good))],
            ),
        }
for _n in CASES:
    if _n.startswith("tile.apply["):
        _step = TILE_STEPS[_n[len("tile.apply[") : -1]][0]
        _PARAMS[_n] = (("tile", lambda x, st=_step: htile.apply(st(), np.asarray(x), tile=0)),)
_PARAMS["tile.statistics"] = (("tile", lambda x: htile.statistics(np.asarray(x), tile=-4)),)
_PARAMS["tile.tonemap_chunked"] = (
    ("chunk", lambda x: htile.tonemap_chunked(_REINHARD, np.asarray(x), chunk=(0, 4))),
    ("op", lambda x: htile.tonemap_chunked(hdrjax.operators.Reinhard2002Local(), np.asarray(x))),
)
_ACCEPTS["tile.apply[Mean]"] = PER_CHANNEL
_ACCEPTS["tile.apply[Neighbourhood]"] = PER_CHANNEL
_ACCEPTS["tile.apply[Median]"] = {"channels1": ("one channel is its own luminance", grey)}
_ACCEPTS["tile.statistics"] = {
    k: (
        "statistics of a luminance image (H, W) or (H, W, 1), as documented",
        lambda fn, good, kind: _float_leaves(
            _measure_plane(np.reshape(BAD_INPUTS[kind](good), good.shape[:2]))
        ),
    )
    for k in ("rank2", "channels1")
}
_unknown = sorted(set(_PARAMS) - set(CASES)) + sorted(set(_ACCEPTS) - set(CASES))
assert not _unknown, f"bad-input entries for cases that do not exist: {_unknown}"
for _n, _p in _PARAMS.items():
    CASES[_n] = dataclasses.replace(CASES[_n], params=_p)
for _n, _a in _ACCEPTS.items():
    CASES[_n] = dataclasses.replace(CASES[_n], accepts=_a)
