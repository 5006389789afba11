"""``hdrjax merge IMG… -o OUT.exr`` and ``hdrjax fuse IMG… -o OUT.png``: HDR images from
exposure brackets (merged linear radiance), and exposure fusion straight to a display
image."""

import argparse
import math
import os

from ._common import (
    HDR_EXT,
    LDR_EXT,
    DataError,
    UsageError,
    output_ext,
    positive_float,
    positive_int,
    refuse_overwriting_inputs,
)

METHODS = ("debevec", "robertson", "mitsunaga1999")
"""Responses recovered from the bracket itself (:func:`hdrjax.merge.recover_response`)."""
WEIGHTS = ("hat", "triangle", "gaussian", "granados2010")
"""``--weights`` (:data:`hdrjax.merge.WEIGHTS`, listed here so that the parser imports no
JAX)."""


def _non_negative(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (v >= 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"expected a finite number ≥ 0, got {text!r}")
    return v


def _add_bracket_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "images",
        nargs="+",
        metavar="IMG",
        help="the exposures: 8/16-bit PNG, TIFF, JPEG or camera RAW (.dng .cr2 .cr3 .nef "
        ".arw .raf .orf .rw2 .pef .srw, decoded linear by LibRaw), in any order",
    )
    p.add_argument(
        "--exposure-times",
        nargs="+",
        type=positive_float,
        metavar="T",
        help="exposure time of each image in seconds, in the order of the images "
        "(replaces EXIF; needed for files without it)",
    )
    p.add_argument(
        "--align",
        action="store_true",
        help="align a hand-held bracket first (translations by median threshold bitmaps, "
        "Ward 2003)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "merge",
        help="merge an exposure bracket (PNG/TIFF/JPEG/RAW) into an HDR image (.exr/.hdr/.pfm)",
        description="Merge an exposure bracket into linear radiance: recover the camera "
        "response (Debevec & Malik 1997, Robertson et al. 2003, Mitsunaga & Nayar 1999) or "
        "load one, merge with per-code weights, optionally align (Ward 2003), remove ghosts "
        "(Grosch 2006) and calibrate to cd/m² from the f-number and ISO (ISO 12232).",
    )
    _add_bracket_arguments(p)
    p.add_argument(
        "-o", "--output", required=True, help="output: .exr, .hdr (Radiance RGBE) or .pfm"
    )
    p.add_argument(
        "--response",
        metavar="METHOD|FILE",
        help="camera response: recovered from the bracket ('debevec', 'robertson', "
        "'mitsunaga1999'), 'linear' (RAW or linear data), or a file saved by --save-response "
        "or pfshdrcalibrate (default: debevec; linear when every image is camera RAW)",
    )
    p.add_argument(
        "--save-response",
        metavar="FILE",
        help="write the response used (.json, else pfshdrcalibrate's text format)",
    )
    p.add_argument(
        "--samples",
        type=positive_int,
        metavar="N",
        help="pixels sampled for the response recovery (default: the method's)",
    )
    p.add_argument(
        "--weights",
        choices=WEIGHTS,
        default="hat",
        help="per-code weights of the merge: hat (Reinhard et al. 2010, default), triangle "
        "(Debevec & Malik 1997), gaussian (Robertson et al. 2003), granados2010 (noise-based, "
        "for RAW; Granados et al. 2010)",
    )
    p.add_argument(
        "--deghost",
        action="store_true",
        help="leave out pixels that contradict the middle exposure (moving objects; Grosch 2006)",
    )
    p.add_argument(
        "--calibrate",
        action="store_true",
        help="scale to cd/m² from the f-number and ISO of the exposures (EXIF, or "
        "--f-number/--iso), ISO 12232 saturation-based speed; the file then declares "
        "luminance in cd/m² (falsecolor and vision need no --scale)",
    )
    p.add_argument(
        "--f-number", type=positive_float, help="f-number for --calibrate (replaces EXIF)"
    )
    p.add_argument("--iso", type=positive_float, help="ISO speed for --calibrate (replaces EXIF)")
    p.set_defaults(func=run_merge)

    f = subparsers.add_parser(
        "fuse",
        help="fuse an exposure bracket straight to a display image (.png/.jpg/.tif; "
        "Mertens et al. 2007)",
        description="Exposure fusion (Mertens, Kautz & Van Reeth 2007): a display image "
        "blended from the well-exposed, contrasted, saturated parts of each exposure, in a "
        "Laplacian pyramid; no response, no HDR intermediate. Camera RAW members are "
        "sRGB-encoded first.",
    )
    _add_bracket_arguments(f)
    f.add_argument("-o", "--output", required=True, help="output: .png, .jpg or .tif")
    f.add_argument(
        "--contrast", type=_non_negative, default=1.0, help="weight exponent ω_C (default 1)"
    )
    f.add_argument(
        "--saturation", type=_non_negative, default=1.0, help="weight exponent ω_S (default 1)"
    )
    f.add_argument(
        "--exposedness", type=_non_negative, default=1.0, help="weight exponent ω_E (default 1)"
    )
    f.add_argument(
        "--sigma",
        type=positive_float,
        default=0.2,
        help="width of the well-exposedness Gaussian around 0.5 (default 0.2)",
    )
    f.add_argument("--bits", type=int, choices=(8, 16), default=8, help="PNG/TIFF bit depth")
    f.set_defaults(func=run_fuse)


class _Steps:
    """A progress bar over a command's steps (tqdm on standard error, only on a terminal)."""

    def __init__(self, total: int, quiet: bool):
        import sys

        from tqdm.auto import tqdm

        self.bar = tqdm(
            total=total,
            unit="step",
            leave=False,
            dynamic_ncols=True,
            disable=quiet or not sys.stderr.isatty(),
        )

    def __call__(self, name: str) -> None:
        self.bar.set_description(name)

    def done(self) -> None:
        self.bar.update(1)

    def close(self) -> None:
        self.bar.close()


def _check_outputs(args: argparse.Namespace, extra_inputs=(), extra_outputs=()) -> str:
    refuse_overwriting_inputs(
        [args.output, *extra_outputs], [*args.images, *(p for p in extra_inputs if p)]
    )
    if args.output == "-":
        raise UsageError(f"-o -: {args.command} writes a file, not standard output")
    allowed = HDR_EXT if args.command == "merge" else LDR_EXT
    ext = output_ext(args, allowed)
    if args.exposure_times is not None and len(args.exposure_times) != len(args.images):
        raise UsageError(
            f"--exposure-times: expected one time per image ({len(args.images)}), "
            f"got {len(args.exposure_times)}"
        )
    return ext


def _read(args: argparse.Namespace, need_times: bool = True):
    """The bracket (``hdrjax.merge.read_bracket``); errors → DataError naming the file."""
    from .. import merge as hm

    try:
        bracket = hm.read_bracket(
            args.images, args.exposure_times, need_times=need_times, progress=not args.quiet
        )
    except FileNotFoundError as e:
        raise DataError(f"{e.filename}: no such file") from None
    except ValueError as e:
        text = " ".join(str(e).split())
        if "no exposure time in EXIF" in text:
            text = text.replace("(exposure_times, one per file)", "(--exposure-times)")
        raise DataError(text) from None
    if len(bracket.paths) < 2:
        raise UsageError(f"a bracket needs at least 2 images, got 1 ({bracket.paths[0]})")
    return bracket


def _seconds(t: float) -> str:
    if t < 1 and abs(1 / t - round(1 / t)) < 1e-6 * (1 / t):
        return f"1/{round(1 / t)} s"
    return f"{t:g} s"


def _describe(bracket) -> list[str]:
    n, h, w = bracket.images.shape[:3]
    bits = 8 * bracket.images.dtype.itemsize
    lines = [f"bracket: {n} exposures, {w}x{h}, {bits}-bit"]
    for j, p in enumerate(bracket.paths):
        t = bracket.exposure_times[j]
        parts = [f"  {os.path.basename(p)}", _seconds(t) if math.isfinite(t) else "time ?"]
        if bracket.f_numbers is not None and math.isfinite(bracket.f_numbers[j]):
            parts.append(f"f/{bracket.f_numbers[j]:g}")
        if bracket.isos is not None and math.isfinite(bracket.isos[j]):
            parts.append(f"ISO {bracket.isos[j]:g}")
        lines.append("  ".join(parts))
    return lines


def _align(codes, steps: _Steps) -> tuple:
    from .. import merge as hm

    steps("aligning")
    shifts = hm.align_mtb(codes)
    codes = hm.apply_shifts(codes, shifts)
    steps.done()
    text = ", ".join(f"({dx:+d}, {dy:+d})" for dx, dy in shifts.tolist())
    return codes, f"aligned (Ward 2003 MTB): shifts (dx, dy) {text}", int(abs(shifts).max())


def _response_choice(text: str | None, all_raw: bool) -> tuple[str | None, str | None]:
    """``(method, file)`` of ``--response``: a method name or ``"linear"``, else a file."""
    if text is None:
        return ("linear" if all_raw else "debevec"), None
    key = text.lower().replace("-", "").replace("_", "").replace(" ", "")
    if key in (*METHODS, "linear"):
        return key, None
    if not os.path.exists(text):
        raise UsageError(
            f"--response {text}: neither a method ({', '.join(METHODS)}, linear) nor an "
            "existing file"
        )
    return None, text


def _linear_response(levels: int):
    import numpy as np

    z = np.arange(levels, dtype=np.float64) / (levels - 1)
    with np.errstate(divide="ignore"):
        g = np.log(z)
    return np.repeat(g[:, None], 3, axis=1)


def _calibration(args: argparse.Namespace, bracket) -> tuple[float, float]:
    """One f-number and ISO for the bracket: ``--f-number``/``--iso``, else EXIF (every
    member must have them, and the same ones)."""
    out = []
    for flag, given, values, what in (
        ("--f-number", args.f_number, bracket.f_numbers, "f-number"),
        ("--iso", args.iso, bracket.isos, "ISO"),
    ):
        if given is not None:
            out.append(float(given))
            continue
        for j, p in enumerate(bracket.paths):
            if values is None or not math.isfinite(values[j]):
                raise DataError(f"{p}: no {what} in EXIF; --calibrate needs it (or give {flag})")
        if len(set(values.tolist())) > 1:
            first, j = bracket.paths[0], int((values != values[0]).argmax())
            raise DataError(
                f"{bracket.paths[j]}: {what} {values[j]:g}, but {first} has {values[0]:g}; "
                f"--calibrate needs one {what} for the bracket (or give {flag})"
            )
        out.append(float(values[0]))
    return out[0], out[1]


def run_merge(args: argparse.Namespace) -> int:
    from ..merge import RAW_EXTENSIONS

    all_raw = all(os.path.splitext(p)[1].lower() in RAW_EXTENSIONS for p in args.images)
    method, response_file = _response_choice(args.response, all_raw)
    ext = _check_outputs(args, [response_file], [args.save_response])
    if args.samples is not None and method not in METHODS:
        raise UsageError(
            f"--samples applies to a recovered response ({', '.join(METHODS)}), "
            f"not --response {args.response}"
        )
    if (args.f_number is not None or args.iso is not None) and not args.calibrate:
        raise UsageError("--f-number and --iso apply with --calibrate")

    import numpy as np

    from .. import io as hio, merge as hm
    from ..layers import LayeredImage

    steps = _Steps(3 + args.align + args.deghost + bool(args.save_response), args.quiet)
    try:
        steps("reading")
        bracket = _read(args)
        steps.done()
        lines = _describe(bracket)
        calibration = _calibration(args, bracket) if args.calibrate else None
        codes, times = bracket.images, bracket.exposure_times
        levels = 256 if codes.dtype == np.uint8 else 65536
        border = 0
        if args.align:
            codes, text, border = _align(codes, steps)
            lines.append(text)
        steps("response")
        if response_file is not None:
            try:
                g = np.asarray(hm.load_response(response_file))
            except (ValueError, OSError) as e:
                text = " ".join(str(e).split())
                named = os.path.basename(response_file) in text
                raise DataError(text if named else f"{response_file}: {text}") from None
            if g.shape[0] != levels:
                raise DataError(
                    f"{response_file}: a response for {g.shape[0]} code values; the bracket "
                    f"is {8 * codes.dtype.itemsize}-bit ({levels} code values)"
                )
            lines.append(f"response: {response_file}")
        elif method == "linear":
            g = _linear_response(levels)
            lines.append("response: linear (g(z) = ln(z / z_max))")
        else:
            # the border the alignment uncovered repeats edge pixels, which are not what
            # each exposure saw: the response is recovered from the inside
            b = border if 0 < 2 * border < min(codes.shape[1:3]) else 0
            inside = codes[:, b : codes.shape[1] - b, b : codes.shape[2] - b]
            g = np.asarray(hm.recover_response(inside, times, method=method, samples=args.samples))
            lines.append(f"response: {method} (recovered from the bracket)")
        steps.done()
        if args.save_response:
            steps("saving the response")
            try:
                hm.save_response(args.save_response, g)
            except (ValueError, OSError) as e:
                raise DataError(f"{args.save_response}: cannot write: {e}") from None
            steps.done()
            lines.append(f"wrote: {args.save_response} (response)")
        mask = None
        if args.deghost:
            steps("ghosts")
            mask = hm.ghost_mask(codes, times, g)
            steps.done()
            left = 1.0 - float(np.mean(np.asarray(mask)))
            lines.append(f"deghosted (Grosch 2006): {100 * left:.2f} % of the pixels left out")
        steps("merging")
        rgb = hm.merge(codes, times, g, weights=args.weights, mask=mask)
        lines.append(f"weights: {args.weights}")
        quantity = "relative"
        if calibration is not None:
            f_number, iso = calibration
            scale = float(hm.absolute_scale(f_number, iso))
            rgb = hm.calibrate(rgb, f_number=f_number, iso=iso)
            quantity = "luminance"
            lines.append(
                f"calibrated (ISO 12232): f/{f_number:g}, ISO {iso:g}: {scale:.6g} cd/m² per "
                "unit of merged radiance"
            )
            if ext == ".pfm":
                lines.append("note: PFM stores no unit; write .exr or .hdr to keep cd/m²")
        image = np.asarray(rgb, dtype=np.float32)
        steps.done()
        try:
            # calibrated: the pixels are cd/m², so OpenEXR's whiteLuminance (cd/m² of RGB
            # (1, 1, 1)) is 1, which tools that know only the standard attribute read
            white = 1.0 if quantity == "luminance" else None
            hio.write(args.output, LayeredImage(image, quantity=quantity, white_luminance=white))
        except (ValueError, OSError) as e:
            raise DataError(f"{args.output}: cannot write: {e}") from None
    finally:
        steps.close()
    for line in lines:
        print(line)
    unit = "cd/m²" if quantity == "luminance" else "relative"
    print(f"wrote: {args.output} ({image.shape[1]}x{image.shape[0]}, {unit})")
    return 0


def run_fuse(args: argparse.Namespace) -> int:
    ext = _check_outputs(args)
    if args.bits == 16 and ext in (".jpg", ".jpeg"):
        raise UsageError("--bits 16 needs .png or .tif output (JPEG is 8-bit)")

    import numpy as np

    from .. import io as hio, merge as hm
    from ..display import encode, quantize

    steps = _Steps(3 + args.align, args.quiet)
    try:
        steps("reading")
        bracket = _read(args, need_times=False)
        steps.done()
        lines = _describe(bracket)
        codes = bracket.images
        if args.align:
            codes, text, _ = _align(codes, steps)
            lines.append(text)
        steps("fusing")
        raw = [os.path.splitext(p)[1].lower() in hm.RAW_EXTENSIONS for p in bracket.paths]
        if any(raw):  # linear members: display-encode them as the others are
            top = np.float32(np.iinfo(codes.dtype).max)
            x = codes.astype(np.float32) / top
            images = np.stack(
                [np.asarray(encode(m, "srgb")) if r else m for m, r in zip(x, raw, strict=True)]
            )
        else:
            images = codes
        fused = hm.fuse(
            images,
            contrast=args.contrast,
            saturation=args.saturation,
            exposedness=args.exposedness,
            sigma=args.sigma,
        )
        out = quantize(np.asarray(fused), args.bits)
        steps.done()
        steps("writing")
        try:
            hio.write_display(args.output, out, bits=args.bits)
        except (ValueError, OSError) as e:
            raise DataError(f"{args.output}: cannot write: {e}") from None
        steps.done()
    finally:
        steps.close()
    for line in lines:
        print(line)
    print(
        f"fused (Mertens et al. 2007): contrast {args.contrast:g}, saturation "
        f"{args.saturation:g}, exposedness {args.exposedness:g}, sigma {args.sigma:g}"
    )
    print(f"wrote: {args.output} ({out.shape[1]}x{out.shape[0]}, {args.bits}-bit)")
    return 0
