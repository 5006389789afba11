"""``hdrjax panorama IN -o OUT --projection cube|fisheye|equirect|perspective|disc``: convert
between spherical projections, take a pinhole view, turn a polar image into a disc.

The input's projection comes from ``--input-projection``, else from the file (its ``projection``
metadata), else from its shape (2:1 equirectangular; 6:1, 1:6 or 4:3 a cube map). Cube maps
are stored as a horizontal strip (6:1), a vertical strip (1:6) or a horizontal cross (4:3)
of the faces of :func:`hdrjax.panorama.cubemap_directions` (OpenGL order +X −X +Y −Y +Z −Z,
each face as OpenGL's cube map table lays it out); the cross puts −X, +Z, +X, −Z in its
middle row with +Y above and −Y below +Z, where the faces' edges meet.
"""

import argparse

from ._common import (
    HDR_EXT,
    DataError,
    UsageError,
    add_format_argument,
    output_ext,
    output_file,
    positive_float,
    positive_int,
    read_image,
    refuse_overwriting_inputs,
)

SOURCES = ("auto", "equirect", "cube", "fisheye", "polar")
TARGETS = ("equirect", "cube", "fisheye", "perspective", "disc")
LAYOUTS = ("strip", "vstrip", "cross")
# the file metadata's projection names (hdrjax.layers.LayeredImage.projection)
_FILE_NAMES = {
    "equirectangular": "equirect",
    "cubemap": "cube",
    "fisheye": "fisheye",
    "polar": "polar",
}
_CROSS = {0: (1, 2), 1: (1, 0), 2: (0, 1), 3: (2, 1), 4: (1, 1), 5: (1, 3)}
"""Cube face → (row, column) of its square in the 4:3 horizontal cross."""


def _angle(text: str) -> float:
    """argparse type: a finite angle in degrees."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected degrees, got {text!r}") from None
    if v != v or abs(v) == float("inf"):
        raise argparse.ArgumentTypeError(f"expected finite degrees, got {text!r}")
    return v


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "panorama",
        help="convert panoramas (equirect, cube, fisheye), take a perspective view, "
        "turn a polar image into a disc",
        description="Resample a spherical panorama into another projection, or take a "
        "pinhole (perspective) view of it in any direction, with bilinear interpolation; "
        "turn a polar (azimuth x polar angle) sensor image into a disc. Frame: Y up, the "
        "equirectangular centre looks ahead (-Z), +X to the right. The quantity, unit and "
        "primaries of the file are kept; layers on the pixel grid are dropped (they no "
        "longer match the pixels).",
    )
    p.add_argument("input", help="HDR image: .exr, .hdr or .pfm")
    p.add_argument(
        "-o", "--output", required=True, help="output: .exr, .hdr or .pfm; '-': standard output"
    )
    add_format_argument(p, ("hdr", "pfm"))
    p.add_argument(
        "--projection", dest="to", required=True, choices=TARGETS, help="the output projection"
    )
    p.add_argument(
        "--input-projection",
        dest="source",
        choices=SOURCES,
        default="auto",
        help="the input projection (default: the file's metadata, else its shape: 2:1 "
        "equirect; 6:1, 1:6 or 4:3 cube)",
    )
    p.add_argument(
        "--size",
        type=positive_int,
        metavar="N",
        help="output size in pixels: equirect height (width 2N), cube face side, fisheye "
        "or disc diameter, perspective width (default: from the input)",
    )
    p.add_argument("--width", type=positive_int, help="perspective view width (default 512)")
    p.add_argument(
        "--height", type=positive_int, help="perspective view height (default 3/4 of the width)"
    )
    p.add_argument(
        "--fov",
        type=positive_float,
        metavar="DEG",
        help="field of view of the output: horizontal for perspective (default 90, below "
        "180), the image circle's for fisheye (default 180)",
    )
    p.add_argument(
        "--input-fov",
        dest="from_fov",
        type=positive_float,
        default=180.0,
        metavar="DEG",
        help="field of view of an input fisheye's image circle (default 180; equidistant lens)",
    )
    p.add_argument("--yaw", type=_angle, default=0.0, metavar="DEG", help="view azimuth, right +")
    p.add_argument("--pitch", type=_angle, default=0.0, metavar="DEG", help="view elevation, up +")
    p.add_argument(
        "--roll", type=_angle, default=0.0, metavar="DEG", help="camera turn about its axis, cw +"
    )
    p.add_argument(
        "--theta-max",
        type=positive_float,
        default=90.0,
        metavar="DEG",
        help="polar input: the polar angle of its bottom row's edge (default 90)",
    )
    p.add_argument(
        "--layout",
        choices=LAYOUTS,
        default="strip",
        help="cube output layout: strip (6:1, default), vstrip (1:6) or cross (4:3)",
    )
    p.set_defaults(func=run)


def detect(img, source: str, path: str) -> str:
    """The input projection: ``source`` unless ``auto``; the file's metadata; its shape."""
    if source != "auto":
        return source
    if img.projection in _FILE_NAMES:
        return _FILE_NAMES[img.projection]
    h, w = img.height, img.width
    if w == 2 * h:
        return "equirect"
    if w == 6 * h or h == 6 * w or 3 * w == 4 * h:
        return "cube"
    raise UsageError(
        f"{path}: cannot tell the projection of a {w}x{h} image from its file; "
        f"give --input-projection ({', '.join(SOURCES[1:])})"
    )


def read_faces(x, path: str):
    """The six ``(S, S, C)`` faces of a cube map stored as a strip or a cross (module doc)."""
    import numpy as np

    h, w = x.shape[:2]
    if w == 6 * h:
        return np.stack([x[:, k * h : (k + 1) * h] for k in range(6)])
    if h == 6 * w:
        return np.stack([x[k * w : (k + 1) * w] for k in range(6)])
    if 3 * w == 4 * h and w % 4 == 0:
        s = w // 4
        return np.stack([x[r * s : (r + 1) * s, c * s : (c + 1) * s] for r, c in _CROSS.values()])
    raise DataError(
        f"{path}: a {w}x{h} image is no cube map layout; expected a 6:1 or 1:6 strip or a "
        "4:3 cross of square faces"
    )


def write_faces(faces, layout: str):
    """The faces ``(6, S, S, C)`` laid out as ``layout`` (``strip``, ``vstrip``, ``cross``)."""
    import numpy as np

    f = np.asarray(faces)
    if layout == "strip":
        return np.concatenate(list(f), axis=1)
    if layout == "vstrip":
        return np.concatenate(list(f), axis=0)
    s, c = f.shape[1], f.shape[3]
    out = np.zeros((3 * s, 4 * s, c), f.dtype)
    for k, (r, col) in _CROSS.items():
        out[r * s : (r + 1) * s, col * s : (col + 1) * s] = f[k]
    return out


def _check_options(args: argparse.Namespace, source: str) -> None:
    if args.to != "perspective":
        for flag in ("yaw", "pitch", "roll"):
            if getattr(args, flag) != 0.0:
                raise UsageError(f"--{flag} applies to --projection perspective only")
        for flag in ("width", "height"):
            if getattr(args, flag) is not None:
                raise UsageError(f"--{flag} applies to --projection perspective only (use --size)")
    elif args.size is not None and args.width is not None:
        raise UsageError("--size and --width both set the view width; give one")
    if args.fov is not None:
        if args.to not in ("perspective", "fisheye"):
            raise UsageError("--fov applies to --projection perspective or fisheye")
        if args.to == "perspective" and not args.fov < 180:
            raise UsageError(
                f"--fov: a perspective view needs less than 180 degrees, got {args.fov:g}"
            )
    if (source == "polar") != (args.to == "disc"):
        raise UsageError(
            "--projection disc needs a polar input (--input-projection polar)"
            if args.to == "disc"
            else "a polar input converts to a disc only (--projection disc)"
        )
    if args.layout != "strip" and args.to != "cube":
        raise UsageError("--layout applies to --projection cube only")


def convert(x, source: str, args: argparse.Namespace, path: str):
    """The output pixels and the output's projection name (file metadata) for ``x``."""
    import numpy as np

    from .. import panorama as hp

    if source == "polar":
        size = args.size or min(x.shape[0] * 2, 4096)
        out = hp.polar_to_cartesian(x, size, theta_max_deg=args.theta_max)
        return out, None
    faces = read_faces(x, path) if source == "cube" else None
    to = args.to
    if to == "cube" and source == "cube" and args.size in (None, faces.shape[1]):
        return write_faces(faces, args.layout), "cubemap"  # a new layout only

    def equirect(height=None):
        """The input as an equirectangular map (``height`` rows, default from the input)."""
        if source == "equirect":
            if height is None or height == x.shape[0]:
                return x
            return hp.sample_equirect(x, hp.equirect_directions(height, 2 * height))
        if source == "cube":
            return hp.cubemap_to_equirect(faces, height or 2 * faces.shape[1])
        return hp.fisheye_to_equirect(x, height or min(x.shape[:2]), fov_deg=args.from_fov)

    if to == "equirect":
        return equirect(args.size), "equirectangular"
    if to == "cube":
        e = equirect()
        return write_faces(hp.equirect_to_cubemap(e, args.size or e.shape[0] // 2), args.layout), (
            "cubemap"
        )
    if to == "fisheye":
        e = equirect()
        fov = args.fov or 180.0
        return hp.equirect_to_fisheye(e, args.size or e.shape[0], fov_deg=fov), "fisheye"
    width = args.size or args.width or 512
    height = args.height or max(1, round(width * 3 / 4))
    view = hp.equirect_to_perspective(
        equirect(),
        height,
        width,
        fov_deg=args.fov or 90.0,
        yaw_deg=args.yaw,
        pitch_deg=args.pitch,
        roll_deg=args.roll,
    )
    return np.asarray(view), None


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import io as hio

    output_ext(args, HDR_EXT)
    refuse_overwriting_inputs([args.output], [args.input])
    img = read_image(args.input)
    source = detect(img, args.source, args.input)
    _check_options(args, source)
    x = np.asarray(img.image, np.float32)
    out, projection = convert(x, source, args, args.input)
    out = np.asarray(out, np.float32)
    grid = {k for k in img.layers if img.is_grid_layer(k)}
    result = img.replace(
        image=out,
        layers={k: v for k, v in img.layers.items() if k not in grid},
        layer_channels={k: v for k, v in img.layer_channels.items() if k not in grid},
        pixel_types={k: v for k, v in img.pixel_types.items() if k == "image"},
        data_window=None,
        display_window=None,
        sensor_size=None,
        projection=projection,
    )
    try:
        with output_file(args) as path:
            hio.write(path, result)
    except (ValueError, OSError) as e:
        raise DataError(f"{args.output}: cannot write: {e}") from None
    h, w = x.shape[:2]
    print(f"input: {args.input} ({w}x{h}, {source})")
    what = args.to
    if args.to == "perspective":
        what += (
            f" fov {args.fov or 90.0:g} yaw {args.yaw:g} pitch {args.pitch:g} roll {args.roll:g}"
        )
    print(f"{what}: {out.shape[1]}x{out.shape[0]}")
    if grid:
        print("dropped grid layers: " + ", ".join(sorted(grid)))
    print(f"wrote: {args.output}")
    return 0
