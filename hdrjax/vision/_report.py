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
:func:`hdrjax.vision._fovea.adaptation_samples`) by ``hdrjax.stats.percentile`` (histogram
method, error bound reported). pcond reads it off its 100-bin histogram, in which the
foveal (1° mean) samples carry the same total weight as the pixel samples; they are left out
of the percentile here (``hdrjax.stats.percentile`` is unweighted, and replicating them
doubled the analysis time) but kept in the mean brightness. Foveal means are less extreme
than pixels, so this ``L_5%`` is at most pcond's: the colour and acuity rules fire slightly
earlier. The luminance range uses every pixel, not only the subsample.
"""

import dataclasses
import functools
import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._colour import luminance
from .._stats import percentile
from ._contrast import WEBER_ONSET
from ._fovea import _with_pixels, block_mean, mean_brightness
from ._jensen2001 import LOG_HIGH
from ._pcond import VEIL_RANGE, acuity
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
            foveal samples and pixels.
        adaptation_centre: foveal (~1°) adaptation luminance at the image centre.
        adaptation_foveal: the foveal image, ``(fy, fx)`` block means (NumPy).
        luminance_p05: 5th-percentile pixel luminance (NaN when no pixel is in range).
        p05_rel_error: bound on its relative error (histogram percentile).
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
            f" (±{100 * self.p05_rel_error:.2g} %)",
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


# Three programs rather than one: XLA:CPU ran the fused single program at half the speed
# of these three back to back (2048×1024: 45 ms against 26 ms).
@functools.partial(jax.jit, static_argnames=("block", "weights"))
def _fovea_pass(rgb: jax.Array, block: tuple[int, int], weights: tuple[float, ...]):
    L = luminance(rgb, weights)
    return block_mean(L, jnp.isfinite(L), *block)


@functools.partial(jax.jit, static_argnames=("weights",))
def _range_pass(rgb: jax.Array, weights: tuple[float, ...]):
    L = luminance(rgb, weights)
    fin = jnp.isfinite(L)
    ok = fin & (L > LMIN) & (L < LMAX)
    inf = jnp.asarray(jnp.inf, L.dtype)
    # every pixel, not only pcond's random samples (which may miss a small lamp)
    return jnp.min(jnp.where(ok, L, inf)), jnp.max(jnp.where(ok, L, -inf)), jnp.sum(~fin)


@functools.partial(jax.jit, static_argnames=("block", "weights"))
def _sample_pass(rgb: jax.Array, fovea: jax.Array, cnt: jax.Array, block: tuple[int, int], weights):
    s = _with_pixels(luminance(rgb, weights), block, fovea, cnt)
    p05, err = percentile(s.pixels, 5.0, where=s.pixels_ok)
    inf = jnp.asarray(jnp.inf, fovea.dtype)
    fy, fx = fovea.shape
    return {
        "fovea": fovea,
        "centre": fovea[fy // 2, fx // 2],
        "adaptation": mean_brightness(s),
        "flo": jnp.min(jnp.where(s.fovea_ok, fovea, inf)),
        "fhi": jnp.max(jnp.where(s.fovea_ok, fovea, -inf)),
        "p05": p05,
        "err": err,
    }


def _measure(rgb: jax.Array, block: tuple[int, int], weights: tuple[float, ...]) -> dict:
    fovea, cnt = _fovea_pass(rgb, block, weights)
    lo, hi, n_bad = _range_pass(rgb, weights)
    m = _sample_pass(rgb, fovea, cnt, block, weights)
    m = jax.device_get({**m, "plo": lo, "phi": hi, "n_nonfinite": n_bad})
    m["lo"] = min(float(m["flo"]), float(m["plo"]))
    m["hi"] = max(float(m["fhi"]), float(m["phi"]))
    return m


def decide(
    view: ResolvedView, adaptation: float, p05: float, lo: float, hi: float, any_light: bool
) -> dict[str, Decision]:
    """Apply the selection rules (module docstring) to measured statistics."""
    out: dict[str, Decision] = {}
    spd = view.samples_per_degree
    if not any_light:
        why = "no pixel inside the visible range 1e-7–1e5 cd/m²"
        return {n: Decision(n, False, math.nan, math.nan, "-", why) for n in EFFECTS}
    R = float(acuity(p05))
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
