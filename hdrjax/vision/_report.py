"""Scene analysis: which human-vision effects a scene calls for, and why.

The rules are Radiance ``pcond``'s (``check2do`` in NREL/Radiance ``src/px/pcond.c``; Ward
Larson, Rushmeier & Piatko 1997, doi:10.1109/2945.646233), computed on the statistics of
:mod:`hdrjax.vision._fovea` (foveal ~1° samples plus every pixel, inside the visible range
1e-7–1e5 cd/m²):

- ``acuity``: the acuity at the 5th-percentile luminance, ``R(L_5%)`` cycles/degree, is
  below the image's sampling rate ``(1/pixel_deg_x + 1/pixel_deg_y)/2`` samples/degree
  (pcond: ``hacuity(l) < (xres/hfov + yres/vfov)/2``).
- ``glare``: the samples span at least ``e^4.5`` ≈ 90:1 (pcond: ``bwmax - bwmin >= 4.5``).
  pcond pads its histogram range (×1.01 at the top, one bin at the bottom) and clamps its
  minimum to 1e-7 cd/m², so one black pixel switches its veil on; here the range is that of
  the samples above 1e-7 cd/m² themselves.
- ``colour_loss``: ``L_5% < 5.62`` cd/m², the top of the mesopic range (pcond).
- ``blue_shift``: ``L_5% < 10^0.6 = 3.98`` cd/m², the top of Jensen et al. 2001's rod range
  (the same rule as pcond's colour rule, applied to that model's limit). When both colour
  effects apply, the blue shift renders the colour loss (it contains it).
- ``contrast``: global adaptation below ``10^1.9 = 79.4`` cd/m², where the cone TVI departs
  from Weber's law (Ferwerda et al. 1996): above it, matching threshold visibility only
  multiplies the image by a constant of the display. pcond itself never drops ``-s``.

``L_5%`` is the 5th percentile of the pixel subsample (pcond's random pixel samples; see
:func:`hdrjax.vision._fovea.adaptation_samples`), exact: NumPy's ``np.percentile`` (linear
interpolation) of the subsample's luminances, found by :func:`subsample_percentile` without
sorting or histogramming every pixel. pcond reads it off its 100-bin histogram, in which the
foveal (1° mean) samples carry the same total weight as the pixel samples; they are left out
of the percentile here (an unweighted percentile of the pixels) but kept in the mean
brightness. Foveal means are less extreme than pixels, so this ``L_5%`` is at most pcond's:
the colour and acuity rules fire slightly earlier. The luminance range uses every pixel, not
only the subsample.

Cost: :func:`analyze_rgb` reads the image once, in one XLA program (luminance, foveal block
sums, extremes, ``Σ ln L`` of the subsample: :func:`fast_statistics`) when every pixel is
finite and inside the visible range, and a few more masked programs otherwise; the small
results are combined in float64 NumPy. The exact 5th percentile costs one more pass in NumPy
(a sparse grid, then one narrow band of pixels). :func:`hdrjax.vision.simulate` defers it:
when the whole luminance range lies on one side of every percentile threshold (a daylight
scene) the rules need no percentile, and it is computed only if the report's
``luminance_p05`` or ``decisions`` are read (:func:`_selected_by_range`). With ``then=`` the
statistics are computed in the tone-mapping operator's own program, on its luminance
(:func:`hdrjax.vision._simulate._analyze_and_tonemap`), so a daylight scene costs about one
tone mapping.
"""

import dataclasses
import functools
import math
from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._colour import luminance
from .._photometry import LMAX, LMIN, TOP_MESOPIC
from ._contrast import WEBER_ONSET
from ._fovea import block_reduce, pixel_stride
from ._jensen2001 import LOG_HIGH
from ._pcond import VEIL_RANGE
from ._spencer1995 import variant_for
from ._view import ResolvedView

EFFECTS: tuple[str, ...] = ("acuity", "glare", "colour_loss", "blue_shift", "contrast")
"""Effect names, in the order :func:`hdrjax.vision.simulate` applies them (pcond's order:
acuity sampling, veil, colour loss, then the luminance mapping)."""

BLUE_SHIFT_TOP = 10.0**LOG_HIGH
"""cd/m²: Jensen et al. 2001's night vision ends here (fully photopic above)."""


@dataclasses.dataclass(frozen=True)
class Decision:
    """Whether one effect applies, the number it was decided on and the threshold.

    Attributes:
        name: effect name (one of :data:`EFFECTS`).
        applies: the rule's verdict.
        value: the scene's number (units in ``rule``).
        threshold: the rule's threshold.
        rule: the rule, e.g. ``"L_5% < 5.62 cd/m²"``.
        reason: one sentence with the numbers.
    """

    name: str
    applies: bool
    value: float
    threshold: float
    rule: str
    reason: str


@dataclasses.dataclass(frozen=True)
class SceneReport:
    """What :func:`analyze` measured and decided (plain Python numbers, cd/m²).

    Attributes:
        view: the resolved field of view.
        adaptation_global: global adaptation luminance, pcond's ``exp(mean ln L)`` over
            foveal samples and pixels (sums in float64 over float32 row sums).
        adaptation_centre: foveal (~1°) adaptation luminance at the image centre.
        adaptation_foveal: the foveal image, ``(fy, fx)`` block means (NumPy).
        luminance_p05: 5th-percentile pixel luminance (NaN when no pixel is in range),
            equal to ``np.percentile`` of the subsample's luminances (see *Deferred p05*).
        p05_rel_error: bound on its relative error: 0, the percentile is exact (the field
            stays for reports that held a histogram estimate).
        luminance_min, luminance_max: extreme samples inside (1e-7, 1e5) cd/m².
        dynamic_range: ``ln(luminance_max/luminance_min)`` (pcond's histogram range).
        n_pixels: number of pixels; n_nonfinite: pixels whose luminance is NaN or ±Inf.
        glare_variant: Spencer PSF variant for the global adaptation.
        selected: names of the effects, in application order: from :func:`analyze`, those
            pcond's rules select; from :func:`simulate`, those it applied (its ``effects``
            argument may override the rules).
        decisions: one :class:`Decision` per effect, in application order.

    Deferred p05: :func:`hdrjax.vision.simulate` decides the percentile rules from the
    luminance range alone when the whole range lies on one side of every threshold (a
    daylight scene: its darkest pixel is above 5.62 cd/m²), and finds the exact
    ``luminance_p05`` (and the :class:`Decision` texts that quote it) only when one of them
    is first read; until then the report holds the image's luminance (``H×W`` floats). The
    values are the same as :func:`analyze`'s, which computes them at once.
    """

    view: ResolvedView
    adaptation_global: float
    adaptation_centre: float
    adaptation_foveal: np.ndarray
    p05_rel_error: float
    luminance_min: float
    luminance_max: float
    dynamic_range: float
    n_pixels: int
    n_nonfinite: int
    glare_variant: str
    selected: tuple[str, ...]
    p05_source: "float | Callable[[], float]" = dataclasses.field(repr=False, compare=False)
    """The 5th percentile, or the function that computes it on first use (internal)."""

    @functools.cached_property
    def luminance_p05(self) -> float:
        """5th-percentile pixel luminance, cd/m² (computed on first use when deferred)."""
        src = self.p05_source
        if not callable(src):
            return float(src)
        value = float(src())
        object.__setattr__(self, "p05_source", value)  # drop the luminance it held
        return value

    @functools.cached_property
    def decisions(self) -> dict[str, Decision]:
        """One :class:`Decision` per effect, with the numbers and thresholds."""
        lo, hi = self.luminance_min, self.luminance_max
        any_light = math.isfinite(lo) and math.isfinite(hi)
        return decide(self.view, self.adaptation_global, self.luminance_p05, lo, hi, any_light)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (the foveal image as nested lists)."""
        d: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            if f.name == "p05_source":
                continue
            if f.name == "p05_rel_error":
                d["luminance_p05"] = self.luminance_p05
            d[f.name] = getattr(self, f.name)
        d["view"] = dataclasses.asdict(self.view)
        d["adaptation_foveal"] = np.asarray(self.adaptation_foveal).tolist()
        d["decisions"] = {k: dataclasses.asdict(v) for k, v in self.decisions.items()}
        d["selected"] = list(self.selected)
        return _json_safe(d)

    def __str__(self) -> str:
        v = self.view
        lines = [
            f"Scene: {v.width}×{v.height} px, view {v.hfov:.4g}°×{v.vfov:.4g}° "
            f"{v.projection}, {v.samples_per_degree:.4g} samples/degree"
            + (f", {self.n_nonfinite} non-finite pixels ignored" if self.n_nonfinite else ""),
            f"  adaptation, global (pcond mean brightness)  {self.adaptation_global:.4g} cd/m²",
            f"  adaptation, foveal at the centre            {self.adaptation_centre:.4g} cd/m²",
            f"  5th-percentile luminance                    {self.luminance_p05:.4g} cd/m²"
            + (f" (±{100 * self.p05_rel_error:.2g} %)" if self.p05_rel_error else " (exact)"),
            f"  luminance range (samples)                   {self.luminance_min:.4g} to "
            f"{self.luminance_max:.4g} cd/m² (ln range {self.dynamic_range:.3g})",
            f"  glare PSF variant                           {self.glare_variant}",
            "  effect       applies  because",
        ]
        for d in self.decisions.values():
            lines.append(f"  {d.name:<12} {'yes' if d.applies else 'no':<8} {d.reason}")
        if self.selected != tuple(n for n, d in self.decisions.items() if d.applies):
            lines.append(
                f"  effects simulated: {', '.join(self.selected) or 'none'} (chosen by the"
                " effects argument, not by these rules)"
            )
        return "\n".join(lines)

    def __repr__(self) -> str:
        """One line: size and view, adaptation, luminance range, the selected effects (the
        5th percentile only once it is known: a repr does not compute a deferred one)."""
        v = self.view
        p05 = self.p05_source
        known = "" if callable(p05) else f", L_5% {float(p05):.4g} cd/m²"
        return (
            f"SceneReport({v.width}×{v.height} px, {v.hfov:.4g}°×{v.vfov:.4g}° {v.projection}, "
            f"adaptation {self.adaptation_global:.4g} cd/m² (global), "
            f"{self.adaptation_centre:.4g} cd/m² (centre), luminance {self.luminance_min:.4g}"
            f" to {self.luminance_max:.4g} cd/m²{known}, "
            f"effects: {', '.join(self.selected) or 'none'})"
        )

    def _repr_html_(self) -> str:
        """A notebook's view: the measurements, then each effect's verdict and reason."""
        from .. import _repr

        v = self.view
        rows = [
            ("size", f"{v.width} × {v.height} px"),
            ("view", f"{v.hfov:.4g}° × {v.vfov:.4g}° {v.projection}"),
            ("adaptation, global", f"{self.adaptation_global:.4g} cd/m²"),
            ("adaptation, centre", f"{self.adaptation_centre:.4g} cd/m²"),
            ("5th-percentile luminance", f"{self.luminance_p05:.4g} cd/m²"),
            ("luminance range", f"{self.luminance_min:.4g} to {self.luminance_max:.4g} cd/m²"),
            ("glare PSF variant", self.glare_variant),
            ("foveal image", _repr.value(self.adaptation_foveal, "cd/m²")),
        ]
        if self.n_nonfinite:
            rows.append(("non-finite pixels", f"{self.n_nonfinite} (ignored)"))
        effects = [
            (d.name, "yes" if d.applies else "no", d.reason) for d in self.decisions.values()
        ]
        body = _repr.table(rows) + _repr.table(effects, ("effect", "applies", "because"))
        note = f"effects simulated: {', '.join(self.selected) or 'none'}"
        return _repr.view("SceneReport (Ward Larson et al. 1997's rules)", body, note=note)


def _json_safe(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_json_safe(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def fast_statistics(L: jax.Array, block: tuple[int, int], stride: tuple[int, int]) -> tuple:
    """The statistics of :func:`_fast_pass` from a luminance image (traceable): block sums
    of ``L/(by·bx)``, ``min L``, ``max L`` and per-row sums of ``ln L`` over the pixel
    subsample, with no mask (:func:`fast_report` checks afterwards that none was needed).
    The foveal means, logarithms and extremes are left to NumPy: a consumer of the block
    sums in this program would get its own copy of the strided-slice reduction."""
    by, bx = block
    sy, sx = stride
    num = block_reduce(L * (1.0 / (by * bx)), by, bx, jnp.add, 0.0)
    ln_rows = jnp.sum(jnp.log(L[sy // 2 :: sy, sx // 2 :: sx]), axis=1)
    return num, jnp.min(L), jnp.max(L), ln_rows


@functools.partial(jax.jit, static_argnames=("weights", "block", "stride"))
def _fast_pass(rgb: jax.Array, weights: tuple[float, ...], block, stride) -> tuple:
    """Luminance and the statistics of an image whose pixels are all finite and inside
    ``(LMIN, LMAX)`` (the usual case; :func:`fast_report` checks it from the results), in
    one program: ``L`` and :func:`fast_statistics`. Without masks every reduction
    vectorises on XLA:CPU. ``L`` is returned for the percentile (NumPy reads it without a
    copy); as an output it is also written once, where the reductions read it (fused into
    each of them, the luminance of the interleaved RGB would not vectorise)."""
    L = luminance(rgb, weights)
    return (L, *fast_statistics(L, block, stride))


# The masked statistics, for images with non-finite or out-of-range pixels. One output per
# block reduction: XLA:CPU ran two strided-slice block reductions in one program 3x slower
# than the two programs back to back.
@functools.partial(jax.jit, static_argnames=("block",))
def _masked_fovea_sum(L: jax.Array, block: tuple[int, int]) -> jax.Array:
    by, bx = block
    x = jnp.where(jnp.isfinite(L), L, 0.0) * (1.0 / (by * bx))
    return block_reduce(x, by, bx, jnp.add, 0.0)


@functools.partial(jax.jit, static_argnames=("block",))
def _masked_fovea_count(L: jax.Array, block: tuple[int, int]) -> jax.Array:
    return block_reduce(jnp.isfinite(L).astype(L.dtype), *block, jnp.add, 0.0)


@functools.partial(jax.jit, static_argnames=("stride",))
def _masked_rows(L: jax.Array, stride: tuple[int, int]) -> dict:
    ok = jnp.isfinite(L) & (L > LMIN) & (L < LMAX)
    inf = jnp.asarray(jnp.inf, L.dtype)
    sy, sx = stride
    sub = L[sy // 2 :: sy, sx // 2 :: sx]
    sok = jnp.isfinite(sub) & (sub > LMIN) & (sub < LMAX)
    return {
        # range over every pixel (not only the subsample, which may miss a small lamp)
        "lo": jnp.min(jnp.where(ok, L, inf)),
        "hi": jnp.max(jnp.where(ok, L, -inf)),
        # per-row sums over the pixel subsample (counts exact in float32 up to 2^24 a row)
        "ln": jnp.sum(jnp.log(jnp.where(sok, sub, 1.0)), axis=1),
        "n_ok": jnp.sum(sok.astype(L.dtype), axis=1),
        "n_low": jnp.sum((sub <= LMIN).astype(L.dtype), axis=1),  # incl. -inf, not NaN
    }


def _block_counts(n: int, b: int) -> np.ndarray:
    """Pixels in each block of ``b`` along an axis of ``n`` (the last block may be short)."""
    c = np.full(-(-n // b), float(b))
    c[-1] = n - b * (c.size - 1)
    return c


SPARSE_SAMPLES = 32768
"""Pixels of the sparse grid whose order statistics bracket the percentile
(:func:`subsample_percentile`)."""


def subsample_percentile(sub: np.ndarray, q: float, n_ok: int, n_low: int) -> float:
    """Exact ``np.percentile`` (linear) of the values of ``sub`` inside ``(LMIN, LMAX)``.

    Equal to ``np.percentile(sub[(sub > LMIN) & (sub < LMAX)], q)`` up to the rounding of
    the final interpolation, without sorting or histogramming every pixel (a histogram
    scatter cost 60 % of the analysis on XLA:CPU): the order statistics of a sparse regular
    grid of about :data:`SPARSE_SAMPLES` pixels give an interval ``[a, b]`` that holds the
    wanted ranks with ±5σ of sampling margin; two vectorised counts over the subsample
    check that it does (``#(L < a) <= k`` and ``#(L <= b) >= k + 2``), and the few pixels
    inside it are partitioned for ranks ``k`` and ``k + 1``. If a check fails (a grid that
    misrepresents the image), every valid pixel is partitioned instead: same value.

    Args:
        sub: the pixel subsample, cd/m² (any shape; NaN/Inf and out-of-range are ignored).
        q: percentile in [0, 100].
        n_ok: number of values of ``sub`` inside ``(LMIN, LMAX)``.
        n_low: number of values ``<= LMIN`` (including ``-inf``).
    """
    if n_ok == 0:
        return math.nan
    rank = q / 100.0 * (n_ok - 1)
    k = int(math.floor(rank))
    k1 = min(k + 1, n_ok - 1)
    a, b = LMIN, LMAX  # exclusive bounds of the values kept
    if n_ok > 4 * SPARSE_SAMPLES:
        step = max(1, int(math.sqrt(sub.size / SPARSE_SAMPLES)))
        grid = sub[(slice(step // 2, None, step),) * sub.ndim].ravel()
        grid = np.sort(grid[(grid > LMIN) & (grid < LMAX)])
        m = grid.size
        if m >= 1024:
            p = q / 100.0
            margin = 5.0 * math.sqrt(p * (1.0 - p) / m) + 2.0 / m
            ja, jb = math.floor((p - margin) * m), math.ceil((p + margin) * m)
            a = float(grid[ja]) if ja >= 0 else LMIN
            b = float(grid[jb]) if jb < m else LMAX
    if n_ok == sub.size and a > LMIN and b < LMAX:
        # every value is finite and positive: as integers their bit patterns have the same
        # order, so one subtraction gives both tests (below a: negative; in [a, b]: an
        # unsigned difference <= that of b)
        it = np.dtype(f"int{8 * sub.dtype.itemsize}")
        d = sub.view(it) - np.asarray(a, sub.dtype).view(it)
        below = int(np.count_nonzero(d < 0))
        span = (np.asarray(b, sub.dtype).view(it) - np.asarray(a, sub.dtype).view(it)).view(
            np.dtype(f"u{it}")
        )
        band = sub[d.view(f"u{it}") <= span]
    else:
        below = int(np.count_nonzero(sub < a)) - n_low if a > LMIN else 0
        band = sub[(sub >= a) & (sub <= b)] if a > LMIN else sub[(sub > a) & (sub <= b)]
        if b == LMAX:
            band = band[band < LMAX]
    if not (below <= k and below + band.size >= k1 + 1):  # the grid misled: every pixel
        band, below = sub[(sub > LMIN) & (sub < LMAX)], 0
    elif a == b:  # ranks k and k+1 hold the one value of the band (a flat image)
        return float(a)
    band = np.partition(band, k - below)
    lo = float(band[k - below])
    hi = float(np.min(band[k - below + 1 :])) if k1 > k else lo
    return lo + (hi - lo) * (rank - k)


def _fovea_terms(num: np.ndarray, cnt: np.ndarray, block: tuple[int, int]) -> tuple:
    """The foveal image (block means of the finite pixels, float32 as the image) and the
    terms of its in-range samples: ``(Σ ln, count, min, max)`` (logarithms of the float32
    means, summed in float64)."""
    ok = cnt > 0
    full = bool(ok.all())
    fovea = num * (block[0] * block[1]) / (cnt if full else np.where(ok, cnt, 1.0))
    fovea = (fovea if full else np.where(ok, fovea, 0.0)).astype(num.dtype)
    lo, hi = float(fovea.min()), float(fovea.max())
    if full and lo > LMIN and hi < LMAX:  # every sample counts (the usual case)
        return fovea, (float(np.sum(np.log(fovea), dtype=np.float64)), fovea.size, lo, hi)
    fvals = fovea[ok & (fovea > LMIN) & (fovea < LMAX)]
    if not fvals.size:
        return fovea, (0.0, 0, math.inf, -math.inf)
    terms = (float(np.sum(np.log(fvals), dtype=np.float64)), fvals.size)
    return fovea, (*terms, float(fvals.min()), float(fvals.max()))


@functools.lru_cache(maxsize=64)
def _edge_factors(n: int, b: int, dtype: Any) -> np.ndarray:
    """``b / (pixels in each block)`` along an axis: 1 but for a short last block."""
    f = (b / _block_counts(n, b)).astype(dtype)
    f.flags.writeable = False
    return f


def _assemble(
    view: ResolvedView,
    fovea: np.ndarray,
    fterms: tuple[float, int, float, float],
    ln_sum: float,
    n_ok: int,
    lo: float,
    hi: float,
    n_nonfinite: int,
    p05: "float | None",
    p05_of: Callable[[], float],
) -> SceneReport:
    """The report from the combined statistics. ``p05`` may be ``None`` (deferred): the
    percentile rules are then decided from the range, or ``p05_of()`` is called now."""
    # pcond mean brightness: foveal and pixel samples weighted equally (mean_brightness)
    f_sum, f_n, f_lo, f_hi = fterms
    means = [f_sum / f_n] if f_n else []
    if n_ok:
        means.append(ln_sum / n_ok)
    if f_n:
        lo, hi = min(f_lo, lo), max(f_hi, hi)
    any_light = math.isfinite(lo) and math.isfinite(hi)
    La = math.exp(sum(means) / len(means)) if means else LMIN
    source: float | Callable[[], float]
    selected = _selected_by_range(view, La, lo, hi) if p05 is None and any_light else None
    if selected is None:
        if p05 is None:
            p05 = p05_of()
        if any_light and not math.isfinite(p05):  # only foveal samples in range
            p05 = lo
        p05 = p05 if any_light else math.nan
        d = decide(view, La, p05, lo, hi, any_light)
        selected = tuple(n for n, x in d.items() if x.applies)
        source = p05
    else:
        source = p05_of
    fy, fx = fovea.shape
    return SceneReport(
        view=view,
        adaptation_global=La,
        adaptation_centre=float(fovea[fy // 2, fx // 2]),
        adaptation_foveal=fovea,
        p05_rel_error=0.0,
        luminance_min=lo if any_light else math.nan,
        luminance_max=hi if any_light else math.nan,
        dynamic_range=math.log(hi / lo) if any_light else math.nan,
        n_pixels=int(view.height * view.width),
        n_nonfinite=int(n_nonfinite),
        glare_variant=variant_for(La),
        selected=selected,
        p05_source=source,
    )


def fast_report(
    view: ResolvedView, L: jax.Array, *stats: Any, defer_p05: bool = False
) -> SceneReport | None:
    """The report from :func:`fast_statistics` (``*stats``) when no mask was needed (every
    pixel finite and inside ``(LMIN, LMAX)``: the extremes are in range, and every foveal
    sample is finite, as a NaN/Inf pixel makes its block's mean and ``ln`` non-finite), else
    ``None``.

    With ``defer_p05`` the 5th percentile is left for first use when the luminance range
    decides its rules (see :class:`SceneReport`)."""
    num, lmin, lmax, ln_rows = jax.device_get(stats)
    if not (lmin > LMIN and lmax < LMAX):  # compared in their dtype, as the masks
        return None
    H, W = L.shape
    (by, bx), (sy, sx) = view.fovea_block, pixel_stride(view.fovea_block)
    # block means: factors 1 for full blocks (exact), by/rows, bx/columns at the short edges
    fovea = num * _edge_factors(H, by, num.dtype)[:, None] * _edge_factors(W, bx, num.dtype)
    f_ln = np.log(fovea)
    f_sum, f_min, f_max = float(np.sum(f_ln, dtype=np.float64)), fovea.min(), fovea.max()
    if not math.isfinite(f_sum):  # a NaN/Inf pixel makes its block's mean non-finite
        return None
    n_ok = len(range(sy // 2, H, sy)) * len(range(sx // 2, W, sx))
    if f_min > LMIN and f_max < LMAX:  # every foveal sample counts (the usual case)
        fterms = (f_sum, fovea.size, float(f_min), float(f_max))
    else:  # means that round past an end of the range
        fvals = fovea[(fovea > LMIN) & (fovea < LMAX)]
        fterms = (
            float(np.sum(np.log(fvals), dtype=np.float64)),
            fvals.size,
            float(fvals.min(initial=math.inf)),
            float(fvals.max(initial=-math.inf)),
        )

    def p05_of() -> float:
        sub = np.asarray(L)[sy // 2 :: sy, sx // 2 :: sx]
        return subsample_percentile(sub, 5.0, sub.size, 0)

    return _assemble(
        view,
        fovea,
        fterms,
        float(np.sum(ln_rows, dtype=np.float64)),
        n_ok,
        float(lmin),
        float(lmax),
        0,
        None if defer_p05 else p05_of(),
        p05_of,
    )


def masked_report(view: ResolvedView, L: jax.Array) -> SceneReport:
    """The report of an image with non-finite or out-of-range pixels (masked programs)."""
    block = view.fovea_block
    stride = pixel_stride(block)
    H, W = L.shape
    num = np.asarray(_masked_fovea_sum(L, block))
    cnt = np.asarray(_masked_fovea_count(L, block), np.float64)
    r = jax.device_get(_masked_rows(L, stride))
    n_ok = int(np.sum(r["n_ok"], dtype=np.float64))
    n_low = int(np.sum(r["n_low"], dtype=np.float64))
    fovea, fterms = _fovea_terms(num, cnt, block)
    sy, sx = stride

    def p05_of() -> float:
        sub = np.asarray(L)[sy // 2 :: sy, sx // 2 :: sx]
        return subsample_percentile(sub, 5.0, n_ok, n_low)

    return _assemble(
        view,
        fovea,
        fterms,
        float(np.sum(r["ln"], dtype=np.float64)),
        n_ok,
        float(r["lo"]),
        float(r["hi"]),
        int(H * W - np.sum(cnt, dtype=np.float64)),
        p05_of(),
        p05_of,
    )


def _acuity_of(L: float) -> float:
    """:func:`hdrjax.vision.acuity` of one Python number, in float64 (tested equal): the
    eager JAX call cost more than the rest of the decisions."""
    return 17.25 * math.atan(1.4 * math.log10(max(L, LMIN)) + 0.35) + 25.72


def decide(
    view: ResolvedView, adaptation: float, p05: float, lo: float, hi: float, any_light: bool
) -> dict[str, Decision]:
    """Apply the selection rules (module docstring) to measured statistics."""
    out: dict[str, Decision] = {}
    spd = view.samples_per_degree
    if not any_light:
        why = "no pixel inside the visible range 1e-7–1e5 cd/m²"
        return {n: Decision(n, False, math.nan, math.nan, "-", why) for n in EFFECTS}
    R = _acuity_of(p05)
    out["acuity"] = Decision(
        "acuity",
        R < spd,
        R,
        spd,
        "R(L_5%) < image samples/degree",
        f"R(L_5%) = {R:.3g} c/deg {'<' if R < spd else '>='} {spd:.3g} samples/deg"
        + (" (the image holds detail the eye cannot resolve)" if R < spd else ""),
    )
    rng = math.log(hi / lo)
    out["glare"] = Decision(
        "glare",
        rng >= VEIL_RANGE,
        rng,
        VEIL_RANGE,
        "ln(L_max/L_min) >= 4.5 (90:1)",
        f"range {hi / lo:.3g}:1 (ln {rng:.3g}) {'>=' if rng >= VEIL_RANGE else '<'} e^4.5 = 90:1",
    )
    out["colour_loss"] = Decision(
        "colour_loss",
        p05 < TOP_MESOPIC,
        p05,
        TOP_MESOPIC,
        "L_5% < 5.62 cd/m²",
        f"L_5% = {p05:.3g} cd/m² {'<' if p05 < TOP_MESOPIC else '>='} 5.62 cd/m² "
        "(top of the mesopic range)",
    )
    bs = p05 < BLUE_SHIFT_TOP
    out["blue_shift"] = Decision(
        "blue_shift",
        bs,
        p05,
        BLUE_SHIFT_TOP,
        "L_5% < 3.98 cd/m²",
        f"L_5% = {p05:.3g} cd/m² {'<' if bs else '>='} 3.98 cd/m² (top of Jensen 2001's "
        "rod range)" + ("; renders the colour loss" if bs else ""),
    )
    ct = adaptation < WEBER_ONSET
    out["contrast"] = Decision(
        "contrast",
        ct,
        adaptation,
        WEBER_ONSET,
        "L_wa < 79.4 cd/m²",
        f"L_wa = {adaptation:.3g} cd/m² {'<' if ct else '>='} 79.4 cd/m² "
        + ("(TVI below Weber's law)" if ct else "(Weber's law: a display constant only)"),
    )
    return out


def _selected_by_range(
    view: ResolvedView, adaptation: float, lo: float, hi: float
) -> tuple[str, ...] | None:
    """The selection of :func:`decide` without the 5th percentile, which lies in
    ``[lo, hi]``: every percentile rule (``R(L_5%) < samples/degree``, ``L_5% < 5.62``,
    ``L_5% < 3.98``) is monotone in it, so it is decided when ``lo`` and ``hi`` give the
    same verdict. ``None`` when one of them does not (the percentile is needed)."""
    spd = view.samples_per_degree
    verdicts = {}
    for name, value_of, threshold in (
        ("acuity", _acuity_of, spd),
        ("colour_loss", float, TOP_MESOPIC),
        ("blue_shift", float, BLUE_SHIFT_TOP),
    ):
        at_lo, at_hi = value_of(lo) < threshold, value_of(hi) < threshold
        if at_lo != at_hi:
            return None
        verdicts[name] = at_lo
    verdicts["glare"] = math.log(hi / lo) >= VEIL_RANGE
    verdicts["contrast"] = adaptation < WEBER_ONSET
    return tuple(n for n in EFFECTS if verdicts[n])


def analyze_rgb(
    rgb: jax.Array,
    view: ResolvedView,
    weights: tuple[float, float, float],
    *,
    defer_p05: bool = False,
) -> SceneReport:
    """:func:`hdrjax.vision.analyze` on an RGB array already in cd/m² (``defer_p05``: see
    :class:`SceneReport`)."""
    if isinstance(rgb, jax.core.Tracer):
        raise ValueError(
            "analyze needs concrete values (its verdicts decide what gets compiled): call it "
            "outside jax.jit/vmap/grad, or pass the effects explicitly to HumanVision"
        )
    block = view.fovea_block
    L, *stats = _fast_pass(rgb, tuple(float(w) for w in weights), block, pixel_stride(block))
    rep = fast_report(view, L, *stats, defer_p05=defer_p05)
    return rep if rep is not None else masked_report(view, L)


__all__ = [
    "BLUE_SHIFT_TOP",
    "EFFECTS",
    "Decision",
    "SceneReport",
    "analyze_rgb",
    "decide",
    "fast_report",
    "masked_report",
    "fast_statistics",
]
