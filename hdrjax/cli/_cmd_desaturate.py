"""``hdrjax desaturate INPUT -o OUTPUT.exr``: highlight desaturation (Birukov et al.,
GraphiCon 2022, section 4.2)."""

import argparse

from ._common import (
    HDR_EXT,
    DataError,
    add_format_argument,
    output_ext,
    output_file,
    positive_float,
    read_image,
    refuse_overwriting_inputs,
)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "desaturate",
        help="desaturate the highlights of an HDR image (before tone mapping)",
        description="Move the channels of bright pixels towards their mean: nothing at and "
        "below the threshold, fully grey at the image's maximum luminance, linear between. "
        "The automatic threshold is twice the luminance exceeded by 10%% of the pixels.",
    )
    p.add_argument("input", help="HDR image (RGB): .exr, .hdr or .pfm")
    p.add_argument(
        "-o", "--output", required=True, help="output: .exr, .hdr or .pfm; '-': standard output"
    )
    add_format_argument(p, ("hdr", "pfm"))
    p.add_argument(
        "--threshold",
        type=positive_float,
        help="luminance threshold in the image's unit (default: automatic)",
    )
    p.add_argument(
        "--exact", action="store_true", help="exact (sorted) percentile for the automatic threshold"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import io as hio
    from ..display import desaturate_highlights, highlight_threshold

    output_ext(args, HDR_EXT)
    refuse_overwriting_inputs([args.output], [args.input])
    img = read_image(args.input)
    if img.kind != "rgb":
        raise DataError(f"{args.input}: channels {', '.join(img.channels)}; expected R, G, B")
    method = "exact" if args.exact else "histogram"
    rgb = np.asarray(img.image, np.float32)
    w = img.luminance_weights
    if args.threshold is None:
        t, err = highlight_threshold(rgb, weights=w, method=method)
        t, note = float(t), f"automatic, 2 x L90, relative error <= {float(err):.2g}"
    else:
        t, note = args.threshold, "given"
    out = np.asarray(desaturate_highlights(rgb, t, weights=w))
    try:
        with output_file(args) as path:
            hio.write(path, img.replace(image=out))
    except (ValueError, OSError) as e:
        raise DataError(f"{args.output}: cannot write: {e}") from None
    unit = f" {img.unit}" if img.unit else ""
    print(f"input: {args.input} ({rgb.shape[1]}x{rgb.shape[0]})")
    print(f"threshold: {t:.6g}{unit} ({note})")
    print(f"wrote: {args.output}")
    return 0
