"""``hdrjax info INPUT``: size, layers, luminance statistics and estimated parameters."""

import argparse

from ._cmd_tonemap import (
    add_colour_arguments,
    colour_settings,
    describe,
    describe_conversion,
    load_rgb,
    with_file_weights,
)
from ._common import positive_float


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "info",
        help="print size, layers, luminance statistics and estimated operator parameters",
        description="Describe an HDR image: size, channels and layers, luminance statistics "
        "(min, percentiles, log-average, max, dynamic range in stops), the parameters "
        "each operator would estimate from it, and each automatic estimate "
        "(hdrjax.estimate) with the statistics it used.",
    )
    p.add_argument("input", help="HDR image: .exr, .hdr or .pfm")
    p.add_argument(
        "--scale", type=positive_float, default=1.0, help="multiply the input by this factor first"
    )
    p.add_argument(
        "--exact",
        action="store_true",
        help="exact (sorted) percentiles instead of the histogram estimate",
    )
    add_colour_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import equinox as eqx
    import jax
    import jax.numpy as jnp
    import numpy as np

    from .. import luminance
    from .._stats import percentile, summarise
    from ..operators import get_operator, operator_names, parameter_info

    img, rgb = load_rgb(args.input, args.scale, args)
    h, w = rgb.shape[:2]
    chans = img.image.shape[-1] if img.image.ndim == 3 else 1
    print(f"file: {args.input}")
    print(f"size: {w} x {h}, {chans} channel(s) in the main image")
    layers = getattr(img, "layers", {}) or {}
    if layers:
        print("layers: " + ", ".join(f"{k} {tuple(np.shape(v))}" for k, v in layers.items()))
    unit = getattr(img, "unit", None)
    if unit:
        print(f"unit: {unit}")
    print(describe_conversion(img, args))
    space, cat = colour_settings(args)
    wts = img.luminance_weights_in(space, cat=cat)
    print("luminance weights: (" + ", ".join(f"{v:.5f}" for v in wts) + f") in {space.name}")
    L = luminance(jnp.asarray(rgb), wts)
    method = "exact" if args.exact else "histogram"
    qs = jnp.array([1.0, 5.0, 50.0, 95.0, 99.0])

    @jax.jit
    def statistics(L):
        # one pass: the histogram's percentiles come from the same statistics
        finite_only = jnp.where(jnp.isfinite(L), L, jnp.nan)
        stats = summarise(finite_only, method=method, keep_source=False)[1]
        if method == "exact":
            return stats.luminance_stats(), percentile(L, qs, method="exact")
        return stats.luminance_stats(), stats.quantile(jnp.asarray(qs, L.dtype) / 100.0)

    st, (ps, err) = statistics(L)
    n_bad = int(st.n_nonfinite)
    print("luminance (finite pixels):")
    print(
        f"  min {float(st.min):.6g}   min>0 {float(st.min_positive):.6g}   max {float(st.max):.6g}"
    )
    names = ("p1", "p5", "median", "p95", "p99")
    print(
        "  "
        + "   ".join(f"{n} {float(v):.6g}" for n, v in zip(names, ps, strict=True))
        + (f"   (histogram, rel. error <= {float(err):.2g})" if method == "histogram" else "")
    )
    print(
        f"  log-average {float(st.log_average):.6g}   dynamic range"
        f" {float(st.dynamic_range_stops):.2f} stops"
    )
    print(
        f"  non-positive pixels {int(st.n_pixels - st.n_positive - st.n_nonfinite)},"
        f" NaN/Inf pixels {n_bad}"
    )
    print("estimated parameters:")
    # every operator that declares an estimated parameter, bound in one compiled call to
    # statistics measured once per statistics setting (most operators share one)
    classes = [get_operator(name) for name in operator_names()]
    ops = [
        with_file_weights(c(), img, args)
        for c in classes
        if any(i.estimated for i in parameter_info(c))
    ]
    all_measured = eqx.filter_jit(_measure_all)(ops, jnp.asarray(rgb))
    for op, measured in zip(ops, all_measured, strict=True):
        text = describe(measured).splitlines()
        keep = [ln for ln in text[1:] if ln.split(":")[0].strip() in op.unset()]
        if keep:  # reinhard2002_auto measures in its branches: its choice is printed below
            print(f"  {op.name}: " + ", ".join(s.strip() for s in keep))
    use_local = bool(next(m for m in all_measured if m.name == "reinhard2002_auto").local)
    print(
        f"  reinhard2002_auto: {'local' if use_local else 'global'} operator"
        f" ({float(st.dynamic_range_stops):.1f} zones {'>' if use_local else '<='} 11)"
    )
    print_estimates(jnp.asarray(rgb), wts, method)
    print("operators: " + ", ".join(operator_names()))
    return 0


def print_estimates(rgb, weights, method: str) -> None:
    """Each :mod:`hdrjax.estimate` value and the statistics it was computed from."""
    import jax

    from .. import estimate as E

    print("automatic estimates (value; the statistics it used):")

    order: list[list[str]] = []  # each estimate's statistics in its own order (jit sorts)

    @jax.jit
    def estimates(rgb):  # one compiled call for all of them
        out = (
            E.jgt_key(rgb, percentile_method=method, weights=weights),
            E.jgt_white(rgb, percentile_method=method, weights=weights),
            E.log_average(rgb, weights=weights),
            E.adaptation_luminance(rgb, weights=weights),
            E.adaptation_luminance(rgb, robust=True, weights=weights),
            E.desaturation_threshold(rgb, method=method, weights=weights),
        )
        order[:] = [list(e.statistics) for e in out]
        return out

    units = ("", " (scaled units)", "", "", "", "")
    for est, unit, keys in zip(estimates(rgb), units, order, strict=True):
        stats = ", ".join(f"{k} {_fmt(est.statistics[k])}" for k in keys)
        print(f"  {est.name}: {_fmt(est.value)}{unit}   ({stats})")


def _measure_all(ops: list, rgb):
    """``[op.measure(rgb) for op in ops]``, with the statistics measured once per setting
    (``op.measure`` is ``op.bind(op.statistics(rgb))``)."""
    stats: dict = {}
    out = []
    for op in ops:
        settings = op.statistics_settings()
        if settings is None:
            out.append(op.measure(rgb))
            continue
        key = (tuple(settings), tuple(op.weights_))
        if key not in stats:
            stats[key] = op.statistics(rgb)
        out.append(op.bind(stats[key]))
    return out


def _fmt(v) -> str:
    import numpy as np

    v = np.asarray(v)
    if v.dtype == bool:
        return "yes" if bool(v) else "no"
    if np.issubdtype(v.dtype, np.integer):
        return str(int(v))
    return f"{float(v):.6g}"
