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
sums, extremes, ``Σ ln L`` of the subsample) when every pixel is finite and inside the
visible range, and a few more masked programs otherwise; the small results are combined in
float64 NumPy. On a 2048×1024 panorama it costs about a third of a Reinhard 2002 tone
mapping (benchmarks/bench_vision.py: 14 ms against 48 ms, fastest calls on a shared 2-core
CPU); the previous version (a histogram scatter over every pixel and four programs) cost
160 ms, three tone mappings.
"""

import dataclasses
import functools
import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._colour import luminance
from ._contrast import WEBER_ONSET
from ._fovea import block_reduce, pixel_stride
from ._jensen2001 import LOG_HIGH
from ._pcond import VEIL_RANGE
from ._photometry import LMAX, LMIN, TOP_MESOPIC
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
            equal to ``np.percentile`` of the subsample's luminances.
        p05_rel_error: bound on its relative error: 0, the percentile is exact (the field
            stays for reports that held a histogram estimate).
        luminance_min, luminance_max: extreme samples inside (1e-7, 1e5) cd/m².
        dynamic_range: ``ln(luminance_max/luminance_min)`` (pcond's histogram range).
        n_pixels: number of pixels; n_nonfinite: pixels whose luminance is NaN or ±Inf.
        glare_variant: Spencer PSF variant for the global adaptation.
        decisions: one :class:`Decision` per effect, in application order.
    """

    view: ResolvedView
    adaptation_global: float
    adaptation_centre: float
    adaptation_foveal: np.ndarray
    luminance_p05: float
    p05_rel_error: float
    luminance_min: float
    luminance_max: float
    dynamic_range: float
    n_pixels: int
    n_nonfinite: int
    glare_variant: str
    decisions: dict[str, Decision]

    @property
    def selected(self) -> tuple[str, ...]:
        """Names of the effects that apply, in application order."""
        return tuple(n for n, d in self.decisions.items() if d.applies)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (the foveal image as nested lists)."""
        d = dataclasses.asdict(self)
        d["adaptation_foveal"] = np.asarray(self.adaptation_foveal).tolist()
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
        return "\n".join(lines)


def _json_safe(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_json_safe(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


@functools.partial(jax.jit, static_argnames=("weights", "block", "stride"))
def _fast_pass(rgb: jax.Array, weights: tuple[float, ...], block, stride) -> tuple:
    """Luminance and the statistics of an image whose pixels are all finite and inside
    ``(LMIN, LMAX)`` (the usual case; :func:`_measure` checks it from the results), in one
    program: ``L``, block sums of ``L/(by·bx)``, ``min L``, ``max L`` and per-row sums of
    ``ln L`` over the pixel subsample. Without masks every reduction vectorises on XLA:CPU.
    ``L`` is returned for the percentile (NumPy reads it without a copy)."""
    L = luminance(rgb, weights)
    by, bx = block
    sy, sx = stride
    num = block_reduce(L * (1.0 / (by * bx)), by, bx, jnp.add, 0.0)
    ln_rows = jnp.sum(jnp.log(L[sy // 2 :: sy, sx // 2 :: sx]), axis=1)
    return L, num, jnp.min(L), jnp.max(L), ln_rows


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


def _measure(rgb: jax.Array, block: tuple[int, int], weights: tuple[float, ...]) -> dict:
    """Statistics of :class:`SceneReport`; the small arrays are combined in float64 NumPy."""
    stride = pixel_stride(block)
    L, num, lmin, lmax, ln_rows = _fast_pass(rgb, weights, block, stride)
    H, W = L.shape
    sy, sx = stride
    sub = np.asarray(L)[sy // 2 :: sy, sx // 2 :: sx]
    num = np.asarray(num)
    lmin, lmax = np.asarray(lmin), np.asarray(lmax)  # compared in their dtype, as the masks
    if lmin > LMIN and lmax < LMAX and np.isfinite(num).all():  # (a NaN/Inf pixel makes
        # its block sum non-finite): every pixel is finite and in range, no mask needed
        cnt = np.outer(_block_counts(H, block[0]), _block_counts(W, block[1]))
        ln, n_ok, n_low, lo, hi = np.asarray(ln_rows), sub.size, 0, float(lmin), float(lmax)
    else:
        num = np.asarray(_masked_fovea_sum(L, block))
        cnt = np.asarray(_masked_fovea_count(L, block), np.float64)
        r = jax.device_get(_masked_rows(L, stride))
        ln, lo, hi = r["ln"], float(r["lo"]), float(r["hi"])
        n_ok = int(np.sum(r["n_ok"], dtype=np.float64))
        n_low = int(np.sum(r["n_low"], dtype=np.float64))
    ok = cnt > 0
    fovea = np.where(ok, num * (block[0] * block[1]) / np.where(ok, cnt, 1.0), 0.0)
    fovea = fovea.astype(num.dtype)
    fvals = fovea[ok & (fovea > LMIN) & (fovea < LMAX)].astype(np.float64)
    # pcond mean brightness: foveal and pixel samples weighted equally (mean_brightness)
    means = [float(np.mean(np.log(fvals)))] if fvals.size else []
    if n_ok:
        means.append(float(np.sum(ln, dtype=np.float64)) / n_ok)
    fy, fx = fovea.shape
    return {
        "fovea": fovea,
        "centre": float(fovea[fy // 2, fx // 2]),
        "adaptation": math.exp(sum(means) / len(means)) if means else LMIN,
        "p05": subsample_percentile(sub, 5.0, n_ok, n_low),
        "err": 0.0,
        "lo": min(float(fvals.min()), lo) if fvals.size else lo,
        "hi": max(float(fvals.max()), hi) if fvals.size else hi,
        "n_nonfinite": int(H * W - np.sum(cnt, dtype=np.float64)),
    }


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


def analyze_rgb(
    rgb: jax.Array, view: ResolvedView, weights: tuple[float, float, float]
) -> SceneReport:
    """:func:`hdrjax.vision.analyze` on an RGB array already in cd/m²."""
    if isinstance(rgb, jax.core.Tracer):
        raise ValueError(
            "analyze needs concrete values (its verdicts decide what gets compiled): call it "
            "outside jax.jit/vmap/grad, or pass the effects explicitly to HumanVision"
        )
    m = _measure(rgb, view.fovea_block, tuple(float(w) for w in weights))
    lo, hi = m["lo"], m["hi"]
    any_light = math.isfinite(lo) and math.isfinite(hi)
    La = float(m["adaptation"])
    p05 = float(m["p05"])
    if any_light and not math.isfinite(p05):  # only foveal samples in range
        p05 = lo
    return SceneReport(
        view=view,
        adaptation_global=La,
        adaptation_centre=float(m["centre"]),
        adaptation_foveal=np.asarray(m["fovea"]),
        luminance_p05=p05 if any_light else math.nan,
        p05_rel_error=float(m["err"]),
        luminance_min=lo if any_light else math.nan,
        luminance_max=hi if any_light else math.nan,
        dynamic_range=math.log(hi / lo) if any_light else math.nan,
        n_pixels=int(rgb.shape[0] * rgb.shape[1]),
        n_nonfinite=int(m["n_nonfinite"]),
        glare_variant=variant_for(La),
        decisions=decide(view, La, p05, lo, hi, any_light),
    )


__all__ = ["BLUE_SHIFT_TOP", "EFFECTS", "Decision", "SceneReport", "analyze_rgb", "decide"]
