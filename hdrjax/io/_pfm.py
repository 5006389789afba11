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


def parse_header(head: bytes, name: str) -> tuple[int, int, int, float, int]:
    """Parse the text header at the start of ``head`` (its first 256 bytes suffice).

    Returns:
        ``(width, height, channels, scale, offset_of_pixel_data)``; ``scale`` keeps its
        sign (the byte order).

    Raises:
        ReadError: wrong magic, malformed header or absurd size.
    """
    head = head[:256]
    m = _HEAD_RE.match(head)
    if m is None:
        if not head.startswith((b"PF", b"Pf")):
            raise ReadError(f"{name}: not a PFM file (expected 'PF' or 'Pf' magic)")
        raise ReadError(f"{name}: malformed PFM header; expected 'PF|Pf', 'W H', 'scale'")
    magic, w, h, scale_text = m.groups()
    w, h = int(w), int(h)
    if min(w, h) < 1:
        raise ReadError(f"{name}: empty PFM image {w} x {h}; expected at least 1 x 1")
    if not (0 < w <= MAX_DIM and 0 < h <= MAX_DIM):
        raise ReadError(f"{name}: absurd PFM image size {w} x {h} (limit {MAX_DIM})")
    try:
        scale = float(scale_text)
    except ValueError:
        raise ReadError(f"{name}: bad PFM scale {scale_text.decode('latin-1')!r}") from None
    if scale == 0 or not math.isfinite(scale):
        raise ReadError(f"{name}: bad PFM scale {scale} (must be non-zero and finite)")
    return w, h, (3 if magic == b"PF" else 1), scale, m.end()


def _check_size(name: str, have: int, need: int) -> None:
    if have < need:
        raise ReadError(
            f"{name}: truncated PFM file ({max(have, 0)} of {need} bytes of pixel data)"
        )


def _pixels(raw: bytes | memoryview, w: int, h: int, c: int, scale: float, off: int) -> np.ndarray:
    dtype = np.dtype("<f4") if scale < 0 else np.dtype(">f4")
    arr = np.frombuffer(raw, dtype=dtype, count=w * h * c, offset=off).reshape(h, w, c)
    return np.ascontiguousarray(arr[::-1], dtype=np.float32)


def decode_pfm(data: bytes | memoryview, name: str = "image.pfm") -> tuple[np.ndarray, float]:
    """Decode a PFM file held in memory; returns ``((H, W, C) float32, scale)``.

    ``scale`` is the absolute value of the header's scale field (1.0 by convention). Bytes
    after the pixel data are ignored, as pfstools' ``pfsinpfm`` ignores them.

    Raises:
        ReadError: wrong magic, malformed header, absurd size or truncated data.
    """
    w, h, c, scale, off = parse_header(bytes(data[:256]), name)
    _check_size(name, len(data) - off, w * h * c * 4)
    return _pixels(data, w, h, c, scale, off), abs(scale)


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
    """Read a PFM file; see :func:`decode_pfm`.

    The header is read first and the declared size checked against the file's size, so
    only the pixel data is read (never more than the header declares, whatever follows).
    """
    path = Path(path)
    try:
        with open(path, "rb") as f:
            head = f.read(256)
            w, h, c, scale, off = parse_header(head, path.name)
            need = w * h * c * 4
            _check_size(path.name, os.fstat(f.fileno()).st_size - off, need)
            f.seek(off)
            raw = f.read(need)
    except OSError as e:
        raise OSError(f"{path.name}: cannot read ({e.strerror or e})") from None
    _check_size(path.name, len(raw), need)  # the file shrank while being read
    return _pixels(raw, w, h, c, scale, 0), abs(scale)


__all__ = ["decode_pfm", "encode_pfm", "parse_header", "read_pfm_file"]
