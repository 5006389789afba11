"""``hdrjax filter INPUT -o OUTPUT --median 5``: mean or median filter an HDR image."""

import argparse

from ._common import (
    HDR_EXT,
    DataError,
    UsageError,
    add_format_argument,
    output_ext,
    output_file,
    read_image,
    refuse_overwriting_inputs,
)


def _odd(text: str) -> int:
    try:
        k = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an odd integer, got {text!r}") from None
    if k < 1 or k % 2 == 0:
        raise argparse.ArgumentTypeError(f"expected an odd window size >= 1, got {k}")
    return k


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "filter",
        help="mean or median filter an HDR image (noise of stochastic simulations)",
        description="Filter the main image with a k×k mean or median window, edges "
        "replicated by default. The median chooses by luminance (whole pixels, colours never "
        "mixed) unless --criterion says channels or vector. Layers are kept.",
    )
    p.add_argument("input", help="HDR image: .exr, .hdr or .pfm")
    p.add_argument(
        "-o", "--output", required=True, help="output: .exr, .hdr or .pfm; '-': standard output"
    )
    add_format_argument(p, ("hdr", "pfm"))
    kind = p.add_mutually_exclusive_group(required=True)
    kind.add_argument("--median", type=_odd, metavar="K", help="median filter, K×K window")
    kind.add_argument("--mean", type=_odd, metavar="K", help="mean (box) filter, K×K window")
    p.add_argument("--passes", type=int, default=1, help="how many times (default 1)")
    p.add_argument(
        "--criterion",
        choices=("luminance", "channels", "vector"),
        default="luminance",
        help="median criterion (default luminance)",
    )
    p.add_argument(
        "--mode",
        choices=("nearest", "reflect", "mirror", "wrap"),
        default="nearest",
        help="edge handling (default nearest: replicate)",
    )
    p.add_argument("-v", "--verbose", action="store_true", help="print the time taken")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import time

    import jax
    import numpy as np

    from .. import io as hio
    from ..filters import mean_filter, median_filter

    output_ext(args, HDR_EXT)
    refuse_overwriting_inputs([args.output], [args.input])
    if args.passes < 1:
        raise UsageError(f"--passes: expected an integer >= 1, got {args.passes}")
    img = read_image(args.input)
    x = np.asarray(img.image, np.float32)
    t0 = time.perf_counter()
    if args.mean:
        out = mean_filter(x, args.mean, passes=args.passes, mode=args.mode)
        what = f"mean {args.mean}x{args.mean}"
    else:
        criterion = args.criterion
        if criterion == "luminance" and img.kind not in ("rgb", "y"):
            raise UsageError(
                f"{args.input}: channels {', '.join(img.channels)} have no luminance; "
                "use --criterion channels or vector"
            )
        weights = img.luminance_weights if img.kind == "rgb" else None
        out = median_filter(
            x, args.median, criterion=criterion, passes=args.passes, mode=args.mode, weights=weights
        )
        what = f"median {args.median}x{args.median} ({criterion})"
    out = np.asarray(jax.block_until_ready(out))
    dt = time.perf_counter() - t0
    try:
        with output_file(args) as path:
            hio.write(path, img.replace(image=out))
    except (ValueError, OSError) as e:
        raise DataError(f"{args.output}: cannot write: {e}") from None
    h, w = x.shape[:2]
    print(f"input: {args.input} ({w}x{h})")
    print(f"{what}, {args.passes} pass(es), edges {args.mode}")
    if args.verbose:
        print(f"time: {dt:.3f}s (incl. compile)")
    print(f"wrote: {args.output}")
    return 0
