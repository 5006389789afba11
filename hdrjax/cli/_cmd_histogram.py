"""``hdrjax histogram IN -o plot.png``: the histogram of log10 luminance, with percentile
markers and, optionally, an operator's tone curve over it."""

import argparse
import functools

from ._common import (
    DataError,
    UsageError,
    add_format_argument,
    output_ext,
    output_file,
    positive_int,
    refuse_overwriting_inputs,
)

FIGURE_EXT = (".png", ".svg", ".pdf")
DEFAULT_PERCENTILES = (1.0, 5.0, 50.0, 95.0, 99.0)


def _percentiles(text: str) -> tuple[float, ...]:
    """argparse type: comma-separated percentiles in [0, 100]."""
    try:
        values = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected percentiles separated by commas, got {text!r}"
        ) from None
    if not all(0 <= v <= 100 for v in values):
        raise argparse.ArgumentTypeError(f"expected percentiles in [0, 100], got {text!r}")
    return values


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "histogram",
        help="plot the histogram of log luminance, with percentiles and an operator's curve",
        description="Plot the fraction of pixels per bin of log10 luminance (cd/m² when "
        "the file is calibrated or declares its white luminance, else relative), from the "
        "smallest positive to the largest finite luminance, with markers at percentiles (the "
        "package's histogram percentiles, relative error below 0.1 percent) and the "
        "log-average. --method draws that operator's display luminance against world "
        "luminance on a second axis, its image-dependent parameters measured from this "
        "image, as pfsview and Luminance HDR show them. Writes PNG, SVG or PDF.",
    )
    p.add_argument("input", help="HDR image: .exr, .hdr or .pfm")
    p.add_argument(
        "-o", "--output", required=True, help="the plot: .png, .svg or .pdf; '-': standard output"
    )
    add_format_argument(p, ("png",))
    p.add_argument("--bins", type=positive_int, default=100, help="histogram bins (default 100)")
    p.add_argument(
        "--marks",
        dest="percentiles",
        type=_percentiles,
        default=DEFAULT_PERCENTILES,
        metavar="P1,P2,...",
        help="the percentiles to mark (default 1,5,50,95,99)",
    )
    p.add_argument("--method", help="draw this tone-mapping operator's curve (a registered name)")
    p.add_argument("--title", help="plot title (default: the file name)")
    p.set_defaults(func=run)


def _statistics(L, rgb, qs, bins: int, op=None):
    """``((n_positive, ln_lo, span, percentiles, rel_error, log_average, counts), measured)``
    of luminance ``L``: the mergeable statistics of :func:`hdrjax.stats.summarise` (those
    of ``op`` when it reads histogram statistics, so that one pass serves the plot and the
    operator's :meth:`~hdrjax.operators.AbstractOperator.bind`); ``counts``: positive
    pixels in ``bins`` equal bins of ``ln L`` from ``ln_lo`` (the smallest positive
    luminance) over ``span`` (to the largest). ``measured``: ``op`` with its unset
    parameters estimated from this image (``None`` without ``op``)."""
    import jax.numpy as jnp

    from ..operators import measure_in_space

    settings = op.statistics_settings() if op is not None else None
    st = op.statistics(jnp.asarray(rgb)) if settings is not None else None
    if st is None or st.counts is None:  # no operator, or one with exact percentiles
        st = _compiled_summarise()(jnp.asarray(L))
    summary = _compiled_summary()(st, jnp.asarray(qs, jnp.float32), bins)
    if op is None:
        return summary, None
    if settings is not None and st.m is not None and settings.method == "histogram":
        return summary, _compiled_calls()[0](op, st)
    return summary, measure_in_space(op, jnp.asarray(rgb), None)


@functools.cache
def _compiled_calls():
    """``op.bind(stats)`` and ``op.curve(L)`` compiled (eagerly, each of their many small
    operations would compile on its own)."""
    import equinox as eqx

    return eqx.filter_jit(lambda op, st: op.bind(st)), eqx.filter_jit(lambda op, L: op.curve(L))


@functools.cache
def _compiled_summarise():
    """:func:`hdrjax.stats.summarise` of the finite pixels, compiled once per process (the
    module imports no JAX: ``hdrjax --help`` builds this parser)."""
    import jax
    import jax.numpy as jnp

    from .._stats import summarise

    @jax.jit
    def run(L):
        return summarise(jnp.where(jnp.isfinite(L), L, jnp.nan), keep_source=False)[1]

    return run


@functools.cache
def _compiled_summary():
    """What the plot reads from statistics (:func:`_statistics`), compiled once."""
    import jax
    import jax.numpy as jnp

    from .._stats import coarse_counts

    @functools.partial(jax.jit, static_argnames="bins")
    def run(st, qs, bins: int):
        ls = st.luminance_stats()
        ln_lo = jnp.log(ls.min_positive)
        span = jnp.log(jnp.maximum(ls.max, ls.min_positive)) - ln_lo
        flat = ~(span > 0)  # one value: the axis spans a factor 2 each way
        ln_lo = jnp.where(flat, ln_lo - jnp.log(2.0), ln_lo)
        span = jnp.where(flat, 2 * jnp.log(2.0), span)
        ps, err = st.quantile(qs.astype(ln_lo.dtype) / 100.0)
        counts = coarse_counts(st.counts, st.m, ln_lo, span, bins)
        return ls.n_positive, ln_lo, span, ps, err, ls.log_average, counts

    return run


def _curve(measured, rgb, weights, edges_log10):
    """``(x, y, label)``: the measured operator's display luminance against world
    luminance: its curve for luminance-curve operators; for the others (local or
    per-channel operators, whose display luminance is no function of world luminance
    alone) the mean display luminance of the pixels of each bin."""
    import jax.numpy as jnp
    import numpy as np

    from .. import luminance
    from ..operators import AbstractLuminanceCurve

    if isinstance(measured, AbstractLuminanceCurve) and not measured.unset():
        x = np.linspace(edges_log10[0], edges_log10[-1], 256)
        y = np.asarray(_compiled_calls()[1](measured, jnp.asarray(10.0**x)), np.float64)
        return x, y, f"{measured.name} curve"
    Lw = np.asarray(luminance(jnp.asarray(rgb), weights), np.float64)
    Ld = np.asarray(luminance(measured(jnp.asarray(rgb)), weights), np.float64)
    ok = np.isfinite(Lw) & (Lw > 0) & np.isfinite(Ld)
    n = len(edges_log10) - 1
    idx = np.clip(np.digitize(np.log10(Lw[ok]), edges_log10) - 1, 0, n - 1)
    count = np.bincount(idx, minlength=n)
    mean = np.bincount(idx, Ld[ok], minlength=n) / np.maximum(count, 1)
    centres = 0.5 * (edges_log10[1:] + edges_log10[:-1])
    return centres[count > 0], mean[count > 0], f"{measured.name}: mean per bin"


def _operator(name: str):
    from ..operators import make_operator

    try:
        return make_operator(name)
    except ValueError as e:
        raise UsageError(f"--method: {str(e).removeprefix('method: ')}") from None


def run(args: argparse.Namespace) -> int:
    import math

    import numpy as np

    from .. import luminance
    from ..io import atomic_path
    from ._cmd_tonemap import colour_settings, load_rgb, with_file_weights

    ext = output_ext(args, FIGURE_EXT)
    refuse_overwriting_inputs([args.output], [args.input])
    if args.bins < 2:
        raise UsageError(f"--bins: expected an integer >= 2, got {args.bins}")
    op = _operator(args.method) if args.method else None
    img, rgb = load_rgb(args.input)
    if img.quantity == "relative" and img.white_luminance is not None:
        # the file declares its scale (EXR whiteLuminance): plot cd/m²
        rgb = rgb * np.float32(img.white_luminance)
        img = img.to_absolute()
    space, cat = colour_settings(None)
    weights = img.luminance_weights_in(space, cat=cat)
    L = np.asarray(luminance(rgb, weights), np.float32)
    qs = np.asarray(args.percentiles, np.float32)
    if op is not None:
        op = with_file_weights(op, img)
    summary, measured = _statistics(L, rgb, qs, args.bins, op)
    n_pos, ln_lo, span, ps, err, log_avg, counts = summary
    if int(n_pos) == 0:
        raise DataError(f"{args.input}: no pixel with positive finite luminance")
    edges = (float(ln_lo) + float(span) * np.linspace(0.0, 1.0, args.bins + 1)) / math.log(10)
    frac = np.asarray(counts, np.float64) / int(n_pos)
    calibrated = img.quantity != "relative" and img.unit
    what = f"log₁₀ {img.quantity} ({img.unit})" if calibrated else "log₁₀ relative luminance"

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.stairs(frac, edges, fill=True, color="0.75", label="pixels")
    ax.set_xlabel(what)
    ax.set_ylabel("fraction of pixels")
    ax.set_xlim(edges[0], edges[-1])
    ax.set_ylim(0.0, float(frac.max()) * 1.05 or 1.0)
    # percentiles as ticks of a top axis: their labels never sit under the data or legend
    marks = [
        (math.log10(float(v)), f"p{q:g}")
        for q, v in zip(args.percentiles, np.asarray(ps, np.float64), strict=True)
        if v > 0 and np.isfinite(v)
    ]
    for x, _ in marks:
        ax.axvline(x, color="C3", ls="--", lw=1, gid="percentile")
    top = ax.secondary_xaxis("top")
    top.set_xticks([x for x, _ in marks], [t for _, t in marks], rotation=90, fontsize=8)
    top.tick_params(colors="C3")
    handles = [*ax.get_legend_handles_labels()[0]]
    if float(log_avg) > 0:
        handles.append(
            ax.axvline(math.log10(float(log_avg)), color="C2", lw=1.2, label="log-average")
        )
    if op is not None:
        x, y, label = _curve(measured, rgb, weights, edges)
        cax = ax.twinx()
        handles += cax.plot(x, y, color="C0", lw=2, label=label, gid="tone_curve")
        cax.axhline(1.0, color="0.3", ls=":", lw=1)
        cax.set_ylim(
            min(0.0, float(np.nanmin(y))) - 0.02, min(max(float(np.nanmax(y)), 1.0), 1.2) + 0.05
        )
        cax.set_ylabel("display luminance $L_d$ (1 = display white)")
    # with a curve: mid-right, below its shoulder; without: wherever the bars leave room
    (cax if op is not None else ax).legend(
        handles=handles, loc="center right" if op is not None else "best", fontsize="small"
    )
    ax.set_title(args.title or img.name)
    try:
        with output_file(args) as path:
            with atomic_path(path, overwrite=not getattr(args, "no_clobber", False)) as tmp:
                fig.savefig(tmp, format=ext[1:], dpi=120)
    except (ValueError, OSError) as e:
        raise DataError(f"{args.output}: cannot write: {e}") from None
    h, w = L.shape
    unit = f" {img.unit}" if calibrated else ""
    print(f"input: {args.input} ({w}x{h}), {what}")
    print(
        "percentiles: "
        + ", ".join(
            f"p{q:g} {float(v):.6g}{unit}"
            for q, v in zip(args.percentiles, np.asarray(ps), strict=True)
        )
        + f" (histogram, rel. error <= {float(err):.2g})"
    )
    print(f"log-average: {float(log_avg):.6g}{unit}")
    if op is not None:
        print(f"curve: {op.name}")
    print(f"wrote: {args.output}")
    return 0
