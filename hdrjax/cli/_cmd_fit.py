"""``hdrjax fit INPUT --target mean=0.4 -o OUTPUT``: fit operator parameters to targets."""

import argparse
import os
import re

from ._cmd_tonemap import (
    add_colour_arguments,
    add_encoding_arguments,
    add_input_output_method_arguments,
    add_set_argument,
    add_table_and_scale_arguments,
    build_operator,
    check_output,
    colour_settings,
    describe,
    encode_output,
    eqx_jit_measure,
    load_rgb,
    with_file_weights,
    write_output,
)
from ._common import (
    HDR_EXT,
    LDR_EXT,
    CLIError,
    DataError,
    UsageError,
    refuse_overwriting_inputs,
)

EXIT_NOT_CONVERGED = 3
"""Exit status when the fit did not converge (ran out of steps, or ended non-finite)."""

TARGET_FORMS = (
    "mean=V (mean display luminance), pNN=V (display-luminance percentile NN, e.g. p1=0.02,"
    " p99=0.95), clipped=F (fraction of pixels at display white), reference=FILE (a display"
    " image of the input's size: 8-bit .png/.jpg/.tif decoded with --transfer, or linear"
    " .exr/.hdr/.pfm); and quality metrics to maximise: tmqi, naturalness, pu-ssim=FILE"
)

EPILOG = f"""targets (repeat --target; all are fitted together, as a sum of squared residuals):
  mean=V          mean display luminance V (display units, 0..1)
  pNN=V           display-luminance percentile NN (0..100) equal to V, e.g. p1=0.02, p99=0.95
  clipped=F       fraction F of pixels at display white (soft count)
  reference=FILE  agreement with a display image of the input's size (RMS log error):
                  8-bit .png/.jpg/.tif decoded with --transfer, or linear .exr/.hdr/.pfm

quality metrics to maximise (their residual is 1 - metric; they combine with the above):
  tmqi            TMQI Q of the rendition against the input (Yeganeh & Wang 2013), the
                  rendition encoded as written (--transfer, --gamma); prints Q, S and N
  naturalness     TMQI's statistical naturalness N of the rendition alone (combine it with
                  a fidelity target: alone it ignores the scene)
  pu-ssim=FILE    PU21 SSIM (Mantiuk & Azimi 2021) against a reference rendition FILE (as
                  for reference=), both shown on a display of white --peak cd/m² (100)
                  and black 0.1 cd/m²

exit status:
  0  the fit converged; the image was written
  1  bad or unreadable data (input, reference), or the output could not be written
  2  usage error (unknown option, operator or parameter; malformed --target)
  {EXIT_NOT_CONVERGED}  the fit did not converge: the status is printed and nothing is written,
     unless --force (the image with the last parameters is written, the status is still
     {EXIT_NOT_CONVERGED}); with --throw the failure is an error and nothing is written

The fit works on the image box-filtered to --max-size pixels on its long side (default 64;
0 = full resolution); the written image is the full-resolution input tone-mapped with the
fitted parameters, and its statistics are printed too.
"""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "fit",
        help="fit operator parameters so the tone-mapped image meets target statistics",
        description="Fit an operator's parameters (Levenberg-Marquardt, hdrjax.fit) so the "
        "display image meets the targets, print the fitted parameters, loss, steps and "
        "status, and write the tone-mapped image.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_input_output_method_arguments(p)
    p.add_argument(
        "--target",
        action="append",
        required=True,
        metavar="STAT=VALUE",
        help="a target (repeatable): mean=V, pNN=V, clipped=F, reference=FILE, or a metric to"
        " maximise: tmqi, naturalness, pu-ssim=FILE",
    )
    p.add_argument(
        "--param",
        action="append",
        metavar="NAME",
        help="a parameter to fit (repeatable; default: the operator's, which `hdrjax "
        "operators NAME` lists, e.g. key and L_white for reinhard2002)",
    )
    add_set_argument(p, ": the start value of a fitted one, or a fixed value")
    p.add_argument("--max-steps", type=int, default=100, help="solver step limit (100)")
    p.add_argument(
        "--max-size",
        type=int,
        default=64,
        help="fit on the image box-filtered to this long side (64; 0 = full resolution)",
    )
    p.add_argument(
        "--throw",
        action=argparse.BooleanOptionalAction,
        default=False,
        help="treat non-convergence as an error (message on stderr, nothing written)",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="write the image even when the fit did not converge (exit status stays "
        f"{EXIT_NOT_CONVERGED})",
    )
    add_table_and_scale_arguments(p)
    add_colour_arguments(p)
    add_encoding_arguments(
        p,
        peak_help="cd/m² of the display's white: for --display PQ (default 1000), and for "
        "--target pu-ssim=, both renditions shown at this white (default 100)",
    )
    p.set_defaults(func=run)


_PCT = re.compile(r"^p(\d+(?:\.\d*)?)$")


def _bad_target(text: str, why: str) -> UsageError:
    return UsageError(f"--target {text!r}: {why}; valid forms: {TARGET_FORMS}")


def _unit_value(text: str, value: str) -> float:
    try:
        v = float(value)
    except ValueError:
        raise _bad_target(text, f"{value!r} is not a number") from None
    if not 0.0 <= v <= 1.0:
        raise _bad_target(text, f"{v:g} is outside [0, 1] (display units)")
    return v


METRICS = ("tmqi", "naturalness")
"""The ``--target`` metrics given by name alone (maximised; no value)."""

REFERENCE_KINDS = ("reference", "pu-ssim")
"""The ``--target`` kinds whose value is a reference file."""


def parse_targets(texts: list[str]) -> list[tuple[str, str, str]]:
    """Split ``--target`` texts into ``(kind, key, value)``; bad syntax → UsageError naming
    the text and the valid forms. ``kind`` is ``mean``, ``percentile``, ``clipped``,
    ``reference``, ``tmqi``, ``naturalness`` or ``pu-ssim``."""
    out = []
    for text in texts:
        name, sep, value = text.partition("=")
        name = name.strip().lower()
        value = value.strip()
        if name in METRICS:
            if sep:
                raise _bad_target(text, f"{name} is maximised and takes no value")
            out.append((name, name, ""))
            continue
        if not sep or not value:
            raise _bad_target(text, "expected STAT=VALUE")
        if name == "mean":
            out.append(("mean", name, str(_unit_value(text, value))))
        elif name in ("clipped", "clip"):
            out.append(("clipped", "clipped", str(_unit_value(text, value))))
        elif name in ("reference", "ref"):
            out.append(("reference", "reference", value))
        elif name in ("pu-ssim", "pussim", "pu_ssim"):
            out.append(("pu-ssim", "pu-ssim", value))
        elif m := _PCT.match(name):
            q = float(m.group(1))
            if not 0.0 <= q <= 100.0:
                raise _bad_target(text, f"percentile {q:g} is outside [0, 100]")
            out.append(("percentile", f"p{q:g}", str(_unit_value(text, value))))
        else:
            raise _bad_target(text, f"unknown statistic {name!r}")
    return out


def read_reference(path: str, transfer: str, gamma: float):
    """A display image as linear RGB in [0, 1] (NumPy float32): 8-bit files are decoded
    with ``transfer``, float files are taken as display-referred linear."""
    import numpy as np

    ext = os.path.splitext(path)[1].lower()
    if not os.path.exists(path):
        raise DataError(f"{path}: no such file (reference)")
    if ext in HDR_EXT:
        return np.asarray(load_rgb(path)[1], np.float32)
    if ext not in LDR_EXT:
        raise UsageError(
            f"{path}: unsupported reference type {ext or '(none)'};"
            f" expected one of {', '.join(LDR_EXT + HDR_EXT)}"
        )
    from PIL import Image

    from ..display import srgb_decode

    try:
        with open(path, "rb") as f:
            head = f.read(26)
        if head[:8] == b"\x89PNG\r\n\x1a\n" and head[24] == 16:
            # Pillow reads 16-bit RGB PNGs as 8-bit: refuse rather than lose the precision
            raise DataError(
                f"{path}: 16-bit PNG references are not supported (they would be read at 8"
                " bits); pass the reference as .exr/.pfm (display-referred linear) or 8-bit"
            )
        with Image.open(path) as im:
            if im.mode not in ("RGB", "L"):
                im = im.convert("RGB")
            arr = np.asarray(im)
    except OSError as e:
        raise DataError(f"{path}: cannot read reference: {e}") from None
    if arr.ndim == 2:
        arr = np.repeat(arr[..., None], 3, axis=-1)
    x = arr.astype(np.float32) / 255.0
    if transfer == "srgb":
        return np.asarray(srgb_decode(x), np.float32)
    if transfer == "gamma":
        return np.power(x, np.float32(gamma))
    return x


def _reference_of_size(path: str, args, shape):
    """:func:`read_reference`, of the input's height and width (else DataError)."""
    ref = read_reference(path, args.transfer, args.gamma)
    if ref.shape[:2] != tuple(shape):
        raise DataError(
            f"{path}: reference is {ref.shape[1]}x{ref.shape[0]},"
            f" the input {shape[1]}x{shape[0]}; expected the same size"
        )
    return ref


def _tmqi_gamma(args) -> float | None:
    """TMQI reads the rendition as written: sRGB-encoded (``None``), ``x^(1/γ)``, or
    linear (γ = 1)."""
    return {"srgb": None, "gamma": float(args.gamma), "linear": 1.0}[args.transfer]


def build_target(parsed, args, shape, weights, max_size):
    """The :mod:`hdrjax.targets` target of the parsed ``--target`` list and, per part, the
    labels of its statistics (in order)."""
    import numpy as np

    from .. import targets as ht
    from ..fit import downscale

    parts, labels = [], []
    pct = [(k, float(v)) for kind, k, v in parsed if kind == "percentile"]
    for kind, _, value in parsed:
        if kind == "mean":
            parts.append(ht.MeanLuminance(float(value), weights=weights))
            labels.append((f"mean={float(value):g}", float(value)))
        elif kind == "clipped":
            parts.append(ht.ClippedFraction(float(value)))
            labels.append((f"clipped={float(value):g}", float(value)))
        elif kind == "reference":
            ref = _reference_of_size(value, args, shape)
            parts.append(ht.Reference(downscale(ref, max_size)))
            labels.append((f"reference={value} (RMS log error)", 0.0))
        elif kind == "pu-ssim":
            ref = _reference_of_size(value, args, shape)
            peak = args.peak or 100.0
            black = min(0.1, peak / 2)
            shown = black + (peak - black) * np.clip(downscale(ref, max_size), 0.0, 1.0)
            parts.append(ht.PUSSIM(shown, peak=peak, black=black))
            labels.append((f"pu-ssim={value} (PU21 SSIM, maximised)", 1.0))
        elif kind == "tmqi":
            parts.append(ht.TMQI(gamma=_tmqi_gamma(args)))
            labels.extend(
                (f"tmqi {part} (maximised)", 1.0)
                for part in ("Q", "S (structural fidelity)", "N (naturalness)")
            )
        elif kind == "naturalness":
            parts.append(ht.Naturalness(gamma=_tmqi_gamma(args)))
            labels.append(("naturalness (TMQI N, maximised)", 1.0))
    if pct:  # one Percentiles target: one sort per evaluation
        qs = [float(k[1:]) for k, _ in pct]
        parts.append(
            ht.Percentiles(np.asarray(qs), np.asarray([v for _, v in pct]), weights=weights)
        )
        labels.extend((f"{k}={v:g}", v) for k, v in pct)
    target = parts[0]
    for t in parts[1:]:
        target = target + t
    return target, labels


def run(args: argparse.Namespace) -> int:
    check_output(args)
    parsed = parse_targets(args.target)
    refuse_overwriting_inputs(
        [args.output], [v for kind, _, v in parsed if kind in REFERENCE_KINDS]
    )
    if args.max_steps < 1:
        raise UsageError(f"--max-steps: expected an integer >= 1, got {args.max_steps}")
    if args.max_size < 0:
        raise UsageError(f"--max-size: expected an integer >= 0, got {args.max_size}")
    op = build_operator(args)
    params = tuple(args.param) if args.param else op.default_fit_params
    if not params:
        from ..operators import parameter_info

        names = ", ".join(i.name for i in parameter_info(op) if not i.static)
        raise UsageError(
            f"--param: {op.name} has no parameters fitted by default; give --param NAME"
            f" (one of {names})"
            if names
            else f"--param: {op.name} has no parameters to fit"
        )
    img, rgb = load_rgb(args.input, args.scale, args)
    op = with_file_weights(op, img, args)
    max_size = args.max_size or None

    import jax.numpy as jnp
    import numpy as np
    import optimistix as optx

    from .. import fit as hfit, spaces

    space, cat = colour_settings(args)
    weights = img.luminance_weights_in(space, cat=cat)
    target, labels = build_target(parsed, args, rgb.shape[:2], weights, max_size)
    x = jnp.asarray(rgb)
    start = eqx_jit_measure(op, x)  # the automatic estimates: the fit's starting point
    try:
        res = hfit.fit(
            start, x, target, params=params, max_steps=args.max_steps, max_size=max_size,
            throw=args.throw,
        )  # fmt: skip
        ok = bool(res.success)
    except ValueError as e:
        raise UsageError(str(e)) from None
    except Exception as e:  # throw=True: equinox's runtime error
        if not args.throw:
            raise
        lines = [ln for ln in str(e).splitlines() if "EquinoxRuntimeError:" in ln]
        why = lines[0].split("EquinoxRuntimeError:", 1)[1].strip() if lines else type(e).__name__
        raise _NotConverged(f"the fit did not converge: {why}") from None
    h, w = rgb.shape[:2]
    small = hfit.downscale(x, max_size).shape
    print(f"input: {args.input} ({w}x{h}), fitted at {small[1]}x{small[0]}")
    print(f"operator: {res.operator.name}")
    print("fitted parameters:")
    before = start.parameters()
    for n in res.names:
        v = np.asarray(res.params[n])
        text = f"{float(v):.6g}" if v.ndim == 0 else np.array2string(v, precision=5)
        s = before.get(n)
        was = f"{s:.6g}" if isinstance(s, float) else str(s)
        print(f"  {n}: {text}  (start {was})")
    rest = describe(res.operator).splitlines()[1:]
    fixed = [ln for ln in rest if ln.split(":")[0].strip() not in res.names]
    if fixed:
        print("other parameters:")
        print("\n".join(fixed))
    stats = np.asarray(res.statistics)
    print("targets (fitted image):")
    for (label, _), s in zip(labels, stats, strict=True):
        print(f"  {label}: {float(s):.6g}")
    print(f"loss: {float(res.loss):.6g}")
    print(f"steps: {int(res.steps)}")
    status = "converged" if ok else f"not converged: {optx.RESULTS[res.result]}"  # type: ignore[misc]
    print(f"status: {status}")
    if not ok and not args.force:
        print(f"not written: {args.output} (the fit did not converge; --force writes it)")
        return EXIT_NOT_CONVERGED
    display = res.operator(x)
    if not any(kind in REFERENCE_KINDS for kind, _, _ in parsed):
        full = np.asarray(target.statistics_for(display, x))
        print(
            "targets (full resolution): "
            + ", ".join(f"{lab}: {float(s):.4g}" for (lab, _), s in zip(labels, full, strict=True))
        )
    converted = not spaces.is_identity(img.conversion(space, cat=cat))
    write_output(args, encode_output(args, display, converted))
    print(f"wrote: {args.output}")
    if res.result != optx.RESULTS.successful:
        return EXIT_NOT_CONVERGED
    return 0


class _NotConverged(CLIError):
    exit_code = EXIT_NOT_CONVERGED
