"""OpenEXR reading and writing of layered images (through the ``OpenEXR`` bindings).

Channel-name conventions (read and written; the reader also accepts the listed aliases):

============  =====================================  ==========================================
layer         EXR channels written                   also read
============  =====================================  ==========================================
image (RGB)   ``R``, ``G``, ``B``                    ``Y`` (grey), ``Y``/``RY``/``BY``
spectral      ``S0.<λ>nm`` (decimal comma, e.g.      same, with ``.`` or ``,``
              ``S0.550,000000nm``), attribute
              ``spectralLayoutVersion``
reflective    ``T.<λ>nm`` (channel names keep the    same, with ``.`` or ``,``
spectral      ``T.`` prefix)
alpha         ``A``
depth         ``Z``
position      ``P.X``, ``P.Y``, ``P.Z``              ``position.*``, ``Pworld.*``, ``x/y/z``,
                                                     ``R/G/B`` inside the group
object_id     ``object_id`` (uint)                   ``objectId``, ``ObjectID``, ``id``
error         ``error``
hits          ``hits`` (uint when integral)
grid          ``grid`` or ``grid.R/G/B``
free name     ``name`` or ``name.<channel>``
non-grid      attribute ``hdrjax.layer.<name>``
              (JSON with base64 data, bit-exact)
============  =====================================  ==========================================

Multi-view files (``multiView`` attribute) keep the default view unprefixed and other views
as ``<view>.<channel>``; ``read(..., layer="left")`` selects a view. Multi-part files: the
chosen part (``part=``, default 0) gives the image; every other part becomes a layer named
after the part, placed into the chosen part's data window (pixels outside the other
part's data window are NaN, or 0xFFFFFFFF for uint layers). Subsampled channels (RY, BY)
are upsampled by linear interpolation. Tiled and mip-mapped files give their top level.
"""

import base64
import json
import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from ..layers import _model as M
from ..layers._errors import LayerShapeError, MissingLayerError, ReadError
from . import _exr_core

EXR_MAGIC = b"\x76\x2f\x31\x01"
MAX_PIXELS = 1 << 30
"""Largest data window (pixels) accepted."""

_STRUCTURAL = {
    "channels",
    "dataWindow",
    "displayWindow",
    "compression",
    "type",
    "lineOrder",
    "chunkCount",
    "tiles",
    "name",
    "view",
    "multiView",
    "chromaticities",
    "whiteLuminance",
    "version",
}
_QUANTITY_ATTR = "quantity"
_UNIT_ATTR = "unit"
_SENSOR_ATTR = "hdrjax.sensorSize"
_PROJ_ATTR = "hdrjax.projection"
_SIBLINGS_ATTR = "hdrjax.siblings"
_NONGRID_PREFIX = "hdrjax.layer."
_CHANNELS_PREFIX = "hdrjax.channels."

_POSITION_GROUPS = {"P", "position", "Position", "Pworld", "P_world", "pos"}
_OBJECT_ID_NAMES = {"object_id", "objectId", "ObjectID", "objectID", "object_index", "id", "ID"}
_ORDER = ["R", "G", "B", "A", "X", "Y", "Z", "x", "y", "z", "u", "v", "w"]
_SPECTRAL_RE = re.compile(r"^(\d+(?:[.,]\d+)?)(nm)$")
# Fichet, Pacanowski & Wilkie 2021 (JCGT 10(3)): emissive bands in group S0 (S1-S3 are the
# other Stokes components, read as layers), reflective bands in group T
_SPECTRAL_GROUPS = ("S0", "T")
_REFLECTIVE = "T"

_COMPRESSION = {
    "none": "NO_COMPRESSION",
    "rle": "RLE_COMPRESSION",
    "zips": "ZIPS_COMPRESSION",
    "zip": "ZIP_COMPRESSION",
    "piz": "PIZ_COMPRESSION",
    "pxr24": "PXR24_COMPRESSION",
    "b44": "B44_COMPRESSION",
    "b44a": "B44A_COMPRESSION",
    "dwaa": "DWAA_COMPRESSION",
    "dwab": "DWAB_COMPRESSION",
}


def _exr():
    import OpenEXR

    return OpenEXR


def _sort_key(base: str) -> tuple[int, str]:
    return (_ORDER.index(base) if base in _ORDER else len(_ORDER), base)


def _window(w: Any) -> tuple[int, int, int, int]:
    lo, hi = w
    return (int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1]))


def stored_pixel_type(arr: np.ndarray) -> str:
    return {np.dtype(np.float16): "half", np.dtype(np.float32): "float"}.get(arr.dtype, "uint")


def _upsample(arr: np.ndarray, xs: int, ys: int, h: int, w: int) -> np.ndarray:
    """Linear interpolation of a channel sampled every ``xs``/``ys`` pixels to ``(h, w)``."""
    a = arr.astype(np.float32)

    def axis(n_out: int, n_in: int, s: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.arange(n_out, dtype=np.float64) / s
        i0 = np.minimum(np.floor(t).astype(np.int64), n_in - 1)
        i1 = np.minimum(i0 + 1, n_in - 1)
        return i0, i1, (t - i0).astype(np.float32)

    if ys > 1:
        i0, i1, f = axis(h, a.shape[0], ys)
        a = a[i0] * (1 - f)[:, None] + a[i1] * f[:, None]
    if xs > 1:
        i0, i1, f = axis(w, a.shape[1], xs)
        a = a[:, i0] * (1 - f)[None, :] + a[:, i1] * f[None, :]
    return np.ascontiguousarray(a[:h, :w])


def _split(name: str) -> tuple[str, str]:
    """``"P.X"`` → ``("P", "X")``; ``"R"`` → ``("", "R")``; spectral names keep their dot."""
    group, dot, rest = name.partition(".")
    if dot and group in _SPECTRAL_GROUPS and _SPECTRAL_RE.match(rest):
        return group, rest
    prefix, dot, base = name.rpartition(".")
    return (prefix, base) if dot else ("", name)


def _json_layer(value: Any) -> str:
    if isinstance(value, dict):
        return json.dumps({"kind": "dict", "value": value}, allow_nan=True)
    arr = np.ascontiguousarray(value)
    return json.dumps(
        {
            "kind": "array",
            "dtype": arr.dtype.str,
            "shape": list(arr.shape),
            "data": base64.b64encode(arr.tobytes()).decode("ascii"),
        }
    )


def _unjson_layer(text: str, name: str, key: str) -> Any:
    try:
        obj = json.loads(text)
        if obj["kind"] == "dict":
            return dict(obj["value"])
        dtype = np.dtype(obj["dtype"])
        if dtype.kind not in "biuf":
            raise ValueError(f"dtype {dtype}")
        shape = tuple(int(s) for s in obj["shape"])
        raw = base64.b64decode(obj["data"], validate=True)
        if len(raw) != dtype.itemsize * math.prod(shape):
            raise ValueError("size mismatch")
        return np.frombuffer(raw, dtype=dtype).reshape(shape).copy()
    except (ValueError, KeyError, TypeError) as e:
        raise ReadError(f"{name}: corrupt non-grid layer attribute {key!r} ({e})") from None


def _check_header(name: str, size: int, headers: list[dict]) -> None:
    for h in headers:
        try:
            x0, y0, x1, y1 = _window(h["dataWindow"])
        except (KeyError, TypeError, ValueError):
            raise ReadError(f"{name}: OpenEXR part without a valid dataWindow") from None
        if x1 < x0 or y1 < y0:
            raise ReadError(f"{name}: empty OpenEXR data window {(x0, y0, x1, y1)}")
        w, hh = x1 - x0 + 1, y1 - y0 + 1
        nbytes = 0
        for ch in h.get("channels", []):
            xs, ys = max(int(ch.xSampling), 1), max(int(ch.ySampling), 1)
            nbytes += 4 * (-(-w // xs)) * (-(-hh // ys))
        # compressed data cannot shrink more than ~1000x (zlib's limit); refuse windows that
        # the file size cannot possibly hold, before anything is allocated
        if w * hh > MAX_PIXELS or nbytes > 2048 * size + (64 << 20):
            raise ReadError(f"{name}: absurd OpenEXR data window {w} x {hh} for a {size}-byte file")
        if h.get("type") is not None and "deep" in str(h.get("type")):
            raise ReadError(f"{name}: deep OpenEXR images are not supported")


def open_exr(path: Path):
    name = path.name
    OpenEXR = _exr()
    try:
        with open(path, "rb") as f:
            magic = f.read(4)
        size = path.stat().st_size
    except OSError as e:
        raise OSError(f"{name}: cannot read ({e.strerror or e})") from None
    if magic != EXR_MAGIC:
        raise ReadError(f"{name}: not an OpenEXR file (bad magic number)")
    # the bindings print (rather than raise) what they find wrong; ask the C library first,
    # silently, so that a truncated file or a corrupt header never reaches them
    problem = _exr_core.check(str(path), size)
    if problem is not None:
        raise ReadError(f"{name}: corrupt or truncated OpenEXR file ({problem[:160]})")
    try:
        head = OpenEXR.File(str(path), header_only=True)
        nparts = len(head.parts)
        if nparts == 0:
            raise ReadError(f"{name}: corrupt OpenEXR header (no parts)")
        _check_header(name, size, [p.header for p in head.parts])
        f = OpenEXR.File(str(path), separate_channels=True)
    except ReadError:
        raise
    except Exception as e:  # the bindings raise RuntimeError/OpenEXR.error/ValueError/...
        msg = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise ReadError(f"{name}: corrupt or unsupported OpenEXR file ({msg[:160]})") from None
    if len(f.parts) != nparts:
        # the chunks are framed correctly (checked above): their content is not; the library
        # has printed its reason
        raise ReadError(
            f"{name}: corrupt OpenEXR pixel data ({nparts - len(f.parts)} of {nparts} "
            "part(s) could not be decoded by the OpenEXR library)"
        )
    return f


def part_channels(part, name: str) -> tuple[dict[str, np.ndarray], tuple[int, int, int, int]]:
    """Channels of a part at full data-window resolution (subsampled ones upsampled)."""
    header = part.header
    dw = _window(header["dataWindow"])
    w, h = dw[2] - dw[0] + 1, dw[3] - dw[1] + 1
    out = {}
    for cname, ch in part.channels.items():
        px = ch.pixels
        if px is None:
            raise ReadError(f"{name}: channel {cname!r} has no pixel data")
        px = np.asarray(px)
        if px.dtype not in (np.float16, np.float32, np.uint32):
            raise ReadError(f"{name}: channel {cname!r} has unknown pixel type {px.dtype}")
        xs, ys = int(ch.xSampling), int(ch.ySampling)
        if px.ndim != 2:
            raise ReadError(f"{name}: channel {cname!r} has shape {px.shape}, expected 2-D")
        if (xs, ys) != (1, 1):
            want = (-(-h // ys), -(-w // xs))
            if px.shape != want:
                raise ReadError(f"{name}: subsampled channel {cname!r} has shape {px.shape}")
            px = _upsample(px, xs, ys, h, w)
        elif px.shape != (h, w):
            raise ReadError(
                f"{name}: channel {cname!r} has shape {px.shape}, expected {(h, w)} "
                "from the data window"
            )
        out[cname] = px
    return out, dw


def _canonical(group: str, bases: list[str]) -> str:
    if group in _POSITION_GROUPS:
        return M.POSITION
    if group == "" and len(bases) == 1:
        b = bases[0]
        if b in _OBJECT_ID_NAMES:
            return M.OBJECT_ID
        if b == "A":
            return M.ALPHA
        if b == "Z":
            return M.DEPTH
        return b
    return group


_XYZ_ORDER = {"X": 0, "x": 0, "R": 0, "Y": 1, "y": 1, "G": 1, "Z": 2, "z": 2, "B": 2}


def xyz_order(bases: list[str], full: list[str]) -> list[str] | None:
    """``full`` reordered as X, Y, Z when ``bases`` name three coordinates, else ``None``."""
    if len(bases) != 3 or sorted(_XYZ_ORDER.get(b, 9) for b in bases) != [0, 1, 2]:
        return None
    return [f for _, f in sorted(zip([_XYZ_ORDER[b] for b in bases], full, strict=True))]


def stack_channels(chans: dict[str, np.ndarray], names: list[str]) -> np.ndarray:
    arrs = [chans[n] for n in names]
    if len(arrs) == 1:
        return arrs[0]
    dt = np.result_type(*arrs)
    return np.stack([a.astype(dt, copy=False) for a in arrs], axis=2)


def as_layer_array(arr: np.ndarray) -> np.ndarray:
    return arr.astype(np.float32) if arr.dtype == np.float16 else arr


def channel_groups(chans: dict[str, np.ndarray]) -> dict[str, list[str]]:
    groups: dict[str, list[str]] = {}
    for cname in chans:
        g, b = _split(cname)
        groups.setdefault(g, []).append(b)
    for g in groups:
        groups[g].sort(key=_sort_key)
    return groups


def _image_from_group(
    group: str, bases: list[str], chans: dict[str, np.ndarray]
) -> tuple[np.ndarray, tuple[str, ...], list[str], np.ndarray | None] | None:
    """``(image, channel names, used bases, wavelengths)`` if the group holds an image."""

    def full(b: str) -> str:
        return f"{group}.{b}" if group else b

    s = set(bases)
    if {"R", "G", "B"} <= s:
        used = ["R", "G", "B"]
        return stack_channels(chans, [full(b) for b in used]), ("R", "G", "B"), used, None
    if {"Y", "RY", "BY"} <= s:
        used = ["Y", "RY", "BY"]
        return stack_channels(chans, [full(b) for b in used]), ("Y", "RY", "BY"), used, None
    if "Y" in s and not ({"X", "Z"} <= s):
        return stack_channels(chans, [full("Y")]), ("Y",), ["Y"], None
    spec = [(float(m.group(1).replace(",", ".")), b) for b in bases if (m := _SPECTRAL_RE.match(b))]
    if spec and group in ("", *_SPECTRAL_GROUPS):
        spec.sort()
        used = [b for _, b in spec]
        wl = np.array([v for v, _ in spec], dtype=np.float32)
        # the T. prefix stays in the names: it is what says the bands are reflectance
        names = tuple(full(b) for b in used) if group == _REFLECTIVE else tuple(used)
        return stack_channels(chans, [full(b) for b in used]), names, used, wl
    return None


def _place(arr: np.ndarray, src: tuple, dst: tuple) -> np.ndarray:
    """Put ``arr`` (covering window ``src``) into window ``dst``; NaN / 0xFFFFFFFF outside."""
    if src == dst:
        return arr
    w, h = dst[2] - dst[0] + 1, dst[3] - dst[1] + 1
    fill = np.uint32(0xFFFFFFFF) if arr.dtype == np.uint32 else np.nan
    out = np.full((h, w) + arr.shape[2:], fill, dtype=arr.dtype)
    x0, y0 = max(src[0], dst[0]), max(src[1], dst[1])
    x1, y1 = min(src[2], dst[2]), min(src[3], dst[3])
    if x0 <= x1 and y0 <= y1:
        out[y0 - dst[1] : y1 - dst[1] + 1, x0 - dst[0] : x1 - dst[0] + 1] = arr[
            y0 - src[1] : y1 - src[1] + 1, x0 - src[0] : x1 - src[0] + 1
        ]
    return out


def _plain(value: Any) -> Any:
    """Header attribute values as plain Python / NumPy data (enums as their names)."""
    if isinstance(value, (str, int, float, bool)):
        return value
    if isinstance(value, np.ndarray):
        return value
    if isinstance(value, (list, tuple)):
        return type(value)(_plain(v) for v in value)
    if hasattr(value, "name") and hasattr(value, "value") and type(value).__module__ == "OpenEXR":
        return value.name
    return value


def _sibling_path(path: Path, recorded: str) -> Path:
    """A sibling file as recorded in ``path``'s header: a name in the same folder, a path
    relative to the folder's real location (``hdrjax.io.write`` takes it between real
    paths, so ``..`` steps are exact), or an absolute path."""
    p = Path(recorded)
    if p.is_absolute():
        return p
    if len(p.parts) == 1:
        return path.parent / p
    return Path(os.path.normpath(os.path.join(os.path.realpath(path.parent), p)))


def read_exr(
    path: str | os.PathLike, *, part: int | str | None = None, layer: str | None = None
) -> M.LayeredImage:
    """Read an OpenEXR file as a :class:`LayeredImage` (see the module doc for layouts).

    Args:
        path: the ``.exr`` file.
        part: part index or name for multi-part files (default: the first part).
        layer: the channel group (layer or view) to use as the main image, e.g.
            ``"left"`` in a stereo file, ``"position"`` for the positions.

    Raises:
        ReadError: not an OpenEXR file, corrupt data, absurd data window, or no image.
        MissingLayerError: ``part`` or ``layer`` is not in the file.
    """
    path = Path(path)
    name = path.name
    f = open_exr(path)
    try:
        parts = list(f.parts)
    except Exception as e:
        raise ReadError(f"{name}: corrupt OpenEXR file ({e})") from None
    names = []
    for i, p in enumerate(parts):
        try:
            names.append(str(p.name()) or f"part{i}")
        except Exception:
            names.append(f"part{i}")
    if part is None:
        index = 0
    elif isinstance(part, int) and not isinstance(part, bool):
        if not 0 <= part < len(parts):
            raise MissingLayerError(f"{name} has no part {part}; it has {len(parts)} part(s)")
        index = part
    else:
        if str(part) not in names:
            raise MissingLayerError(
                f"{name} has no {str(part)!r} part; parts present: {', '.join(names)}"
            )
        index = names.index(str(part))
    main = parts[index]
    header = main.header
    try:
        chans, dw = part_channels(main, name)
    except ReadError:
        raise
    except Exception as e:
        raise ReadError(f"{name}: corrupt OpenEXR pixel data ({e})") from None
    groups = channel_groups(chans)
    views = [str(v) for v in header.get("multiView", []) or []]

    # -- choose the main image ---------------------------------------------------------
    if layer is not None:
        aliases = {M.POSITION: [g for g in groups if g in _POSITION_GROUPS]}
        target = layer if layer in groups else next(iter(aliases.get(layer, [])), None)
        if target is None:
            raise MissingLayerError(f"{name} has no {layer!r} channel group")
        bases = groups[target]
        got = _image_from_group(target, bases, chans)
        if got is None:
            full = [f"{target}.{b}" for b in bases]
            img = stack_channels(chans, full)
            got = (img, tuple(bases), bases, None)
        main_group = target
    else:
        main_group = ""
        got = _image_from_group("", groups.get("", []), chans) if "" in groups else None
        if got is None:
            for g, bases in groups.items():
                got = _image_from_group(g, bases, chans)
                if got is not None:
                    main_group = g
                    break
        if got is None and len(groups) == 1:
            # a part holding one layer only (e.g. "position" in a one-part-per-layer file):
            # its channels are the image
            ((main_group, bases),) = groups.items()
            full = [f"{main_group}.{b}" if main_group else b for b in bases]
            got = (stack_channels(chans, full), tuple(bases), bases, None)
        if got is None:
            raise ReadError(
                f"{name}: no image channels (R, G, B / Y / Y, RY, BY / S0.<λ>nm) in part "
                f"{names[index]!r}; channels present: {', '.join(sorted(chans)) or 'none'}; "
                "pass layer= to pick one"
            )
    image, ch_names, used, wavelengths = got
    ptype = stored_pixel_type(chans[f"{main_group}.{used[0]}" if main_group else used[0]])

    # -- layers of the chosen part -----------------------------------------------------
    layers: dict[str, Any] = {}
    layer_channels: dict[str, tuple[str, ...]] = {}
    pixel_types: dict[str, str] = {"image": ptype}
    for g, bases in groups.items():
        rest = [b for b in bases if not (g == main_group and b in used)]
        if not rest:
            continue
        if g == main_group:
            items = [(_canonical("", [b]), [b]) for b in rest]
        elif g == "":
            # the default view's channels, when another view or layer was selected
            items = [(views[0] if views else "main", rest)]
        else:
            items = [(_canonical(g, rest), rest)]
        for key, bs in items:
            full = [f"{g}.{b}" if g else b for b in bs]
            if key == M.POSITION:
                ordered = xyz_order(bs, full)
                if ordered is None:
                    key = g
                else:
                    full, bs = ordered, ["X", "Y", "Z"]
            if key in layers:
                key = g + "." + bs[0] if g else bs[0]
            arr = stack_channels(chans, full)
            pixel_types[key] = stored_pixel_type(arr)
            layers[key] = as_layer_array(arr)
            if len(bs) > 1:
                layer_channels[key] = tuple(bs)
    # -- other parts become layers -----------------------------------------------------
    for i, p in enumerate(parts):
        if i == index:
            continue
        try:
            pch, pdw = part_channels(p, name)
        except ReadError:
            raise
        except Exception as e:
            raise ReadError(
                f"{name}: corrupt OpenEXR pixel data in part {names[i]!r} ({e})"
            ) from None
        pg = channel_groups(pch)
        for g, bases in pg.items():
            full = [f"{g}.{b}" if g else b for b in bases]
            key = names[i] if len(pg) == 1 else f"{names[i]}.{g or 'main'}"
            canon = _canonical(g, bases)
            if canon in (M.POSITION, M.OBJECT_ID, M.ERROR, M.HITS, M.GRID) and canon not in layers:
                key = canon
            elif names[i] in M.KNOWN_LAYERS and names[i] not in layers and len(pg) == 1:
                key = names[i]
            if key == M.POSITION:
                ordered = xyz_order(bases, full)
                if ordered is not None:
                    full, bases = ordered, ["X", "Y", "Z"]
            arr = stack_channels(pch, full)
            pixel_types[key] = stored_pixel_type(arr)
            layers[key] = _place(as_layer_array(arr), pdw, dw)
            if len(bases) > 1:
                layer_channels[key] = tuple(bases)

    # -- metadata ----------------------------------------------------------------------
    attributes: dict[str, Any] = {}
    for k, v in header.items():
        if k in _STRUCTURAL:
            continue
        if k.startswith(_NONGRID_PREFIX) and isinstance(v, str):
            layers[k[len(_NONGRID_PREFIX) :]] = _unjson_layer(v, name, k)
            continue
        if k.startswith(_CHANNELS_PREFIX) and isinstance(v, (list, tuple)):
            layer_channels[k[len(_CHANNELS_PREFIX) :]] = tuple(str(x) for x in v)
            continue
        attributes[k] = _plain(v)
    if len(parts) > 1:
        attributes["parts"] = names
    if views:
        attributes["multiView"] = views
    if "view" in header:
        attributes["view"] = str(header["view"])
    for k in list(layer_channels):
        if k not in layers:
            del layer_channels[k]
    if wavelengths is not None:
        layers[M.WAVELENGTHS] = wavelengths
    chroma = header.get("chromaticities")
    wl = header.get("whiteLuminance")
    quantity = str(attributes.pop(_QUANTITY_ATTR, "relative"))
    unit = attributes.pop(_UNIT_ATTR, None)
    sensor = attributes.pop(_SENSOR_ATTR, None)
    projection = attributes.pop(_PROJ_ATTR, None)
    siblings = attributes.pop(_SIBLINGS_ATTR, None)
    if projection is None and "envmap" in attributes:
        projection = {"ENVMAP_LATLONG": "equirectangular", "ENVMAP_CUBE": "cubemap"}.get(
            str(attributes["envmap"])
        )
    if quantity not in M.QUANTITIES:
        raise ReadError(
            f"{name}: unknown quantity attribute {quantity!r}; expected one of "
            + ", ".join(M.QUANTITIES)
        )
    sib: dict[str, Path] = {}
    if isinstance(siblings, (list, tuple)):
        for item in siblings:
            q, _, fname = str(item).partition("=")
            if q and fname:
                sib[q] = _sibling_path(path, fname)
    try:
        return M.LayeredImage(
            image=image,
            channels=ch_names,
            quantity=quantity,
            unit=str(unit) if unit is not None else None,
            chromaticities=tuple(chroma) if chroma is not None else None,
            layers=layers,
            layer_channels=layer_channels,
            attributes=attributes,
            path=path,
            white_luminance=float(wl) if wl is not None else None,
            data_window=dw,
            display_window=_window(header["displayWindow"]) if "displayWindow" in header else dw,
            pixel_types=pixel_types,
            sensor_size=tuple(float(v) for v in sensor) if sensor is not None else None,
            projection=str(projection) if projection is not None else None,
            siblings=sib,
        )
    except LayerShapeError:
        raise
    except ReadError:
        raise
    except (TypeError, ValueError) as e:
        raise ReadError(f"{name}: bad OpenEXR metadata ({e})") from None


# -- writing ------------------------------------------------------------------------------


def _spectral_name(wl: float, group: str = "S0") -> str:
    return f"{group}." + f"{wl:.6f}".replace(".", ",") + "nm"


def _layer_channel_names(img: M.LayeredImage, key: str, arr: np.ndarray) -> list[str]:
    k = 1 if arr.ndim == 2 else arr.shape[2]
    if key == M.POSITION:
        return ["P.X", "P.Y", "P.Z"]
    if k == 1:
        return [{M.ALPHA: "A", M.DEPTH: "Z"}.get(key, key)]
    names = img.layer_channels.get(key)
    if names is None or len(names) != k:
        names = ("R", "G", "B") if k == 3 else tuple(str(i) for i in range(k))
    return [f"{key}.{n}" for n in names]


def _cast(arr: np.ndarray, ptype: str, what: str) -> np.ndarray:
    if ptype == "half":
        return np.ascontiguousarray(arr, dtype=np.float16)
    if ptype == "float":
        return np.ascontiguousarray(arr, dtype=np.float32)
    if ptype == "uint":
        a = np.asarray(arr)
        if not np.issubdtype(a.dtype, np.integer):
            if not np.all(np.isfinite(a)) or np.any(a < 0) or np.any(a != np.round(a)):
                raise ValueError(f"{what}: uint pixel type needs integers >= 0")
        if a.size and (a.min() < 0 or a.max() > 0xFFFFFFFF):
            raise ValueError(f"{what}: values out of the uint32 range")
        return np.ascontiguousarray(a, dtype=np.uint32)
    raise ValueError(f"{what}: unknown pixel type {ptype!r}; expected 'half', 'float' or 'uint'")


def _default_layer_type(
    img: M.LayeredImage, key: str, arr: np.ndarray, pixel_type: str | None
) -> str:
    if np.issubdtype(arr.dtype, np.integer) or arr.dtype == np.bool_:
        return "uint"
    if pixel_type is not None:
        return pixel_type
    return img.pixel_types.get(key, "half" if arr.dtype == np.float16 else "float")


def layer_planes(img: M.LayeredImage, key: str, pixel_type: str | None) -> dict[str, np.ndarray]:
    """EXR channel name → plane (cast to its pixel type) for grid layer ``key``.

    Integer layers are stored as uint; ``object_id`` and integral ``hits`` always so.
    """
    arr = np.asarray(img.layers[key])
    lt = _default_layer_type(
        img, key, arr, pixel_type if key not in (M.OBJECT_ID, M.HITS) else None
    )
    if key == M.HITS and not np.issubdtype(arr.dtype, np.integer):
        lt = "float" if pixel_type is None else pixel_type
    names = _layer_channel_names(img, key, arr)
    what = f"{img.name}: layer {key!r}"
    return {
        cn: _cast(arr if arr.ndim == 2 else arr[:, :, i], lt, what) for i, cn in enumerate(names)
    }


def compression_of(name: str):
    """The ``OpenEXR.Compression`` called ``name`` (``"zip"``, ``"piz"``, ``"none"``, ...)."""
    try:
        return getattr(_exr(), _COMPRESSION[name.lower()])
    except KeyError:
        raise ValueError(
            f"unknown EXR compression {name!r}; expected one of {', '.join(_COMPRESSION)}"
        ) from None


def _simple_attr(v: Any) -> bool:
    if isinstance(v, (str, float, bool)) or (isinstance(v, int) and -(2**31) <= v < 2**31):
        return True
    if isinstance(v, np.ndarray):  # typed (v2f, m33f, ...) in the EXR spec: not rewritten
        return False
    if isinstance(v, (list, tuple)):
        return len(v) > 0 and all(isinstance(x, str) for x in v)
    return False


def exr_parts(
    img: M.LayeredImage,
    *,
    pixel_type: str | None = None,
    compression: str = "zip",
    multipart: bool = False,
) -> list:
    """``OpenEXR.Part`` objects for ``img`` (one part, or one per grid layer)."""
    OpenEXR = _exr()
    comp = compression_of(compression)
    header: dict[str, Any] = {"compression": comp, "type": OpenEXR.scanlineimage}
    for k, v in img.attributes.items():
        if k in _STRUCTURAL or k in ("parts", "envmap", "preview") or not _simple_attr(v):
            continue
        header[k] = v
    if img.chromaticities is not None:
        header["chromaticities"] = tuple(float(c) for c in img.chromaticities)
    if img.white_luminance is not None:
        header["whiteLuminance"] = float(img.white_luminance)
    if img.quantity != "relative":
        header[_QUANTITY_ATTR] = img.quantity
    if img.unit is not None:
        header[_UNIT_ATTR] = img.unit
    if img.sensor_size is not None:
        header[_SENSOR_ATTR] = np.array(img.sensor_size, dtype=np.float32)
    if img.projection is not None:
        header[_PROJ_ATTR] = img.projection
        if img.projection == "equirectangular":
            header["envmap"] = OpenEXR.ENVMAP_LATLONG
    if img.siblings:
        # as hdrjax.io.write gives them: relative to the file's folder, or absolute
        header[_SIBLINGS_ATTR] = [
            f"{q}={Path(p).as_posix()}" for q, p in sorted(img.siblings.items())
        ]
    ptype = pixel_type or img.pixel_types.get("image", "float")
    if ptype == "uint":
        raise ValueError("the main image cannot be stored as uint; use 'half' or 'float'")
    main: dict[str, np.ndarray] = {}
    kind = img.kind
    if kind == "spectral":
        from ..spectral import spectral_kind

        group = _REFLECTIVE if spectral_kind(img.channels) == "reflective" else "S0"
        names = [_spectral_name(float(w), group) for w in img.wavelengths]
        header["spectralLayoutVersion"] = "1.0"
        if img.quantity == "radiance" and group == "S0":
            header["emissiveUnits"] = "W.m^-2.sr^-1"
    elif kind == "ych":
        names = ["Y", "RY", "BY"]
    else:
        names = list(img.channels)
        if len(set(names)) != len(names) or any("." in n for n in names):
            names = [f"c{i}" for i in range(len(names))]
    for i, n in enumerate(names):
        main[n] = _cast(img.image[:, :, i], ptype, f"{img.name}: image")
    extra_parts = []
    for key, value in img.layers.items():
        if key == M.WAVELENGTHS and kind == "spectral":
            continue
        if isinstance(value, dict) or not img.is_grid_layer(key):
            header[_NONGRID_PREFIX + key] = _json_layer(value)
            continue
        target = {} if multipart else main
        for cn, plane in layer_planes(img, key, pixel_type).items():
            if cn in target:
                raise ValueError(f"{img.name}: two layers write EXR channel {cn!r}")
            target[cn] = plane
        if key in img.layer_channels and key != M.POSITION:
            header[_CHANNELS_PREFIX + key] = list(img.layer_channels[key])
        if multipart:
            extra_parts.append((key, target))
    if img.data_window is not None and img.display_window is not None:
        h, w = img.image.shape[:2]
        x0, y0 = img.data_window[:2]
        header["dataWindow"] = (
            np.array([x0, y0], np.int32),
            np.array([x0 + w - 1, y0 + h - 1], np.int32),
        )
        header["displayWindow"] = tuple(
            np.array(v, np.int32) for v in (img.display_window[:2], img.display_window[2:])
        )
    parts = [OpenEXR.Part(header, main, "image" if multipart else "")]
    for key, chans in extra_parts:
        ph = {
            k: header[k]
            for k in ("compression", "type", "dataWindow", "displayWindow")
            if k in header
        }
        parts.append(OpenEXR.Part(ph, chans, key))
    return parts


def write_exr(
    path: Path,
    img: M.LayeredImage,
    *,
    pixel_type: str | None = None,
    compression: str = "zip",
    multipart: bool = False,
) -> None:
    """Write ``img`` to ``path`` (a temporary name; :func:`hdrjax.io.write` renames it)."""
    OpenEXR = _exr()
    parts = exr_parts(img, pixel_type=pixel_type, compression=compression, multipart=multipart)
    f = OpenEXR.File(parts) if multipart else OpenEXR.File(parts[0].header, parts[0].channels)
    try:
        f.write(str(path))
    except Exception as e:
        raise OSError(f"{img.name}: cannot write OpenEXR file {path} ({e})") from None


__all__ = ["read_exr", "write_exr"]
