"""``hdrjax operators [NAME]``: the registered operators, or one operator's parameters.

Everything printed is what the operators declare (:func:`hdrjax.operators.parameter_info`
and their class attributes), the way pfstmo's manual pages describe its operators.
"""

import argparse
import inspect
import textwrap

from ._common import UsageError


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
    p.set_defaults(func=run)


def summary(cls) -> str:
    """The first paragraph of an operator's docstring, on one line, without markup."""
    doc = inspect.cleandoc(cls.__doc__ or "").split("\n\n")[0]
    return " ".join(doc.replace("``", "").split())


def run(args: argparse.Namespace) -> int:
    from ..operators import get_operator, operator_names

    if args.name is None:
        names = operator_names()
        width = max(len(n) for n in names) + 2
        for name in names:
            cls = get_operator(name)
            print(_wrap(summary(cls), name.ljust(width), width))
            if cls.reference:
                print(_wrap(cls.reference, " " * width, width + 2))
        print("\n`hdrjax operators NAME` lists an operator's parameters.")
        return 0
    try:
        cls = get_operator(args.name)
    except ValueError as e:
        raise UsageError(str(e)) from None
    print(describe_operator(cls))
    return 0


def describe_operator(cls) -> str:
    """An operator's manual page: description, reference, properties, parameters."""
    from ..operators import parameter_info

    lines = [_wrap(summary(cls), f"{cls.name}: ", 4)]
    if cls.reference:
        lines.append(_wrap(cls.reference, "reference: ", 4))
    maps = (
        "each channel (R, G, B)"
        if cls.per_channel
        else "luminance, with the weights of the file's primaries"
    )
    lines.append(f"maps: {maps}")
    lines.append(f"scale invariant: {'yes' if cls.scale_invariant else 'no'}")
    fitted = ", ".join(cls.default_fit_params) or "none (give --param)"
    lines.append(f"fitted by default (hdrjax fit): {fitted}")
    infos = parameter_info(cls)
    if not infos:
        lines.append("parameters: none")
        return "\n".join(lines)
    lines.append("parameters (hdrjax tonemap --set PARAM=VALUE):")
    for info in infos:
        unit = f" [{info.unit}]" if info.unit else ""
        lines.append(f"  {info.name}{unit}")
        lines.append(_wrap(info.help, " " * 6, 6))
        facts = [f"default: {_default(info)}"]
        if info.range_text():
            facts.append(("choices: " if info.choices else "range: ") + info.range_text())
        if info.estimated:
            facts.append(f"estimated from the image (over frames: {info.pooling})")
        if info.static:
            facts.append("setting (not differentiable)")
        lines.append(_wrap("; ".join(facts), " " * 6, 6))
    return "\n".join(lines)


def _default(info) -> str:
    if info.required:
        return "required"
    v = info.default
    if v is None:
        return "estimated" if info.estimated else "none"
    if isinstance(v, tuple):
        return "(" + ", ".join(f"{x:.4g}" for x in v) + ")"
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def _wrap(text: str, first: str, indent: int) -> str:
    return textwrap.fill(
        text, width=92, initial_indent=first, subsequent_indent=" " * indent, break_on_hyphens=False
    )
