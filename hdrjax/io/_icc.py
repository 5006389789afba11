"""ICC profiles that describe display-encoded files: matrix/TRC display profiles, v2.4.

Written by hdrjax (struct + NumPy): Pillow's LittleCMS can only create sRGB, and the
profile must follow the pixels whatever display they were encoded for.

Version 2.4 (ICC.1:2001-04) rather than 4.3 (ICC.1:2010): every colour-managed reader
takes v2 matrix/TRC profiles (LittleCMS, Chrome's skcms, Firefox's qcms, Apple ColorSync),
and so do older readers that take no v4; such a profile describes these displays
completely. An RGB profile holds the tags ICC.1:2001-04 requires
of a three-component matrix-based display profile:

* ``desc`` (textDescriptionType) and ``cprt`` (textType);
* ``wtpt``: the media white point, i.e. the display's own white (D65 for every display
  here) in unadapted XYZ with Y = 1, as in the IEC 61966-2-1 sRGB v2 profile. (LittleCMS
  reads the white of a v2 display profile as D50 whatever the tag says; v4 would write D50
  here and the adaptation in ``chad``, a tag v2 does not have);
* ``rXYZ``/``gXYZ``/``bXYZ``: the columns of the RGB→XYZ matrix chromatically adapted to
  the PCS illuminant D50 (0.9642, 1, 0.8249) with the linearised Bradford transform
  (ICC.1:2010, Annex E); they sum to D50;
* ``rTRC``/``gTRC``/``bTRC`` (one curve shared by the three tags), ``curveType``, mapping a
  code value in [0, 1] to the linear display value in [0, 1] (the EOTF):

  - power laws (``"gamma"``, BT.1886's 2.4, ``"linear"``): a single exponent, stored
    as u8Fixed8Number (2.2 is written 563/256 = 2.1992: the format's precision);
  - IEC 61966-2-1 sRGB: 1024 samples of the piecewise curve, as the standard's own
    profile (linear interpolation between them errs by under 4e-7, well below the
    samples' 16-bit step of 1.5e-5);
  - SMPTE ST 2084 PQ: 4096 samples of the EOTF divided by the display's peak (the
    cd/m² the encoder maps linear 1.0 to; 1000 by default) and clipped at 1 above it.
    An ICC profile is relative: it cannot hold absolute luminance, which the PNG
    ``cICP`` chunk carries; a colour-managed SDR reader therefore shows the peak as
    white. PQ rises steeply near its top, hence 4 times the samples (largest
    interpolation error 4e-4 of the peak, against 9e-4 with 1024);
  - BT.2100 HLG: 1024 samples of the inverse OETF (scene-linear E in [0, 1], BT.2100
    Table 5; interpolation error under 4e-6), the inverse of what the encoder applied.
    An HLG display would apply the OOTF on top (system gamma 1.2 at 1000 cd/m²); a
    profile reader shows the linear signal without it.

A greyscale image gets a monochrome display profile (colour space ``GRAY``: ``desc``,
``cprt``, ``wtpt``, ``kTRC``), as PNG requires for grey images and TIFF/JPEG readers
expect for one-channel data.

References: ICC.1:2001-04, "File Format for Color Profiles" (version 2.4); ICC.1:2010,
"Image technology colour management — Architecture, profile format and data structure"
(version 4.3, Annex E for the Bradford transform); IEC 61966-2-1:1999 (sRGB); SMPTE ST
2084:2014 and ITU-R BT.2100-2 (PQ and HLG).
"""

import functools
import struct
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..display import Display

ICC_VERSION = 0x02400000
"""Profile version field: 2.4.0 (ICC.1:2001-04)."""

PCS_WHITE = (0.9642, 1.0, 0.8249)
"""XYZ of the PCS illuminant D50, as the ICC profile header gives it."""

BRADFORD = np.array(
    [[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]]
)
"""XYZ→cone-response matrix of the linearised Bradford transform (ICC.1:2010, Annex E;
Lam 1985), the same figures as colour-science's ``CAT_BRADFORD``."""

# The header holds a creation date. Fixed (the profile is a function of the
# display alone) so that writing the same image twice gives the same bytes.
_DATE = (2025, 1, 1, 0, 0, 0)
_COPYRIGHT = "No copyright, use freely"

# Samples of a tabulated curve, per transfer (see the module docstring for the errors).
_SAMPLES = {"srgb": 1024, "pq": 4096, "hlg": 1024}

# SMPTE ST 2084 constants (BT.2100-2, Table 4)
_PQ_M1, _PQ_M2 = 2610 / 16384, 2523 / 4096 * 128
_PQ_C1, _PQ_C2, _PQ_C3 = 3424 / 4096, 2413 / 4096 * 32, 2392 / 4096 * 32
# ARIB STD-B67 / BT.2100 HLG constants (BT.2100-2, Table 5)
_HLG_A = 0.17883277
_HLG_B = 1.0 - 4.0 * _HLG_A
_HLG_C = 0.5 - _HLG_A * np.log(4.0 * _HLG_A)


def bradford_to_d50(white: np.ndarray) -> np.ndarray:
    """3×3 matrix adapting XYZ seen under ``white`` (XYZ, Y = 1) to the PCS's D50.

    Von Kries scaling of the Bradford cone responses (ICC.1:2010, Annex E):
    ``M⁻¹ diag(ρ_D50 / ρ_src) M`` with ``M`` = :data:`BRADFORD`.
    """
    cone_src = BRADFORD @ np.asarray(white, np.float64)
    cone_dst = BRADFORD @ np.asarray(PCS_WHITE)
    return np.linalg.solve(BRADFORD, np.diag(cone_dst / cone_src) @ BRADFORD)


def _srgb_eotf(v: np.ndarray) -> np.ndarray:
    # IEC 61966-2-1:1999 eq. (5), the inverse of the encoder's piecewise curve
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def _pq_eotf(v: np.ndarray, peak: float) -> np.ndarray:
    # SMPTE ST 2084 EOTF (cd/m², up to 10000) over the display peak, clipped at the peak
    p = v ** (1.0 / _PQ_M2)
    y = (np.maximum(p - _PQ_C1, 0.0) / (_PQ_C2 - _PQ_C3 * p)) ** (1.0 / _PQ_M1)
    return np.minimum(10000.0 * y / peak, 1.0)


def _hlg_inverse_oetf(v: np.ndarray) -> np.ndarray:
    # BT.2100 HLG inverse OETF: E' = sqrt(3E) below 1/2, a log curve above
    low = v**2 / 3.0
    high = (np.exp((np.maximum(v, 0.5) - _HLG_C) / _HLG_A) + _HLG_B) / 12.0
    return np.where(v <= 0.5, low, high)


def decoder(transfer: str, peak: float) -> Callable[[np.ndarray], np.ndarray]:
    """The tabulated curve of a transfer: code value [0, 1] → linear display value [0, 1].

    Args:
        transfer: ``"srgb"``, ``"pq"`` or ``"hlg"`` (the power laws are stored as an
            exponent, not a table).
        peak: cd/m² at linear 1.0 (PQ only).
    """
    if transfer == "srgb":
        return _srgb_eotf
    if transfer == "pq":
        return functools.partial(_pq_eotf, peak=peak)
    if transfer == "hlg":
        return _hlg_inverse_oetf
    raise ValueError(f"transfer: no tabulated curve for {transfer!r}")


def power_law(display: "Display") -> float | None:
    """The exponent of a display whose EOTF is a plain power law, else ``None``."""
    if display.transfer == "linear":
        return 1.0
    if display.transfer in ("gamma", "bt1886"):
        return float(display.gamma if display.gamma is not None else 2.4)
    return None


def _s15f16(values) -> bytes:
    return b"".join(struct.pack(">i", round(float(v) * 65536.0)) for v in values)


def _xyz_tag(xyz) -> bytes:
    return b"XYZ \x00\x00\x00\x00" + _s15f16(xyz)


def _text_tag(text: str) -> bytes:
    return b"text\x00\x00\x00\x00" + text.encode("ascii") + b"\x00"


def _desc_tag(text: str) -> bytes:
    # textDescriptionType (ICC.1:2001-04): ASCII, then an empty Unicode and an
    # empty ScriptCode description (counts 0; the ScriptCode field is always 67 bytes)
    ascii_ = text.encode("ascii") + b"\x00"
    return (
        b"desc\x00\x00\x00\x00"
        + struct.pack(">I", len(ascii_))
        + ascii_
        + struct.pack(">II", 0, 0)
        + struct.pack(">HB", 0, 0)
        + bytes(67)
    )


def _curve_tag(display: "Display", peak: float) -> bytes:
    gamma = power_law(display)
    if gamma is not None:
        # one entry: the exponent as u8Fixed8Number (ICC.1:2001-04, curveType)
        return b"curv\x00\x00\x00\x00" + struct.pack(">IH", 1, round(gamma * 256.0))
    n = _SAMPLES[display.transfer]
    y = decoder(display.transfer, peak)(np.linspace(0.0, 1.0, n))
    table = np.rint(np.clip(y, 0.0, 1.0) * 65535.0).astype(">u2")
    return b"curv\x00\x00\x00\x00" + struct.pack(">I", n) + table.tobytes()


def _assemble(colour_space: bytes, tags: list[tuple[bytes, bytes]]) -> bytes:
    # header (128 bytes), tag count and table, then the tag data, each element on a
    # 4-byte boundary (ICC.1:2001-04); tags with equal bytes share one element
    table, data, offsets = [], b"", {}
    start = 128 + 4 + 12 * len(tags)
    for sig, body in tags:
        if body not in offsets:
            offsets[body] = start + len(data)
            data += body + bytes(-len(body) % 4)
        table.append(struct.pack(">4sII", sig, offsets[body], len(body)))
    size = start + len(data)
    header = (
        struct.pack(">II", size, 0)  # size, preferred CMM: none
        + struct.pack(">I", ICC_VERSION)
        + b"mntr"
        + colour_space
        + b"XYZ "
        + struct.pack(">6H", *_DATE)
        + b"acsp"
        + bytes(4)  # primary platform: none
        + struct.pack(">I", 0)  # flags: not embedded-only, may be used independently
        + bytes(8)  # device manufacturer and model: none
        + bytes(8)  # device attributes: all bits 0
        + struct.pack(">I", 0)  # rendering intent: perceptual
        + _s15f16(PCS_WHITE)
        + bytes(4)  # creator: none registered
        + bytes(44)  # profile ID (v4 only) and reserved bytes
    )
    assert len(header) == 128
    return header + struct.pack(">I", len(tags)) + b"".join(table) + data


@functools.lru_cache(maxsize=32)
def display_profile(display: "Display", *, grey: bool = False, peak: float = 1000.0) -> bytes:
    """An ICC v2.4 display profile for pixels encoded for ``display``.

    Args:
        display: the display the code values were encoded for (its ``space`` gives the
            primaries and white, its ``transfer`` the curve).
        grey: a monochrome profile (``GRAY``, one ``kTRC``) for one-channel images.
        peak: cd/m² the encoder maps linear 1.0 to (PQ only): the profile's white.

    Returns:
        The profile's bytes (about 0.5 kB with a power law, 2.5 kB for sRGB, 8.5 kB for
        PQ); see the module docstring for the tags.
    """
    from .. import spaces  # imports JAX: only when a profile is written

    sp = spaces.space(display.space)
    white = sp.to_xyz @ np.ones(3)  # the display's white, Y = 1
    curve = _curve_tag(display, peak)
    tags = [(b"desc", _desc_tag(display.name)), (b"cprt", _text_tag(_COPYRIGHT))]
    tags.append((b"wtpt", _xyz_tag(white)))
    if grey:
        return _assemble(b"GRAY", [*tags, (b"kTRC", curve)])
    colorants = bradford_to_d50(white) @ sp.to_xyz  # columns: adapted r, g, b
    for i, sig in enumerate((b"rXYZ", b"gXYZ", b"bXYZ")):
        tags.append((sig, _xyz_tag(colorants[:, i])))
    tags += [(b"rTRC", curve), (b"gTRC", curve), (b"bTRC", curve)]
    return _assemble(b"RGB ", tags)


__all__ = ["BRADFORD", "ICC_VERSION", "PCS_WHITE", "bradford_to_d50", "display_profile"]
