"""``hdrjax compare INPUT -o report.html``: several operators side by side, scored.

Runs :func:`hdrjax.report.compare` and writes its table as one self-contained HTML page
(and, with ``--json-out``, the numbers).
"""

import argparse
import os

from ._common import (
    DataError,
    DeprecatedAlias,
    UsageError,
    positive_float,
    read_image,
    refuse_overwriting_inputs,
)
from ._registry import find

HTML_EXT = (".html", ".htm")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "compare",
        help="compare tone-mapping operators on one image: an HTML report of TMQI, clipping, "
        "times and parameters",
        description="Tone-map one HDR image with several operators and write one "
        "self-contained HTML page: each rendition as a thumbnail (the full image on click), "
        "its TMQI quality Q with structural fidelity S and naturalness N (Yeganeh & Wang "
        "2013), PU-SSIM against a reference rendition (Mantiuk & Azimi 2021) with "
        "--reference, the clipped pixels, the mean display luminance, the operator's "
        "compile and warm run times, and its parameters (estimated, given or fitted). "
        "Columns sort on click; the page needs no network.",
    )
    p.add_argument("input", help="HDR image: .exr, .hdr (Radiance RGBE) or .pfm")
    p.add_argument("-o", "--output", required=True, help="the report: an .html file")
    p.add_argument(
        "--json-out",
        dest="json_path",
        metavar="FILE.json",
        help="also write the table's numbers as JSON",
    )
    p.add_argument(
        "--json", dest="json_path", action=DeprecatedAlias, replacement="use --json-out FILE.json"
    )
    p.add_argument(
        "--sheet",
        metavar="FILE",
        help="also write a contact sheet of the renditions with their scores (.png)",
    )
    which = p.add_mutually_exclusive_group()
    which.add_argument(
        "--methods",
        metavar="A,B,...",
        help="operators to compare, comma-separated (see `hdrjax operators`; default "
        "reinhard2002, reinhard2005, drago2003, mai2011, durand2002, agx)",
    )
    which.add_argument(
        "--all",
        action="store_true",
        help="every registered operator that needs no parameter the image cannot give",
    )
    p.add_argument(
        "--fit",
        choices=("tmqi",),
        help="fit each operator's default fit parameters (`hdrjax operators NAME`) to "
        "maximise TMQI before scoring",
    )
    p.add_argument(
        "--reference",
        metavar="FILE",
        help="a reference rendition (.png/.jpg/.tif, sRGB, the input's size) for PU-SSIM",
    )
    p.add_argument(
        "--peak",
        type=positive_float,
        default=100.0,
        help="cd/m² of display white for PU-SSIM's display model (default 100; black is "
        "--peak / 1000)",
    )
    p.add_argument(
        "--scale",
        type=positive_float,
        default=1.0,
        help="multiply the input by this factor first (e.g. to cd/m²)",
    )
    p.add_argument(
        "--max-size",
        type=int,
        metavar="PIXELS",
        help="box-filter the input (and the reference) to at most this many pixels on its "
        "long side first",
    )
    p.add_argument(
        "--repeats", type=int, default=5, help="timed runs per operator (median; default 5)"
    )
    # compile times are part of the report: JAX's persistent compilation cache would turn
    # them into load times, so this command leaves it off (as `operators` does)
    p.set_defaults(func=run, uses_jax=False)


def _check_paths(args: argparse.Namespace) -> None:
    outputs = [args.output, args.json_path, args.sheet]
    refuse_overwriting_inputs(outputs, [args.input, args.reference])  # first, as every command
    if os.path.splitext(args.output)[1].lower() not in HTML_EXT:
        raise UsageError(f"{args.output}: expected an .html file for -o")
    if args.sheet is not None and os.path.splitext(args.sheet)[1].lower() != ".png":
        raise UsageError(f"{args.sheet}: expected a .png file for --sheet")
    named = [os.path.abspath(p) for p in outputs if p is not None]
    if len(set(named)) < len(named):
        raise UsageError("-o, --json-out and --sheet must name different files")
    for path in outputs:
        if path is None:
            continue
        folder = os.path.dirname(os.path.abspath(path))
        if not os.path.isdir(folder):
            raise DataError(f"{path}: folder {folder} does not exist")


def _methods(args: argparse.Namespace) -> list[str] | None:
    if args.methods is None:
        return None
    names = [m.strip() for m in args.methods.split(",") if m.strip()]
    if not names:
        raise UsageError("--methods: expected operator names, comma-separated")
    for name in names:
        try:
            find(name)
        except ValueError as e:
            raise UsageError(f"--methods: {str(e).removeprefix('method: ')}") from None
    return names


def run(args: argparse.Namespace) -> int:
    _check_paths(args)
    methods = _methods(args)
    if args.max_size is not None and args.max_size < 1:
        raise UsageError(f"--max-size: expected a positive integer, got {args.max_size}")
    if args.repeats < 1:
        raise UsageError(f"--repeats: expected a positive integer, got {args.repeats}")
    from ..report import compare, fit_target
    from ..report._columns import milliseconds

    if args.fit is not None:
        try:
            fit_target(args.fit)
        except ValueError as e:
            raise UsageError(f"--{e}") from None
    if args.reference is not None and not os.path.exists(args.reference):
        raise DataError(f"{args.reference}: no such file")
    image = read_image(args.input)
    try:
        table = compare(
            image,
            methods,
            all=args.all,
            fit=args.fit,
            reference=args.reference,
            peak=args.peak,
            black=args.peak / 1000,
            scale=args.scale,
            max_size=args.max_size,
            repeats=args.repeats,
        )
    except ValueError as e:
        text = " ".join(str(e).split())
        named = text.startswith(args.input) or (args.reference and args.reference in text)
        raise DataError(text if named else f"{args.input}: {text}") from None
    from ..io import atomic_path

    page = table.to_html().encode("utf-8")
    doc = table.to_json().encode("utf-8") if args.json_path else None
    sheet = None
    if args.sheet:
        import io

        buffer = io.BytesIO()
        table.figure().savefig(buffer, format="png", dpi=100)
        sheet = buffer.getvalue()
    for path, data in ((args.json_path, doc), (args.sheet, sheet), (args.output, page)):
        if path is None or data is None:
            continue
        try:
            with atomic_path(path) as tmp, open(tmp, "wb") as f:
                f.write(data)
        except OSError as e:
            raise DataError(f"{path}: cannot write ({e.strerror or e})") from None
    for row in table:
        fit = "" if row.fit_s is None else f", fit {row.fit_s:.2f} s"
        print(
            f"{row.method:<24} Q {row.q:.4f} (S {row.s:.4f}, N {row.n:.4f})"
            + ("" if row.pu_ssim is None else f", PU-SSIM {row.pu_ssim:.4f}")
            + f", clipped {100 * row.clipped:.2f} %, warm {milliseconds(row.warm_s)} ms,"
            f" compile {row.compile_s:.2f} s{fit}"
        )
    for name, reason in table.skipped.items():
        print(f"{name:<24} not compared: {reason}")
    for path in (args.json_path, args.sheet):
        if path:
            print(f"wrote: {path}")
    print(f"wrote: {args.output}")
    return 0
