"""A PNG reader for the files hdrjax writes, from the PNG specification (independent of the
writer): chunk CRCs checked, rows unfiltered by hand (filter None or Sub), no interlace."""

import struct
import zlib

import numpy as np


def decode_png(data: bytes) -> tuple[np.ndarray, dict]:
    """``(pixels (H, W, C) uint8 or >u2, {chunk type: body})`` of PNG bytes."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, chunks = 8, b"", {}
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + n]
        assert struct.unpack(">I", data[pos + 8 + n : pos + 12 + n])[0] == zlib.crc32(kind + body)
        chunks[kind] = body
        if kind == b"IDAT":
            idat += body
        pos += 12 + n
    w, h, depth, ctype = struct.unpack(">IIBB", chunks[b"IHDR"][:10])
    c = {0: 1, 2: 3, 6: 4}[ctype]
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(h, -1)
    assert np.all(raw[:, 0] == raw[0, 0]) and raw[0, 0] in (0, 1), "filter None or Sub"
    rows = raw[:, 1:].astype(np.int64)
    if raw[0, 0] == 1:  # Sub: Raw(x) = Sub(x) + Raw(x - bpp) mod 256, a running sum per byte
        bpp = c * depth // 8
        rows = np.cumsum(rows.reshape(h, -1, bpp), axis=1).reshape(h, -1) % 256
    px = rows.astype(np.uint8).view(">u2" if depth == 16 else np.uint8)
    return px.reshape(h, w, c), chunks
