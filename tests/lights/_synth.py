"""Synthetic environment maps with known lights (discs of given direction, size and colour)."""

import math
from pathlib import Path

import numpy as np

from tests.conftest import DATA, shared_file

H, W = 256, 512
"""Size of every synthetic map (one compiled plan serves all of them)."""
PIXEL_DEG = 360.0 / W
"""Angle of one pixel at the equator, degrees."""


def pixel_directions(h: int = H, w: int = W) -> np.ndarray:
    """hdrjax directions of the pixel centres, float64 ``(h, w, 3)``."""
    az = np.radians(360.0 * (np.arange(w) + 0.5) / w - 180.0)[None, :]
    el = np.radians(90.0 - 180.0 * (np.arange(h) + 0.5) / h)[:, None]
    return np.stack(
        np.broadcast_arrays(np.cos(el) * np.sin(az), np.sin(el), -np.cos(el) * np.cos(az)), -1
    )


def direction(az_deg: float, el_deg: float) -> np.ndarray:
    az, el = math.radians(az_deg), math.radians(el_deg)
    return np.array([math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)])


def pixel_solid_angles(h: int = H, w: int = W) -> np.ndarray:
    """Exact solid angle of each pixel (sr), ``(h, w)``."""
    theta = np.pi * np.arange(h + 1) / h
    band = 2 * np.pi * (np.cos(theta[:-1]) - np.cos(theta[1:])) / w
    return np.repeat(band[:, None], w, axis=1)


def disc_map(
    lights: list[tuple[float, float, float, tuple[float, float, float]]],
    background: float | tuple[float, float, float] = 0.05,
    h: int = H,
    w: int = W,
) -> tuple[np.ndarray, list[dict]]:
    """A map with uniform discs ``(az°, el°, radius°, rgb)`` on a constant background.

    Returns the float32 map and, per disc, its pixel mask, the energy centroid direction of
    its pixels, its pixelised solid angle and its share of ∑ L dω.
    """
    d = pixel_directions(h, w)
    img = np.empty((h, w, 3))
    img[:] = background
    dw = pixel_solid_angles(h, w)
    truth = []
    for az, el, radius, rgb in lights:
        c = direction(az, el)
        mask = np.degrees(np.arccos(np.clip(d @ c, -1, 1))) <= radius
        img[mask] = rgb
        truth.append({"mask": mask, "dir": c, "rgb": np.array(rgb, float)})
    lum = img @ np.array([0.2126, 0.7152, 0.0722])
    total = (lum * dw).sum()
    for t in truth:
        e = lum * dw * t["mask"]
        v = (d * e[..., None]).sum((0, 1))
        t["centroid"] = v / np.linalg.norm(v)
        t["solid_angle"] = float((dw * t["mask"]).sum())
        t["share"] = float(e.sum() / total)
    return img.astype(np.float32), truth


def angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    c = np.linalg.norm(np.cross(a, b))
    return float(np.degrees(np.arctan2(c, np.dot(a, b))))


def rooitou() -> Path:
    """The shipped CC0 map (data/rooitou_park_1k.hdr), else the shared copy."""
    p = DATA / "rooitou_park_1k.hdr"
    return p if p.exists() else shared_file("rooitou_park_1k.hdr")
