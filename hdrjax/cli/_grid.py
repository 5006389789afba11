"""``--grid DEG|layer`` of the display commands: the angular grid of a panorama or fisheye,
or the file's own ``grid`` layer, drawn over the display image."""

import argparse

from ._common import DataError, UsageError, positive_float

GRID_PROJECTIONS = ("equirectangular", "fisheye")


def _grid(text: str) -> str | float:
    """argparse type: ``layer`` or degrees in (0, 90]."""
    if text == "layer":
        return text
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected degrees or 'layer', got {text!r}") from None
    if not 0 < v <= 90:
        raise argparse.ArgumentTypeError(f"expected degrees in (0, 90], got {text!r}")
    return v


def add_grid_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--grid",
        type=_grid,
        metavar="DEG|layer",
        help="draw the azimuth/elevation grid every DEG degrees, labelled (equirectangular "
        "or fisheye images), or 'layer': the file's own grid layer",
    )
    p.add_argument(
        "--input-projection",
        dest="projection",
        choices=GRID_PROJECTIONS,
        help="the image's projection for --grid DEG (default: the file's, else "
        "equirectangular for a 2:1 image)",
    )
    p.add_argument(
        "--input-fov",
        dest="grid_fov",
        type=positive_float,
        default=180.0,
        metavar="DEG",
        help="a fisheye's image circle for --grid (default 180; equidistant lens)",
    )
    p.add_argument("--grid-color", default="white", help="grid colour (default white)")


def draw_grid(args: argparse.Namespace, img, display):
    """``display`` (sRGB ``(H, W, 3)`` in [0, 1]) with the grid ``args`` ask for, or as it
    is without ``--grid``. ``img``: the LayeredImage the display shows."""
    import numpy as np
    from matplotlib.colors import to_rgb

    from ..plot import with_angular_grid

    if args.grid is None:
        if args.projection is not None:
            raise UsageError("--input-projection applies to --grid DEG")
        return display
    try:
        colour = np.asarray(to_rgb(args.grid_color), np.float32)
    except ValueError:
        raise UsageError(f"--grid-color: unknown colour {args.grid_color!r}") from None
    out = np.asarray(display, np.float32)
    h, w = out.shape[:2]
    if args.grid == "layer":
        if args.projection is not None:
            raise UsageError("--input-projection applies to --grid DEG, not --grid layer")
        if not img.has_layer("grid"):
            raise DataError(f"{args.input}: no 'grid' layer to draw (--grid layer)")
        g = np.asarray(img.layer("grid"), np.float32)
        if g.ndim == 3 and g.shape[2] == 3:  # a coloured grid image: its colours, where drawn
            cover = np.clip(np.nan_to_num(g.max(axis=2)), 0.0, 1.0)[..., None]
            return out * (1 - cover) + np.clip(np.nan_to_num(g), 0.0, 1.0) * cover
        cover = np.clip(np.nan_to_num(g.reshape(h, w)), 0.0, 1.0)[..., None]
        return out * (1 - cover) + colour * cover
    projection = args.projection or img.projection
    if projection is None and w == 2 * h:
        projection = "equirectangular"
    if projection not in GRID_PROJECTIONS:
        raise UsageError(
            f"{args.input}: --grid needs an equirectangular or fisheye image (its projection "
            f"is {projection or 'unknown'}); give --input-projection"
        )
    return with_angular_grid(
        out,
        projection=projection,
        step_deg=float(args.grid),
        fov_deg=args.grid_fov,
        color=tuple(float(c) for c in colour),
    )
