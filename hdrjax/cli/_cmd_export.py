"""``hdrjax export INPUT -o OUTPUT``: convert between HDR formats, or export a plain view."""

import argparse
import os

from ._common import (
    CLIError,
    DataError,
    DeprecatedAlias,
    UsageError,
    add_format_argument,
    output_ext,
    output_file,
    refuse_overwriting_inputs,
)

HDR_EXT = (".exr", ".hdr", ".pic", ".pfm")
LDR_EXT = (".png", ".jpg", ".jpeg", ".tif", ".tiff")


def as_data_error(e: Exception, *paths: str) -> CLIError:
    """A one-line DataError for an io/measure failure, naming the file (shared by the
    layers, measure and export commands); an output that appeared after the ``--no-clobber``
    check is refused as that check refuses it (UsageError)."""
    if isinstance(e, FileExistsError):
        name = str(e).split(": already exists")[0]
        return UsageError(f"{name}: already exists (--no-clobber)")
    msg = str(e)
    named = any(os.path.basename(p) in msg for p in paths)
    return DataError(msg if named else f"{paths[0]}: {msg}")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "export",
        help="convert an HDR file to .exr/.hdr/.pfm (layers kept where the format can), or "
        "export a clipped sRGB view to .png/.jpg/.tif",
        description="Format conversion. HDR outputs keep the values (EXR keeps every layer; "
        "Radiance and PFM drop layers unless --sidecars writes them next to the output). "
        "LDR outputs are the linear image times 2^EXPOSURE, clipped and sRGB-encoded (use "
        "`hdrjax tonemap` for tone mapping). An existing output is replaced (never the "
        "input) unless --no-clobber is given.",
    )
    p.add_argument("input", help="HDR file: .exr, .hdr or .pfm")
    p.add_argument("-o", "--output", required=True, help="output file; '-': standard output")
    add_format_argument(p)
    p.add_argument("--part", help="EXR part to export (index or name)")
    p.add_argument("--layer", help="layer or view to export as the main image")
    p.add_argument(
        "--pixel-type",
        choices=("half", "float"),
        help="EXR pixel type (default: as read, else float)",
    )
    p.add_argument("--compression", default="zip", help="EXR compression (default zip)")
    p.add_argument(
        "--sidecars", action="store_true", help="write grid layers to OUTPUT_STEM.<layer>.exr files"
    )
    p.add_argument(
        "--exposure",
        type=float,
        default=0.0,
        metavar="EV",
        help="LDR outputs: multiply by 2^EV before clipping (default 0)",
    )
    p.add_argument("--bits", type=int, choices=(8, 16), default=8, help="PNG/TIFF bit depth")
    p.add_argument(
        "--overwrite",
        dest=argparse.SUPPRESS,
        nargs=0,
        action=DeprecatedAlias,
        replacement="outputs are replaced by default now (--no-clobber refuses them)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import warnings

    import numpy as np

    from .. import io as hio

    ext = output_ext(args, HDR_EXT + LDR_EXT)
    if args.output == "-" and args.sidecars:
        raise UsageError("--sidecars: files next to the output; not with -o - (standard output)")
    if args.bits == 16 and ext in (".jpg", ".jpeg"):
        raise UsageError("--bits 16 needs .png or .tif output (JPEG is 8-bit)")
    if ext in LDR_EXT and (args.sidecars or args.pixel_type):
        raise UsageError("--sidecars and --pixel-type apply to HDR outputs only")
    if args.input != "-" and not os.path.exists(args.input):
        raise DataError(f"{args.input}: no such file")
    refuse_overwriting_inputs([args.output], [args.input])
    part = int(args.part) if args.part is not None and args.part.isdigit() else args.part
    try:
        img = hio.read(args.input, part=part, layer=args.layer)
        if ext in LDR_EXT:
            from ..display import encode, quantize

            rgb = img.rgb() * np.float32(2.0**args.exposure)
            out = np.asarray(encode(rgb, "srgb"))
            with output_file(args) as path:
                hio.write_display(
                    path, quantize(out, args.bits), bits=args.bits, overwrite=not args.no_clobber
                )
        else:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                with output_file(args) as path:
                    hio.write(
                        path,
                        img,
                        pixel_type=args.pixel_type,
                        compression=args.compression,
                        sidecars=True if args.sidecars else None,
                        overwrite=not args.no_clobber,
                    )
            for w in caught:
                print(f"note: {w.message}")
    except (ValueError, OSError) as e:
        raise as_data_error(e, args.input, args.output) from None
    print(f"wrote: {args.output} ({img.width}x{img.height}, {', '.join(img.channels)})")
    return 0
