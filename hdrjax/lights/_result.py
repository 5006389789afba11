"""Result types of light detection (pytrees: they go through ``jit`` and ``vmap``)."""

import json
import math
from typing import Any

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from .. import _repr
from ._geometry import (
    Convention,
    azimuth_elevation,
    convert_direction,
    direction_to_uv,
    to_z_up,
)


def _np(x: Any) -> np.ndarray:
    return np.asarray(x)


class Lights(eqx.Module):
    """Light sources found in one map (or a batch: every array then has the batch axes first).

    Arrays over lights have ``max_lights`` rows; the first ``count`` are the lights, sorted
    by energy (largest first), the rest are padding (``valid`` False, zeros, label −1).
    Positions are in the **input** image's pixel coordinates (column ``x``, row ``y``,
    integers at pixel centres). Directions use hdrjax's convention (Y-up, looking along
    −Z, +X right, as :mod:`hdrjax.panorama`; see :meth:`directions` for others).
    Luminance is in the map's units (relative or cd/m²); a solid angle in sr; "energy" is
    luminance integrated over solid angle (∑ L dω, i.e. the cosine-of-elevation weighted
    sum over an equirectangular map).

    For a plain image (``projection == "plane"``) there is no sphere: ``direction`` is
    zero, ``solid_angle``/``angular_diameter`` are zero, and energy is ∑ L over pixels.

    Attributes:
        count: number of lights found (≤ ``max_lights``).
        n_found: lights the merge produced before the ``max_lights`` cap.
        truncated: a cap (candidates, representatives or lights) was hit.
        valid: which rows are lights.
        direction: unit vectors (hdrjax convention), ``(K, 3)``: the energy-weighted mean
            of the light's pixels' directions, normalised. :attr:`azimuth`,
            :attr:`elevation` (degrees) and :attr:`angular_diameter` are derived on access.
        pixel: light centre, input pixels ``(K, 2)`` as ``(x, y)``: the energy-weighted
            mean of its pixel coordinates (columns unwrapped across the seam).
        peak_pixel: the light's brightest local maximum (the cluster's seed), ``(K, 2)``.
        peak_luminance: largest pixel luminance in the light (input resolution when the
            map was reduced by an integer factor, else working resolution).
        mean_luminance: solid-angle mean luminance over the light's pixels.
        colour: mean linear RGB over the light's pixels (``(K, 3)``).
        irradiance: ∑ RGB dω over the light's pixels (``(K, 3)``; normal-incidence
            irradiance from the light, for a directional light of the same colour).
        solid_angle: sr.
        area: pixels of the input image covered by the light.
        energy: ∑ L dω over the light's pixels.
        energy_share: ``energy`` over ∑ L dω of the whole map (finite pixels).
        n_samples: quasi-Monte-Carlo samples whose local maximum lies in the light.
        labels: ``(h, w)`` int32 label image at the working resolution (``-1`` = no light).
        samples: candidate samples' pixels ``(C, 2)`` (input pixels; padding rows are zero).
        sample_light: the light each candidate joined (``-1`` = none / padding).
        threshold: luminance threshold used (``inf`` when the map has no light to find).
        projection: ``"equirectangular"`` or ``"plane"`` (static).
        input_shape: ``(H, W)`` of the input map (static).
    """

    count: Int[Array, "*batch"]
    n_found: Int[Array, "*batch"]
    truncated: Bool[Array, "*batch"]
    valid: Bool[Array, "*batch K"]
    direction: Float[Array, "*batch K 3"]
    pixel: Float[Array, "*batch K 2"]
    peak_pixel: Float[Array, "*batch K 2"]
    peak_luminance: Float[Array, "*batch K"]
    mean_luminance: Float[Array, "*batch K"]
    colour: Float[Array, "*batch K 3"]
    irradiance: Float[Array, "*batch K 3"]
    solid_angle: Float[Array, "*batch K"]
    area: Float[Array, "*batch K"]
    energy: Float[Array, "*batch K"]
    energy_share: Float[Array, "*batch K"]
    n_samples: Int[Array, "*batch K"]
    labels: Int[Array, "*batch h w"]
    samples: Float[Array, "*batch C 2"]
    sample_light: Int[Array, "*batch C"]
    threshold: Float[Array, "*batch"]
    projection: str = eqx.field(static=True, default="equirectangular")
    input_shape: tuple[int, int] = eqx.field(static=True, default=(0, 0))

    @property
    def azimuth(self) -> Float[Array, "*batch K"]:
        """Degrees, 0 at the image centre and positive to the right (hdrjax convention; 0
        for padding and plain images)."""
        return jnp.where(self.valid, azimuth_elevation(self.direction)[0], 0.0)

    @property
    def elevation(self) -> Float[Array, "*batch K"]:
        """Degrees (0 for padding and plain images)."""
        return jnp.where(self.valid, azimuth_elevation(self.direction)[1], 0.0)

    @property
    def angular_diameter(self) -> Float[Array, "*batch K"]:
        """Degrees: the diameter of the disc with the light's solid angle."""
        c = jnp.clip(1 - self.solid_angle / (2 * math.pi), -1.0, 1.0)
        return 2 * jnp.degrees(jnp.arccos(c))

    def directions(self, convention: Convention = "hdrjax") -> Float[Array, "*batch K 3"]:
        """Light directions in a renderer's convention (see :mod:`hdrjax.lights._geometry`).

        ``"z_up"`` is also accepted: hdrjax directions with the up axis moved to +Z
        (:func:`~hdrjax.lights.to_z_up`). Padding rows stay zero.
        """
        if self.projection != "equirectangular":
            raise ValueError("directions: a plain image has no directions")
        if convention == "z_up":
            d = to_z_up(self.direction)
        else:
            d = convert_direction(self.direction, "hdrjax", convention)
        return jnp.where(self.valid[..., None], d, 0.0)

    def labels_at(self, shape: tuple[int, int] | None = None) -> np.ndarray:
        """The label image resampled (nearest) to ``shape`` (default: the input's ``(H, W)``)."""
        lab = _np(self.labels)
        if lab.ndim != 2:
            raise ValueError("labels_at: call it on one map's result, not a batch")
        h, w = self.input_shape if shape is None else shape
        ys = np.minimum((np.arange(h) + 0.5) * lab.shape[0] / h, lab.shape[0] - 1).astype(int)
        xs = np.minimum((np.arange(w) + 0.5) * lab.shape[1] / w, lab.shape[1] - 1).astype(int)
        return lab[ys[:, None], xs[None, :]]

    def to_records(self) -> list[dict[str, Any]]:
        """The lights of one map as a list of plain dicts (JSON-ready), largest energy first."""
        if _np(self.count).ndim != 0:
            raise ValueError("to_records: call it on one map's result, not a batch")
        out = []
        for k in range(int(self.count)):
            rec: dict[str, Any] = {
                "pixel": [float(v) for v in _np(self.pixel[k])],
                "peak_pixel": [float(v) for v in _np(self.peak_pixel[k])],
                "peak_luminance": float(self.peak_luminance[k]),
                "mean_luminance": float(self.mean_luminance[k]),
                "colour": [float(v) for v in _np(self.colour[k])],
                "irradiance": [float(v) for v in _np(self.irradiance[k])],
                "area_px": float(self.area[k]),
                "energy": float(self.energy[k]),
                "energy_share": float(self.energy_share[k]),
                "n_samples": int(self.n_samples[k]),
            }
            if self.projection == "equirectangular":
                rec = {
                    "direction": [float(v) for v in _np(self.direction[k])],
                    "azimuth_deg": float(self.azimuth[k]),
                    "elevation_deg": float(self.elevation[k]),
                    "solid_angle_sr": float(self.solid_angle[k]),
                    "angular_diameter_deg": float(self.angular_diameter[k]),
                    **rec,
                }
            out.append(rec)
        return out

    def to_json(self, **extra: Any) -> str:
        """JSON text: the conventions, the threshold and :meth:`to_records` (plus ``extra``)."""
        doc = {
            "projection": self.projection,
            "input_shape": list(self.input_shape),
            "convention": "hdrjax: Y-up, ahead -Z, right +X; az = 360*(x+0.5)/W - 180 "
            "(positive right), el = 90 - 180*(y+0.5)/H; "
            "d = (cos el sin az, sin el, -cos el cos az)",
            "threshold": _finite_or_none(float(self.threshold)),
            "count": int(self.count),
            "truncated": bool(self.truncated),
            **extra,
            "lights": self.to_records(),
        }
        return json.dumps(doc, indent=2)

    def _angles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:attr:`azimuth`, :attr:`elevation` and :attr:`angular_diameter` in NumPy, for
        the printed views (the formulas of :func:`~hdrjax.lights.azimuth_elevation`; eager
        JAX would compile a program per operation)."""
        d = _np(self.direction).astype(np.float64)
        az = np.degrees(np.arctan2(d[..., 0], -d[..., 2]))
        el = np.degrees(np.arctan2(d[..., 1], np.hypot(d[..., 0], d[..., 2])))
        c = np.clip(1 - _np(self.solid_angle) / (2 * math.pi), -1.0, 1.0)
        return az, el, 2 * np.degrees(np.arccos(c))

    def _where(self, k: int) -> str:
        """Light ``k``'s position: azimuth/elevation and width on a sphere, else pixels."""
        if self.projection == "equirectangular":
            az, el, diameter = (float(a[k]) for a in self._angles())
            return f"az {az:+.1f}°, el {el:+.1f}°, {diameter:.2g}° wide"
        x, y = (float(v) for v in _np(self.pixel[k]))
        return f"at x {x:.1f}, y {y:.1f} px"

    def __repr__(self) -> str:
        """``Lights(2 lights in an equirectangular 64×32 map: #1 az +36.0°, el +10.4°, 1.6°
        wide, 63 % of the energy; …)``: the first three lights of one map, or the counts of
        a batch."""
        from .. import _repr

        w, h = self.input_shape[1], self.input_shape[0]
        kind = f"{self.projection} {w}×{h} map"
        where = f"{'an' if self.projection[0] in 'aeiou' else 'a'} {kind}"
        if not _repr.concrete(self.count):
            return f"Lights(traced, {where})"
        count = _np(self.count)
        if count.ndim:
            return f"Lights(batch {count.shape}: {_repr.value(count)} lights, {kind}s)"
        n, share = int(count), _np(self.energy_share)
        shown = [
            f"#{k + 1} {self._where(k)}, {100 * share[k]:.3g} % of the energy"
            for k in range(min(n, 3))
        ]
        more = [f"… {n - 3} more"] if n > 3 else []
        cap = f" (capped; {int(self.n_found)} found)" if bool(self.truncated) else ""
        lights = "1 light" if n == 1 else f"{n} lights"
        return (
            f"Lights({lights}{cap} in {where}" + (": " if n else "") + "; ".join(shown + more) + ")"
        )

    def overlay(self, size: int = 256) -> np.ndarray:
        """``(h, w, 3)`` uint8 picture of one map's lights, at most ``size`` pixels wide:
        each light's region in its own colour on dark grey (on a panorama, lighter lines mark
        the horizon and azimuth 0), a white cross at its centre (:attr:`pixel`). The map
        itself is not part of the result: :func:`hdrjax.lights.plot_lights` draws the
        lights over it."""
        lab = _np(self.labels)
        if lab.ndim != 2:
            raise ValueError("overlay: call it on one map's result, not a batch")
        H, W = self.input_shape if self.input_shape != (0, 0) else lab.shape
        f = min(1.0, size / W)
        h, w = max(1, round(H * f)), max(1, round(W * f))
        at, centres = self.labels_at((h, w)), _np(self.pixel)
        palette = np.array(_PALETTE, np.uint8)
        out = np.full((h, w, 3), 40, np.uint8)
        if self.projection == "equirectangular":  # the horizon and straight ahead (az 0)
            out[h // 2, :], out[:, w // 2] = 80, 80
        out = np.where(at[..., None] >= 0, palette[np.maximum(at, 0) % len(palette)], out)
        out = out.astype(np.uint8)
        arm = max(2, w // 128)
        for k in range(int(self.count)):
            x, y = centres[k]
            cx = int(np.clip((x + 0.5) * w / W - 0.5, 0, w - 1))
            cy = int(np.clip((y + 0.5) * h / H - 0.5, 0, h - 1))
            out[cy, max(0, cx - arm) : cx + arm + 1] = 255
            out[max(0, cy - arm) : cy + arm + 1, cx] = 255
        return out

    def _repr_html_(self) -> str:
        """A notebook's view: the lights' regions and centres (:meth:`overlay`) beside a
        table of the lights (position, luminance, colour, share of the energy)."""
        from .. import _repr

        if not _repr.concrete(self.count) or _np(self.count).ndim:
            return _repr.preformatted(repr(self))
        sphere = self.projection == "equirectangular"
        head = ["light"]
        head += ["azimuth °", "elevation °", "diameter °", "solid angle sr"] if sphere else []
        head += ["x px", "y px", "peak luminance", "mean luminance", "colour", "energy %"]
        rows = []
        az, el, diameter = self._angles()
        a = {n: _np(getattr(self, n)) for n in _SHOWN}
        for k in range(int(self.count)):
            row = [f"#{k + 1}"]
            if sphere:
                row += [f"{az[k]:+.1f}", f"{el[k]:+.1f}", f"{diameter[k]:.3g}"]
                row += [f"{a['solid_angle'][k]:.3g}"]
            row += [f"{v:.1f}" for v in a["pixel"][k]]
            row += [_repr.value(a[n][k]) for n in ("peak_luminance", "mean_luminance", "colour")]
            row += [f"{100 * a['energy_share'][k]:.3g}"]
            rows.append(row)
        w, h = self.input_shape[1], self.input_shape[0]
        title = f"Lights: {int(self.count)} in a {self.projection} {w}×{h} map"
        note = (
            f"threshold {_repr.value(self.threshold)} (the map's units); luminance in the "
            "map's units; energy = Σ L dω"
            + (f"; capped: {int(self.n_found)} found" if bool(self.truncated) else "")
        )
        image = _repr.thumbnail(self.overlay()) if self.labels.size else ""
        return _repr.view(title, _repr.table(rows, head), image=image, note=note)


_SHOWN = ("solid_angle", "pixel", "peak_luminance", "mean_luminance", "colour", "energy_share")
"""The fields of each light that :meth:`Lights._repr_html_` tabulates."""

_PALETTE = (
    (230, 159, 0),
    (86, 180, 233),
    (0, 158, 115),
    (240, 228, 66),
    (0, 114, 178),
    (213, 94, 0),
    (204, 121, 167),
)
"""Region colours of :meth:`Lights.overlay` (Okabe and Ito's colour-blind-safe palette,
without its black)."""


def _finite_or_none(v: float) -> float | None:
    return v if math.isfinite(v) else None


class MedianCutLights(eqx.Module):
    """Debevec's median-cut lights: ``2**levels`` regions of equal energy, one light each.

    Attributes:
        direction: energy centroid of each region (hdrjax convention), ``(N, 3)``
            (:attr:`azimuth`, :attr:`elevation` and :attr:`pixel` are derived on access).
        irradiance: ∑ RGB dω over the region (the light's colour × intensity), ``(N, 3)``.
        energy: ∑ L dω over the region.
        energy_share: ``energy`` over the map's total.
        region: ``(x0, y0, x1, y1)`` half-open pixel box at the working resolution.
        input_shape: ``(H, W)`` of the input map (static).
    """

    __repr__ = _repr.fields_repr
    _repr_html_ = _repr.fields_html

    direction: Float[Array, "*batch N 3"]
    irradiance: Float[Array, "*batch N 3"]
    energy: Float[Array, "*batch N"]
    energy_share: Float[Array, "*batch N"]
    region: Int[Array, "*batch N 4"]
    input_shape: tuple[int, int] = eqx.field(static=True, default=(0, 0))

    @property
    def azimuth(self) -> Float[Array, "*batch N"]:
        """Degrees, 0 at the image centre and positive to the right (hdrjax convention)."""
        return azimuth_elevation(self.direction)[0]

    @property
    def elevation(self) -> Float[Array, "*batch N"]:
        """Degrees."""
        return azimuth_elevation(self.direction)[1]

    @property
    def pixel(self) -> Float[Array, "*batch N 2"]:
        """The lights' positions in input pixels ``(x, y)``."""
        h, w = self.input_shape
        u, v = jnp.moveaxis(direction_to_uv(self.direction), -1, 0)
        return jnp.stack([u * w - 0.5, v * h - 0.5], axis=-1)

    def to_records(self) -> list[dict[str, Any]]:
        """One map's lights as JSON-ready dicts, in region order."""
        if _np(self.energy).ndim != 1:
            raise ValueError("to_records: call it on one map's result, not a batch")
        return [
            {
                "direction": [float(v) for v in _np(self.direction[k])],
                "azimuth_deg": float(self.azimuth[k]),
                "elevation_deg": float(self.elevation[k]),
                "pixel": [float(v) for v in _np(self.pixel[k])],
                "irradiance": [float(v) for v in _np(self.irradiance[k])],
                "energy": float(self.energy[k]),
                "energy_share": float(self.energy_share[k]),
            }
            for k in range(self.energy.shape[-1])
        ]


__all__ = ["Lights", "MedianCutLights"]
