"""``hdrjax tonemap INPUT -o OUTPUT``: tone-map an HDR file to a display image."""

import argparse
import dataclasses
import math
import os
import time
from typing import Any

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
from ._registry import operators

SHORTCUTS = {"white": "L_white"}
"""Named options whose parameter has another name; the others (``--key``, ``--L-wa``…)
set the parameter of their own name. Each is a shortcut for ``--set PARAM=VALUE``."""
SHORTCUT_OPTIONS = (
    "key", "white", "L_wa", "L_max", "L_da", "exposure_time", "f_number", "iso", "ev100"
)  # fmt: skip
"""The named options ``tonemap`` and ``fit`` take (``batch`` the first five)."""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "tonemap",
        help="tone-map an HDR image (.exr, .hdr, .pfm) to .png/.jpg/.tif/.exr",
        description="Tone-map an HDR image. Parameters left out are estimated from the image "
        "(Reinhard 2002 JGT key and white point, log-average adaptation luminance).",
    )
    add_input_output_method_arguments(p)
    add_set_argument(p)
    add_parameter_shortcuts(p, SHORTCUT_OPTIONS)
    add_table_and_scale_arguments(p)
    add_colour_arguments(p)
    add_encoding_arguments(p)
    p.add_argument(
        "--exposure",
        type=float,
        default=0.0,
        metavar="EV",
        help="exposure compensation in stops before tone mapping: the input times 2^EV "
        "(with --scale, both apply)",
    )
    p.add_argument("-v", "--verbose", action="store_true", help="print timings too")
    p.set_defaults(func=run)


def add_colour_arguments(p: argparse.ArgumentParser) -> None:
    """``--working-space`` and ``--cat``: the space every file is converted into on
    reading (see :func:`load_rgb`)."""
    p.add_argument(
        "--working-space",
        default="sRGB",
        metavar="NAME",
        help="linear RGB space the file is converted into before tone mapping: a "
        "colour-science colourspace name ('sRGB' (default), 'ACEScg', 'ITU-R BT.2020', "
        "'Display P3'...) or 'CIE XYZ'",
    )
    p.add_argument(
        "--cat",
        default="CAT02",
        metavar="NAME",
        help="chromatic adaptation between different white points (default CAT02; "
        "'Bradford', 'CAT16', 'Von Kries', 'XYZ Scaling'...)",
    )


def colour_settings(args: argparse.Namespace):
    """``(Space, cat)`` from ``--working-space``/``--cat`` (defaults when the command has
    no such options); unknown names → UsageError."""
    from .. import spaces

    try:
        space = spaces.space(getattr(args, "working_space", spaces.DEFAULT_SPACE))
        cat = spaces.check_cat(getattr(args, "cat", spaces.DEFAULT_CAT))
    except ValueError as e:
        flag, prefix = ("--cat", "cat: ") if "cat:" in str(e) else ("--working-space", "")
        text = str(e).removeprefix(prefix).removeprefix("working space: ")
        raise UsageError(f"{flag}: {text}") from None
    return space, cat


def add_set_argument(p: argparse.ArgumentParser, extra: str = "") -> None:
    """``--set PARAM=VALUE`` (repeatable): any parameter of the ``--method`` operator."""
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="PARAM=VALUE",
        help="set a parameter of the operator (repeatable; `hdrjax operators NAME` lists them"
        f" with their ranges){extra}",
    )


def add_parameter_shortcuts(p: argparse.ArgumentParser, options: tuple[str, ...]) -> None:
    """Named options ``--key``, ``--white``… for common parameters (shortcuts for ``--set``),
    their help and type from the registered operators' metadata (:mod:`._registry`: no JAX
    import)."""
    entries = operators()
    for dest in options:
        name = SHORTCUTS.get(dest, dest)
        found = [(op.name, info) for op in entries for info in op.parameters if info.name == name]
        _, first = found[0]
        positive = all(i.range is not None and i.range[0] >= 0 for _, i in found)
        unit = f" [{first.unit}]" if first.unit else ""
        p.add_argument(
            "--" + dest.replace("_", "-"),
            dest=dest,
            type=positive_float if positive else float,
            help=f"{first.help}{unit} (--set {name}=VALUE; {', '.join(op for op, _ in found)})",
        )


def add_input_output_method_arguments(p: argparse.ArgumentParser) -> None:
    """``INPUT``, ``-o/--output`` and ``--method`` (shared with ``hdrjax fit``)."""
    p.add_argument("input", help="HDR image: .exr, .hdr (Radiance RGBE) or .pfm")
    add_output_argument(p)
    p.add_argument(
        "--method",
        default="reinhard2002",
        help="operator name (see `hdrjax operators`; default reinhard2002)",
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


def add_encoding_arguments(
    p: argparse.ArgumentParser,
    peak_help: str = "cd/m² of the display's white for --display PQ (default 1000)",
) -> None:
    """``--display``, ``--peak``, ``--gamut``, ``--transfer``, ``--gamma``, ``--bits``: how
    :func:`write_output` encodes (``peak_help``: what else the command uses ``--peak``
    for)."""
    p.add_argument(
        "--display",
        metavar="NAME",
        help="display the .png/.jpg/.tif is encoded and tagged for: 'sRGB' (default), "
        "'Display P3', 'ITU-R BT.2020', 'ITU-R BT.2100 PQ', 'ITU-R BT.2100 HLG' (short: P3, "
        "BT2020, PQ, HLG; PQ/HLG are 16-bit)",
    )
    p.add_argument(
        "--peak",
        type=positive_float,
        help=peak_help,
    )
    p.add_argument(
        "--gamut",
        choices=("clip", "luminance", "compress"),
        help="colours outside the display's gamut: 'luminance' (default with --display: "
        "towards the grey of the same luminance), 'compress' (ACES reference gamut "
        "compression), 'clip' (each channel)",
    )
    p.add_argument(
        "--transfer",
        choices=("srgb", "gamma", "linear"),
        default="srgb",
        help="display encoding for .png/.jpg/.tif without --display (default srgb)",
    )
    p.add_argument("--gamma", type=positive_float, default=2.2, help="for --transfer gamma")
    p.add_argument(
        "--bits", type=int, choices=(8, 16), help="PNG/TIFF bit depth (8; 16 for PQ/HLG)"
    )


def output_display(args: argparse.Namespace):
    """The :class:`hdrjax.display.Display` of ``--display`` (or of ``--transfer``);
    unknown names → UsageError."""
    from ..display import get_display

    name = getattr(args, "display", None)
    if name is not None and args.transfer != "srgb":
        raise UsageError("--transfer does not apply with --display (the display sets the curve)")
    try:
        return get_display(name or {"srgb": "sRGB"}.get(args.transfer, args.transfer), args.gamma)
    except ValueError as e:
        raise UsageError(f"--display: {str(e).removeprefix('display: ')}") from None


def output_bits(args: argparse.Namespace) -> int:
    """``--bits``, by default 16 for HDR displays (PQ, HLG) and 8 otherwise."""
    if args.bits is not None:
        return args.bits
    return 16 if output_display(args).hdr else 8


def check_output(args: argparse.Namespace) -> str:
    """Validate ``args.output`` against the encoding options; returns its extension."""
    ext = output_ext(args, LDR_EXT + HDR_EXT)
    disp, bits = output_display(args), output_bits(args)
    if bits == 16 and ext in (".jpg", ".jpeg"):
        what = f"--display {disp.name}" if disp.hdr and args.bits is None else "--bits 16"
        raise UsageError(f"{what} needs .png or .tif output (JPEG is 8-bit)")
    if disp.hdr and bits == 8:
        raise UsageError(f"--display {disp.name} needs 16 bits: leave out --bits 8")
    if getattr(args, "peak", None) is not None and disp.transfer != "pq":
        raise UsageError(f"--peak applies to --display PQ, not {disp.name}")
    refuse_overwriting_inputs([args.output], [args.input, args.table])
    return ext


def tonemap_and_encode(args: argparse.Namespace, op, rgb, matrix=None):
    """``(measured operator, encode_output's array)`` for the file's pixels ``rgb`` (NumPy,
    converted by ``matrix`` into the working space). A pointwise operator runs on
    fixed-shape chunks of the pixels (:func:`hdrjax.tile.tonemap_chunked`): the same
    compiled programs for every image size; a local one on the whole image."""
    import numpy as np

    from ..tile import chunkable, tonemap_chunked

    converted = matrix is not None
    if chunkable(op, rgb.shape):
        finish = display_encoding(args, converted)
        return tonemap_chunked(op, np.asarray(rgb), matrix, finish=finish)
    measured = eqx_jit_measure(op, rgb, matrix)
    return measured, encode_output(args, apply_in_space(measured, rgb, matrix), converted)


def encode_output(args: argparse.Namespace, display, converted: bool = False):
    """Display-referred linear RGB in the working space → the array written to
    ``args.output`` (NumPy): encoded for the display for .png/.jpg/.tif, linear float for
    .exr/.hdr/.pfm. ``converted`` says the file was converted into the working space:
    colours outside an sRGB display's gamut then come from the file's wider primaries and
    the gamut method maps them; pixels that were sRGB to begin with are clipped and
    encoded as they are."""
    import jax
    import numpy as np

    return np.asarray(jax.block_until_ready(encode_display(args, display, converted)))


def encode_display(args: argparse.Namespace, display, converted: bool = False):
    """:func:`encode_output` without the copy to NumPy (a device array)."""
    return display_encoding(args, converted)(display)


@dataclasses.dataclass(frozen=True)
class DisplayEncoding:
    """How ``tonemap`` encodes the operator's output for its file (:func:`encode_display`),
    as a value: equal settings compare and hash equal, so the compiled chunk program that
    ends with it is reused (:func:`hdrjax.tile.tonemap_chunked`)."""

    ldr: bool  # encoded for a display (.png/.jpg/.tif), else linear float
    display: Any  # hdrjax.display.Display
    space: Any  # hdrjax.spaces.Space: the working space
    gamut: str | None
    peak: float | None
    converted: bool  # the file was converted into the working space

    def __call__(self, linear):
        from ..display import encode

        if not self.ldr:
            return linear
        disp, space = self.display, self.space
        if disp.name == "sRGB" and space.is_rec709 and self.gamut is None and not self.converted:
            return encode(linear, "srgb")  # the common case: no conversion, per-channel clip
        kw = {} if self.peak is None else {"peak": self.peak}
        return encode(linear, display=disp, space=space, gamut=self.gamut, **kw)


def display_encoding(args: argparse.Namespace, converted: bool = False) -> DisplayEncoding:
    """The :class:`DisplayEncoding` of the command's arguments."""
    ldr = output_ext(args) in LDR_EXT
    return DisplayEncoding(
        ldr=ldr,
        display=output_display(args) if ldr else None,
        space=colour_settings(args)[0] if ldr else None,
        gamut=getattr(args, "gamut", None),
        peak=getattr(args, "peak", None),
        converted=converted,
    )


def write_output(args: argparse.Namespace, encoded) -> None:
    """Write :func:`encode_output`'s array to ``args.output`` (atomic), tagged with its
    display (or, for .exr, the working space's chromaticities); errors → DataError."""
    import numpy as np

    from .. import io as hio
    from ..display import quantize
    from ..layers import LayeredImage

    try:
        with output_file(args) as path:
            if output_ext(args) in LDR_EXT:
                bits = output_bits(args)
                disp = output_display(args)
                hio.write_display(path, quantize(encoded, bits), bits=bits, display=disp)
            else:
                space, _ = colour_settings(args)
                c = None if space.is_rec709 else space.chromaticities
                hio.write(path, LayeredImage(encoded.astype(np.float32), chromaticities=c))
    except (ValueError, OSError) as e:
        raise DataError(f"{args.output}: cannot write: {e}") from None


def parse_set(cls, texts: list[str]) -> dict:
    """``--set PARAM=VALUE`` texts as the operator's parameters: numbers (comma-separated
    for a vector), integers, or names where the parameter has choices. An unknown
    parameter, a malformed value or one outside the parameter's range → UsageError naming
    the parameter and what it takes."""
    infos = {i.name: i for i in _parameter_info(cls)}
    settable = [n for n, i in infos.items() if _settable(i)]
    out = {}
    for text in texts:
        name, sep, value = text.partition("=")
        name, value = name.strip(), value.strip()
        if not sep or not name or not value:
            raise UsageError(f"--set {text!r}: expected PARAM=VALUE")
        info = infos.get(name) or infos.get(name.replace("-", "_"))
        if info is None:
            raise UsageError(
                f"--set {text!r}: {cls.name} has no parameter {name!r};"
                f" valid: {', '.join(settable)}"
            )
        if not _settable(info):
            raise UsageError(f"--set {text!r}: {info.name} is not set with --set ({info.help})")
        if info.name in out:
            raise UsageError(f"--set {text!r}: {info.name} is given twice")
        out[info.name] = _parse_value(cls, info, text, value)
    return out


def _parameter_info(cls):
    from ..operators import parameter_info

    return parameter_info(cls)


def _settable(info) -> bool:
    """Scalars, fixed-length vectors and named settings (not the weights, which come from
    the file, nor a table's knots)."""
    return info.shape is not None and not isinstance(info.default, tuple)


def _parse_value(cls, info, text: str, value: str):
    kind = "one of" if info.choices else "a number in"
    unit = f", {info.unit}" if info.unit else ""
    expected = f"{info.name}: expected {kind} {info.range_text() or 'any value'} ({cls.name}{unit})"
    if info.choices or value in info.names:  # names: words a number parameter takes
        v = value
    else:
        parts = value.split(",")
        n = 1 if info.shape == () else int(info.shape[0])
        if len(parts) != n:
            raise UsageError(f"--set {text!r}: {expected}, {n} comma-separated, got {value!r}")
        integer = isinstance(info.default, int) and not isinstance(info.default, bool)
        try:
            nums = [int(x) if integer else float(x) for x in parts]
        except ValueError:
            raise UsageError(f"--set {text!r}: {expected}, got {value!r}") from None
        v = nums[0] if info.shape == () else tuple(nums)
    if not info.contains(v):
        raise UsageError(f"--set {text!r}: {expected}, got {value!r}")
    return v


def build_operator(args: argparse.Namespace):
    """The operator the arguments describe (``--method``, ``--set``, the named shortcuts,
    ``--table``); unknown names, misplaced options and values outside a parameter's range
    → UsageError."""
    from ..operators import Tabulated, get_operator

    try:
        cls = get_operator(args.method)
    except ValueError as e:
        raise UsageError(str(e)) from None
    infos = {i.name: i for i in _parameter_info(cls)}
    params = {}
    for dest in SHORTCUT_OPTIONS:
        value = getattr(args, dest, None)
        if value is None:
            continue
        name = SHORTCUTS.get(dest, dest)
        flag = "--" + dest.replace("_", "-")
        info = infos.get(name)
        if info is None:
            raise UsageError(f"{flag} does not apply to --method {cls.name}")
        if not info.contains(value):
            unit = f", {info.unit}" if info.unit else ""
            raise UsageError(
                f"{flag}: {name}: expected a number in {info.range_text()} ({cls.name}{unit}),"
                f" got {value:g}"
            )
        params[name] = value
    for name, value in parse_set(cls, getattr(args, "set", None) or []).items():
        if name in params:
            raise UsageError(f"--set {name}=...: {name} is also given by its named option")
        params[name] = value
    if cls.name == "tabulated":
        if not args.table:
            raise UsageError("--method tabulated needs --table FILE")
        try:
            return Tabulated.from_file(args.table, **params)
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


def load_rgb(path: str, scale: float = 1.0, args: argparse.Namespace | None = None):
    """Read an HDR file as float32 linear RGB in the working space (``args``'s
    ``--working-space``/``--cat``, sRGB and CAT02 otherwise); errors → DataError."""
    import numpy as np

    img, native, m = load_native(path, scale, args)
    if m is None:
        return img, native
    return img, np.ascontiguousarray(native @ m.T.astype(np.float32), dtype=np.float32)


def load_native(path: str, scale: float = 1.0, args: argparse.Namespace | None = None):
    """``(image, native RGB, matrix)``: the file's own RGB and the matrix (``scale``
    included) taking it to the working space, ``None`` when that is the identity."""
    import numpy as np

    from .. import spaces

    space, cat = colour_settings(args)
    img = read_image(path)
    try:
        native = img.native_rgb()
        m = img.conversion(space, cat=cat) * scale
    except ValueError as e:
        raise DataError(str(e) if os.path.basename(path) in str(e) else f"{path}: {e}") from None
    if not spaces.is_identity(m):
        return img, native, m
    return img, (native * np.float32(scale) if scale != 1.0 else native), None


def exposure_scale(args: argparse.Namespace) -> float:
    """``--scale`` × 2^``--exposure``; a factor that is not a positive finite float32 (an
    exposure of ±200 stops, say) is a usage error naming ``--exposure``."""
    try:
        factor = args.scale * 2.0**args.exposure
    except OverflowError:
        factor = math.inf
    if not (math.isfinite(args.exposure) and 1e-38 < factor < 3e38):
        raise UsageError(
            f"--exposure: expected stops that keep the image in float32 range, got {args.exposure}"
        )
    return factor


def run(args: argparse.Namespace) -> int:
    check_output(args)
    op = build_operator(args)
    t0 = time.perf_counter()
    img, rgb, m = load_native(args.input, exposure_scale(args), args)
    t_read = time.perf_counter() - t0

    import numpy as np

    op = with_file_weights(op, img, args)
    t1 = time.perf_counter()
    measured, out = tonemap_and_encode(args, op, rgb, m)
    t_map = time.perf_counter() - t1
    n_bad = int(np.count_nonzero(~np.all(np.isfinite(rgb), axis=-1)))
    t2 = time.perf_counter()
    write_output(args, out)
    t_write = time.perf_counter() - t2
    h, w = rgb.shape[:2]
    print(f"input: {args.input} ({w}x{h})")
    if m is not None:
        print(f"  {describe_conversion(img, args)}")
    if n_bad:
        print(f"  {n_bad} pixel(s) with NaN/Inf values excluded from statistics")
    print(describe(measured, op.unset(), op.parameters()))
    print(f"wrote: {args.output}")
    if args.verbose:
        print(
            f"time: read {t_read:.3f}s, tone map {t_map:.3f}s (incl. compile), write {t_write:.3f}s"
        )
    return 0


def describe_conversion(img, args: argparse.Namespace | None = None) -> str:
    """One line: the file's primaries and white, and the working space they go to."""
    space, cat = colour_settings(args)
    src = img.space
    if img.kind == "spectral":
        wl = img.wavelengths
        return (
            f"spectral: {len(wl)} bands, {wl[0]:g}-{wl[-1]:g} nm, integrated to CIE XYZ "
            f"(CIE 1931 2° observer), converted to {space.name}"
        )
    if src == space:
        return f"primaries: {src.name}, working space {space.name} (not converted)"
    c = ", ".join(f"{v:.4f}" for v in src.chromaticities[:6])
    white = ", ".join(f"{v:.4f}" for v in src.white)
    how = "no adaptation (XYZ)" if src.is_xyz or space.is_xyz else cat
    if not (src.is_xyz or space.is_xyz) and src.white == space.white:
        how = "same white"
    return f"primaries ({c}), white ({white}): converted to {space.name} ({how})"


def with_file_weights(op, img, args: argparse.Namespace | None = None):
    """The operator for the file's pixels in the working space: luminance weights that
    give the file's own luminance (operators that have a setting) and the working space's
    primaries (operators whose colour model declares ``chromaticities``)."""
    space, cat = colour_settings(args)
    weights = img.luminance_weights_in(space, cat=cat)
    return op.for_primaries(weights, None if space.is_rec709 else space.chromaticities)


def eqx_jit_measure(op, rgb, matrix=None):
    """``op.measure(rgb)`` compiled (statistics of large images are slow eagerly), of
    ``rgb`` converted by ``matrix`` (:func:`load_native`): see
    :func:`hdrjax.operators.measure_in_space`."""
    from ..operators import measure_in_space

    return measure_in_space(op, rgb, matrix)


def apply_in_space(op, rgb, matrix=None):
    """``op(rgb)``, ``rgb`` converted by ``matrix`` in the same compiled program
    (:func:`hdrjax.operators.apply_in_space`)."""
    from ..operators import apply_in_space as apply

    return apply(op, rgb, matrix)
