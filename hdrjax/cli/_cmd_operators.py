"""``hdrjax operators [NAME]``: the registered operators, or one operator's parameters.

Everything printed is what the operators declare (:func:`hdrjax.operators.parameter_info`
and their class attributes), the way pfstmo's manual pages describe its operators, read
through :mod:`._registry` (the recorded manifest: no JAX import, unless plug-ins are
present).
"""

import argparse
import textwrap

from ._common import UsageError
from ._registry import OperatorEntry, find, operators


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "operators",
        help="list the tone-mapping operators, or one operator's parameters",
        description="Without NAME: every registered operator with a one-line description "
        "and its reference. With NAME: the operator's parameters (what `hdrjax tonemap "
        "--set PARAM=VALUE` takes) with their unit, default, valid range and whether they "
        "are estimated from the image.",
    )
    p.add_argument("name", nargs="?", help="an operator name (case and _/- insensitive)")
    # nothing to compile: main leaves JAX's compilation cache (and JAX) alone
    p.set_defaults(func=run, uses_jax=False)


def run(args: argparse.Namespace) -> int:
    if args.name is None:
        entries = operators()
        width = max(len(op.name) for op in entries) + 2
        for op in entries:
            print(_wrap(op.summary, op.name.ljust(width), width))
            if op.reference:
                print(_wrap(op.reference, " " * width, width + 2))
        print("\n`hdrjax operators NAME` lists an operator's parameters.")
        return 0
    try:
        op = find(args.name)
    except ValueError as e:
        raise UsageError(str(e)) from None
    print(describe_operator(op))
    return 0


def describe_operator(op: OperatorEntry) -> str:
    """An operator's manual page: description, reference, properties, parameters."""
    lines = [_wrap(op.summary, f"{op.name}: ", 4)]
    if op.reference:
        lines.append(_wrap(op.reference, "reference: ", 4))
    maps = (
        "each channel (R, G, B)"
        if op.per_channel
        else "luminance, with the weights of the file's primaries"
    )
    lines.append(f"maps: {maps}")
    lines.append(f"scale invariant: {'yes' if op.scale_invariant else 'no'}")
    fitted = ", ".join(op.default_fit_params) or "none (give --param)"
    lines.append(f"fitted by default (hdrjax fit): {fitted}")
    if not op.parameters:
        lines.append("parameters: none")
        return "\n".join(lines)
    lines.append("parameters (hdrjax tonemap --set PARAM=VALUE):")
    for info in op.parameters:
        unit = f" [{info.unit}]" if info.unit else ""
        lines.append(f"  {info.name}{unit}")
        lines.append(_wrap(info.help, " " * 6, 6))
        facts = [f"default: {info.default}"]
        if info.range_text:
            facts.append(("choices: " if info.choices else "range: ") + info.range_text)
        if info.estimated:
            facts.append(f"estimated from the image (over frames: {info.pooling})")
        if info.static:
            facts.append("setting (not differentiable)")
        lines.append(_wrap("; ".join(facts), " " * 6, 6))
    return "\n".join(lines)


def _wrap(text: str, first: str, indent: int) -> str:
    return textwrap.fill(
        text, width=92, initial_indent=first, subsequent_indent=" " * indent, break_on_hyphens=False
    )
