"""Portable float map (``.pfm``) reading and writing.

Format: a text header ``PF`` (3 channels) or ``Pf`` (1 channel), then ``W H``, then a scale
whose sign gives the byte order (negative: little-endian, positive: big-endian) and whose
magnitude is an optional scale factor, each followed by one whitespace byte; then
float32 rows stored **bottom to top**. The reader returns rows top to bottom.
"""

import math
import os
import re
from pathlib import Path

import numpy as np

from ..layers._errors import ReadError

MAX_DIM = 1 << 20
_HEAD_RE = re.compile(rb"^(P[Ff])\s+(\d+)\s+(\d+)\s+([-+0-9.eE]+)\s")


def decode_pfm(data: bytes | memoryview, name: str = "image.pfm") -> tuple[np.ndarray, float]:
    """Decode a PFM file held in memory; returns ``((H, W, C) float32, scale)``.

    ``scale`` is the absolute value of the header's scale field (1.0 by convention).

    Raises:
        ReadError: wrong magic, malformed header, absurd size or truncated data.
    """
    head = bytes(data[:256])
    m = _HEAD_RE.match(head)
    if m is None:
        if not head.startswith((b"PF", b"Pf")):
            raise ReadError(f"{name}: not a PFM file (expected 'PF' or 'Pf' magic)")
        raise ReadError(f"{name}: malformed PFM header; expected 'PF|Pf', 'W H', 'scale'")
    magic, w, h, scale_text = m.groups()
    w, h = int(w), int(h)
    if not (0 < w <= MAX_DIM and 0 < h <= MAX_DIM):
        raise ReadError(f"{name}: absurd PFM image size {w} x {h} (limit {MAX_DIM})")
    try:
        scale = float(scale_text)
    except ValueError:
        raise ReadError(f"{name}: bad PFM scale {scale_text.decode('latin-1')!r}") from None
    if scale == 0 or not math.isfinite(scale):
        raise ReadError(f"{name}: bad PFM scale {scale} (must be non-zero and finite)")
    c = 3 if magic == b"PF" else 1
    off = m.end()
    need = w * h * c * 4
    if len(data) - off < need:
        raise ReadError(
            f"{name}: truncated PFM file ({len(data) - off} of {need} bytes of pixel data)"
        )
    dtype = np.dtype("<f4") if scale < 0 else np.dtype(">f4")
    arr = np.frombuffer(data, dtype=dtype, count=w * h * c, offset=off).reshape(h, w, c)
    return np.ascontiguousarray(arr[::-1], dtype=np.float32), abs(scale)


def encode_pfm(image: np.ndarray, *, little_endian: bool = True) -> bytes:
    """Encode ``(H, W, 1 or 3)`` (or ``(H, W)``) float values as PFM bytes."""
    a = np.asarray(image, dtype=np.float32)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3 or a.shape[2] not in (1, 3):
        raise ValueError(f"PFM holds 1 or 3 channels; got an image of shape {a.shape}")
    h, w, c = a.shape
    magic = "PF" if c == 3 else "Pf"
    dtype = "<f4" if little_endian else ">f4"
    head = f"{magic}\n{w} {h}\n{-1.0 if little_endian else 1.0}\n".encode("ascii")
    return head + np.ascontiguousarray(a[::-1], dtype=dtype).tobytes()


def read_pfm_file(path: str | os.PathLike) -> tuple[np.ndarray, float]:
    """Read a PFM file; see :func:`decode_pfm`."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise OSError(f"{path.name}: cannot read ({e.strerror or e})") from None
    return decode_pfm(data, path.name)


__all__ = ["decode_pfm", "encode_pfm", "read_pfm_file"]
