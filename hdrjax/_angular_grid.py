"""The angular grid of a panorama or view drawn over its display image (matplotlib; NumPy
side, never jitted). Public through :mod:`hdrjax.plot`.

Lines of constant azimuth and elevation every ``step_deg`` degrees, labelled in degrees, as
lighting-simulation viewers draw them over a rendered fisheye or panorama. Directions and
pixel coordinates follow :mod:`hdrjax.panorama` (Y up, −Z ahead, azimuth positive to the
right, elevation positive up; pixel ``i`` spans ``[i, i + 1)``). Each line is the exact
image of its circle on the sphere, sampled every quarter degree and drawn as a polyline
(broken where it leaves the image or crosses the equirectangular seam).
"""

import math
from typing import Any

import numpy as np

PROJECTIONS = ("equirectangular", "fisheye", "perspective")
_SAMPLES_PER_DEG = 4


def _dirs(az_deg: np.ndarray, el_deg: np.ndarray) -> np.ndarray:
    az, el = np.radians(az_deg), np.radians(el_deg)
    ce = np.cos(el)
    return np.stack([ce * np.sin(az), np.sin(el), -ce * np.cos(az)], axis=-1)


def _basis(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Rows: the camera's right, up and forward vectors, as the views are sampled."""
    from .panorama import camera_basis

    return np.asarray(camera_basis(yaw, pitch, roll), np.float64)


def project(
    d: np.ndarray,
    height: int,
    width: int,
    *,
    projection: str = "equirectangular",
    fov_deg: float = 180.0,
    yaw_deg: float = 0.0,
    pitch_deg: float = 0.0,
    roll_deg: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Continuous pixel coordinates ``(x, y)`` of unit directions ``d`` (``(..., 3)``) in an
    image of the given projection; NaN where the direction is not in the image.

    ``fov_deg``: the fisheye's image circle (equidistant lens, diameter ``min(H, W)``), or the
    perspective view's horizontal field; ``yaw_deg``, ``pitch_deg``, ``roll_deg``: the
    perspective view's orientation (:func:`hdrjax.panorama.equirect_to_perspective`).
    """
    d = np.asarray(d, np.float64)
    if projection == "equirectangular":
        az = np.arctan2(d[..., 0], -d[..., 2])
        el = np.arcsin(np.clip(d[..., 1], -1.0, 1.0))
        return (az / (2 * math.pi) + 0.5) * width, (0.5 - el / math.pi) * height
    if projection == "fisheye":
        theta = np.arccos(np.clip(-d[..., 2], -1.0, 1.0))
        psi = np.arctan2(d[..., 1], d[..., 0])
        half = math.radians(fov_deg) / 2.0
        r = theta / half * (min(height, width) / 2.0)
        x = width / 2.0 + r * np.cos(psi)
        y = height / 2.0 - r * np.sin(psi)
        out = theta > half
    elif projection == "perspective":
        c = d @ _basis(yaw_deg, pitch_deg, roll_deg).T
        focal = (width / 2.0) / math.tan(math.radians(fov_deg) / 2.0)
        ahead = c[..., 2] > 1e-6
        depth = np.where(ahead, c[..., 2], 1.0)
        x = width / 2.0 + focal * c[..., 0] / depth
        y = height / 2.0 - focal * c[..., 1] / depth
        out = ~ahead
    else:
        raise ValueError(
            f"projection: expected one of {', '.join(PROJECTIONS)}, got {projection!r}"
        )
    out = out | (x < 0) | (x > width) | (y < 0) | (y > height)
    return np.where(out, np.nan, x), np.where(out, np.nan, y)


def grid_lines(
    height: int, width: int, *, step_deg: float = 30.0, **view: Any
) -> list[tuple[str, float, np.ndarray, np.ndarray]]:
    """The grid's polylines: ``(kind, degrees, x, y)`` with ``kind`` ``"azimuth"`` or
    ``"elevation"``, pixel coordinates with NaN breaks (``view``: :func:`project`'s
    keywords)."""
    if not (step_deg > 0 and math.isfinite(step_deg) and step_deg <= 90):
        raise ValueError(f"step_deg: expected degrees in (0, 90], got {step_deg!r}")
    lines = []
    n_el = int(math.floor(90 / step_deg + 1e-9))
    elevations = [k * step_deg for k in range(-n_el, n_el + 1) if abs(k * step_deg) < 90]
    azimuths = [k * step_deg for k in range(int(math.ceil(-180 / step_deg - 1e-9)), 0)]
    azimuths += [k * step_deg for k in range(int(math.floor(180 / step_deg - 1e-9)) + 1)]
    az_all = np.linspace(-180.0, 180.0, 360 * _SAMPLES_PER_DEG + 1)
    el_all = np.linspace(-90.0, 90.0, 180 * _SAMPLES_PER_DEG + 1)
    for el in elevations:
        lines.append(
            (
                "elevation",
                el,
                *project(_dirs(az_all, np.full_like(az_all, el)), height, width, **view),
            )
        )
    for az in azimuths:
        lines.append(
            (
                "azimuth",
                az,
                *project(_dirs(np.full_like(el_all, az), el_all), height, width, **view),
            )
        )
    out = []
    for kind, deg, x, y in lines:
        # break the polyline where it jumps (the equirectangular seam)
        jump = np.abs(np.diff(x)) > width / 2
        if np.any(jump):
            x = np.insert(x, np.nonzero(jump)[0] + 1, np.nan)
            y = np.insert(y, np.nonzero(jump)[0] + 1, np.nan)
        if np.any(np.isfinite(x)):
            out.append((kind, float(deg), x, y))
    return out


def _label(deg: float) -> str:
    v = round(deg, 6)
    text = f"{v:g}°"
    return text.replace("-", "\u2212")


def angular_grid(
    ax: Any,
    height: int,
    width: int,
    *,
    projection: str = "equirectangular",
    step_deg: float = 30.0,
    fov_deg: float = 180.0,
    yaw_deg: float = 0.0,
    pitch_deg: float = 0.0,
    roll_deg: float = 0.0,
    color: Any = "white",
    linewidth: float = 0.8,
    labels: bool = True,
    fontsize: float | None = None,
) -> list[Any]:
    """Draw the angular grid of a ``height × width`` image onto ``ax`` (module docstring).

    ``ax`` shows the image with ``imshow``'s default extent (pixel ``i`` centred on ``i``),
    so the grid's pixel coordinates are shifted by half a pixel. Azimuth lines (gid
    ``"azimuth"``) and elevation lines (gid ``"elevation"``) every ``step_deg`` degrees;
    with ``labels``, each elevation is written where its line crosses the azimuth line
    nearest the view's centre and each azimuth where its line crosses the elevation line
    nearest the centre (the horizon for panoramas and fisheyes), in degrees with a dark
    outline so that they read on any background; a label that would overlap one already
    placed is left out.

    Args:
        ax: a matplotlib Axes showing the image.
        height, width: the image's size in pixels.
        projection: ``"equirectangular"``, ``"fisheye"`` (equidistant, looking along −Z) or
            ``"perspective"``.
        step_deg: degrees between lines, in (0, 90].
        fov_deg: the fisheye's image circle or the perspective view's horizontal field.
        yaw_deg, pitch_deg, roll_deg: the perspective view's orientation.
        color, linewidth: of the lines and labels.
        labels: write the degrees.
        fontsize: label size in points (default: from the image size).

    Returns:
        The artists drawn (lines, then labels).
    """
    import matplotlib.patheffects as pe

    view = dict(projection=projection, fov_deg=fov_deg, yaw_deg=yaw_deg)
    view.update(pitch_deg=pitch_deg, roll_deg=roll_deg)
    artists = []
    for kind, deg, x, y in grid_lines(height, width, step_deg=step_deg, **view):
        width_k = linewidth * (1.6 if deg == 0 else 1.0)
        (ln,) = ax.plot(x - 0.5, y - 0.5, color=color, lw=width_k, alpha=0.8, gid=kind)
        artists.append(ln)
    if not labels:
        return artists
    if fontsize is None:
        fontsize = float(np.clip(min(height, width) / 28.0, 5.0, 11.0))
    outline = [pe.withStroke(linewidth=2, foreground="black")]
    # labels sit on the grid line nearest the view's centre (a crossing of two lines)
    centre_az = step_deg * round(yaw_deg / step_deg) if projection == "perspective" else 0.0
    centre_el = step_deg * round(pitch_deg / step_deg) if projection == "perspective" else 0.0
    # a label that would overlap one already placed is left out (in screen pixels)
    px_per_pt = ax.figure.dpi / 72.0
    placed: list[tuple[float, float, float, float]] = []
    for kind, deg, _, _ in grid_lines(height, width, step_deg=step_deg, **view):
        az, el = (deg, centre_el) if kind == "azimuth" else (centre_az, deg)
        if kind == "elevation" and deg == centre_el:
            continue  # the crossing of the two central lines is labelled once, by azimuth
        x, y = project(_dirs(np.array(az), np.array(el)), height, width, **view)
        if not (np.isfinite(x) and np.isfinite(y)):
            continue
        text = _label(deg)
        sx, sy = ax.transData.transform((float(x) - 0.5, float(y) - 0.5))
        box = (
            sx,
            sy,
            sx + (0.65 * len(text) + 0.6) * fontsize * px_per_pt,
            sy + 1.3 * fontsize * px_per_pt,
        )
        if any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in placed):
            continue
        placed.append(box)
        txt = ax.text(
            float(x) - 0.5 + fontsize * 0.3,
            float(y) - 0.5 - fontsize * 0.3,
            text,
            color=color,
            fontsize=fontsize,
            ha="left",
            va="bottom",
            gid=f"{kind}_label",
            path_effects=outline,
            clip_on=True,
        )
        artists.append(txt)
    return artists


def with_angular_grid(image: Any, **options: Any) -> np.ndarray:
    """A display image (sRGB, ``(H, W, 3)`` in [0, 1]) with its angular grid drawn over it
    (:func:`angular_grid`'s options), at the image's own size; returns float32 sRGB in
    [0, 1]."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    img = np.asarray(image, np.float32)
    if img.ndim != 3 or img.shape[-1] != 3 or 0 in img.shape:
        raise ValueError(f"image: expected a display image (H, W, 3), got shape {img.shape}")
    h, w = img.shape[:2]
    dpi = 100.0
    fig = Figure(figsize=(w / dpi, h / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.imshow(np.clip(np.nan_to_num(img), 0.0, 1.0), interpolation="nearest")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_axis_off()
    angular_grid(ax, h, w, **options)
    canvas.draw()
    out = np.asarray(canvas.buffer_rgba())[..., :3].astype(np.float32) / 255.0
    # the canvas rounds W/dpi·dpi: crop or pad by the last row/column to the image's size
    out = out[:h, :w]
    if out.shape[:2] != (h, w):
        out = np.pad(out, ((0, h - out.shape[0]), (0, w - out.shape[1]), (0, 0)), mode="edge")
    return out


__all__ = ["PROJECTIONS", "angular_grid", "grid_lines", "project", "with_angular_grid"]
