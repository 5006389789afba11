"""``read`` and ``write``: one entry point for EXR, Radiance and PFM files, with sidecars.

Sidecar convention (Birukov et al. 2022, section 3): a simulation may put some layers, and other
quantities of the same camera, in files that share the main file's name and differ only
in their extension:

- ``scene.exr``                      main image (and any layers stored inside it)
- ``scene.position.exr``             layer ``position`` (channels ``P.X``, ``P.Y``, ``P.Z``)
- ``scene.object_id.exr``            layer ``object_id`` (uint channel ``object_id``)
- ``scene.<layer>.{exr,pfm,hdr}``    any known layer (``error``, ``hits``, ``grid``, ...),
  or a free-named one listed in the main EXR's ``hdrjax.sidecars`` attribute
- ``scene.illuminance.exr``          another quantity of the same simulation: a sibling,
  listed in :attr:`LayeredImage.siblings` (not loaded; read it with :func:`read`)

When the main file is itself named after its quantity (``scene.luminance.exr``), sidecar
layers and siblings are also looked up under the shared stem (``scene.position.exr``,
``scene.illuminance.exr``). Layers inside the main file take precedence over sidecars.
"""

import os
import stat
import sys
import tempfile
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from jaxtyping import Float

from .. import _check
from .._colour import luminance_weights
from ..layers import _model as M
from ..layers._errors import MissingLayerError, ReadError
from . import _exr, _pfm, _rgbe
from ._atomic import atomic_path

READ_FORMATS = {".exr": "exr", ".hdr": "hdr", ".pic": "hdr", ".rgbe": "hdr", ".pfm": "pfm"}
"""File extensions :func:`read` and :func:`write` know, mapped to the format."""

_SIDECAR_EXTS = (".exr", ".pfm", ".hdr")
_SIDECAR_ATTR = "hdrjax.sidecars"
_SIDECAR_LAYERS = tuple(k for k in M.KNOWN_LAYERS if k in M.GRID_LAYERS)
_XYZ_CHROMATICITIES = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0 / 3.0, 1.0 / 3.0)


def _sniff(head: bytes) -> str | None:
    if head.startswith(_exr.EXR_MAGIC):
        return "exr"
    if head.startswith((b"PF", b"Pf")):
        return "pfm"
    if b"#?" in head[:64]:
        return "hdr"
    return None


def _format(path: Path, data: bytes | None = None) -> str:
    """The format of ``path`` (its extension, else its first bytes: ``data`` when the
    input was read into memory)."""
    fmt = READ_FORMATS.get(path.suffix.lower())
    if fmt is not None:
        return fmt
    if data is None:
        try:
            with open(path, "rb") as f:
                data = f.read(64)
        except OSError as e:
            raise OSError(f"{path.name}: cannot read ({e.strerror or e})") from None
    fmt = _sniff(data[:64])
    if fmt is None:
        raise ReadError(
            f"{path.name}: unknown image format {path.suffix!r}; expected .exr, .hdr, .pic or .pfm"
        )
    return fmt


def _stream_bytes(path: Path) -> bytes | None:
    """All of ``path`` when it is not a regular file (a pipe, ``/dev/stdin``, a process
    substitution), read once: such an input cannot be sniffed and then read again.
    ``None`` for a regular file."""
    if str(path) == "-":
        return sys.stdin.buffer.read()
    try:
        mode = path.stat().st_mode
    except OSError:
        return None
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as e:
        raise OSError(f"{path}: cannot read ({e.strerror or e})") from None


def _read_bytes(
    data: bytes, path: Path, part: int | str | None, layer: str | None
) -> M.LayeredImage:
    """:func:`read` of ``data``, the whole input read from a pipe."""
    fmt = _format(path, data)
    if fmt == "exr":  # the OpenEXR bindings read files only
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / "input.exr"
            p.write_bytes(data)
            try:
                img = read(p, part=part, layer=layer, sidecars=False)
            except (ValueError, OSError) as e:
                raise type(e)(str(e).replace("input.exr", path.name)) from None
        return img.replace(path=path)
    if part not in (None, 0, "0"):
        raise MissingLayerError(f"{path.name} has no part {part!r}; it has 1 part")
    if fmt == "hdr":
        img = _hdr_image(*_rgbe.decode_radiance(data, path.name), path)
    else:
        pixels, scale = _pfm.decode_pfm(data, path.name)
        img = M.LayeredImage(image=pixels, path=path, attributes={"scale": scale})
    return img if layer is None else img.select(layer)


def _read_hdr(path: Path) -> M.LayeredImage:
    return _hdr_image(*_rgbe.read_rgbe_file(path), path)


def _hdr_image(rgb: np.ndarray, info: dict, path: Path) -> M.LayeredImage:
    chroma = None
    if info["format"] == "32-bit_rle_xyze":
        chroma = _XYZ_CHROMATICITIES
    elif info["primaries"] is not None:
        # Photoshop writes PRIMARIES=0 0 0 0 0 0 0 0: only valid primaries are used
        try:
            luminance_weights(info["primaries"])
            chroma = info["primaries"]
        except ValueError:
            chroma = None
    var = {k.upper(): v for k, v in info["variables"].items()}
    quantity = var.get("QUANTITY", "relative").strip().lower()
    if quantity not in M.QUANTITIES:
        quantity = "relative"
    attributes: dict[str, Any] = {"header": info["lines"], "orientation": info["orientation"]}
    if info["exposure"] != 1.0:
        attributes["exposure"] = info["exposure"]
    if var.get("SIDECARS"):
        attributes[_SIDECAR_ATTR] = var["SIDECARS"].split()
    projection = var.get("PROJECTION")
    return M.LayeredImage(
        image=rgb,
        channels=("R", "G", "B"),
        quantity=quantity,
        unit=var.get("UNIT"),
        chromaticities=chroma,
        attributes=attributes,
        path=path,
        projection=projection if projection in _PROJECTIONS else None,
    )


_PROJECTIONS = ("equirectangular", "polar", "fisheye", "cubemap")


def _read_pfm(path: Path) -> M.LayeredImage:
    img, scale = _pfm.read_pfm_file(path)
    return M.LayeredImage(image=img, path=path, attributes={"scale": scale})


def _read_main(path: Path, fmt: str, part: int | str | None, layer: str | None) -> M.LayeredImage:
    if fmt == "exr":
        return _exr.read_exr(path, part=part, layer=layer)
    if part not in (None, 0, "0"):
        raise MissingLayerError(f"{path.name} has no part {part!r}; it has 1 part")
    return _read_hdr(path) if fmt == "hdr" else _read_pfm(path)


def _stems(path: Path) -> list[str]:
    """The stems under which sidecars are looked up: ``scene`` for ``scene.exr`` and for
    ``scene.luminance.exr`` (``scene.luminance`` too in the latter case)."""
    stem = path.name[: -len(path.suffix)] if path.suffix else path.name
    out = [stem]
    base, dot, last = stem.rpartition(".")
    if dot and base and last.lower() in M.QUANTITIES:
        out.append(base)
    return out


def find_sidecars(
    path: str | os.PathLike, extra_layers: Sequence[str] = ()
) -> tuple[dict[str, Path], dict[str, Path]]:
    """Sidecar layer files and sibling quantity files of ``path``.

    Args:
        path: the main file.
        extra_layers: free layer names to look for besides the known ones.

    Returns:
        ``(layers, siblings)``: layer name → file, quantity → file.
    """
    path = Path(path)
    folder = path.parent
    layers: dict[str, Path] = {}
    siblings: dict[str, Path] = {}
    own_quantity = None
    stems = _stems(path)
    if len(stems) > 1:
        own_quantity = stems[0].rpartition(".")[2].lower()
    names = list(_SIDECAR_LAYERS) + [n for n in extra_layers if n not in _SIDECAR_LAYERS]
    for stem in stems:
        for key in names:
            for ext in _SIDECAR_EXTS:
                p = folder / f"{stem}.{key}{ext}"
                if key not in layers and p.is_file() and p != path:
                    layers[key] = p
                    break
        for q in M.QUANTITIES:
            if q == own_quantity or q in siblings:
                continue
            for ext in _SIDECAR_EXTS:
                p = folder / f"{stem}.{q}{ext}"
                if p.is_file() and p != path:
                    siblings[q] = p
                    break
    return layers, siblings


def _read_sidecar(p: Path, key: str) -> tuple[np.ndarray, tuple[str, ...] | None, str | None]:
    fmt = _format(p)
    if fmt != "exr":
        img = _read_main(p, fmt, None, None)
        arr = img.image[:, :, 0] if img.image.shape[2] == 1 else img.image
        return arr, None, "float"
    f = _exr.open_exr(p)
    chans, _ = _exr.part_channels(f.parts[0], p.name)
    groups = _exr.channel_groups(chans)
    if len(groups) != 1:
        raise ReadError(
            f"{p.name}: a sidecar layer file must hold one channel group; found "
            + ", ".join(g or "(unprefixed)" for g in groups)
        )
    ((g, bases),) = groups.items()
    full = [f"{g}.{b}" if g else b for b in bases]
    if key == M.POSITION:
        ordered = _exr.xyz_order(bases, full)
        if ordered is None:
            raise ReadError(
                f"{p.name}: a position sidecar needs channels X, Y, Z; found {', '.join(bases)}"
            )
        full, bases = ordered, ["X", "Y", "Z"]
    arr = _exr.stack_channels(chans, full)
    ptype = _exr.stored_pixel_type(arr)
    return _exr.as_layer_array(arr), (tuple(bases) if len(bases) > 1 else None), ptype


def _attach_sidecars(img: M.LayeredImage) -> M.LayeredImage:
    assert img.path is not None
    extra = img.attributes.get(_SIDECAR_ATTR, ())
    extra = [str(x) for x in extra] if isinstance(extra, (list, tuple)) else []
    files, siblings = find_sidecars(img.path, extra)
    if not files and not siblings:
        return img
    layers = dict(img.layers)
    lc = dict(img.layer_channels)
    pt = dict(img.pixel_types)
    found = {}
    for key, p in files.items():
        if key in layers:
            continue
        arr, chans, ptype = _read_sidecar(p, key)
        if arr.shape[:2] != img.image.shape[:2]:
            raise ReadError(
                f"{p.name}: sidecar layer {key!r} is {arr.shape[1]} x {arr.shape[0]}, but "
                f"{img.name} is {img.width} x {img.height}"
            )
        layers[key] = arr
        if chans:
            lc[key] = chans
        if ptype:
            pt[key] = ptype
        found[key] = p
    sib = dict(siblings)
    sib.update(img.siblings)
    attributes = dict(img.attributes)
    if found:
        attributes["sidecar_files"] = {k: str(v) for k, v in found.items()}
    return img.replace(
        layers=layers, layer_channels=lc, pixel_types=pt, siblings=sib, attributes=attributes
    )


def read(
    path: str | os.PathLike,
    *,
    part: int | str | None = None,
    layer: str | None = None,
    sidecars: bool = True,
) -> M.LayeredImage:
    """Read an HDR file (OpenEXR, Radiance RGBE, PFM) with its layers and sidecars.

    Args:
        path: ``.exr``, ``.hdr`` / ``.pic`` or ``.pfm`` (other names are sniffed); ``"-"``
            reads standard input. Pipes and other non-regular files (``/dev/stdin``,
            ``<(...)``) are read into memory once, then sniffed and decoded; they have no
            sidecars.
        part: EXR part index or name (default: the first part).
        layer: a layer or view to use as the main image instead of the default one (e.g.
            ``"left"`` for a stereo EXR, ``"position"``); sidecar layers count too.
        sidecars: look for sidecar layer files and sibling quantity files (see the
            module doc).

    Returns:
        A :class:`~hdrjax.layers.LayeredImage`; ``.image`` is float32 ``(H, W, C)``
        (half floats are converted), ``.rgb()`` gives linear RGB.

    Raises:
        ReadError: bad, truncated or unsupported file (message names the file).
        MissingLayerError: ``part`` or ``layer`` not found (a ``ReadError``).
        OSError: the file cannot be opened.
    """
    path = Path(path)
    if str(path) != "-" and not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a folder, expected an image file")
    data = _stream_bytes(path)
    if data is not None:  # a pipe: no sidecars next to it
        if str(path) == "-":
            path = Path("<stdin>")
        return _read_bytes(data, path, part, layer)
    fmt = _format(path)
    selected = layer is None
    if fmt == "exr" and layer is not None:
        try:
            img = _exr.read_exr(path, part=part, layer=layer)
            selected = True
        except MissingLayerError:
            # not a channel group of its own: a single-channel layer, another part or a
            # sidecar; the read below raises for a bad part, select() for a missing layer
            img = _read_main(path, fmt, part, None)
    else:
        img = _read_main(path, fmt, part, None)
    if sidecars:
        img = _attach_sidecars(img)
    if not selected:
        img = img.select(layer)
    return img


def _as_layered(image: Any) -> M.LayeredImage:
    if isinstance(image, M.LayeredImage):
        return image
    arr = np.asarray(image)
    if arr.ndim == 3 and arr.shape[2] == 4:
        return M.LayeredImage(image=arr[:, :, :3], layers={M.ALPHA: arr[:, :, 3]})
    if arr.ndim == 2:
        arr = arr[:, :, None]
    return M.LayeredImage(image=arr)


def write(
    path: str | os.PathLike,
    image: M.LayeredImage | Float[np.ndarray, "H W C"] | Any,
    *,
    pixel_type: str | None = None,
    compression: str = "zip",
    multipart: bool = False,
    sidecars: bool | Sequence[str] | None = None,
    overwrite: bool = True,
    rle: bool = True,
) -> Path:
    """Write an image or layered image to ``.exr``, ``.hdr`` or ``.pfm``, atomically.

    Args:
        path: output file; the format comes from the extension.
        image: a :class:`~hdrjax.layers.LayeredImage` or an array ``(H, W)``,
            ``(H, W, 3)`` (RGB) or ``(H, W, 4)`` (RGB + alpha), linear values.
        pixel_type: EXR only: ``"float"`` or ``"half"`` for the image and float layers
            (integer layers are always ``uint``). Default: the types the image was read
            with, else float.
        compression: EXR compression (``"zip"``, ``"piz"``, ``"none"``, ...).
        multipart: EXR only: one part per grid layer (part names = layer names).
        sidecars: ``True`` writes every grid layer to ``<stem>.<layer>.exr`` next to the
            main file; a list writes those layers. ``None`` (default): EXR keeps all
            layers inside; Radiance/PFM cannot hold layers and drop them with a warning.
        overwrite: when ``False``, refuse to replace existing files (``FileExistsError``).
        rle: Radiance only: run-length encode the scanlines.

    Returns:
        The path of the main file. Each file goes to a temporary name in the same folder
        and is renamed into place, so a failure never leaves a half-written file.

    Raises:
        ValueError: unknown extension, or data the format cannot hold (spectral images
            in Radiance/PFM, uint main images).
        FileExistsError: a target exists and ``overwrite`` is ``False``.
    """
    path = Path(path)
    fmt = READ_FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise ValueError(
            f"{path.name}: unknown HDR format {path.suffix!r}; expected .exr, .hdr, .pic or .pfm"
        )
    img = _as_layered(image)
    # no format holds an empty image (Radiance and PFM would write a file no reader opens)
    shape = img.image.shape if isinstance(image, M.LayeredImage) else np.shape(image)
    _check.nonempty(shape, "image", "(H, W) or (H, W, C)", (0, 1))
    grid = [k for k in img.layers if img.is_grid_layer(k)]
    if sidecars is True:
        side = grid
    elif sidecars in (None, False):
        side = []
    else:
        side = list(sidecars)
        for k in side:
            img.layer(k)  # raises MissingLayerError
            if not img.is_grid_layer(k):
                raise ValueError(
                    f"{img.name}: layer {k!r} is not on the pixel grid; it cannot be a sidecar"
                )
    stem = path.name[: -len(path.suffix)]
    side_paths = {k: path.parent / f"{stem}.{k}.exr" for k in side}
    if not overwrite:
        for p in [path, *side_paths.values()]:
            if p.exists():
                raise FileExistsError(f"{p}: already exists (pass overwrite=True to replace it)")
    main = img.replace(layers={k: v for k, v in img.layers.items() if k not in side})
    free = [k for k in side if k not in _SIDECAR_LAYERS]
    if fmt == "exr":
        if main.siblings:
            main = main.replace(siblings=_sibling_links(path, main.siblings))
        if free:
            attrs = dict(main.attributes)
            attrs[_SIDECAR_ATTR] = free
            main = main.replace(attributes=attrs)
        with atomic_path(path, overwrite=overwrite) as tmp:
            _exr.write_exr(
                tmp, main, pixel_type=pixel_type, compression=compression, multipart=multipart
            )
    else:
        if free and fmt == "pfm":
            raise ValueError(
                f"{path.name}: free-named sidecar layers ({', '.join(free)}) need a main file "
                "that lists them (.exr or .hdr); PFM has no room for metadata"
            )
        dropped = [k for k in main.layers if k != M.WAVELENGTHS]
        if dropped:
            names = ", ".join(sorted(dropped))
            warnings.warn(
                f"{path.name}: {fmt.upper()} cannot hold layers; dropped {names} "
                "(write .exr, or pass sidecars=True)",
                stacklevel=2,
            )
        if fmt == "hdr":
            data = _encode_hdr(main, rle=rle, sidecars=free)
        else:
            if main.kind == "y":
                arr = main.image
            elif main.kind in ("rgb", "ych"):
                arr = main.rgb()  # PFM has no primaries: readers take sRGB
            else:
                raise ValueError(
                    f"{path.name}: PFM holds 1 or 3 channels; image has {', '.join(main.channels)}"
                )
            data = _pfm.encode_pfm(arr)
        with atomic_path(path, overwrite=overwrite) as tmp:
            tmp.write_bytes(data)
    for k, p in side_paths.items():
        with atomic_path(p, overwrite=overwrite) as tmp:
            _write_sidecar(tmp, img, k, pixel_type=pixel_type, compression=compression)
    return path


def _sibling_links(path: Path, siblings: dict[str, Path]) -> dict[str, Path]:
    """Sibling files as ``path`` records them: relative to its folder (between real paths,
    so the link survives moving both together; absolute where no relative path exists,
    e.g. another drive). A sibling whose file does not exist, or that is ``path`` itself,
    is dropped with a warning: a link that points nowhere is worse than none."""
    folder = os.path.realpath(path.parent)
    out = {}
    for q, p in sorted(siblings.items()):
        target = os.path.realpath(p)
        if not os.path.isfile(target) or target == os.path.join(folder, path.name):
            why = "is the output itself" if os.path.isfile(target) else "does not exist"
            warnings.warn(f"{path.name}: sibling {q} {p} {why}; not recorded", stacklevel=3)
            continue
        try:
            out[q] = Path(os.path.relpath(target, folder))
        except ValueError:  # no relative path (another drive)
            out[q] = Path(target)
    return out


def _encode_hdr(img: M.LayeredImage, *, rle: bool, sidecars: Sequence[str] = ()) -> bytes:
    if img.kind not in ("rgb", "y", "ych"):
        raise ValueError(
            f"{img.name}: Radiance files hold RGB; image has {', '.join(img.channels)}"
        )
    lines = []
    if img.quantity != "relative":
        lines.append(f"QUANTITY={img.quantity}")
    if img.projection is not None:
        lines.append(f"PROJECTION={img.projection}")
    if sidecars:
        lines.append("SIDECARS=" + " ".join(sidecars))
    if img.chromaticities is not None:
        lines.append("PRIMARIES=" + " ".join(f"{c:.6g}" for c in img.chromaticities))
    # the pixels as they are, in the primaries the PRIMARIES line names
    return _rgbe.encode_rgbe(img.native_rgb(), rle=rle, header_lines=lines)


def _write_sidecar(
    path: Path, src: M.LayeredImage, key: str, *, pixel_type: str | None, compression: str
) -> None:
    """Grid layer ``key`` of ``src`` as its own EXR file (channel names as in a main file)."""
    import OpenEXR

    header = {
        "compression": _exr.compression_of(compression),
        "type": OpenEXR.scanlineimage,
        "hdrjax.layerName": key,
    }
    try:
        OpenEXR.File(header, _exr.layer_planes(src, key, pixel_type)).write(str(path))
    except Exception as e:
        raise OSError(f"{path}: cannot write OpenEXR sidecar ({e})") from None


__all__ = ["READ_FORMATS", "find_sidecars", "read", "write"]
