"""``hdrjax measure FILE``: distance between pixels, readout at a pixel, region statistics."""

import argparse
import functools
import json
import os

from ._cmd_export import as_data_error
from ._common import DataError, DeprecatedAlias, UsageError, refuse_overwriting_inputs


def _point(text: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y, got {text!r}") from None
    return x, y


def _rect(text: str) -> tuple[float, float, float, float]:
    try:
        x0, y0, x1, y1 = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X0,Y0,X1,Y1, got {text!r}") from None
    return x0, y0, x1, y1


def _sensor_size(text: str) -> tuple[float, float]:
    """argparse type: ``W×H`` millimetres (``36x24``, ``36×24`` or ``36,24``), both > 0."""
    parts = text.replace("×", "x").replace("X", "x").replace(",", "x").split("x")
    try:
        w, h = (float(v) for v in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WxH in millimetres, got {text!r}") from None
    if not (0 < w < float("inf") and 0 < h < float("inf")):
        raise argparse.ArgumentTypeError(f"expected sizes > 0 in millimetres, got {text!r}")
    return w, h


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "measure",
        help="distance between two pixels (3D from the position layer, else 2D), readouts, "
        "region statistics",
        description="Measure on a layered HDR file. --from/--to: distance between two pixels, "
        "in 3D (scene units) from the 'position' layer when there is one, else in 2D (metres "
        "on a virtual sensor of known size, else pixels). --at: everything known about a "
        "pixel. --rect/--polygon: statistics of a region, optionally saved as JSON.",
    )
    p.add_argument("input", help="HDR file: .exr, .hdr or .pfm (sidecar layers are found)")
    p.add_argument("--from", dest="a", type=_point, metavar="X,Y", help="first pixel")
    p.add_argument("--to", dest="b", type=_point, metavar="X,Y", help="second pixel")
    p.add_argument(
        "--2d",
        dest="force_2d",
        action="store_true",
        help="2D distance even when the file has positions",
    )
    p.add_argument(
        "--view-scale",
        dest="scale",
        type=float,
        default=100.0,
        metavar="PERCENT",
        help="coordinates are on a view scaled to PERCENT of the pixel grid (default 100)",
    )
    p.add_argument(
        "--scale",
        dest="scale",
        type=float,
        action=DeprecatedAlias,
        replacement="use --view-scale PERCENT (--scale is a multiplier elsewhere)",
    )
    p.add_argument("--at", type=_point, metavar="X,Y", help="print the readout at a pixel")
    p.add_argument("--rect", type=_rect, metavar="X0,Y0,X1,Y1", help="rectangular region")
    p.add_argument(
        "--polygon",
        type=_point,
        nargs="+",
        metavar="X,Y",
        help="polygon region (3 or more vertices)",
    )
    p.add_argument("--region-out", metavar="FILE.json", help="save the region and its statistics")
    p.add_argument(
        "--overwrite",
        dest=argparse.SUPPRESS,
        nargs=0,
        action=DeprecatedAlias,
        replacement="outputs are replaced by default now (--no-clobber refuses them)",
    )
    p.add_argument("--part", help="EXR part (index or name)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument(
        "--sensor-size",
        type=_sensor_size,
        metavar="WxH",
        help="the virtual sensor's width and height in millimetres (36x24, 36×24 or 36,24) "
        "for 2D distances in metres; overrides the size the file records",
    )
    p.add_argument(
        "-v", "--verbose", action="store_true", help="say where the sensor size came from"
    )
    p.set_defaults(func=run)


def _with_sensor_size(img, args: argparse.Namespace):
    """``img`` with ``--sensor-size`` (mm) as its sensor size (metres); with ``--verbose``,
    says whether that replaces the size the file records."""
    import sys

    size = (args.sensor_size[0] / 1000.0, args.sensor_size[1] / 1000.0)
    say = functools.partial(print, file=sys.stderr if args.json else sys.stdout)  # JSON stays clean
    if args.verbose:
        given = f"{args.sensor_size[0]:g} mm x {args.sensor_size[1]:g} mm"
        if img.sensor_size is None:
            say(f"sensor size: {given} (--sensor-size; the file records none)")
        elif any(abs(a - b) > 1e-6 * b for a, b in zip(img.sensor_size, size, strict=True)):
            old = f"{img.sensor_size[0] * 1000:g} mm x {img.sensor_size[1] * 1000:g} mm"
            say(f"sensor size: {given} (--sensor-size overrides the file's {old})")
        else:
            say(f"sensor size: {given} (--sensor-size, as the file records)")
    return img.replace(sensor_size=size)


def run(args: argparse.Namespace) -> int:
    from .. import io as hio, measure as hm

    if (args.a is None) != (args.b is None):
        raise UsageError("--from and --to go together")
    if args.rect and args.polygon:
        raise UsageError("give --rect or --polygon, not both")
    if args.region_out and not (args.rect or args.polygon):
        raise UsageError("--region-out needs --rect or --polygon")
    if args.a is None and args.at is None and not (args.rect or args.polygon):
        raise UsageError("nothing to measure: give --from X,Y --to X,Y, --at X,Y or a region")
    if not (args.scale > 0):
        raise UsageError(f"--view-scale must be > 0, got {args.scale:g}")
    refuse_overwriting_inputs([args.region_out], [args.input])
    if args.input != "-" and not os.path.exists(args.input):
        raise DataError(f"{args.input}: no such file")
    part = int(args.part) if args.part is not None and args.part.isdigit() else args.part
    out: dict = {}
    try:
        img = hio.read(args.input, part=part)
        if args.sensor_size is not None:
            img = _with_sensor_size(img, args)
        if args.a is not None:
            d = hm.distance(
                img,
                args.a,
                args.b,
                mode="2d" if args.force_2d else "auto",
                scale_percent=args.scale,
            )
            out["distance"] = d.to_dict()
        if args.at is not None:
            out["readout"] = hm.readout(img, args.at, scale_percent=args.scale)
        region = None
        if args.rect:
            region = hm.Region.rect(*args.rect)
        elif args.polygon:
            if len(args.polygon) < 3:
                raise UsageError("--polygon needs at least 3 vertices")
            region = hm.Region.polygon(args.polygon)
        if region is not None:
            out["region"] = {"region": region.to_dict(), "stats": hm.region_stats(img, region)}
            if args.region_out:
                hm.save_region(args.region_out, img, region, overwrite=not args.no_clobber)
    except (ValueError, OSError) as e:
        raise as_data_error(e, args.input) from None
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    if "distance" in out:
        d = out["distance"]
        print(f"distance: {d['value']:.6g} {d['unit']} ({d['mode']}): {d['note']}")
        print(f"  from pixel {tuple(d['a'])} to pixel {tuple(d['b'])}")
        if d["point_a"] is not None:
            pa = ", ".join(f"{v:.6g}" for v in d["point_a"])
            pb = ", ".join(f"{v:.6g}" for v in d["point_b"])
            print(f"  scene points ({pa}) -> ({pb})")
    if "readout" in out:
        r = out["readout"]
        unit = f" {r['unit']}" if r["unit"] else ""
        value = "n/a" if r["value"] is None else f"{r['value']:.6g}{unit}"
        print(f"pixel {tuple(r['pixel'])}: {r['quantity']} {value}")
        print("  " + ", ".join(f"{k}={v:.6g}" for k, v in r["channels"].items()))
        for key in ("error", "hits", "position", "object_id"):
            if r[key] is not None:
                print(f"  {key}: {r[key]}")
    if "region" in out:
        s = out["region"]["stats"]
        unit = f" {s['unit']}" if s["unit"] else ""
        print(f"region ({out['region']['region']['kind']}): {s['pixels']} pixels")
        if s["mean"] is not None:
            stats = f"mean {s['mean']:.6g}, min {s['min']:.6g}, max {s['max']:.6g}"
            print(f"  {s['quantity']}: {stats}{unit}")
        if s["mean_error"] is not None:
            print(f"  mean error: {s['mean_error']:.6g}")
        if s["total_hits"] is not None:
            print(f"  total hits: {s['total_hits']}")
        if args.region_out:
            print(f"wrote: {args.region_out}")
    return 0
