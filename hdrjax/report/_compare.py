"""Compare tone-mapping operators on one image: metrics, times and parameters per operator.

For each operator, the rendition ``encode(op(image), "srgb")`` (display-encoded sRGB in
[0, 1], not quantised) is scored with:

- **TMQI** ``Q`` and its parts, structural fidelity ``S`` and statistical naturalness
  ``N`` (Yeganeh & Wang 2013, :func:`hdrjax.metrics.tmqi`) against the HDR image;
- **PU-SSIM** (Mantiuk & Azimi 2021, :func:`hdrjax.metrics.pu_ssim`) against a reference
  *rendition*, when one is given: a display-encoded sRGB image of the same scene (an
  expert's grading, a camera's JPEG, another operator's output). Both renditions are
  taken to absolute luminance on one display model, ``L = L_black + (L_peak − L_black)
  · srgb_decode(v)`` cd/m² (``peak`` 100 cd/m², ``black`` 0.1 cd/m² by default: an SDR
  display of contrast 1000:1), and compared after PU21 encoding. The HDR image itself is
  not a reference for PU-SSIM: its luminances are the scene's, not a display's (TMQI's
  ``S`` is the metric that compares against it);
- **clipped** fraction: pixels with a channel encoded to 0 although that channel of the
  image is positive (``op`` output ≤ 0: ``clipped_black``; a channel black in the scene
  loses nothing) or encoded to 1 (output ≥ 1: ``clipped_white``), among the pixels that
  are finite in the image and the output;
- **mean display luminance**: the mean Rec. 709 luminance of the clipped linear output, in
  [0, 1] (a fraction of display white; :class:`hdrjax.targets.MeanLuminance`'s statistic).

Times (seconds, on the device JAX runs on): ``compile_s`` is the time to trace and compile
the operator, parameter estimation included, for this image's shape and dtype
(ahead-of-time, ``jax.jit(...).lower(...).compile()``), measured the first time this
process compiles that program; later comparisons reuse the program and report that same
measurement. ``warm_s`` is the median of ``repeats`` runs of the compiled program after one
untimed run. Neither includes reading the file, encoding or the metrics. With a fit,
``fit_s`` is the wall time of :func:`hdrjax.fit.fit`, its compilation included, and the
operator timed is the fitted one (its parameters all set: no estimation left).
"""

import collections
import dataclasses
import json
import os
import statistics
import time
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike, Float

from .. import _check
from .._colour import REC709_WEIGHTS, luminance
from ..display import encode, quantize, srgb_decode
from ..metrics import pu_ssim, tmqi
from ..operators import get_operator, make_operator, operator_names, parameter_info
from ._columns import COLUMNS
from ._html import render_fragment, render_page

DEFAULT_METHODS = ("reinhard2002", "reinhard2005", "drago2003", "mai2011", "durand2002", "agx")
"""What :func:`compare` runs when no methods are given: global (Reinhard et al. 2002,
Reinhard & Devlin 2005, Drago et al. 2003, Mai et al. 2011), local (Durand & Dorsey 2002)
and a view transform (AgX)."""
FIT_TARGETS = ("tmqi",)
"""The targets ``compare(..., fit=...)`` maximises (see :func:`fit_target`)."""
REFERENCE_PEAK = 100.0
"""cd/m² of display white for PU-SSIM's display model (an SDR display)."""
REFERENCE_BLACK = 0.1
"""cd/m² of display black for PU-SSIM's display model (contrast 1000:1)."""
PARAMETER_SETTINGS = ("weights", "chromaticities")
"""Fields left out of a row's parameters: the image's primaries, not the operator's."""
_COMPILED_MAX = 64
"""Compiled operator programs kept for reuse (an LRU)."""


_COLUMN = {c.key: c for c in COLUMNS}


@dataclasses.dataclass(frozen=True)
class ComparisonRow:
    """One operator's rendition, scored (see the module docstring for each value).

    ``operator`` (the operator with every parameter set, as it rendered) and ``rendition``
    (the 8-bit sRGB image, ``(H, W, 3)`` uint8) are kept for inspection and the HTML page;
    they are not part of :meth:`to_dict`.
    """

    method: str
    q: float | None
    s: float | None
    n: float | None
    pu_ssim: float | None
    clipped: float | None
    clipped_black: float | None
    clipped_white: float | None
    mean_luminance: float | None
    compile_s: float | None
    warm_s: float | None
    fit_s: float | None
    fit_success: bool | None
    params: dict[str, Any]
    """Every parameter's value, estimated, fitted or given (JSON values)."""
    estimated: tuple[str, ...]
    """Parameters estimated from the image."""
    fitted: tuple[str, ...]
    """Parameters fitted to the target."""
    operator: Any = dataclasses.field(default=None, repr=False, compare=False)
    rendition: np.ndarray | None = dataclasses.field(default=None, repr=False, compare=False)

    def to_dict(self) -> dict[str, Any]:
        """The row as JSON values (non-finite numbers as ``None``)."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            if f.name in ("operator", "rendition"):
                continue
            v = getattr(self, f.name)
            if isinstance(v, tuple):
                v = list(v)
            elif isinstance(v, float) and not np.isfinite(v):
                v = None
            out[f.name] = v
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "ComparisonRow":
        """A row from :meth:`to_dict`'s values (without operator and rendition)."""
        names = [f.name for f in dataclasses.fields(cls) if f.name not in ("operator", "rendition")]
        missing = [n for n in names if n not in d]
        if missing:
            raise ValueError(f"row: missing {', '.join(missing)}")
        kw = {n: d[n] for n in names}
        kw["estimated"] = tuple(kw["estimated"])
        kw["fitted"] = tuple(kw["fitted"])
        kw["params"] = dict(kw["params"])
        return cls(**kw)


@dataclasses.dataclass(frozen=True)
class ComparisonTable:
    """The result of :func:`compare`: one :class:`ComparisonRow` per operator.

    Rows come sorted by TMQI ``Q``, best first (:meth:`sorted` for another column). Index by
    position or by method name; :meth:`to_dicts`/:meth:`to_json` for the numbers,
    :meth:`to_html` for the page (thumbnails, full images on click, sortable columns), and
    in a notebook the table shows itself (thumbnails only).

    Attributes:
        rows: the rows, in the table's order.
        source: the image's file name, or ``None`` for an array.
        shape: ``(H, W)`` of the image the operators ran on (after ``max_size``).
        reference: the reference rendition's file name, ``"array"``, or ``None``.
        peak, black: the display model of PU-SSIM (cd/m²).
        fit: the fit target's name, or ``None``.
        device: the device the times were measured on.
        skipped: operators left out, with the reason (``compare(all=True)``).
    """

    rows: tuple[ComparisonRow, ...]
    source: str | None = None
    shape: tuple[int, int] = (0, 0)
    reference: str | None = None
    peak: float = REFERENCE_PEAK
    black: float = REFERENCE_BLACK
    fit: str | None = None
    device: str = ""
    skipped: dict[str, str] = dataclasses.field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self) -> Iterator[ComparisonRow]:
        return iter(self.rows)

    def __getitem__(self, key: int | str) -> ComparisonRow:
        if isinstance(key, str):
            for row in self.rows:
                if row.method == key:
                    return row
            raise KeyError(f"{key!r}: not in the table; methods: {', '.join(self.methods)}")
        return self.rows[key]

    @property
    def methods(self) -> tuple[str, ...]:
        """The methods, in the table's order."""
        return tuple(r.method for r in self.rows)

    def sorted(self, by: str = "q", descending: bool | None = None) -> "ComparisonTable":
        """The table sorted by a column (``"method"`` or a :data:`COLUMNS` key).

        ``descending``: ``None`` puts the better end first (high ``Q``, ``S``, ``N``,
        PU-SSIM; low clipping and times; mean luminance ascending). Rows without a value
        (no reference, no fit) come last either way; ties keep method-name order.
        """
        if by != "method" and by not in _COLUMN:
            raise ValueError(f"by: expected one of {', '.join(['method', *_COLUMN])}, got {by!r}")
        if descending is None:
            descending = by != "method" and bool(_COLUMN[by].higher_is_better)
        rows = sorted(self.rows, key=lambda r: r.method)
        present = [r for r in rows if getattr(r, by) is not None]
        absent = [r for r in rows if getattr(r, by) is None]
        present.sort(key=lambda r: getattr(r, by), reverse=descending)
        return dataclasses.replace(self, rows=tuple(present + absent))

    def best(self, by: str = "q") -> ComparisonRow:
        """The row at the better end of a column (highest ``Q`` by default)."""
        return self.sorted(by).rows[0]

    def to_dicts(self) -> list[dict[str, Any]]:
        """The rows as JSON values, in the table's order."""
        return [r.to_dict() for r in self.rows]

    def to_dict(self) -> dict[str, Any]:
        """The table as JSON values: its settings and ``rows``."""
        return {
            "source": self.source,
            "shape": list(self.shape),
            "reference": self.reference,
            "peak": self.peak,
            "black": self.black,
            "fit": self.fit,
            "device": self.device,
            "skipped": dict(self.skipped),
            "rows": self.to_dicts(),
        }

    def to_json(self, indent: int | None = 2) -> str:
        """:meth:`to_dict` as JSON text (strict: no NaN)."""
        return json.dumps(self.to_dict(), indent=indent, allow_nan=False)

    @classmethod
    def from_json(cls, text: str) -> "ComparisonTable":
        """A table from :meth:`to_json`'s text (rows without operators and renditions)."""
        d = json.loads(text)
        return cls(
            rows=tuple(ComparisonRow.from_dict(r) for r in d["rows"]),
            source=d["source"],
            shape=tuple(d["shape"]),  # type: ignore[arg-type]
            reference=d["reference"],
            peak=d["peak"],
            black=d["black"],
            fit=d["fit"],
            device=d["device"],
            skipped=dict(d["skipped"]),
        )

    def to_html(self, *, title: str | None = None, full_images: bool = True) -> str:
        """A self-contained HTML page: thumbnails (the full rendition on click, inlined as
        base64 JPEG with ``full_images``), the metrics, times and parameters, sortable by
        clicking a column heading. No external resources."""
        return render_page(self, title=title, full_images=full_images)

    def _repr_html_(self) -> str:
        return render_fragment(self)

    def figure(self, *, columns: int | None = None, width: float = 12.0):
        """A contact sheet of the renditions in the table's order: a matplotlib
        :class:`~matplotlib.figure.Figure` (no pyplot state), each panel captioned with its
        rank, method, TMQI ``Q`` (``S``, ``N``), PU-SSIM when there is a reference, clipped
        pixels and warm time. ``columns``: panels per row (default: up to 4); ``width`` in
        inches. Raises ``ValueError`` for a table without renditions (read from JSON)."""
        from matplotlib.figure import Figure

        if not self.rows or any(r.rendition is None for r in self.rows):
            raise ValueError(
                "figure: the table has no renditions (a table read from JSON keeps only "
                "the numbers)"
            )
        n = len(self.rows)
        cols = max(1, min(columns or 4, n))
        if columns is not None and columns < 1:
            raise ValueError(f"columns: expected a positive integer, got {columns}")
        rows = -(-n // cols)
        h, w = self.rows[0].rendition.shape[:2]
        panel = width / cols
        fig = Figure(figsize=(width, rows * (panel * h / w + 0.75)), layout="constrained")
        axes = fig.subplots(rows, cols, squeeze=False)
        for k, ax in enumerate(axes.flat):
            ax.set_axis_off()
            if k >= n:
                continue
            r = self.rows[k]
            ax.imshow(r.rendition, interpolation="lanczos")
            lines = [f"{k + 1}. {r.method}"]
            if r.q is not None:
                lines.append(f"Q {r.q:.3f} (S {r.s:.3f}, N {r.n:.3f})")
            extra = [] if r.pu_ssim is None else [f"PU-SSIM {r.pu_ssim:.3f}"]
            if r.clipped is not None:
                extra.append(f"clipped {100 * r.clipped:.1f} %")
            if r.warm_s is not None:
                extra.append(f"{1e3 * r.warm_s:.3g} ms")
            if extra:
                lines.append(" · ".join(extra))
            ax.set_title("\n".join(lines), fontsize=9, loc="left")
        title = self.source or "image"
        fit = f", fitted to maximise {self.fit}" if self.fit else ""
        fig.suptitle(f"{title} ({self.shape[1]}×{self.shape[0]}){fit}", fontsize=11)
        return fig


def fit_target(name: str):
    """The :mod:`hdrjax.targets` target that ``compare(..., fit=name)`` maximises.

    ``"tmqi"``: ``hdrjax.targets.TMQI()`` (Yeganeh & Wang 2013's quality index). Raises a
    one-line ``ValueError`` for an unknown name, or when this hdrjax has no such target.
    """
    _check.one_of(name, "fit", FIT_TARGETS)
    from .. import targets

    target = getattr(targets, "TMQI", None)
    if target is None:
        raise ValueError(
            "fit: 'tmqi' needs hdrjax.targets.TMQI, which this installation of hdrjax does not have"
        )
    return target()


def compare(
    image: Float[ArrayLike, "H W 3"] | str | os.PathLike,
    methods: Sequence[str] | str | None = None,
    *,
    all: bool = False,  # noqa: A002 (the command line's --all)
    fit: str | None = None,
    params: Mapping[str, Mapping[str, Any]] | None = None,
    reference: ArrayLike | str | os.PathLike | None = None,
    peak: float = REFERENCE_PEAK,
    black: float = REFERENCE_BLACK,
    scale: float = 1.0,
    max_size: int | None = None,
    repeats: int = 5,
) -> ComparisonTable:
    """Run several tone-mapping operators on one image and score each rendition.

    Args:
        image: linear RGB ``(H, W, 3)`` (relative or cd/m², see ``scale``), a
            :class:`hdrjax.layers.LayeredImage`, or the path of an HDR file (.exr, .hdr,
            .pfm; converted to linear sRGB primaries, luminance with the file's own
            weights).
        methods: operator names (a sequence, or one comma-separated string); ``None``:
            :data:`DEFAULT_METHODS`.
        all: every registered operator instead (those that need a parameter which cannot
            be estimated, such as ``tabulated``'s table, are listed in ``skipped``; so is
            an operator that fails on this image).
        fit: ``"tmqi"``: fit each operator's default fit parameters
            (``hdrjax operators NAME`` lists them) to maximise TMQI before scoring
            (:func:`fit_target`); operators without any are scored as they are.
        params: given parameters per method, ``{"reinhard2002": {"key": 0.09}}``; those
            left out are estimated from the image (or fitted).
        reference: a reference rendition for PU-SSIM: display-encoded sRGB in [0, 1]
            ``(H, W, 3)`` of the image's shape, or the path of a PNG/JPEG/TIFF of it.
        peak, black: cd/m² of white and black of the display model that takes both
            renditions to luminance for PU-SSIM.
        scale: multiply the image by this first (to cd/m² for operators of absolute
            luminance).
        max_size: box-filter the image (and the reference) down to at most this many
            pixels on its long side first (:func:`hdrjax.fit.downscale`); ``None``: as is.
        repeats: timed runs per operator (the median is reported).

    Returns:
        A :class:`ComparisonTable`, sorted by TMQI ``Q``, best first.

    Raises:
        ValueError: an unknown method, parameter or fit target (one line naming it), an
            image that is not ``(H, W, 3)``, a reference of another shape, an unreadable
            file.

    References: H. Yeganeh and Z. Wang, IEEE TIP 22(2):657–667, 2013,
    https://doi.org/10.1109/TIP.2012.2221725 (TMQI); R. K. Mantiuk and M. Azimi, PCS 2021,
    https://doi.org/10.1109/PCS50896.2021.9477471 (PU21).
    """
    names, skipped = _methods(methods, all)
    given = _given_params(params, names)
    target = fit_target(fit) if fit is not None else None
    _check.positive(scale, "scale")
    _check.positive(peak, "peak")
    _check.positive(black, "black", zero=True)
    if not black < peak:
        raise ValueError(f"black: expected less than peak ({peak:g} cd/m²), got {black!r}")
    repeats = _check.integer(repeats, "repeats")
    if max_size is not None:
        max_size = _check.integer(max_size, "max_size")
    source, rgb, weights = _load_image(image)
    ref_label, ref = _load_reference(reference, rgb.shape)
    if scale != 1.0:
        rgb = rgb * np.float32(scale)
    if max_size is not None:
        from ..fit import downscale

        rgb = np.asarray(downscale(jnp.asarray(rgb), max_size))
        if ref is not None:  # averaged as light, like the image
            ref = np.asarray(downscale(jnp.asarray(ref), max_size))
    ref_luminance = None if ref is None else black + (peak - black) * ref
    hdr = jnp.asarray(rgb)
    rows = []
    for name in names:
        try:
            rows.append(_row(name, given.get(name, {}), hdr, weights, target, ref_luminance,
                             peak, black, repeats))  # fmt: skip
        except Exception as e:  # noqa: BLE001 (one operator failing leaves the others)
            if not all:
                raise ValueError(f"{name}: {_one_line(e)}") from e
            skipped[name] = _one_line(e)
    dev = jax.devices()[0]
    table = ComparisonTable(
        rows=tuple(rows),
        source=source,
        shape=(int(rgb.shape[0]), int(rgb.shape[1])),
        reference=ref_label,
        peak=float(peak),
        black=float(black),
        fit=fit,
        device=f"{dev.platform}: {dev.device_kind}"
        + (f", {os.cpu_count()} cores" if dev.platform == "cpu" else ""),
        skipped=skipped,
    )
    return table.sorted("q")


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split()) or type(e).__name__


def _methods(methods: Sequence[str] | str | None, every: bool) -> tuple[list[str], dict]:
    """Canonical operator names, in order, without repeats; and those ``all`` skips."""
    skipped: dict[str, str] = {}
    if every:
        if methods is not None:
            raise ValueError("methods: give methods or all=True, not both")
        names = []
        for name in operator_names():
            need = [i.name for i in parameter_info(get_operator(name)) if i.required]
            if need:
                skipped[name] = f"needs {', '.join(need)} (not estimated from an image)"
            else:
                names.append(name)
        return names, skipped
    if methods is None:
        methods = DEFAULT_METHODS
    if isinstance(methods, str):
        methods = [m for m in (p.strip() for p in methods.split(",")) if m]
    if not methods:
        raise ValueError("methods: expected at least one operator name, got none")
    names = []
    for m in methods:
        if not isinstance(m, str):
            raise ValueError(f"methods: expected operator names, got {m!r}")
        name = get_operator(m).name  # ValueError naming the method and the valid ones
        if name not in names:
            names.append(name)
    return names, skipped


def _given_params(params: Mapping[str, Mapping[str, Any]] | None, names: list[str]) -> dict:
    out: dict[str, dict[str, Any]] = {}
    for key, values in (params or {}).items():
        name = get_operator(key).name
        if name not in names:
            raise ValueError(f"params: {key!r} is not one of the methods compared")
        out[name] = dict(values)
    return out


def _load_image(image: Any) -> tuple[str | None, np.ndarray, tuple[float, float, float]]:
    """``(source, rgb float32 (H, W, 3), luminance weights)``."""
    from ..layers import LayeredImage

    source = None
    if isinstance(image, (str, os.PathLike)):
        from ..io import read

        source = os.fspath(image)
        image = read(image)  # ReadError (a ValueError) naming the file
    if isinstance(image, LayeredImage):
        if source is None and image.path is not None:
            source = os.fspath(image.path)
        return source, np.asarray(image.rgb(), np.float32), image.luminance_weights_in()
    _check.shape(image, "image", ndim=3)
    rgb = np.asarray(image)
    if not np.issubdtype(rgb.dtype, np.floating) or rgb.dtype == np.float16:
        rgb = rgb.astype(np.float32)
    return None, rgb, REC709_WEIGHTS


def _load_reference(reference: Any, shape: tuple[int, ...]) -> tuple[str | None, Any]:
    """``(label, linear display values in [0, 1] float32)`` of the reference rendition."""
    if reference is None:
        return None, None
    label = "array"
    if isinstance(reference, (str, os.PathLike)):
        from PIL import Image, UnidentifiedImageError

        label = os.fspath(reference)
        try:
            with Image.open(reference) as im:
                reference = np.asarray(im.convert("RGB"), np.float32) / 255.0
        except (OSError, UnidentifiedImageError) as e:
            raise ValueError(f"{label}: cannot read the reference rendition ({e})") from None
    s = _check.shape(reference, "reference", ndim=3)
    if s != tuple(shape):
        raise ValueError(f"reference: expected the image's shape {tuple(shape)}, got shape {s}")
    _check.in_range(np.nan_to_num(np.asarray(reference, np.float64)), "reference", 0.0, 1.0)
    return label, np.asarray(srgb_decode(reference), np.float32)


def _row(name, given, hdr, weights, target, ref_luminance, peak, black, repeats):
    cls = get_operator(name)
    op = make_operator(name, **given).for_primaries(weights)
    estimated = op.unset()
    fitted: tuple[str, ...] = ()
    fit_s = fit_success = None
    if target is not None and cls.default_fit_params:
        from ..fit import fit as run_fit

        fitted = tuple(p for p in cls.default_fit_params if p not in given)
    if fitted:
        t0 = time.perf_counter()
        res = run_fit(op, hdr, target, params=fitted)
        jax.block_until_ready(res)
        fit_s = time.perf_counter() - t0
        fit_success = bool(res.success)
        op = res.operator
        estimated = tuple(n for n in estimated if n not in fitted)
    exe, dyn, compile_s = _compiled(op, hdr)
    out = jax.block_until_ready(exe(dyn, hdr))  # untimed: first run of a fresh program
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(exe(dyn, hdr))
        times.append(time.perf_counter() - t0)
    measured = op.measure(hdr) if op.unset() else op
    scores = _scores(hdr, out, ref_luminance, peak, black)
    return ComparisonRow(
        method=name,
        **scores,
        compile_s=compile_s,
        warm_s=statistics.median(times),
        fit_s=fit_s,
        fit_success=fit_success,
        params=_parameters(measured),
        estimated=tuple(estimated),
        fitted=fitted,
        operator=measured,
        rendition=quantize(encode(out, "srgb"), 8),
    )


def _scores(hdr, out, ref_luminance, peak, black) -> dict[str, float | None]:
    """The row's metrics of one rendition (the module docstring defines each)."""
    enc = encode(out, "srgb")
    q, s, n = (float(v) for v in tmqi(hdr, enc))
    pu = None
    if ref_luminance is not None:
        test = black + (peak - black) * srgb_decode(enc)
        pu = float(pu_ssim(test, ref_luminance))
    o = np.asarray(out, np.float64)
    ok = np.all(np.isfinite(o), axis=-1) & np.all(np.isfinite(np.asarray(hdr)), axis=-1)
    count = max(int(np.count_nonzero(ok)), 1)
    # a channel at 0 only counts where the scene had light in it: black stays black
    # on the linear output: encoding clips there, and its float rounding may miss 1 itself
    low = np.any((o <= 0.0) & (np.asarray(hdr) > 0), axis=-1) & ok
    high = np.any(o >= 1.0, axis=-1) & ok
    L = np.asarray(luminance(np.clip(np.where(ok[..., None], o, 0.0), 0.0, 1.0), REC709_WEIGHTS))
    return {
        "q": q,
        "s": s,
        "n": n,
        "pu_ssim": pu,
        "clipped": float(np.count_nonzero(low | high) / count),
        "clipped_black": float(np.count_nonzero(low) / count),
        "clipped_white": float(np.count_nonzero(high) / count),
        "mean_luminance": float(np.sum(np.where(ok, L, 0.0)) / count),
    }


_COMPILED: collections.OrderedDict = collections.OrderedDict()


def _compiled(op, rgb: jax.Array):
    """``(compiled program, its array arguments, compile seconds)`` of ``op(rgb)``: compiled
    ahead of time and timed the first time, reused (with that time) afterwards."""
    dyn, static = eqx.partition(op, eqx.is_array)
    leaves, treedef = jax.tree_util.tree_flatten(dyn)
    key: Any = (static, treedef, tuple((v.shape, str(v.dtype)) for v in leaves))
    key = (key, rgb.shape, str(rgb.dtype))
    try:
        hit = _COMPILED.get(key)
    except TypeError:  # a plug-in's unhashable setting: compile afresh
        key = hit = None
    if hit is not None:
        _COMPILED.move_to_end(key)
        return hit[0], dyn, hit[1]
    t0 = time.perf_counter()
    exe = jax.jit(lambda d, x: eqx.combine(d, static)(x)).lower(dyn, rgb).compile()
    seconds = time.perf_counter() - t0
    if key is not None:
        _COMPILED[key] = (exe, seconds)
        while len(_COMPILED) > _COMPILED_MAX:
            _COMPILED.popitem(last=False)
    return exe, dyn, seconds


def _parameters(op) -> dict[str, Any]:
    """The operator's parameters as JSON values (arrays of more than 8 values summarised)."""
    out = {}
    for name, v in op.parameters().items():
        if v is None or name in PARAMETER_SETTINGS:
            continue
        out[name] = _json_value(v)
    return out


def _json_value(v: Any) -> Any:
    if isinstance(v, (bool, int, str)):
        return v
    if isinstance(v, float):
        return v if np.isfinite(v) else None
    a = np.asarray(v)
    if a.dtype.kind in "fiub":
        if a.size > 8:
            return f"array of shape {tuple(a.shape)}"
        return [_json_value(x) for x in a.reshape(-1).tolist()] if a.ndim else _json_value(a.item())
    return str(v)
