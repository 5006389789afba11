"""``hdrjax falsecolor INPUT -o OUTPUT.png``: a quantity or layer in false colour, with legend."""

import argparse
import os

from ._common import (
    DataError,
    UsageError,
    add_format_argument,
    output_ext,
    output_file,
    positive_float,
    read_image,
    refuse_overwriting_inputs,
    value_range,
)
from ._grid import add_grid_arguments, draw_grid

DISPLAY_EXT = (".png", ".jpg", ".jpeg", ".tif", ".tiff")
FIGURE_EXT = (".png", ".pdf", ".svg", ".jpg", ".jpeg", ".tif", ".tiff")

# how the known layers are labelled in the legend: name, and unit (None: the image's unit)
LAYER_LABELS = {
    "error": ("calculation error", None),
    "hits": ("ray hits", "rays"),
    "depth": ("depth", None),
    "alpha": ("alpha", ""),
}


def _floats(text: str) -> list[float]:
    """argparse type: comma-separated numbers."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected numbers separated by commas, got {text!r}"
        ) from None
    if not values:
        raise argparse.ArgumentTypeError("expected at least one number")
    return values


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "falsecolor",
        help="show luminance/illuminance or a layer (error, hits) in false colour, with legend",
        description="Map one value per pixel to colours (a matplotlib colormap or your own "
        "colours; linear or log scale; optional bands and iso-lines) and write it with its "
        "legend. Below-range values are black, above-range white, NaN magenta, +Inf cyan, "
        "-Inf navy (change with --under/--over/--nan/--posinf/--neginf).",
    )
    p.add_argument("input", help="HDR image: .exr, .hdr or .pfm")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        help="output image: .png, .jpg or .tif; '-': standard output",
    )
    add_format_argument(p, ("png",))
    p.add_argument(
        "--layer",
        help="a grid layer to show (e.g. error, hits); default: the "
        "image's luminance (or its single channel)",
    )
    p.add_argument(
        "--range",
        type=value_range,
        metavar="LO:HI",
        help="values mapped to the ends of the scale (default: data min:max)",
    )
    p.add_argument(
        "--percentiles",
        type=value_range,
        metavar="LO:HI",
        help="take the range from these percentiles of the positive values, e.g. 1:99",
    )
    p.add_argument("--log", action="store_true", help="logarithmic scale")
    p.add_argument("--cmap", default="viridis", help="matplotlib colormap (default viridis)")
    p.add_argument(
        "--colors",
        help="your own scale: colours separated by commas "
        "(names or #rrggbb), low to high; overrides --cmap",
    )
    p.add_argument(
        "--bands",
        type=_floats,
        metavar="V1,V2,...",
        help="flat colour bands between these increasing values (sets the range)",
    )
    p.add_argument(
        "--isolines", type=_floats, metavar="V1,V2,...", help="draw iso-lines at these values"
    )
    p.add_argument("--ticks", type=_floats, metavar="V1,V2,...", help="legend ticks")
    p.add_argument(
        "--legend",
        default="side",
        metavar="side|none|FILE",
        help="legend beside the image (default), none, or saved to FILE (.png, .pdf, .svg)",
    )
    p.add_argument("--name", help="quantity name for the legend (default from the file)")
    p.add_argument("--unit", help="unit for the legend (default from the file)")
    p.add_argument("--scale", type=positive_float, default=1.0, help="multiply the values first")
    for opt, default in (
        ("under", "black"),
        ("over", "white"),
        ("nan", "magenta"),
        ("posinf", "cyan"),
        ("neginf", "navy"),
    ):
        p.add_argument(f"--{opt}", default=default, help=f"colour (default {default})")
    add_grid_arguments(p)
    p.set_defaults(func=run)


def _values(args: argparse.Namespace):
    """(values (H, W), name, unit) from the file and --layer."""
    import numpy as np

    from ..layers import MissingLayerError

    img = args.image_file = read_image(args.input)  # --grid reads its projection and layers
    if args.layer:
        try:
            v = np.asarray(img.layer(args.layer), np.float32)
        except MissingLayerError as e:
            raise DataError(str(e)) from None
        if not img.is_grid_layer(args.layer):
            raise DataError(f"{args.input}: layer {args.layer!r} is not on the pixel grid")
        if v.ndim == 3 and v.shape[2] == 1:
            v = v[:, :, 0]
        if v.ndim != 2:
            raise DataError(
                f"{args.input}: layer {args.layer!r} has {v.shape[2]} channels; "
                "false colour shows one value per pixel"
            )
        name, unit = LAYER_LABELS.get(args.layer, (args.layer, ""))
        unit = img.unit if unit is None else unit
        return v, name, unit
    if img.kind == "y":
        v = img.image[:, :, 0]
    else:
        try:
            v = np.asarray(img.luminance())  # the file's own (photometric) luminance
        except ValueError as e:
            raise DataError(str(e)) from None
    name = img.quantity if img.quantity != "relative" else "relative luminance"
    return v, name, img.unit


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import io as hio
    from ..display import false_color

    output_ext(args, DISPLAY_EXT)
    legend = args.legend
    if legend not in ("side", "none"):
        if os.path.splitext(legend)[1].lower() not in FIGURE_EXT:
            raise UsageError(f"--legend {legend}: expected side, none or a .png/.pdf/.svg file")
    refuse_overwriting_inputs(
        [args.output, None if legend in ("side", "none") else legend], [args.input]
    )
    if args.range and args.percentiles:
        raise UsageError("--range and --percentiles exclude each other")
    if args.bands and (args.range or args.percentiles):
        raise UsageError("--bands sets the range; leave out --range/--percentiles")
    if args.log and args.range and args.range[0] <= 0:
        raise UsageError(f"--log needs a range above 0, got {args.range[0]:g}:{args.range[1]:g}")
    values, name, unit = _values(args)
    if args.scale != 1.0:
        values = values * np.float32(args.scale)
    cmap = args.cmap
    if args.colors:
        cmap = [c.strip() for c in args.colors.split(",") if c.strip()]
    vmin, vmax = args.range if args.range else (None, None)
    try:
        fc = false_color(
            values,
            cmap=cmap,
            vmin=vmin,
            vmax=vmax,
            percentiles=args.percentiles,
            log=args.log,
            levels=args.bands,
            bands=bool(args.bands),
            isolines=args.isolines,
            name=args.name or name,
            unit=args.unit if args.unit is not None else unit,
            ticks=args.ticks,
            legend=legend != "none",
            under=args.under,
            over=args.over,
            nan=args.nan,
            posinf=args.posinf,
            neginf=args.neginf,
        )
    except ValueError as e:
        raise UsageError(str(e)) from None
    shown = draw_grid(args, args.image_file, np.asarray(fc.image))
    out = fc.scale.composite(shown, specials=fc.specials) if legend == "side" else shown
    try:
        with output_file(args) as path:
            hio.write_display(path, out)
        if legend not in ("side", "none"):
            fc.legend.savefig(legend)
    except (ValueError, OSError) as e:
        raise DataError(f"cannot write: {e}") from None
    s = fc.scale
    h, w = values.shape
    print(f"input: {args.input} ({w}x{h}){' layer ' + args.layer if args.layer else ''}")
    print(f"{s.label}: {'log' if s.log else 'linear'} scale {s.vmin:.6g} .. {s.vmax:.6g}")
    if fc.specials:
        counts = {
            "nan": int(np.isnan(values).sum()),
            "posinf": int((values == np.inf).sum()),
            "neginf": int((values == -np.inf).sum()),
        }
        print("special pixels: " + ", ".join(f"{k} {counts[k]}" for k in fc.specials))
    print(f"wrote: {args.output}" + (f" and {legend}" if legend not in ("side", "none") else ""))
    return 0
