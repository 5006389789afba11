"""The displays an image can be encoded for: primaries, transfer function, file tags.

One table, read by the encoder (:func:`hdrjax.display.encode`), the file writers (PNG
``cICP``/``cHRM``/``gAMA``, ICC profiles in TIFF/JPEG/PNG) and the command line, so the
pixels and the tags that describe them cannot disagree; :func:`get_display` finds an entry
by name.

Coding-independent code points (``cicp``) are ITU-T H.273's: colour primaries 1 (BT.709),
9 (BT.2020), 12 (SMPTE EG 432-1, P3 with a D65 white); transfer characteristics 13 (IEC
61966-2-1 sRGB), 1 (BT.709, displayed with the BT.1886 EOTF), 16 (SMPTE ST 2084 PQ), 18
(ARIB STD-B67 HLG), 4 (gamma 2.2), 8 (linear); matrix 0 (RGB); full range 1.
"""

import dataclasses

from .. import _check

DEFAULT_DISPLAY = "sRGB"
DEFAULT_PEAK = 1000.0
"""cd/m² of the display's white for PQ and HLG (BT.2100's reference HLG display peak)."""


@dataclasses.dataclass(frozen=True)
class Display:
    """A display (or file encoding) an image is encoded for.

    Attributes:
        name: the name users type (``"sRGB"``, ``"ITU-R BT.2100 PQ"``…).
        space: the display's linear RGB space (a :mod:`hdrjax.spaces` name).
        transfer: ``"srgb"`` (IEC 61966-2-1), ``"bt1886"`` (inverse of BT.1886's EOTF
            with a zero black: ``V = L^(1/2.4)``), ``"pq"`` (SMPTE ST 2084), ``"hlg"``
            (BT.2100 HLG OETF), ``"gamma"`` (``V = L^(1/gamma)``) or ``"linear"``.
        gamma: the exponent for ``"gamma"`` (and BT.1886's 2.4).
        cicp: ITU-T H.273 ``(primaries, transfer, matrix, full_range)``, or ``None``
            where H.273 has no code for the curve.
        hdr: whether the display is an HDR one (PQ/HLG: absolute luminance up to a peak;
            16-bit files by default).
    """

    name: str
    space: str
    transfer: str
    gamma: float | None = None
    cicp: tuple[int, int, int, int] | None = None
    hdr: bool = False


DISPLAYS: dict[str, Display] = {
    d.name: d
    for d in (
        Display("sRGB", "sRGB", "srgb", cicp=(1, 13, 0, 1)),
        Display("Display P3", "Display P3", "srgb", cicp=(12, 13, 0, 1)),
        Display("ITU-R BT.2020", "ITU-R BT.2020", "bt1886", 2.4, cicp=(9, 1, 0, 1)),
        Display("ITU-R BT.2100 PQ", "ITU-R BT.2020", "pq", cicp=(9, 16, 0, 1), hdr=True),
        Display("ITU-R BT.2100 HLG", "ITU-R BT.2020", "hlg", cicp=(9, 18, 0, 1), hdr=True),
        Display("linear", "sRGB", "linear", cicp=(1, 8, 0, 1)),
    )
}


_BY_KEY = {_check.name_key(n): d for n, d in DISPLAYS.items()}
_BY_KEY.update({"p3": DISPLAYS["Display P3"], "bt2020": DISPLAYS["ITU-R BT.2020"]})
_BY_KEY.update({"pq": DISPLAYS["ITU-R BT.2100 PQ"], "hlg": DISPLAYS["ITU-R BT.2100 HLG"]})


def get_display(name: "str | Display", gamma: float | None = None) -> Display:
    """The :class:`Display` of a name (case and separators do not matter; ``"P3"``,
    ``"BT2020"``, ``"PQ"``, ``"HLG"`` are short names). ``"gamma"`` is a plain power law
    with sRGB primaries (``gamma``, default 2.2; H.273 code 4 only for 2.2).

    Raises:
        ValueError: an unknown name; the message lists the known ones.
    """
    if isinstance(name, Display):
        return name
    if _check.name_key(name) == "gamma":
        g = 2.2 if gamma is None else float(gamma)
        if not g > 0:
            raise ValueError(f"gamma: expected a number > 0, got {gamma!r}")
        cicp = (1, 4, 0, 1) if g == 2.2 else None
        return Display(f"gamma {g:g}", "sRGB", "gamma", g, cicp)
    try:
        return _BY_KEY[_check.name_key(name)]
    except KeyError:
        known = ", ".join(repr(n) for n in [*DISPLAYS, "gamma"])
        raise ValueError(f"display: unknown name {name!r}; expected one of {known}") from None


__all__ = ["DEFAULT_DISPLAY", "DEFAULT_PEAK", "DISPLAYS", "Display", "get_display"]
