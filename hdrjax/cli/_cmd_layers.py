"""``hdrjax layers FILE``: parts, layers, channels, pixel types, windows and attributes."""

import argparse
import json
import os

from ._cmd_export import as_data_error
from ._common import DataError

_SKIP_ATTRS = {"channels", "dataWindow", "displayWindow", "name", "type", "view", "tiles"}


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "layers",
        help="list the parts, layers, channels, pixel types, windows and attributes of a file",
        description="Describe the structure of an HDR file: for OpenEXR every part with its "
        "channels (pixel type, subsampling), data and display windows and attributes; then "
        "how hdrjax reads it (main image, named layers, sidecar files, sibling quantities).",
    )
    p.add_argument("input", help="HDR file: .exr, .hdr or .pfm")
    p.add_argument("--json", action="store_true", help="print one JSON document instead")
    p.set_defaults(func=run)


def _short(value) -> str:
    text = value.name if hasattr(value, "name") and not isinstance(value, str) else str(value)
    text = " ".join(text.split())
    return text if len(text) <= 70 else text[:67] + "..."


def _window(w) -> list[int]:
    lo, hi = w
    return [int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1])]


def _exr_parts(path: str) -> list[dict]:
    from pathlib import Path

    from ..io import _exr

    f = _exr.open_exr(Path(path))  # full read: the header alone does not give pixel types
    parts = []
    for i, part in enumerate(f.parts):
        h = part.header
        chans = []
        for name, c in sorted(part.channels.items()):
            chans.append(
                {
                    "name": name,
                    "type": _exr.stored_pixel_type(c.pixels),
                    "sampling": [int(c.xSampling), int(c.ySampling)],
                }
            )
        tiles = h.get("tiles")
        parts.append(
            {
                "index": i,
                "name": str(h.get("name", "")),
                "view": str(h.get("view", "")),
                "storage": _short(h.get("type", "scanlineimage")),
                "tiles": _short(tiles) if tiles is not None else None,
                "data_window": _window(h["dataWindow"]),
                "display_window": _window(h["displayWindow"]),
                "channels": chans,
                "attributes": {k: _short(v) for k, v in sorted(h.items()) if k not in _SKIP_ATTRS},
            }
        )
    return parts


def describe(path: str) -> dict:
    """A JSON-ready description of ``path`` (what ``hdrjax layers`` prints)."""
    import numpy as np

    from .. import io as hio

    img = hio.read(path)
    doc: dict = {"file": path, "format": hio.READ_FORMATS.get(os.path.splitext(path)[1].lower())}
    if doc["format"] == "exr":
        doc["parts"] = _exr_parts(path)
    doc["image"] = {
        "size": [img.width, img.height],
        "channels": list(img.channels),
        "pixel_type": img.pixel_types.get("image", "float"),
        "quantity": img.quantity,
        "unit": img.unit,
        "chromaticities": list(img.chromaticities) if img.chromaticities else None,
        "luminance_weights": list(img.luminance_weights),
        "white_luminance": img.white_luminance,
        "projection": img.projection,
        "data_window": list(img.data_window) if img.data_window else None,
        "display_window": list(img.display_window) if img.display_window else None,
    }
    layers: dict[str, dict[str, object]] = {}
    for key in sorted(img.layers):
        v = img.layers[key]
        if isinstance(v, dict):
            layers[key] = {"kind": "non-grid", "type": "dict", "keys": sorted(v)}
            continue
        v = np.asarray(v)
        layers[key] = {
            "kind": "grid" if img.is_grid_layer(key) else "non-grid",
            "shape": list(v.shape),
            "dtype": str(v.dtype),
            "channels": list(img.layer_channels.get(key, ())),
            "pixel_type": img.pixel_types.get(key),
        }
    doc["layers"] = layers
    doc["sidecar_files"] = img.attributes.get("sidecar_files", {})
    doc["siblings"] = {q: str(p) for q, p in img.siblings.items()}
    if doc["format"] != "exr":
        doc["attributes"] = {k: _short(v) for k, v in img.attributes.items() if k != "header"}
    return doc


def _print(doc: dict) -> None:
    print(f"file: {doc['file']} ({doc['format']})")
    for part in doc.get("parts", []):
        name = part["name"] or "(unnamed)"
        view = f", view {part['view']}" if part["view"] else ""
        tiles = f", tiles {part['tiles']}" if part["tiles"] else ""
        print(f"part {part['index']}: {name}{view}, {part['storage']}{tiles}")
        print(f"  data window {part['data_window']}, display window {part['display_window']}")
        for c in part["channels"]:
            sub = (
                ""
                if c["sampling"] == [1, 1]
                else f" (sampling {c['sampling'][0]}x{c['sampling'][1]})"
            )
            print(f"  channel {c['name']}: {c['type']}{sub}")
        for k, v in part["attributes"].items():
            print(f"  attribute {k}: {v}")
    im = doc["image"]
    unit = f" [{im['unit']}]" if im["unit"] else ""
    print(
        f"image: {im['size'][0]} x {im['size'][1]}, channels {', '.join(im['channels'])} "
        f"({im['pixel_type']}), {im['quantity']}{unit}"
    )
    print("  luminance weights: (" + ", ".join(f"{w:.5f}" for w in im["luminance_weights"]) + ")")
    if im["white_luminance"]:
        print(f"  white luminance: {im['white_luminance']:g} cd/m²")
    if im["projection"]:
        print(f"  projection: {im['projection']}")
    for key, v in doc["layers"].items():
        if v.get("type") == "dict":
            print(f"layer {key}: non-grid dict ({', '.join(v['keys'])})")
        else:
            ch = f" [{', '.join(v['channels'])}]" if v["channels"] else ""
            pt = f" stored {v['pixel_type']}" if v.get("pixel_type") else ""
            print(f"layer {key}: {v['kind']} {v['dtype']} {tuple(v['shape'])}{ch}{pt}")
    for key, p in doc["sidecar_files"].items():
        print(f"sidecar {key}: {p}")
    for q, p in doc["siblings"].items():
        print(f"sibling {q}: {p}")
    for k, v in doc.get("attributes", {}).items():
        print(f"attribute {k}: {v}")


def run(args: argparse.Namespace) -> int:
    if args.input != "-" and not os.path.exists(args.input):
        raise DataError(f"{args.input}: no such file")
    try:
        doc = describe(args.input)
    except (ValueError, OSError) as e:
        raise as_data_error(e, args.input) from None
    if args.json:
        print(json.dumps(doc, indent=2))
    else:
        _print(doc)
    return 0
