"""``hdrjax tonemap INPUT -o OUTPUT``: tone-map an HDR file to a display image."""

import argparse
import os
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

# command-line option -> operator parameter, and the operators that accept it
OPTION_PARAMS = {
    "key": "key",
    "white": "L_white",
    "L_wa": "L_wa",
    "L_max": "L_max",
    "L_da": "L_da",
    "exposure_time": "exposure_time",
    "f_number": "f_number",
    "iso": "iso",
    "ev100": "ev100",
}


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "tonemap",
        help="tone-map an HDR image (.exr, .hdr, .pfm) to .png/.jpg/.tif/.exr",
        description="Tone-map an HDR image. Parameters left out are estimated from the image "
        "(Reinhard 2002 JGT key and white point, log-average adaptation luminance).",
    )
    add_input_output_method_arguments(p)
    p.add_argument("--key", type=positive_float, help="Reinhard key a (default: JGT estimate)")
    p.add_argument(
        "--white",
        type=positive_float,
        help="L_white (Reinhard: scaled units; tumblin_reinhard: display units)",
    )
    p.add_argument(
        "--L-wa",
        dest="L_wa",
        type=positive_float,
        help="world adaptation luminance, cd/m² (tumblin_reinhard, tumblin1999)",
    )
    p.add_argument(
        "--L-max",
        dest="L_max",
        type=positive_float,
        help="luminance mapped to white / not clipped (linear, tumblin_reinhard)",
    )
    p.add_argument(
        "--L-da",
        dest="L_da",
        type=positive_float,
        help="display adaptation luminance, cd/m² (tumblin_reinhard, tumblin1999)",
    )
    p.add_argument("--exposure-time", type=positive_float, help="seconds (linear)")
    p.add_argument("--f-number", type=positive_float, help="aperture N (linear)")
    p.add_argument("--iso", type=positive_float, help="ISO speed S (linear)")
    p.add_argument("--ev100", type=float, help="exposure value at ISO 100 (linear)")
    add_table_and_scale_arguments(p)
    add_encoding_arguments(p)
    p.add_argument("-v", "--verbose", action="store_true", help="print timings too")
    p.set_defaults(func=run)


def add_input_output_method_arguments(p: argparse.ArgumentParser) -> None:
    """``INPUT``, ``-o/--output`` and ``--method`` (shared with ``hdrjax fit``)."""
    p.add_argument("input", help="HDR image: .exr, .hdr (Radiance RGBE) or .pfm")
    add_output_argument(p)
    p.add_argument(
        "--method",
        default="reinhard2002",
        help="operator name (see `hdrjax info`; default reinhard2002)",
    )


def add_output_argument(p: argparse.ArgumentParser) -> None:
    """``-o/--output``."""
    p.add_argument(
        "-o",
        "--output",
        required=True,
        help="output: .png (8/16-bit), .jpg, .tif (encoded) or .exr/.hdr/.pfm "
        "(display-referred linear); '-' writes to standard output (needs --format)",
    )
    add_format_argument(p)


def add_table_and_scale_arguments(p: argparse.ArgumentParser) -> None:
    """``--table`` (for ``--method tabulated``, see :func:`build_operator`) and ``--scale``
    (see :func:`load_rgb`), shared with ``hdrjax fit``."""
    p.add_argument("--table", help="CSV/JSON table for --method tabulated")
    p.add_argument(
        "--scale",
        type=positive_float,
        default=1.0,
        help="multiply the input by this factor first (e.g. to cd/m²)",
    )


def add_encoding_arguments(p: argparse.ArgumentParser) -> None:
    """``--transfer``, ``--gamma``, ``--bits``: how :func:`write_output` encodes."""
    p.add_argument(
        "--transfer",
        choices=("srgb", "gamma", "linear"),
        default="srgb",
        help="display encoding for .png/.jpg/.tif (default srgb)",
    )
    p.add_argument("--gamma", type=positive_float, default=2.2, help="for --transfer gamma")
    p.add_argument("--bits", type=int, choices=(8, 16), default=8, help="PNG/TIFF bit depth")


def check_output(args: argparse.Namespace) -> str:
    """Validate ``args.output`` against the encoding options; returns its extension."""
    ext = output_ext(args, LDR_EXT + HDR_EXT)
    if args.bits == 16 and ext in (".jpg", ".jpeg"):
        raise UsageError("--bits 16 needs .png or .tif output (JPEG is 8-bit)")
    refuse_overwriting_inputs([args.output], [args.input, args.table])
    return ext


def encode_output(args: argparse.Namespace, display):
    """Display-referred linear RGB → the array written to ``args.output`` (NumPy): encoded
    for .png/.jpg/.tif, linear float for .exr/.hdr/.pfm."""
    import jax
    import numpy as np

    from ..display import encode

    out = display
    if output_ext(args) in LDR_EXT:
        out = encode(out, args.transfer, gamma=args.gamma)
    return np.asarray(jax.block_until_ready(out))


def write_output(args: argparse.Namespace, encoded) -> None:
    """Write :func:`encode_output`'s array to ``args.output`` (atomic); errors → DataError."""
    import numpy as np

    from .. import io as hio
    from ..display import quantize

    try:
        with output_file(args) as path:
            if output_ext(args) in LDR_EXT:
                hio.write_display(path, quantize(encoded, args.bits), bits=args.bits)
            else:
                hio.write(path, encoded.astype(np.float32))
    except (ValueError, OSError) as e:
        raise DataError(f"{args.output}: cannot write: {e}") from None


def build_operator(args: argparse.Namespace):
    """The operator the arguments describe; unknown names or misplaced options → UsageError."""
    from ..operators import Tabulated, get_operator, parameter_names

    try:
        cls = get_operator(args.method)
    except ValueError as e:
        raise UsageError(str(e)) from None
    params = {}
    valid = parameter_names(cls)
    for opt, name in OPTION_PARAMS.items():
        value = getattr(args, opt, None)
        if value is None:
            continue
        if name not in valid:
            flag = "--" + opt.replace("_", "-")
            raise UsageError(f"{flag} does not apply to --method {cls.name}")
        params[name] = value
    if cls.name == "tabulated":
        if not args.table:
            raise UsageError("--method tabulated needs --table FILE")
        try:
            return Tabulated.from_file(args.table)
        except ValueError as e:
            raise DataError(str(e)) from None
    if args.table:
        raise UsageError(f"--table does not apply to --method {cls.name}")
    try:
        return cls(**params)
    except ValueError as e:
        raise UsageError(str(e)) from None


def describe(op, estimated: tuple[str, ...] = (), given: dict | None = None) -> str:
    """One line per parameter, for the user; ``estimated`` ones are marked. ``given``:
    the user's parameters, shown too when the measured operator replaced them (exposure)."""
    lines = [f"operator: {op.name}"]
    params = op.parameters()
    for name, value in (given or {}).items():
        if value is not None and params.get(name) is None:
            params[name] = value
    for name, value in params.items():
        if value is None:
            continue
        if name == "weights":
            value = "(" + ", ".join(f"{w:.4f}" for w in value) + ")"
        elif isinstance(value, float):
            value = f"{value:.6g}"
        mark = "  (estimated from the image)" if name in estimated else ""
        lines.append(f"  {name}: {value}{mark}")
    return "\n".join(lines)


def load_rgb(path: str, scale: float = 1.0):
    """Read an HDR file as float32 RGB with its luminance weights; errors → DataError."""
    import numpy as np

    img = read_image(path)
    try:
        rgb = img.rgb()
    except ValueError as e:
        raise DataError(str(e) if os.path.basename(path) in str(e) else f"{path}: {e}") from None
    if scale != 1.0:
        rgb = rgb * np.float32(scale)
    return img, rgb


def run(args: argparse.Namespace) -> int:
    check_output(args)
    op = build_operator(args)
    t0 = time.perf_counter()
    img, rgb = load_rgb(args.input, args.scale)
    t_read = time.perf_counter() - t0

    import numpy as np

    op = with_file_weights(op, img)
    t1 = time.perf_counter()
    measured = eqx_jit_measure(op, rgb)
    out = encode_output(args, measured(rgb))
    t_map = time.perf_counter() - t1
    n_bad = int(np.count_nonzero(~np.all(np.isfinite(rgb), axis=-1)))
    t2 = time.perf_counter()
    write_output(args, out)
    t_write = time.perf_counter() - t2
    h, w = rgb.shape[:2]
    print(f"input: {args.input} ({w}x{h})")
    if n_bad:
        print(f"  {n_bad} pixel(s) with NaN/Inf values excluded from statistics")
    print(describe(measured, op.unset(), op.parameters()))
    print(f"wrote: {args.output}")
    if args.verbose:
        print(
            f"time: read {t_read:.3f}s, tone map {t_map:.3f}s (incl. compile), write {t_write:.3f}s"
        )
    return 0


def with_file_weights(op, img):
    """The operator with the file's luminance weights (operators that have a setting)."""
    import dataclasses

    if "weights" in {f.name for f in dataclasses.fields(op)}:
        op = dataclasses.replace(op, weights=img.luminance_weights)
    return op


def eqx_jit_measure(op, rgb):
    """``op.measure(rgb)`` compiled (statistics of large images are slow eagerly)."""
    import equinox as eqx

    return eqx.filter_jit(lambda o, x: o.measure(x))(op, rgb)
