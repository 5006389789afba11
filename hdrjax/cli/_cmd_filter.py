"""``hdrjax filter INPUT -o OUTPUT --median 5``: mean or median filter an HDR image.

The image is filtered in tiles (:func:`hdrjax.tile.apply`, bit-identical to the whole-image
filter): Ctrl-C is seen between two tiles (a single compiled call over a large image runs
to its end first), and a terminal or notebook shows a progress bar over them.
"""

import argparse

from ._common import (
    HDR_EXT,
    DataError,
    UsageError,
    add_format_argument,
    odd_size,
    output_ext,
    output_file,
    read_image,
    refuse_overwriting_inputs,
)

TILE = 512
"""Output tile side: a fraction of a second per tile for the usual windows, so that Ctrl-C
stops the command within a second."""


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
    kind.add_argument("--median", type=odd_size, metavar="K", help="median filter, K×K window")
    kind.add_argument("--mean", type=odd_size, metavar="K", help="mean (box) filter, K×K window")
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

    import numpy as np

    from .. import io as hio, tile as htile
    from .._progress import wait_ready
    from ..filters import mean_filter, median_filter

    output_ext(args, HDR_EXT)
    refuse_overwriting_inputs([args.output], [args.input])
    if args.passes < 1:
        raise UsageError(f"--passes: expected an integer >= 1, got {args.passes}")
    img = read_image(args.input)
    x = np.asarray(img.image, np.float32)
    t0 = time.perf_counter()
    if args.mean:
        fn, settings = mean_filter, {}
        what = f"mean {args.mean}x{args.mean}"
    else:
        criterion = args.criterion
        if criterion == "luminance" and img.kind not in ("rgb", "y"):
            raise UsageError(
                f"{args.input}: channels {', '.join(img.channels)} have no luminance; "
                "use --criterion channels or vector"
            )
        weights = img.luminance_weights if img.kind == "rgb" else None
        weights = None if weights is None else tuple(float(w) for w in weights)
        fn, settings = median_filter, {"criterion": criterion, "weights": weights}
        what = f"median {args.median}x{args.median} ({criterion})"
    size = args.mean or args.median
    if args.mode == "wrap":  # a tile cannot see the opposite edge: one call
        out = fn(x, size, passes=args.passes, mode=args.mode, **settings)
        out = np.asarray(wait_ready(out))
    else:
        step_type = htile.Mean if args.mean else htile.Median
        step = step_type(size=size, passes=args.passes, mode=args.mode, **settings)
        # in place where the decoded pixels are ours to overwrite: one image in memory
        into = x if x.flags.writeable else None
        out = htile.apply(step, x, tile=max(TILE, step.halo(x.shape)[0]), out=into, progress=True)
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
