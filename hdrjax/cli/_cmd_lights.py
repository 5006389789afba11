"""``hdrjax lights FILE -o overlay.png --json-out lights.json``: find the light sources of a map."""

import argparse
import json
import os
import time

from ._common import (
    DataError,
    DeprecatedAlias,
    UsageError,
    positive_float,
    positive_int,
    refuse_overwriting_inputs,
)
from ._registry import constant

OVERLAY_EXT = (".png", ".jpg", ".jpeg", ".pdf", ".svg")


def _non_negative_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (v >= 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return v


def register(subparsers) -> None:
    # hdrjax.lights' defaults, recorded (importing hdrjax.lights imports JAX)
    width, blur = constant("hdrjax.lights.DEFAULT_WIDTH"), constant("hdrjax.lights.DEFAULT_BLUR")
    max_radius = constant("hdrjax.lights.DEFAULT_MAX_RADIUS")
    max_lights = constant("hdrjax.lights.DEFAULT_MAX_LIGHTS")
    p = subparsers.add_parser(
        "lights",
        help="find the light sources of an environment map (or a plain image)",
        description="Find the light sources of an equirectangular environment map (Loghin "
        "2019) or, with --method median-cut, Debevec's median-cut lights. Prints one "
        "line per light; --json-out writes directions, sizes and energy shares, -o draws them over "
        "the tone-mapped map (blue: local maxima, cyan: light centres, red: joined samples).",
    )
    p.add_argument("input", help="HDR image: .exr, .hdr (Radiance RGBE) or .pfm")
    p.add_argument("-o", "--output", help="overlay image (.png, .jpg, .pdf, .svg)")
    p.add_argument(
        "--json-out", dest="json_path", metavar="FILE.json", help="write the lights as JSON here"
    )
    p.add_argument(
        "--json", dest="json_path", action=DeprecatedAlias, replacement="use --json-out FILE.json"
    )
    p.add_argument(
        "--method",
        choices=("loghin2019", "median-cut"),
        default="loghin2019",
        help="detection (default) or Debevec 2005 median cut",
    )
    p.add_argument(
        "--projection",
        choices=("auto", "equirectangular", "plane"),
        default="auto",
        help="auto: the file's projection attribute, else equirectangular when "
        "the image is twice as wide as high, else plane",
    )
    p.add_argument(
        "--width",
        type=positive_int,
        default=width,
        help=f"working width in pixels (default {width})",
    )
    p.add_argument(
        "--samples",
        type=positive_int,
        help="quasi-Monte-Carlo samples (default 0.006 per working pixel)",
    )
    p.add_argument(
        "--threshold",
        type=positive_float,
        help="luminance threshold in the file's units (default: automatic)",
    )
    p.add_argument(
        "--blur",
        type=_non_negative_float,
        default=blur,
        help=f"Gaussian sigma in working pixels (default {blur:g})",
    )
    p.add_argument(
        "--max-radius",
        type=positive_float,
        help=f"largest light radius: degrees (default {max_radius:g}), or "
        "working pixels for a plain image",
    )
    p.add_argument(
        "--max-lights",
        type=positive_int,
        default=max_lights,
        help=f"most lights reported (default {max_lights})",
    )
    p.add_argument(
        "--n-lights",
        type=positive_int,
        default=16,
        help="median cut: number of lights, a power of two (default 16)",
    )
    p.add_argument(
        "--convention",
        choices=constant("hdrjax.lights.CONVENTIONS"),
        default="hdrjax",
        help="direction convention for the JSON and the listing (default hdrjax: "
        "Y-up, ahead -Z, right +X)",
    )
    p.add_argument("-v", "--verbose", action="store_true", help="print timings too")
    p.set_defaults(func=run)


def _projection(args: argparse.Namespace, img, shape: tuple[int, ...]) -> str:
    if args.projection != "auto":
        return args.projection
    declared = getattr(img, "projection", None)
    if declared in ("equirectangular", None):
        if declared == "equirectangular" or shape[1] == 2 * shape[0]:
            return "equirectangular"
        return "plane"
    raise DataError(
        f"{args.input}: projection {declared!r} is not supported by `hdrjax lights` "
        "(equirectangular or plane; use hdrjax.lights.detect_cubemap for cube maps)"
    )


def run(args: argparse.Namespace) -> int:
    for path, kind, exts in (
        (args.output, "-o", OVERLAY_EXT),
        (args.json_path, "--json-out", None),
    ):
        if path and exts and os.path.splitext(path)[1].lower() not in exts:
            raise UsageError(f"{kind} {path}: expected one of {', '.join(exts)}")
    if args.output and args.method == "median-cut":
        raise UsageError("-o draws detected lights; it does not apply to --method median-cut")
    refuse_overwriting_inputs([args.output, args.json_path], [args.input])
    from ._cmd_tonemap import load_rgb

    t0 = time.perf_counter()
    img, rgb = load_rgb(args.input)
    t_read = time.perf_counter() - t0
    projection = _projection(args, img, rgb.shape)
    weights = img.luminance_weights_in()  # the file's own luminance, from sRGB pixels

    import jax

    from .. import lights as hl
    from ..io._atomic import atomic_path, atomic_write_bytes

    t0 = time.perf_counter()
    try:
        if args.method == "median-cut":
            if projection != "equirectangular":
                raise UsageError("--method median-cut needs an equirectangular map")
            res = hl.median_cut(rgb, n_lights=args.n_lights, width=args.width, weights=weights)
        else:
            opts = dict(
                width=args.width,
                n_samples=args.samples,
                threshold=args.threshold,
                blur=args.blur,
                max_lights=args.max_lights,
                weights=weights,
            )
            if projection == "plane":
                res = hl.detect_image(rgb, max_radius=args.max_radius, **opts)
            else:
                radius = hl.DEFAULT_MAX_RADIUS if args.max_radius is None else args.max_radius
                res = hl.detect(rgb, max_radius=radius, **opts)
        jax.block_until_ready(res)
    except ValueError as e:
        raise UsageError(str(e)) from None
    t_detect = time.perf_counter() - t0

    if isinstance(res, hl.MedianCutLights):
        records = res.to_records()
        doc = {
            "file": args.input,
            "method": "median-cut",
            "input_shape": list(rgb.shape[:2]),
            "convention": args.convention,
            "lights": records,
        }
        print(f"{args.input}: {len(records)} median-cut lights")
    else:
        doc = json.loads(res.to_json(file=args.input, method="loghin2019"))
        doc["convention"] = args.convention
        records = doc["lights"]
        thr = doc["threshold"]
        print(
            f"{args.input}: {len(records)} light(s), threshold "
            f"{'none' if thr is None else f'{thr:.4g}'}"
            + (" (capped: raise --max-lights)" if doc["truncated"] else "")
        )
    if projection == "equirectangular" and records:
        if isinstance(res, hl.MedianCutLights):
            dirs = hl.convert_direction(res.direction, "hdrjax", args.convention)
        else:
            dirs = res.directions(args.convention)
        for rec, d in zip(records, dirs.tolist(), strict=False):
            rec["direction"] = d
    for k, rec in enumerate(records):
        where = (
            f"az {rec['azimuth_deg']:+7.2f}° el {rec['elevation_deg']:+6.2f}°"
            if "azimuth_deg" in rec
            else f"x {rec['pixel'][0]:8.2f} y {rec['pixel'][1]:8.2f}"
        )
        size = f", {rec['angular_diameter_deg']:.2f}° wide" if "angular_diameter_deg" in rec else ""
        print(f"  {k:2d}: {where}  energy share {rec['energy_share']:.3f}{size}")
    if args.json_path:
        try:
            os.makedirs(os.path.dirname(os.path.abspath(args.json_path)), exist_ok=True)
            atomic_write_bytes(args.json_path, json.dumps(doc, indent=2).encode())
        except OSError as e:
            raise DataError(f"{args.json_path}: cannot write ({e.strerror or e})") from None
    if args.output:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        ax = hl.plot_lights(rgb, res)
        try:
            os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
            fmt = os.path.splitext(args.output)[1].lstrip(".").lower()
            with atomic_path(args.output) as tmp:
                ax.figure.savefig(tmp, format=fmt, dpi=100, bbox_inches="tight", pad_inches=0)
        except OSError as e:
            raise DataError(f"{args.output}: cannot write ({e.strerror or e})") from None
        finally:
            plt.close(ax.figure)
    if args.verbose:
        print(f"read {t_read * 1e3:.1f} ms, detection {t_detect * 1e3:.1f} ms (with compilation)")
    return 0
