"""Measurement on layered images: distances between pixels, readouts, region statistics.

NumPy side, never jitted (Birukov et al. 2022, section 3.2).

Pixel coordinates are ``(x, y)`` = (column, row) of the image array, the top-left pixel
being ``(0, 0)``; a point is the pixel that contains it (``floor``). Coordinates given
at a user scale (``scale_percent``, the displayed size in percent of the original pixel
grid, as in that paper's distance dialog) are divided by ``scale_percent / 100`` first.

- **3D distance**: when the image has a ``position`` layer, the distance between the scene
  points behind the two pixels, ``|P(b) − P(a)|``, in scene units (the EXR attribute
  ``positionUnit`` when present, else ``"scene units"``).
- **2D distance**: otherwise (or when asked), the distance on the image plane: in metres
  when the image is a virtual sensor with a known physical size (``sensor_size``, width
  and height in metres; the pixel pitch is ``sensor_size / (W, H)``), else in pixels of
  the original grid. The result says which mode was used and why.
"""

import dataclasses
import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..io._atomic import atomic_write_bytes
from ..layers import _model as M
from ..layers._errors import ReadError


@dataclasses.dataclass(frozen=True)
class Distance:
    """The result of :func:`distance`.

    Attributes:
        value: the distance, in ``unit``.
        unit: ``"m"`` (2D on a sensor of known size), ``"px"`` (2D, original pixels), or the
            position layer's unit (3D).
        mode: ``"3d"`` or ``"2d"``.
        a: first pixel, ``(x, y)`` in the original pixel grid.
        b: second pixel.
        point_a: scene point behind ``a`` (3D mode), else ``None``.
        point_b: scene point behind ``b`` (3D mode), else ``None``.
        note: why this mode was used (e.g. "no 'position' layer: 2D distance").
    """

    value: float
    unit: str
    mode: str
    a: tuple[int, int]
    b: tuple[int, int]
    point_a: tuple[float, float, float] | None = None
    point_b: tuple[float, float, float] | None = None
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return dataclasses.asdict(self)


def _pixel(
    img: M.LayeredImage, xy: Sequence[float], scale_percent: float, what: str
) -> tuple[int, int]:
    if not (scale_percent > 0 and math.isfinite(scale_percent)):
        raise ValueError(f"scale_percent must be a positive number, got {scale_percent}")
    try:
        x, y = (float(v) for v in xy)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: expected (x, y), got {xy!r}") from None
    f = 100.0 / scale_percent
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"{what}: coordinates must be finite, got {xy!r}")
    px, py = int(math.floor(x * f)), int(math.floor(y * f))
    if not (0 <= px < img.width and 0 <= py < img.height):
        raise ValueError(
            f"{img.name}: {what} ({x:g}, {y:g}) at scale {scale_percent:g}% is pixel "
            f"({px}, {py}), outside the {img.width} x {img.height} image"
        )
    return px, py


def distance(
    img: M.LayeredImage,
    a: Sequence[float],
    b: Sequence[float],
    *,
    mode: str = "auto",
    scale_percent: float = 100.0,
) -> Distance:
    """Distance between the pixels ``a`` and ``b`` (see the module doc).

    Args:
        img: the layered image.
        a: ``(x, y)`` of the first pixel, at ``scale_percent``.
        b: ``(x, y)`` of the second pixel.
        mode: ``"auto"`` (3D when there is a position layer, else 2D), ``"3d"`` or ``"2d"``
            (forced 2D even when positions exist).
        scale_percent: the user scale of the coordinate axes, in percent of the original
            pixel grid (200 means the coordinates were picked on a 2x enlarged view).

    Returns:
        A :class:`Distance` saying the value, unit and mode.

    Raises:
        MissingLayerError: ``mode="3d"`` and there is no ``position`` layer.
        ValueError: a pixel is outside the image, or has no scene point (NaN position)
            in 3D mode.
    """
    if mode not in ("auto", "3d", "2d"):
        raise ValueError(f"mode must be 'auto', '3d' or '2d', got {mode!r}")
    pa = _pixel(img, a, scale_percent, "point a")
    pb = _pixel(img, b, scale_percent, "point b")
    has_pos = img.has_layer(M.POSITION)
    if mode == "3d" and not has_pos:
        img.layer(M.POSITION)  # raises MissingLayerError naming the file and the layers
    if mode != "2d" and has_pos:
        pos = img.layer(M.POSITION)
        qa = pos[pa[1], pa[0]].astype(np.float64)
        qb = pos[pb[1], pb[0]].astype(np.float64)
        bad = [p for p, q in ((pa, qa), (pb, qb)) if not np.all(np.isfinite(q))]
        if bad and mode == "3d":
            raise ValueError(f"{img.name}: pixel {bad[0]} has no scene point (position is NaN)")
        if not bad:
            unit = str(img.attributes.get("positionUnit", "scene units"))
            return Distance(
                value=float(np.linalg.norm(qb - qa)),
                unit=unit,
                mode="3d",
                a=pa,
                b=pb,
                point_a=tuple(float(v) for v in qa),
                point_b=tuple(float(v) for v in qb),
                note="distance between the scene points behind the pixels",
            )
        note = f"pixel {bad[0]} has no scene point: 2D distance"
    elif mode == "2d" and has_pos:
        note = "2D distance (forced; the image has a 'position' layer)"
    else:
        note = "no 'position' layer: 2D distance"
    dx, dy = pb[0] - pa[0], pb[1] - pa[1]
    if img.sensor_size is not None:
        pw = img.sensor_size[0] / img.width
        ph = img.sensor_size[1] / img.height
        return Distance(
            value=math.hypot(dx * pw, dy * ph),
            unit="m",
            mode="2d",
            a=pa,
            b=pb,
            note=note + f" on a {img.sensor_size[0]:g} m x {img.sensor_size[1]:g} m sensor",
        )
    return Distance(
        value=math.hypot(dx, dy),
        unit="px",
        mode="2d",
        a=pa,
        b=pb,
        note=note + " in pixels (sensor size unknown)",
    )


def _quantity_plane(img: M.LayeredImage) -> np.ndarray:
    """The per-pixel value of the image's quantity: Y for RGB / Y / YC images."""
    if img.kind in ("rgb", "y", "ych"):
        return img.luminance()
    if img.image.shape[2] == 1:
        return img.image[:, :, 0]
    raise ValueError(
        f"{img.name}: no single quantity per pixel (channels {', '.join(img.channels)})"
    )


def readout(
    img: M.LayeredImage, xy: Sequence[float], *, scale_percent: float = 100.0
) -> dict[str, Any]:
    """Everything known about one pixel.

    Returns:
        A dict with ``pixel`` ``(x, y)``, ``channels`` (name → value), ``value`` (the
        quantity: luminance Y for RGB, in ``unit``), ``quantity``, ``unit``, and ``error``,
        ``hits``, ``position`` ``(X, Y, Z)``, ``object_id`` — each ``None`` when the layer
        is absent.
    """
    x, y = _pixel(img, xy, scale_percent, "pixel")
    px = img.image[y, x]
    try:
        value: float | None = float(_quantity_plane(img)[y, x])
    except ValueError:
        value = None

    def layer_value(key: str) -> Any:
        if not img.has_layer(key):
            return None
        v = np.asarray(img.layers[key])[y, x]
        if np.ndim(v) == 0:
            return int(v) if np.issubdtype(np.asarray(v).dtype, np.integer) else float(v)
        return tuple(float(t) for t in v)

    return {
        "pixel": (x, y),
        "channels": {c: float(v) for c, v in zip(img.channels, px, strict=True)},
        "value": value,
        "quantity": img.quantity,
        "unit": img.unit,
        "error": layer_value(M.ERROR),
        "hits": layer_value(M.HITS),
        "position": layer_value(M.POSITION),
        "object_id": layer_value(M.OBJECT_ID),
    }


@dataclasses.dataclass(frozen=True)
class Region:
    """A region of the pixel grid: a rectangle or a polygon, in pixel coordinates.

    A pixel belongs to the region when its centre ``(x + 0.5, y + 0.5)`` is inside
    (even-odd rule for polygons; rectangles are ``x0 <= x < x1``, ``y0 <= y < y1`` in
    pixel-edge coordinates).

    Attributes:
        kind: ``"rect"`` or ``"polygon"``.
        points: ``((x0, y0), (x1, y1))`` for a rectangle, the vertices for a polygon.
    """

    kind: str
    points: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        pts = tuple((float(x), float(y)) for x, y in self.points)
        object.__setattr__(self, "points", pts)
        if not all(math.isfinite(v) for p in pts for v in p):
            raise ValueError("region coordinates must be finite")
        if self.kind == "rect":
            if len(pts) != 2:
                raise ValueError("a rectangle is two corners ((x0, y0), (x1, y1))")
        elif self.kind == "polygon":
            if len(pts) < 3:
                raise ValueError("a polygon needs at least 3 vertices")
        else:
            raise ValueError(f"region kind must be 'rect' or 'polygon', got {self.kind!r}")

    @classmethod
    def rect(cls, x0: float, y0: float, x1: float, y1: float) -> "Region":
        """The rectangle with corners ``(x0, y0)`` and ``(x1, y1)`` (pixel-edge coords)."""
        return cls("rect", ((min(x0, x1), min(y0, y1)), (max(x0, x1), max(y0, y1))))

    @classmethod
    def polygon(cls, vertices: Sequence[Sequence[float]]) -> "Region":
        """The polygon through ``vertices`` (closed automatically)."""
        return cls("polygon", tuple((float(x), float(y)) for x, y in vertices))

    def mask(self, height: int, width: int) -> np.ndarray:
        """``(height, width)`` bool mask of the pixels inside."""
        cy = np.arange(height, dtype=np.float64)[:, None] + 0.5
        cx = np.arange(width, dtype=np.float64)[None, :] + 0.5
        if self.kind == "rect":
            (x0, y0), (x1, y1) = self.points
            return (cx >= x0) & (cx < x1) & (cy >= y0) & (cy < y1)
        inside = np.zeros((height, width), bool)
        pts = self.points
        for (xa, ya), (xb, yb) in zip(pts, pts[1:] + pts[:1], strict=True):
            if ya == yb:
                continue
            crosses = (ya > cy) != (yb > cy)  # (H, 1)
            x_at = xa + (cy - ya) * (xb - xa) / (yb - ya)  # (H, 1)
            inside ^= crosses & (cx < x_at)
        return inside

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return {"kind": self.kind, "points": [list(p) for p in self.points]}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Region":
        """Inverse of :meth:`to_dict` (also accepts the output of :func:`region_json`)."""
        try:
            return cls(str(d["kind"]), tuple((float(x), float(y)) for x, y in d["points"]))
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError(f"not a region description ({e})") from None


def region_stats(img: M.LayeredImage, region: Region) -> dict[str, Any]:
    """Pixel statistics of a region.

    Returns:
        A dict with ``pixels`` (count), ``mean``, ``min``, ``max`` of the quantity
        (luminance Y for RGB) ignoring NaN, ``quantity``, ``unit``, ``mean_error`` (or
        ``None`` without an ``error`` layer) and ``total_hits`` (or ``None`` without a
        ``hits`` layer).

    Raises:
        ValueError: the region holds no pixel of the image.
    """
    m = region.mask(img.height, img.width)
    n = int(m.sum())
    if n == 0:
        raise ValueError(f"{img.name}: the region contains no pixel of the image")
    vals = _quantity_plane(img)[m].astype(np.float64)
    finite = vals[np.isfinite(vals)]
    out: dict[str, Any] = {
        "pixels": n,
        "quantity": img.quantity,
        "unit": img.unit,
        "mean": float(finite.mean()) if finite.size else None,
        "min": float(finite.min()) if finite.size else None,
        "max": float(finite.max()) if finite.size else None,
        "mean_error": None,
        "total_hits": None,
    }
    if img.has_layer(M.ERROR):
        e = np.asarray(img.layers[M.ERROR])[m].astype(np.float64)
        e = e[np.isfinite(e)]
        out["mean_error"] = float(e.mean()) if e.size else None
    if img.has_layer(M.HITS):
        h = np.asarray(img.layers[M.HITS])[m]
        total = h.astype(np.int64).sum() if np.issubdtype(h.dtype, np.integer) else np.nansum(h)
        out["total_hits"] = int(total) if np.issubdtype(h.dtype, np.integer) else float(total)
    return out


def region_json(img: M.LayeredImage, region: Region) -> str:
    """The region and its statistics as JSON, for a simulation program to read back.

    The document is ``{"file": ..., "image_size": [W, H], "data_window": ..., "region":
    {"kind": ..., "points": ...}, "stats": {...}}`` (see :func:`region_stats`).
    """
    doc = {
        "file": str(img.path) if img.path is not None else None,
        "image_size": [img.width, img.height],
        "data_window": list(img.data_window) if img.data_window is not None else None,
        "region": region.to_dict(),
        "stats": region_stats(img, region),
    }
    return json.dumps(doc, indent=2)


def save_region(
    path: str | os.PathLike, img: M.LayeredImage, region: Region, *, overwrite: bool = True
) -> Path:
    """Write :func:`region_json` to ``path`` atomically."""
    return atomic_write_bytes(path, (region_json(img, region) + "\n").encode(), overwrite=overwrite)


def load_region(path: str | os.PathLike) -> Region:
    """Read a region written by :func:`save_region` (or a bare ``Region.to_dict()``).

    Raises:
        ReadError: the file is not JSON or holds no region.
    """
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
        return Region.from_dict(doc.get("region", doc))
    except (ValueError, AttributeError) as e:
        raise ReadError(f"{path.name}: not a region file ({e})") from None


__all__ = [
    "Distance",
    "Region",
    "distance",
    "load_region",
    "readout",
    "region_json",
    "region_stats",
    "save_region",
]
