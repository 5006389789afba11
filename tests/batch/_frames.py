"""Small test sequences: crops of a real environment map, panned and scaled per frame."""

from pathlib import Path

import numpy as np

from hdrjax import io as hio

from ..conftest import DATA

H, W = 32, 64


def frame(i: int) -> np.ndarray:
    """Frame ``i``: a 32 × 64 crop (every 8th pixel) of data/venice_sunset_1k.hdr, panned
    by ``16 i`` columns and scaled by ``1 + 0.25 i``."""
    rgb = hio.read(DATA / "venice_sunset_1k.hdr", sidecars=False).rgb()
    crop = rgb[64 : 64 + 8 * H : 8, 16 * i : 16 * i + 8 * W : 8]
    return np.ascontiguousarray(crop * np.float32(1.0 + 0.25 * i), np.float32)


def write_sequence(folder: Path, n: int, ext: str = ".exr") -> list[Path]:
    """``n`` frames ``frame_000<ext>``, ``frame_001<ext>``, …"""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for i in range(n):
        p = folder / f"frame_{i:03d}{ext}"
        hio.write(p, frame(i))
        paths.append(p)
    return paths
