"""Edge handling and row-strip scheduling shared by the filters.

Edge modes use SciPy's names (``scipy.ndimage``): for a row ``a b c d``,

- ``"nearest"`` (replicate, the default): ``a a | a b c d | d d``
- ``"reflect"`` (half-sample symmetric):  ``b a | a b c d | d c``
- ``"mirror"`` (whole-sample symmetric):  ``c b | a b c d | c b``
- ``"wrap"`` (periodic):                  ``c d | a b c d | a b``

Filters run over row strips of ``R`` output rows: each strip gathers its ``R + 2r`` input rows
(edge rows mapped by the mode), so temporaries are a few strips, never the whole image, and
every output pixel is computed from exactly the same inputs as in a whole-image computation.
"""

from typing import Literal

import jax.numpy as jnp
import numpy as np
from jax import Array

Mode = Literal["nearest", "reflect", "mirror", "wrap"]
MODES: tuple[str, ...] = ("nearest", "reflect", "mirror", "wrap")

STRIP_BYTES = 256 * 1024
"""Target size of one strip of keys: about an L2 cache's share on current x86 cores."""


def check_mode(mode: str) -> str:
    if mode not in MODES:
        raise ValueError(f"mode: expected one of {', '.join(MODES)}, got {mode!r}")
    return mode


def map_index(i, n: int, mode: str):
    """Source index in ``[0, n)`` for a (possibly out-of-range) index ``i``; NumPy or JAX."""
    xp = np if isinstance(i, np.ndarray | int) else jnp
    if mode == "nearest":
        return xp.clip(i, 0, n - 1)
    if mode == "wrap":
        return xp.mod(i, n)
    if mode == "reflect":
        j = xp.mod(i, 2 * n)
        return xp.where(j < n, j, 2 * n - 1 - j)
    if n == 1:  # mirror of a single sample
        return i * 0
    j = xp.mod(i, 2 * n - 2)
    return xp.where(j < n, j, 2 * n - 2 - j)


def strip_rows(height: int, width: int, itemsize: int, *, even: bool, rows: int | None) -> int:
    """Rows per strip: ``rows`` if given, else about :data:`STRIP_BYTES` of one row-band."""
    if rows is None:
        rows = max(8, STRIP_BYTES // max(1, width * itemsize))
    rows = max(1, min(int(rows), height))
    if even:
        rows = max(2, rows - rows % 2)
    return rows


def padded_block(x: Array, r: int, mode: str, r0: int, r1: int, c0: int, c1: int) -> Array:
    """Input rows ``r0−r..r1+r−1`` × columns ``c0−r..c1+r−1`` of a 2-D array, edge-mapped.

    For edge bands and small images only: the gather copies the block.
    """
    h, w = x.shape
    rows = map_index(np.arange(r0 - r, r1 + r), h, mode)
    cols = map_index(np.arange(c0 - r, c1 + r), w, mode)
    if len(rows) <= len(cols):  # gather along the short side first
        return jnp.take(jnp.take(x, rows, axis=0), cols, axis=1)
    return jnp.take(jnp.take(x, cols, axis=1), rows, axis=0)


def edge_bands(h: int, w: int, r: int, interior_rows: int) -> list[tuple[int, int, int, int]]:
    """``(r0, r1, c0, c1)`` of the output bands outside the strip-processed interior.

    The interior is rows ``r .. r + interior_rows`` × columns ``r .. w − r``; the bands are
    the top rows, the bottom rows (from ``r + interior_rows``), and the left and right
    columns between them.
    """
    b0 = r + interior_rows
    bands = [(0, r, 0, w), (b0, h, 0, w), (r, b0, 0, r), (r, b0, w - r, w)]
    return [b for b in bands if b[1] > b[0] and b[3] > b[2]]
