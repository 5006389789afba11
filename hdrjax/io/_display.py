"""Export of display-referred (already tone-mapped and encoded) images: PNG, JPEG, TIFF.

Input is display-referred: float in [0, 1] (values outside are clipped, NaN becomes 0) or
integer code values (uint8 / uint16). Nothing here applies a transfer function; encode
with the display module first. Each file is tagged with the display the pixels were
encoded for (``display=``, sRGB by default; the primaries and curve come from
:mod:`hdrjax.display`'s table):

* PNG (PNG Specification, third edition, W3C 2025): ``cICP`` (ITU-T H.273 code points)
  where H.273 has a code for the display; ``cHRM`` (primaries and white); for sRGB the
  ``sRGB`` chunk with ``gAMA`` 1/2.2, as the specification asks; for power laws (gamma,
  BT.1886, linear) ``gAMA``; for the other curves (sRGB curve on other primaries, PQ,
  HLG) an ``iCCP`` ICC profile (with ``gAMA`` 1/2.2 approximating the sRGB curve, never
  for PQ or HLG). ``sRGB`` and ``iCCP`` are never both written (the specification forbids
  it). Readers that know ``cICP`` use it first, then ``iCCP``, ``sRGB``, ``cHRM``/``gAMA``.
* TIFF (tag 34675, by tifffile) and JPEG (APP2, by Pillow): an ICC v2.4 display profile written by
  hdrjax (:mod:`hdrjax.io._icc`) with the display's primaries, white and curve.

PQ and HLG files must be 16-bit (PNG or TIFF): 8 bits band visibly over their range, so
``bits=8`` and JPEG are refused for them. PNG is written by hdrjax itself (zlib + struct),
TIFF by tifffile, so 16-bit RGB works in both; JPEG uses Pillow (8 bit only).
"""

import io as _io
import os
import struct
import zlib
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import _check
from ._atomic import atomic_path
from ._icc import display_profile, power_law

if TYPE_CHECKING:
    from ..display import Display

DISPLAY_FORMATS = {".png": "png", ".jpg": "jpeg", ".jpeg": "jpeg", ".tif": "tiff", ".tiff": "tiff"}
DEFAULT_COMPRESSION = 1
"""zlib level of PNG and TIFF outputs: 1, OpenCV's default.

PNG rows are written with the Sub filter (each byte minus the same byte of the pixel to its
left, PNG spec §9.2), which makes smooth photographic rows compressible. At levels 1–3 zlib
runs its run-length strategy (``Z_RLE``), as OpenCV does: for a tone-mapped 1024×512 frame
that is 0.57 MB in 15 ms, against 0.75 MB in 49 ms for unfiltered rows at level 6 (the old
default) and 0.56 MB in 115 ms for filtered rows at level 6. Levels 4–9 use zlib's default
strategy (9: smallest, slowest); 0 stores the rows uncompressed and unfiltered."""

_RLE_LEVELS = range(1, 4)


def to_code_values(display: np.ndarray, bits: int) -> np.ndarray:
    """``(H, W, C)`` code values (uint8 for 8 bits, uint16 for 16) from display input."""
    if bits not in (8, 16):
        raise ValueError(f"bits must be 8 or 16, got {bits}")
    a = np.asarray(display)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3 or a.shape[2] not in (1, 3, 4):
        raise ValueError(f"display image: expected (H, W), (H, W, 3) or (H, W, 4), got {a.shape}")
    _check.nonempty(np.shape(display), "display image", "(H, W), (H, W, 3) or (H, W, 4)", (0, 1))
    top = (1 << bits) - 1
    if a.dtype == np.uint8:
        return a if bits == 8 else a.astype(np.uint16) * np.uint16(257)
    if a.dtype == np.uint16:
        if bits == 16:
            return a
        return ((a.astype(np.uint32) + 128) // 257).astype(np.uint8)
    if np.issubdtype(a.dtype, np.integer) or a.dtype == np.bool_:
        raise ValueError(f"display image: integer input must be uint8 or uint16, got {a.dtype}")
    f = np.nan_to_num(a.astype(np.float32), nan=0.0, posinf=1.0, neginf=0.0)
    f = np.clip(f, 0.0, 1.0) * np.float32(top) + np.float32(0.5)
    return f.astype(np.uint8 if bits == 8 else np.uint16)


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _check_compression(compression: int) -> int:
    if isinstance(compression, bool) or not isinstance(compression, (int, np.integer)):
        raise ValueError(f"compression: expected a zlib level 0..9, got {compression!r}")
    if not 0 <= int(compression) <= 9:
        raise ValueError(f"compression: expected a zlib level 0..9, got {compression!r}")
    return int(compression)


def _resolve(display: "str | Display") -> "Display":
    # imported on first write: hdrjax.display brings the operators package (~0.8 s)
    from ..display import get_display as find

    return find(display)


def _peak() -> float:
    from ..display import DEFAULT_PEAK

    return DEFAULT_PEAK


def _png_colour_chunks(display: "Display", grey: bool) -> list[bytes]:
    """The PNG chunks that tell readers how to decode code values encoded for ``display``.

    PNG third edition: ``cICP`` holds the H.273 code points (matrix 0, RGB, is the only
    one PNG allows; the table's are all full range); ``cHRM`` the primaries and white ×100000
    (white first); ``gAMA`` 1/γ ×100000; ``iCCP`` a Latin-1 profile name, compression
    method 0 and the zlib-compressed profile; ``sRGB`` the rendering intent. A writer of
    ``sRGB`` or ``iCCP`` is asked to add ``gAMA`` and ``cHRM`` approximating them, for
    readers without colour management.
    """
    from .. import spaces

    sp = spaces.space(display.space)
    out = []
    if display.cicp is not None:
        out.append(_chunk(b"cICP", bytes(display.cicp)))
    xr, yr, xg, yg, xb, yb, xw, yw = sp.chromaticities
    chrm = struct.pack(">8I", *(round(v * 100000) for v in (xw, yw, xr, yr, xg, yg, xb, yb)))
    out.append(_chunk(b"cHRM", chrm))
    gamma = power_law(display)
    if gamma is None and display.transfer == "srgb":
        gamma = 2.2  # the approximation the specification gives for the sRGB curve
    if gamma is not None:
        out.append(_chunk(b"gAMA", struct.pack(">I", round(100000 / gamma))))
    if display.transfer == "srgb" and sp.is_rec709:
        out.append(_chunk(b"sRGB", b"\x00"))  # rendering intent: perceptual
    elif power_law(display) is None:
        icc = display_profile(display, grey=grey, peak=_peak())
        name = display.name.encode("latin-1", "replace")[:79]
        out.append(_chunk(b"iCCP", name + b"\x00\x00" + zlib.compress(icc, 9)))
    return out


def encode_png(
    code: np.ndarray,
    compression: int = DEFAULT_COMPRESSION,
    *,
    display: "str | Display" = "sRGB",
) -> bytes:
    """PNG bytes for ``(H, W, C)`` uint8/uint16 code values, tagged for ``display``.

    ``compression`` is the zlib level (0 stored … 9 smallest); see :data:`DEFAULT_COMPRESSION`.
    ``display`` (a name or a :class:`~hdrjax.display.Display`) chooses the colour chunks
    (``cICP``, ``cHRM``, ``gAMA``, ``sRGB`` or ``iCCP``: see the module docstring).
    """
    compression = _check_compression(compression)
    colour = _png_colour_chunks(_resolve(display), grey=code.shape[2] == 1)
    h, w, c = code.shape
    depth = 16 if code.dtype == np.uint16 else 8
    ctype = {1: 0, 3: 2, 4: 6}[c]
    rows = np.ascontiguousarray(code, dtype=">u2" if depth == 16 else np.uint8).reshape(h, -1)
    rows = rows.view(np.uint8)
    raw = np.empty((h, rows.shape[1] + 1), np.uint8)
    if compression == 0:
        raw[:, 0] = 0  # filter type None
        raw[:, 1:] = rows
    else:
        bpp = c * depth // 8  # filter type Sub: byte minus the byte one pixel to the left
        raw[:, 0] = 1
        raw[:, 1 : 1 + bpp] = rows[:, :bpp]
        np.subtract(rows[:, bpp:], rows[:, :-bpp], out=raw[:, 1 + bpp :])
    strategy = zlib.Z_RLE if compression in _RLE_LEVELS else zlib.Z_DEFAULT_STRATEGY
    packer = zlib.compressobj(compression, zlib.DEFLATED, 15, 8, strategy)
    idat = packer.compress(raw) + packer.flush()
    out = [
        b"\x89PNG\r\n\x1a\n",
        _chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, ctype, 0, 0, 0)),
        *colour,
        _chunk(b"tEXt", b"Software\x00hdrjax"),
        _chunk(b"IDAT", idat),
        _chunk(b"IEND", b""),
    ]
    return b"".join(out)


def write_tiff(
    path: str | os.PathLike,
    code: np.ndarray,
    icc: bytes | None = None,
    compression: int = DEFAULT_COMPRESSION,
) -> None:
    """Baseline little-endian TIFF of uint8/uint16 ``(H, W, C)`` code values, by tifffile.

    Chunky (interleaved) samples; Adobe deflate strips at zlib level ``compression`` (0:
    uncompressed); the ICC profile in tag 34675; ``Software`` "hdrjax"; a fourth channel is
    unassociated alpha (ExtraSamples 2). tifffile's shaped-array JSON description is left out.
    """
    import tifffile

    compression = _check_compression(compression)
    c = code.shape[2]
    tifffile.imwrite(
        path,
        code[:, :, 0] if c == 1 else code,
        photometric="minisblack" if c == 1 else "rgb",
        planarconfig="contig",
        extrasamples=("unassalpha",) if c == 4 else None,
        compression="zlib" if compression else None,
        compressionargs={"level": compression} if compression else None,
        iccprofile=icc or None,
        software="hdrjax",
        metadata=None,
    )


def encode_jpeg(code: np.ndarray, *, quality: int = 95, icc: bytes | None = None) -> bytes:
    """JPEG bytes (Pillow) for uint8 ``(H, W, 1 or 3)`` code values."""
    from PIL import Image

    if code.dtype != np.uint8:
        raise ValueError("JPEG holds 8 bits per channel; use PNG or TIFF for bits=16")
    c = code.shape[2]
    if c == 4:
        raise ValueError("JPEG has no alpha channel; pass an (H, W, 3) image")
    im = Image.fromarray(code[:, :, 0] if c == 1 else code, mode="L" if c == 1 else "RGB")
    buf = _io.BytesIO()
    # full-resolution chroma at high quality: tone-mapped renders have sharp colour edges
    kw: dict[str, int | bytes] = {"quality": int(quality), "subsampling": 0 if quality >= 90 else 2}
    if icc:
        kw["icc_profile"] = icc
    im.save(buf, format="JPEG", **kw)
    return buf.getvalue()


def write_display(
    path: str | os.PathLike,
    display_rgb: np.ndarray,
    *,
    bits: int = 8,
    overwrite: bool = True,
    quality: int = 95,
    compression: int = DEFAULT_COMPRESSION,
    display: "str | Display" = "sRGB",
) -> Path:
    """Write a display-referred image to PNG (8/16 bit), JPEG (8 bit) or TIFF (8/16 bit).

    Args:
        path: output file; the format comes from the extension (``.png``, ``.jpg``,
            ``.jpeg``, ``.tif``, ``.tiff``).
        display_rgb: ``(H, W, 3)`` (or ``(H, W)`` grey, ``(H, W, 4)`` with alpha for
            PNG/TIFF): float in [0, 1], already encoded for ``display`` and clipped; or
            uint8 / uint16 code values.
        bits: 8 or 16 bits per channel (JPEG: 8 only; PQ and HLG: 16 only).
        overwrite: when ``False``, refuse to replace an existing file
            (``FileExistsError``).
        quality: JPEG quality, 1-100.
        compression: PNG/TIFF zlib level, 0 (stored) to 9 (smallest, slowest); 1 by
            default, as OpenCV (Sub-filtered PNG rows, run-length matching: see
            :data:`DEFAULT_COMPRESSION` for sizes and times).
        display: the display the code values were encoded for, a name
            (``"sRGB"``, ``"Display P3"``, ``"ITU-R BT.2020"``, ``"ITU-R BT.2100 PQ"``,
            ``"ITU-R BT.2100 HLG"``, ``"linear"``, ``"gamma"`` for 2.2; case and
            separators do not matter) or a :class:`~hdrjax.display.Display` (another
            gamma). It only tags the file (see the module docstring); the pixels are
            written as given. For PQ the ICC profile puts white at 1000 cd/m² (the
            encoder's default peak); ``cICP`` keeps the absolute scale.

    Returns:
        The path written. The file is written to a temporary name in the same folder and
        renamed into place.

    Raises:
        ValueError: unknown extension or display, bad shape or dtype, 16-bit JPEG, PQ or
            HLG in 8 bits or in JPEG.
        FileExistsError: ``path`` exists and ``overwrite`` is ``False``.
    """
    path = Path(path)
    fmt = DISPLAY_FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise ValueError(
            f"{path.name}: unknown display format {path.suffix!r}; expected .png, .jpg, .jpeg, "
            ".tif or .tiff"
        )
    disp = _resolve(display)
    if fmt == "jpeg" and disp.hdr:
        raise ValueError(
            f"{path.name}: JPEG holds 8 bits per channel, too few for {disp.name}; write a "
            ".png or .tif with bits=16"
        )
    if fmt == "jpeg" and bits != 8:
        raise ValueError(f"{path.name}: JPEG holds 8 bits per channel; use PNG or TIFF for bits=16")
    if disp.hdr and bits != 16:
        # an 8-bit PQ step is 4 % of the luminance at 100 cd/m² (7 % at 1, HLG's 2 %):
        # visible bands, where BT.2100 codes 10 or 12 bits
        raise ValueError(f"{path.name}: {disp.name} needs 16-bit code values; use bits=16")
    if not 1 <= int(quality) <= 100:
        raise ValueError(f"quality must be in 1..100, got {quality}")
    compression = _check_compression(compression)
    code = to_code_values(display_rgb, bits)
    grey = code.shape[2] == 1
    if fmt == "tiff":
        icc = display_profile(disp, grey=grey, peak=_peak())
        with atomic_path(path, overwrite=overwrite) as tmp:
            write_tiff(tmp, code, icc, compression)
        return path
    if fmt == "png":
        data = encode_png(code, compression, display=disp)
    else:
        data = encode_jpeg(
            code, quality=quality, icc=display_profile(disp, grey=grey, peak=_peak())
        )
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_bytes(data)
    return path


__all__ = [
    "DEFAULT_COMPRESSION",
    "DISPLAY_FORMATS",
    "encode_png",
    "to_code_values",
    "write_display",
    "write_tiff",
]
