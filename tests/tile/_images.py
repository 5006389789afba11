"""Small test images shared by the tile tests (cornell_box crops with bad pixels)."""

import functools

import numpy as np

from ..conftest import DATA


@functools.cache
def cornell() -> np.ndarray:
    """data/cornell_box.exr as float32 linear RGB (512×512×3), read once."""
    import hdrjax.io as hio

    return np.asarray(hio.read(DATA / "cornell_box.exr").rgb(), np.float32)


def crop(h: int, w: int, *, bad: bool = True) -> np.ndarray:
    """An ``h×w`` RGB crop of the Cornell box with, if ``bad``, NaN/Inf/negative pixels at
    an image edge, a corner and inside."""
    x = cornell()[100 : 100 + h, 150 : 150 + w].copy()
    if bad:
        x[0, 3, 1] = np.nan
        x[h // 2, w // 3] = np.nan
        x[h - 1, w - 1, 0] = np.nan
        x[h // 3, w // 2, 2] = np.inf
        x[h // 4, w - 2] = -0.5
    return x
