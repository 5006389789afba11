"""Reading an exposure bracket from files: code values, exposure time, f-number and ISO.

Numeric contract: each file becomes ``(H, W, 3)`` integer code values — uint8 for 8-bit
files, uint16 for 16-bit files and camera RAW — and its exposure settings from EXIF:
exposure time in seconds, f-number, ISO speed. The bracket comes back sorted by exposure
time, shortest first, as :class:`BracketFiles`. NumPy, not jitted.

Formats:

- **PNG** (8/16-bit; greyscale, palette, with or without alpha): Pillow. Pillow decodes
  48/64-bit RGB(A) PNG to 8 bits per channel (it keeps only the high byte), so 16-bit colour
  PNGs are decoded twice by Pillow's own PNG decoder, once unpacking the high byte of each
  sample and once the low byte, and put together again — exact, checked against OpenCV's
  and hdrjax's own 16-bit PNG writers.
- **TIFF** (8/16-bit, chunky or planar, greyscale or RGB): tifffile; compressions tifffile
  cannot decode without the ``imagecodecs`` package (LZW, JPEG) fall back to Pillow (with
  the same two-pass decoding for 16-bit colour).
- **JPEG** (8-bit): Pillow.
- **Camera RAW** (``.dng .cr2 .cr3 .nef .arw .raf .orf .rw2 .pef .srw``): LibRaw through
  ``rawpy`` (the ``hdrjax[raw]`` extra), decoded *linear*: gamma (1, 1) (no camera tone
  curve), no automatic brightening, no rescaling of the white level to the image's maximum
  (LibRaw's ``adjust_maximum_thr`` = 0: every member keeps the same scale), the camera's
  as-shot white balance, AHD demosaicing, LibRaw's camera-to-sRGB matrix, 16-bit output
  (65535 = the sensor's white level after black subtraction). Merge such members with
  ``response="linear"``.

Greyscale files are repeated into three channels; alpha is dropped. The EXIF orientation is
applied (LibRaw applies the RAW file's own). Exposure settings come from the EXIF IFD and
IFD 0 (Pillow for PNG/JPEG, tifffile for TIFF and TIFF-based RAW: DNG, NEF, CR2, ARW, PEF,
SRW), with APEX ``ShutterSpeedValue``/``ApertureValue`` when the plain tags are missing, and
LibRaw's own metadata for the RAW files tifffile cannot parse (CR3, RAF, ORF, RW2).
"""

import os
import sys
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

RAW_EXTENSIONS = (".dng", ".cr2", ".cr3", ".nef", ".arw", ".raf", ".orf", ".rw2", ".pef", ".srw")
"""Camera RAW files, decoded linear through LibRaw (``rawpy``)."""
IMAGE_EXTENSIONS = (".png", ".tif", ".tiff", ".jpg", ".jpeg")
"""Encoded 8/16-bit images."""

# EXIF tag numbers (CIPA DC-008, Exif 2.32)
_EXPOSURE_TIME = 33434
_F_NUMBER = 33437
_ISO = (34855, 34867, 34866)  # PhotographicSensitivity, ISOSpeed, RecommendedExposureIndex
_SHUTTER_APEX = 37377  # ShutterSpeedValue, Tv = −log2 t
_APERTURE_APEX = 37378  # ApertureValue, Av = 2 log2 N
_ORIENTATION = 274
_EXIF_IFD = 34665


class BracketFiles(NamedTuple):
    """A bracket read from files, sorted by exposure time (shortest first).

    Attributes:
        images: ``(N, H, W, 3)`` uint8 (8-bit files) or uint16 (16-bit files, camera RAW).
        exposure_times: ``(N,)`` float64 seconds (the caller's, else EXIF; NaN for a
            file without one when read with ``need_times=False``).
        f_numbers: ``(N,)`` float64 f-numbers from EXIF, NaN for a file without one;
            ``None`` when no file has one.
        isos: ``(N,)`` float64 ISO speeds from EXIF, NaN where missing; ``None`` when no
            file has one.
        paths: the files, in the same (sorted) order.
    """

    images: np.ndarray
    exposure_times: np.ndarray
    f_numbers: np.ndarray | None
    isos: np.ndarray | None
    paths: tuple[str, ...]


class _Settings(NamedTuple):
    exposure_time: float | None = None
    f_number: float | None = None
    iso: float | None = None
    orientation: int = 1


def _positive(v: float | None) -> float | None:
    return v if v is not None and np.isfinite(v) and v > 0 else None


def _rational(v: Any) -> float | None:
    """An EXIF RATIONAL as a float: Pillow's ``IFDRational``, tifffile's ``(num, den)``."""
    try:
        if isinstance(v, tuple | list):
            if len(v) == 2 and all(isinstance(x, int | np.integer) for x in v):
                return float(v[0]) / float(v[1]) if v[1] else None
            v = v[0] if v else None
        return None if v is None else float(v)
    except (TypeError, ValueError, ZeroDivisionError):
        return None


def _integer(v: Any) -> float | None:
    """An EXIF SHORT/LONG (possibly a list of them: the first) as a float."""
    try:
        if isinstance(v, tuple | list):
            v = v[0] if v else None
        return None if v is None else float(v)
    except (TypeError, ValueError):
        return None


def _settings(get: Any) -> _Settings:
    """Exposure settings from ``get(tag number)`` (EXIF IFD first, then IFD 0)."""
    t = _positive(_rational(get(_EXPOSURE_TIME)))
    if t is None:
        tv = _rational(get(_SHUTTER_APEX))
        t = _positive(2.0**-tv) if tv is not None and abs(tv) < 64 else None
    n = _positive(_rational(get(_F_NUMBER)))
    if n is None:
        av = _rational(get(_APERTURE_APEX))
        n = _positive(2.0 ** (av / 2)) if av is not None and abs(av) < 64 else None
    iso = None
    for tag in _ISO:
        iso = _positive(_integer(get(tag)))
        if iso is not None:
            break
    orientation = _integer(get(_ORIENTATION))
    o = int(orientation) if orientation is not None and 1 <= orientation <= 8 else 1
    return _Settings(t, n, iso, o)


def _pillow_settings(im: Any) -> _Settings:
    exif = im.getexif()
    sub = exif.get_ifd(_EXIF_IFD)
    return _settings(lambda tag: sub.get(tag, exif.get(tag)))


def _tiff_settings(tif: Any) -> _Settings:
    """Settings from a tifffile ``TiffFile``: the first page's tags and its EXIF IFD
    (tifffile parses the EXIF IFD into a dict keyed by tag name)."""
    import tifffile

    tags = tif.pages[0].tags
    exif_tag = tags.get(_EXIF_IFD)
    exif = exif_tag.value if exif_tag is not None and isinstance(exif_tag.value, dict) else {}

    def get(code: int) -> Any:
        for name in (
            tifffile.TIFF.EXIF_TAGS.get(code, None),
            tifffile.TIFF.TAGS.get(code, None),
            code,
        ):
            if name is not None and name in exif:
                return exif[name]
        tag = tags.get(code)
        return None if tag is None else tag.value

    return _settings(get)


def _orient(a: np.ndarray, orientation: int) -> np.ndarray:
    """Apply an EXIF orientation (TIFF 6.0 tag 274) to ``(H, W, C)`` pixels, as Pillow's
    ``ImageOps.exif_transpose`` does."""
    if orientation == 2:
        a = a[:, ::-1]
    elif orientation == 3:
        a = a[::-1, ::-1]
    elif orientation == 4:
        a = a[::-1]
    elif orientation == 5:
        a = a.transpose(1, 0, 2)
    elif orientation == 6:
        a = np.rot90(a, -1)
    elif orientation == 7:
        a = a[::-1, ::-1].transpose(1, 0, 2)
    elif orientation == 8:
        a = np.rot90(a, 1)
    return np.ascontiguousarray(a)


def _three_channels(a: np.ndarray, name: str, grey: bool) -> np.ndarray:
    """``(H, W, 3)`` from greyscale ``(H, W)``/``(H, W, 1|2)`` (grey, grey + alpha) or
    RGB(A) ``(H, W, 3|4)``; alpha dropped."""
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3:
        raise ValueError(f"{name}: expected a 2-D image, got an array of shape {a.shape}")
    c = a.shape[2]
    if grey or c in (1, 2):
        return np.repeat(a[:, :, :1], 3, axis=2)
    if c in (3, 4):
        return np.ascontiguousarray(a[:, :, :3])
    raise ValueError(f"{name}: expected 1 to 4 channels (grey, RGB, alpha), got {c}")


def _check_depth(a: np.ndarray, name: str) -> np.ndarray:
    if a.dtype == np.bool_:
        return a.astype(np.uint8) * np.uint8(255)
    if a.dtype in (np.uint8, np.uint16):
        return a
    raise ValueError(
        f"{name}: expected 8- or 16-bit integer code values, got {a.dtype} "
        "(linear float images are HDR already: read them with hdrjax.io.read)"
    )


_SIXTEEN = (";16B", ";16L", ";16N")


def _pillow_codes(path: str, name: str) -> tuple[np.ndarray, _Settings]:
    """Code values and settings through Pillow (PNG, JPEG, TIFF fallback)."""
    from PIL import Image

    with Image.open(path) as im:
        # how the file's samples are stored, before anything loads the pixels (which
        # clears the tiles): getexif may load a PNG whose eXIf chunk follows IDAT
        raws = {_rawmode(t) for t in im.tile}
        raw = raws.pop() if len(raws) == 1 else None
        if raws and any(r and r.endswith(_SIXTEEN) for r in raws):
            raise ValueError(f"{name}: 16-bit samples stored in several layouts; not supported")
        settings = _pillow_settings(im)
        if raw == "LA;16B":  # 16-bit grey + alpha: Pillow keeps the high bytes only
            both = _decode_as(path, "RGBA")  # the four bytes of each pixel, as stored
            grey = (both[:, :, 0].astype(np.uint16) << 8) | both[:, :, 1]
            return _three_channels(grey, name, True), settings
        if raw is not None and im.mode in ("RGB", "RGBA") and raw.endswith(_SIXTEEN):
            return _sixteen_bit(path, raw), settings
        if im.mode in ("I;16", "I;16B", "I;16L", "I;16N"):
            return _three_channels(np.asarray(im).astype(np.uint16), name, True), settings
        if im.mode in ("RGB", "RGBA", "L", "LA"):
            return _three_channels(np.asarray(im), name, im.mode in ("L", "LA")), settings
        if im.mode in ("P", "PA", "1", "CMYK", "YCbCr", "LAB", "HSV"):
            return np.asarray(im.convert("RGB")), settings
        raise ValueError(f"{name}: unsupported pixel format {im.mode!r} (expected 8/16-bit)")


def _sixteen_bit(path: str, raw: str) -> np.ndarray:
    """16-bit RGB(A) through Pillow, which unpacks only the high byte of each sample: decode
    twice, unpacking the sample's high byte (as stored: ``;16B`` big-endian, ``;16L``
    little-endian, ``;16N`` native) and then its low byte (the same bytes read with the
    other byte order), and join the two."""
    stem = raw[: -len(";16B")]
    order = raw[-1]
    if order == "N":
        order = "L" if sys.byteorder == "little" else "B"
    swapped = "L" if order == "B" else "B"
    high = _decode_as(path, f"{stem};16{order}")[:, :, :3]
    low = _decode_as(path, f"{stem};16{swapped}")[:, :, :3]
    return (high.astype(np.uint16) << 8) | low.astype(np.uint16)


def _rawmode(tile: Any) -> str | None:
    """The raw mode of a Pillow tile (its decoder arguments: the mode, or a tuple that
    starts with it)."""
    args = tile[3]
    if isinstance(args, tuple) and args and isinstance(args[0], str):
        return args[0]
    return args if isinstance(args, str) else None


def _decode_as(path: str, rawmode: str) -> np.ndarray:
    """Pillow's decoding of the file (every tile: strips, tiles) unpacked with ``rawmode``."""
    from PIL import Image

    with Image.open(path) as im:
        tiles: list[Any] = []
        for t in im.tile:
            args = (rawmode, *t[3][1:]) if isinstance(t[3], tuple) else rawmode
            tiles.append(t._replace(args=args) if hasattr(t, "_replace") else (*t[:3], args))
        im.tile = tiles
        im.load()
        return np.asarray(im)


def _tiff_codes(path: str, name: str) -> tuple[np.ndarray, _Settings]:
    """Code values and settings through tifffile (Pillow for compressions tifffile cannot
    decode by itself)."""
    import tifffile

    try:
        with tifffile.TiffFile(path) as tif:
            settings = _tiff_settings(tif)
            page = tif.pages[0]
            photometric = int(page.photometric)
            try:
                a = page.asarray()
            except (ValueError, KeyError, NotImplementedError) as e:
                if "imagecodecs" not in str(e):
                    raise
                a = None
            axes = page.axes
    except Exception as e:  # tifffile reports damaged files with many exception types
        text = " ".join(str(e).split())
        raise ValueError(f"{name}: not a readable TIFF file ({type(e).__name__}: {text})") from None
    if a is None:
        codes, _ = _pillow_codes(path, name)
        return _orient(codes, settings.orientation), settings
    if photometric not in (0, 1, 2):  # MINISWHITE, MINISBLACK, RGB
        known = photometric in {int(v) for v in tifffile.PHOTOMETRIC}
        kind = tifffile.PHOTOMETRIC(photometric).name if known else str(photometric)
        raise ValueError(f"{name}: unsupported TIFF photometric {kind}; expected RGB or grey")
    a = _check_depth(a, name)
    if photometric == 0:
        a = np.iinfo(a.dtype).max - a
    axes = axes.replace("I", "").replace("Q", "")
    if "S" in axes and axes.index("S") < axes.index("X"):  # planar: samples first
        a = np.moveaxis(a, axes.index("S"), -1)
    codes = _three_channels(a, name, photometric in (0, 1))
    return _orient(codes, settings.orientation), settings


def _raw_codes(path: str, name: str) -> tuple[np.ndarray, _Settings]:
    """Linear 16-bit RGB of a camera RAW file through LibRaw (see the module docstring)."""
    try:
        import rawpy
    except ImportError:
        raise ValueError(
            f"{name}: camera RAW needs the 'rawpy' package (pip install 'hdrjax[raw]')"
        ) from None
    try:
        with rawpy.imread(path) as raw:
            rgb = raw.postprocess(
                gamma=(1, 1),
                no_auto_bright=True,
                output_bps=16,
                use_camera_wb=True,
                adjust_maximum_thr=0.0,
            )
            other = getattr(raw, "other", None)
    except (rawpy.LibRawError, OSError, ValueError) as e:
        raise ValueError(f"{name}: LibRaw cannot read it ({type(e).__name__}: {e})") from None
    settings = _Settings()
    try:
        import tifffile

        with tifffile.TiffFile(path) as tif:
            settings = _tiff_settings(tif)
    except Exception:  # not TIFF-based (CR3, RAF...) or a maker variant: LibRaw's values
        pass
    if other is not None:
        settings = _Settings(
            settings.exposure_time or _positive(float(other.shutter_speed)),
            settings.f_number or _positive(float(other.aperture)),
            settings.iso or _positive(float(other.iso_speed)),
        )
    codes = np.asarray(rgb)
    if codes.dtype != np.uint16 or codes.ndim != 3 or codes.shape[2] != 3:
        raise ValueError(f"{name}: LibRaw returned {codes.dtype} {codes.shape}, not 16-bit RGB")
    return codes, settings


def _read_exposure(path: str | os.PathLike) -> tuple[np.ndarray, _Settings]:
    """One member of a bracket: ``(codes (H, W, 3) uint8|uint16, settings)``."""
    p = os.fspath(path)
    name = p
    if not os.path.exists(p):
        raise FileNotFoundError(2, "no such file", p)
    if os.path.isdir(p):
        raise ValueError(f"{name}: is a folder, not an image")
    ext = os.path.splitext(p)[1].lower()
    if ext in RAW_EXTENSIONS:
        return _raw_codes(p, name)
    if ext not in IMAGE_EXTENSIONS:
        raise ValueError(
            f"{name}: unsupported file type {ext or '(none)'}; expected "
            f"{', '.join(IMAGE_EXTENSIONS)} or camera RAW ({', '.join(RAW_EXTENSIONS)})"
        )
    from PIL import UnidentifiedImageError

    try:
        if ext in (".tif", ".tiff"):
            return _tiff_codes(p, name)
        codes, settings = _pillow_codes(p, name)
    except (UnidentifiedImageError, OSError, SyntaxError, EOFError) as e:
        raise ValueError(f"{name}: cannot read the image ({' '.join(str(e).split())})") from None
    return _orient(codes, settings.orientation), settings


def _bits(a: np.ndarray) -> int:
    return 8 * a.dtype.itemsize


def _optional(values: list[float | None]) -> np.ndarray | None:
    if all(v is None for v in values):
        return None
    return np.array([np.nan if v is None else v for v in values], dtype=np.float64)


def read_bracket(
    paths: str | os.PathLike | Sequence[str | os.PathLike],
    exposure_times: ArrayLike | None = None,
    *,
    need_times: bool = True,
    progress: bool = False,
) -> BracketFiles:
    """Read an exposure bracket from image files (see the module docstring for formats).

    Args:
        paths: the files (PNG, TIFF, JPEG 8/16-bit or camera RAW), in any order.
        exposure_times: ``(N,)`` seconds, one per file in the order of ``paths``; they
            replace the EXIF exposure times. Needed for files without one.
        need_times: ``False`` for uses that need no exposure times (exposure fusion): a
            file without one is then no error, its time is NaN and the bracket keeps the
            order of ``paths``.
        progress: show a progress bar while reading (on a terminal or in a Jupyter
            notebook).

    Returns:
        :class:`BracketFiles`, sorted by exposure time (shortest first).

    Raises:
        FileNotFoundError: a file does not exist (its path named).
        ValueError: one line naming the file and the problem: unreadable or unsupported,
            no exposure time (in EXIF or given), a size or bit depth different from the
            first file's, or the same exposure time as another member.
    """
    if isinstance(paths, str | os.PathLike):
        paths = [paths]
    files = [os.fspath(p) for p in paths]
    if not files:
        raise ValueError("paths: expected at least one image file, got none")
    times = None
    if exposure_times is not None:
        times = np.asarray(exposure_times, dtype=np.float64).reshape(-1)
        if times.shape[0] != len(files):
            raise ValueError(
                f"exposure_times: expected one time per file ({len(files)}), got {times.shape[0]}"
            )
        if not np.all(np.isfinite(times) & (times > 0)):
            raise ValueError(f"exposure_times: expected positive finite seconds, got {times}")
    from .._progress import progress_bar

    images: list[np.ndarray] = []
    found: list[_Settings] = []
    bar = progress_bar(files, desc="reading", unit="file", enabled=progress, leave=False)
    for p in bar:
        codes, settings = _read_exposure(p)
        if images:
            first, ref = files[0], images[0]
            if codes.shape != ref.shape:
                h, w = codes.shape[:2]
                raise ValueError(
                    f"{p}: {w}x{h} pixels, but {first} has {ref.shape[1]}x{ref.shape[0]}; "
                    "a bracket's exposures must have one size"
                )
            if codes.dtype != ref.dtype:
                raise ValueError(
                    f"{p}: {_bits(codes)}-bit, but {first} is {_bits(ref)}-bit; "
                    "a bracket's exposures must have one bit depth"
                )
        images.append(codes)
        found.append(settings)
    if times is None:
        for p, s in zip(files, found, strict=True):
            if s.exposure_time is None and need_times:
                raise ValueError(
                    f"{p}: no exposure time in EXIF and none given (exposure_times, one per file)"
                )
        times = np.array([s.exposure_time or np.nan for s in found], dtype=np.float64)
    known = bool(np.all(np.isfinite(times)))
    order = np.argsort(times, kind="stable") if known else np.arange(len(files))
    for a, b in zip(order[:-1], order[1:], strict=True):
        if known and times[a] == times[b]:
            raise ValueError(
                f"{files[b]}: same exposure time ({times[b]:g} s) as {files[a]}; "
                "a bracket's exposures must be distinct"
            )
    f_numbers = _optional([found[i].f_number for i in order])
    isos = _optional([found[i].iso for i in order])
    return BracketFiles(
        np.stack([images[i] for i in order]),
        times[order],
        f_numbers,
        isos,
        tuple(files[i] for i in order),
    )


__all__ = ["IMAGE_EXTENSIONS", "RAW_EXTENSIONS", "BracketFiles", "read_bracket"]
