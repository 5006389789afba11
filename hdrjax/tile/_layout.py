"""Where the tiles and their windows lie (NumPy side, never jitted).

Each tile is an output block of at most ``tile`` pixels per axis. Its *window* is the input
block the step reads: the tile plus ``halo`` pixels on every side, shifted inwards where it
would leave the image (never padded), so that

- every window has the same shape ``min(n, tile + 2·halo)`` per axis (one compilation);
- a window edge that is a true image edge stays one, and the step's own edge handling
  (replicate/reflect padding, zero padding of a normalised convolution) applies there
  exactly as in the whole-image computation;
- on the other sides the window reaches at least ``halo`` pixels beyond the tile, so the
  step's edge handling there only touches pixels that are cropped away.
"""

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Span:
    """One tile along one axis: output ``[start, stop)``, window ``[w_start, w_start + w_len)``."""

    start: int
    stop: int
    w_start: int
    w_len: int

    @property
    def crop(self) -> slice:
        """The tile's part of the window result."""
        return slice(self.start - self.w_start, self.stop - self.w_start)

    @property
    def window(self) -> slice:
        return slice(self.w_start, self.w_start + self.w_len)

    @property
    def out(self) -> slice:
        return slice(self.start, self.stop)


def check_tile(tile, ndim: int = 2) -> tuple[int, ...]:
    """``tile`` as ``ndim`` positive integers (one integer means a square tile)."""
    t = tuple(tile) if isinstance(tile, tuple | list) else (tile,) * ndim
    if len(t) != ndim or any(
        isinstance(v, bool) or not isinstance(v, int | np.integer) or v < 1 for v in t
    ):
        raise ValueError(f"tile: expected {ndim} integers >= 1 (rows, columns), got {tile!r}")
    return tuple(int(v) for v in t)


def spans(n: int, tile: int, halo: int, axis: str = "rows") -> list[Span]:
    """Tiles along an axis of length ``n`` (see the module docstring).

    Raises:
        ValueError: if ``halo > tile`` while the tile does not span the axis (the windows
            would be mostly halo; use a larger tile).
    """
    if halo < 0:
        raise ValueError(f"halo: expected an integer >= 0, got {halo!r}")
    if halo > tile and tile < n:
        raise ValueError(
            f"tile: {tile} {axis} is smaller than the step's halo of {halo} {axis}; use a"
            f" tile of at least {halo} {axis} (or one spanning the image)"
        )
    w_len = min(n, tile + 2 * halo)
    out = []
    for start in range(0, n, tile):
        stop = min(start + tile, n)
        w_start = min(max(start - halo, 0), n - w_len)
        out.append(Span(start, stop, w_start, w_len))
    return out


__all__ = ["Span", "check_tile", "spans"]
