"""``hdrjax vision INPUT``: which human-vision effects a scene calls for, and the simulation."""

import argparse
import json
import time

from ._common import (
    HDR_EXT,
    LDR_EXT,
    DataError,
    UsageError,
    add_format_argument,
    output_ext,
    output_file,
    positive_float,
    read_image,
    refuse_overwriting_inputs,
)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "vision",
        help="report and simulate human vision (glare, acuity, night colour) for a scene",
        description="Analyse an HDR image in absolute units (cd/m²) as Radiance pcond does: "
        "which effects of human vision apply (loss of acuity, veiling glare, mesopic colour "
        "loss and blue shift, contrast sensitivity) and why; with -o, apply them and write "
        "the result. Relative images need --scale (cd/m² per unit) unless the file declares "
        "its white luminance.",
    )
    p.add_argument("input", help="HDR image: .exr, .hdr (Radiance RGBE) or .pfm")
    p.add_argument(
        "-o",
        "--output",
        help="write the simulated image: .exr/.hdr/.pfm (linear cd/m²) or "
        ".png/.jpg/.tif (tone-mapped, sRGB); '-': standard output",
    )
    add_format_argument(p)
    fov = p.add_mutually_exclusive_group()
    fov.add_argument(
        "--fov",
        type=positive_float,
        help="horizontal field of view in degrees (default: 40° across the longer side, as pcond)",
    )
    fov.add_argument(
        "--pixel-deg",
        type=positive_float,
        help="angular size of one pixel in degrees (equiangular)",
    )
    fov.add_argument(
        "--panorama", action="store_true", help="the image is a 360°×180° lat-long panorama"
    )
    p.add_argument(
        "--scale", type=positive_float, help="cd/m² per stored unit (required for relative images)"
    )
    p.add_argument(
        "--effects",
        default="auto",
        help="auto (default), all, none, or a comma list of: acuity, glare, "
        "colour_loss, blue_shift, contrast",
    )
    p.add_argument(
        "--with",
        dest="force_on",
        action="append",
        default=[],
        metavar="EFFECT",
        help="force an effect on (with --effects auto; repeatable)",
    )
    p.add_argument(
        "--without",
        dest="force_off",
        action="append",
        default=[],
        metavar="EFFECT",
        help="force an effect off (repeatable)",
    )
    p.add_argument(
        "--glare-model",
        choices=("spencer1995", "pcond"),
        default="spencer1995",
        help="Spencer et al. 1995 PSF convolution (default) or pcond's veil",
    )
    p.add_argument(
        "--glare-radius",
        type=positive_float,
        metavar="DEG",
        help="truncate the glare PSF at this angle (faster, less exact)",
    )
    p.add_argument(
        "--display-max",
        type=positive_float,
        default=100.0,
        help="display maximum luminance, cd/m² (default 100)",
    )
    p.add_argument(
        "--tonemap",
        default="auto",
        help="operator for .png/.jpg/.tif output (default: linear at "
        "--display-max after the contrast effect, else reinhard2002)",
    )
    p.add_argument(
        "--perceptual",
        action="store_true",
        help="for .png/.jpg/.tif: Budak and Petrovichev's (2005) perceptual colour-contrast "
        "reproduction (Budak2005) instead of --tonemap",
    )
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.add_argument("-v", "--verbose", action="store_true", help="print timings too")
    p.set_defaults(func=run)


def _view(args: argparse.Namespace):
    from ..vision import View

    if args.panorama:
        return View(hfov=360.0, vfov=180.0, projection="equiangular")
    if args.pixel_deg:
        return View(pixel_deg=args.pixel_deg)
    try:
        return View(hfov=args.fov) if args.fov else View()
    except ValueError as e:
        raise UsageError(str(e)) from None


def _effects(args: argparse.Namespace):
    from ..vision._simulate import effect_name

    try:
        forced = {effect_name(e, "--with"): True for e in args.force_on}
        forced.update({effect_name(e, "--without"): False for e in args.force_off})
        if args.effects.strip().lower() != "auto":
            if forced:
                raise UsageError("--with/--without apply to --effects auto only")
            names = [e for e in args.effects.split(",") if e.strip()]
            if args.effects.strip().lower() in ("all", "none"):
                return args.effects.strip().lower()
            return [effect_name(e, "--effects") for e in names]
    except ValueError as e:
        raise UsageError(str(e)) from None
    return forced or "auto"


def vision_effects() -> tuple[str, ...]:
    from ..vision import EFFECTS

    return EFFECTS


def run(args: argparse.Namespace) -> int:
    ext = output_ext(args, LDR_EXT + HDR_EXT) if args.output else None
    if args.perceptual and ext not in LDR_EXT:
        raise UsageError("--perceptual needs a .png/.jpg/.tif output")
    refuse_overwriting_inputs([args.output], [args.input])
    view, effects = _view(args), _effects(args)
    if args.perceptual:  # Budak2005 re-adapts to the display itself
        if effects == "auto" or isinstance(effects, dict):
            effects = {**(effects if isinstance(effects, dict) else {}), "contrast": False}
        elif effects == "all":
            effects = [e for e in vision_effects() if e != "contrast"]
        elif isinstance(effects, list):
            effects = [e for e in effects if e != "contrast"]
    t0 = time.perf_counter()
    img = read_image(args.input)

    import numpy as np

    from .. import vision

    try:
        rgb, chroma = vision._simulate.absolute_rgb(img, args.scale)
    except ValueError as e:
        raise UsageError(f"{args.input}: {e}") from None
    if args.output is None:
        report = vision.analyze(rgb, view, scale=1.0, chromaticities=chroma)
        out = None
    else:
        out, report = vision.simulate(
            rgb,
            view,
            effects,
            scale=1.0,
            chromaticities=chroma,
            glare_model=args.glare_model,
            glare_radius_deg=args.glare_radius,
            display_max=args.display_max,
        )
    t_sim = time.perf_counter() - t0
    if args.json:
        d = report.to_dict()
        d["input"] = args.input
        if out is not None:
            d["applied"] = list(report.selected)  # simulate's report: what it applied
        print(json.dumps(d, indent=1))
    else:
        print(f"input: {args.input}")
        print(report)
    if out is None:
        return 0
    applied = report.selected
    if ext in LDR_EXT:
        from .. import display, tonemap

        if args.perceptual:
            disp = vision.Budak2005(display_max=args.display_max, chromaticities=chroma)(out)
        else:
            method = args.tonemap
            params = {}
            if method == "auto":
                method = "linear" if "contrast" in applied else "reinhard2002"
                if method == "linear":
                    params["L_max"] = args.display_max
            try:
                disp = display.encode(tonemap(out, method=method, **params))
            except ValueError as e:
                raise UsageError(str(e)) from None
    from .. import io as hio

    try:
        with output_file(args) as path:
            if ext in LDR_EXT:
                hio.write_display(path, display.quantize(disp))
            else:
                hio.write(path, np.asarray(out, np.float32))
    except (ValueError, OSError) as e:
        raise DataError(f"{args.output}: cannot write: {e}") from None
    if not args.json:
        print(f"applied: {', '.join(applied) or 'nothing'}")
        print(f"wrote: {args.output}")
    if args.verbose:
        print(f"time: read+analyse+simulate {t_sim:.3f}s (incl. compile)")
    return 0
