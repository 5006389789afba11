"""``hdrjax batch "frames/*.exr" -o out/``: one pipeline over many frames.

Exit status: 0 when every frame was written (or skipped because its output exists), 1 when
at least one frame failed (each failure is printed; the others are written), 2 for usage
errors.
"""

import argparse
import sys

from ._cmd_tonemap import (
    SHORTCUT_OPTIONS,
    add_colour_arguments,
    add_parameter_shortcuts,
    add_set_argument,
    build_operator,
)
from ._common import (
    DataError,
    DeprecatedAlias,
    UsageError,
    odd_size,
    positive_float,
    positive_int,
    refuse_overwriting_inputs,
)
from ._registry import constant


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "batch",
        help="tone-map many frames (a glob pattern or files) into a folder",
        description="Tone-map a sequence of HDR frames with one pipeline: batched and "
        "compiled in this process, or on a Dask cluster (--workers / --scheduler). Outputs "
        "are OUT/<stem>.<format>; frames whose output exists are skipped (resume). Exit "
        "status: 0 all frames done, 1 some frames failed (listed), 2 usage error.",
    )
    p.add_argument(
        "inputs",
        nargs="+",
        help='frames: files or quoted glob patterns ("frames/*.exr"), expanded by hdrjax',
    )
    p.add_argument("-o", "--output", required=True, help="output folder (created if missing)")
    p.add_argument(
        "--method",
        default="reinhard2002",
        help="operator name (see `hdrjax operators`; default reinhard2002)",
    )
    mode = p.add_mutually_exclusive_group()
    mode.add_argument(
        "--same-parameters",
        dest="parameters",
        action="store_const",
        const="same",
        help="measure the automatic parameters on the whole sequence, use them for all frames",
    )
    mode.add_argument(
        "--per-frame",
        dest="parameters",
        action="store_const",
        const="per-frame",
        help="measure each frame by itself (default)",
    )
    mode.add_argument(
        "--smooth",
        dest="parameters",
        action="store_const",
        const="smooth",
        help="per-frame parameters smoothed over time (no flicker); see --smooth-frames",
    )
    p.set_defaults(parameters="per-frame")
    p.add_argument(
        "--smooth-frames",
        type=float,
        default=5.0,
        help="time constant of --smooth in frames (default 5)",
    )
    p.add_argument(
        "--fps",
        type=positive_float,
        metavar="FPS",
        help="map the frames as a video at FPS frames per second with the operator's time "
        "course of adaptation, carried from frame to frame in order (an operator without "
        "one gives an error listing those that have one)",
    )
    add_set_argument(p)
    add_parameter_shortcuts(p, SHORTCUT_OPTIONS[:5])
    p.add_argument(
        "--format",
        choices=("png", "tif", "jpg", "exr", "hdr", "pfm"),
        default="png",
        help="output format (default png)",
    )
    p.add_argument(
        "--bits", type=int, choices=(8, 16), help="PNG/TIFF bit depth (8; 16 for PQ/HLG)"
    )
    p.add_argument(
        "--zlib-level",
        type=int,
        choices=range(10),
        default=constant("hdrjax.io.DEFAULT_COMPRESSION"),
        metavar="0-9",
        help="PNG/TIFF zlib level (default 1, OpenCV's; 6 is ~8x slower for ~1%% smaller PNGs)",
    )
    p.add_argument(
        "--compression",
        dest="zlib_level",
        type=int,
        choices=range(10),
        action=DeprecatedAlias,
        replacement="use --zlib-level (--compression names the EXR compression in `hdrjax export`)",
    )
    p.add_argument(
        "--transfer", choices=("srgb", "gamma", "linear"), default="srgb", help="display encoding"
    )
    p.add_argument("--gamma", type=positive_float, default=2.2, help="for --transfer gamma")
    p.add_argument(
        "--display",
        metavar="NAME",
        help="display outputs are encoded and tagged for (as tonemap --display; PQ/HLG need "
        "--bits 16)",
    )
    p.add_argument(
        "--gamut",
        choices=("clip", "luminance", "compress"),
        help="colours outside the display's gamut (as tonemap --gamut)",
    )
    p.add_argument(
        "--scale", type=positive_float, default=1.0, help="multiply every frame by this first"
    )
    add_colour_arguments(p)
    p.add_argument("--median", type=odd_size, metavar="K", help="median filter K×K first")
    p.add_argument("--mean", type=odd_size, metavar="K", help="mean filter K×K first")
    p.add_argument(
        "--desaturate", action="store_true", help="desaturate highlights (automatic threshold)"
    )
    p.add_argument(
        "--vision",
        metavar="EFFECTS",
        help="comma-separated human-vision effects (acuity,glare,colour_loss,...); "
        "frames must be in cd/m² (use --scale)",
    )
    p.add_argument(
        "--batch-size", type=positive_int, default=8, help="frames per compiled call (8)"
    )
    p.add_argument(
        "--workers", type=positive_int, help="start a local Dask cluster with N processes"
    )
    p.add_argument(
        "--scheduler", metavar="ADDRESS", help="Dask scheduler address (tcp://host:8786)"
    )
    p.add_argument("--no-resume", action="store_true", help="rewrite existing outputs")
    p.add_argument(
        "--allow-nan", action="store_true", help="render NaN pixels black instead of failing"
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    # existing frames are skipped (resume) or replaced (--no-resume): no --no-clobber
    p.set_defaults(func=run, table=None, overwrite_policy="resume")


def build_pipeline(args: argparse.Namespace):
    """The :class:`hdrjax.batch.Pipeline` the arguments describe (UsageError if invalid)."""
    from ..batch import Pipeline, step

    op = build_operator(args)
    steps = []
    if args.median:
        steps.append(step("median", size=args.median))
    if args.mean:
        steps.append(step("mean", size=args.mean))
    if args.desaturate:
        steps.append(step("desaturate"))
    if args.vision:
        effects = tuple(e.strip() for e in args.vision.split(",") if e.strip())
        steps.append(step("vision", effects=effects))
    if args.bits is None:
        args.bits = 16 if args.display and _hdr_display(args.display) else 8
    if args.bits == 16 and args.format == "jpg" and args.display and _hdr_display(args.display):
        raise UsageError(f"--display {args.display} needs --format png or tif (16 bits)")
    if args.bits == 16 and args.format == "jpg":
        raise UsageError("--bits 16 needs --format png or tif (JPEG is 8-bit)")
    try:
        return Pipeline(
            op,
            steps=tuple(steps),
            format=args.format,
            bits=args.bits,
            compression=args.zlib_level,
            transfer=args.transfer,
            gamma=args.gamma,
            display=args.display,
            gamut=args.gamut,
            scale=args.scale,
            space=args.working_space,
            cat=args.cat,
        )
    except ValueError as e:
        raise UsageError(str(e)) from None


def _hdr_display(name: str) -> bool:
    from ..display import get_display

    try:
        return get_display(name).hdr
    except ValueError as e:
        raise UsageError(f"--display: {str(e).removeprefix('display: ')}") from None


def run(args: argparse.Namespace) -> int:
    from ..batch import expand_paths, run as batch_run
    from ..batch._frames import output_path

    if args.workers is not None and args.scheduler is not None:
        raise UsageError("--workers starts a local cluster; it does not go with --scheduler")
    if not args.smooth_frames >= 0:
        raise UsageError(f"--smooth-frames: expected a number >= 0, got {args.smooth_frames}")
    pipeline = build_pipeline(args)
    try:
        paths = expand_paths(args.inputs)
    except FileNotFoundError as e:
        raise DataError(str(e)) from None
    outputs = [output_path(p, args.output, pipeline.extension) for p in paths]
    refuse_overwriting_inputs([args.output, *outputs], paths)
    try:
        summary = batch_run(
            paths,
            pipeline,
            args.output,
            parameters=args.parameters,
            smooth_frames=args.smooth_frames,
            fps=args.fps,
            batch_size=args.batch_size,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=not args.quiet,
            resume=not args.no_resume,
            allow_nan=args.allow_nan,
        )
    except ValueError as e:
        msg = str(e)  # the fps argument's messages name the option
        raise UsageError(f"--{msg}" if msg.startswith("fps:") else msg) from None
    except ImportError as e:
        raise UsageError(str(e)) from None
    except OSError as e:
        raise DataError(str(e)) from None
    print(f"hdrjax batch: {summary}")
    if len(summary.failed) > 1:
        # each failure was reported as it happened (one line each, between progress
        # updates); a long run's failures are listed together once more at the end
        print(f"failed ({len(summary.failed)}):", file=sys.stderr)
        for msg in summary.failed.values():
            print(f"  {msg}", file=sys.stderr)
    return 1 if summary.failed else 0
