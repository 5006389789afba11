"""Error messages name the argument as the caller wrote it.

A message starts with the name of an argument *of the callable the user called* — not an
internal helper's name for it (``rgb:`` from ``hdrjax.fit.fit``, whose image is ``image``;
``map:`` from ``hdrjax.lights.detect``, whose map is ``envmap``). :func:`case_parameters`
gives, for every case of the conformance table (``_table.py``), the parameter names of the
public callables the case calls; ``test_bad_input.py`` holds every bad-input and
bad-parameter message of the table to them. The public functions outside the table that
take an image (fitting, sweeps, plots, the dispatcher) are checked here, each with the
argument its message must start with.

Operators: a parameter an operator cannot estimate (the table of ``tabulated``) is
required; leaving it out of ``hdrjax.tonemap`` or ``hdrjax.make_operator`` gives a one-line
``ValueError`` that names it and says what it expects (the operator's docstring), for every
registered operator.
"""

import inspect
import re

import numpy as np
import pytest

import hdrjax
import hdrjax.fit as hfit
import hdrjax.lights as hl
import hdrjax.targets as ht
import hdrjax.vision as hv
from hdrjax.operators._base import parameter_help, required_parameters

from ._table import CASES
from .test_coverage import public_callables

PUBLIC = public_callables()

THROUGH: dict[str, tuple[str, ...]] = {
    # cases whose image reaches another public function first: a bad image is that
    # function's argument (the luminance of the statistics, the encoding before quantize)
    **{n: ("hdrjax.luminance",) for n in CASES if n.startswith("stats.")},
    "false_color": ("hdrjax.luminance",),
    "quantize": ("hdrjax.display.encode",),
}

METHODS = ("__init__", "__call__", "build", "measure", "residuals")
"""The methods of a class the cases call (constructor, application, builders)."""


def parameters_of(obj) -> set[str]:
    """Parameter names of a public function, or of a class's constructor and the methods
    the cases call."""
    fns = [getattr(obj, m, None) for m in METHODS] if inspect.isclass(obj) else [obj]
    names: set[str] = set()
    for f in fns:
        try:
            names |= set(inspect.signature(f).parameters)
        except (TypeError, ValueError):
            continue
    return names - {"self", "cls"}


def case_parameters(name: str) -> set[str]:
    """Parameter names of the public callables the case ``name`` calls."""
    covers = CASES[name].covers + THROUGH.get(name, ())
    return set().union(*(parameters_of(PUBLIC[n]) for n in covers))


def check_message(msg: str, arg: str) -> None:
    """One line that starts with ``arg`` and states what is expected and what came."""
    assert "\n" not in msg, f"not one line: {msg!r}"
    assert re.match(rf"^{re.escape(arg)}[: ]", msg), f"does not start with {arg!r}: {msg!r}"
    assert re.search(r"\b(expect(s|ed)?|needs?|must|valid)\b", msg), f"no expected form: {msg!r}"
    assert "got" in msg or "valid" in msg, f"does not say what it got: {msg!r}"


def test_every_case_knows_its_callables():
    """The per-case names are not vacuous: every case resolves to public callables, and
    each case's names refuse most of the names some other public callable takes."""
    assert set(THROUGH) <= set(CASES)
    everything = set().union(*(parameters_of(o) for o in PUBLIC.values()))
    for name in CASES:
        params = case_parameters(name)
        assert params and len(params) < len(everything) / 3, (name, sorted(params))
    # issue 16's names: "rgb" is an argument of some public callable, but not of fit's
    assert "rgb" in everything
    assert "rgb" not in parameters_of(hfit.fit) and "map" not in parameters_of(hl.detect)


# -- public image functions outside the conformance table ---------------------------------

GOOD = np.full((8, 8, 3), 0.5, np.float32)
TARGET = ht.MeanLuminance(0.18)

OUTSIDE = {
    # id: (callable, the argument its message must start with, the call)
    "fit/rank2": (hfit.fit, "image", lambda: hfit.fit("reinhard2002", GOOD[..., 0], TARGET)),
    "fit/complex": (
        hfit.fit,
        "image",
        lambda: hfit.fit("reinhard2002", GOOD.astype(np.complex64), TARGET),
    ),
    "fit/nothing_unset": (hfit.fit, "params", lambda: hfit.fit("gamma", GOOD, TARGET)),
    "fit_batch/rank3": (
        hfit.fit_batch,
        "frames",
        lambda: hfit.fit_batch("reinhard2002", GOOD, TARGET),
    ),
    "fit_sequence/channels1": (
        hfit.fit_sequence,
        "frames",
        lambda: hfit.fit_sequence("reinhard2002", GOOD[None, ..., :1], TARGET),
    ),
    "lights.detect/one_row": (
        hl.detect,
        "envmap",
        lambda: hl.detect(GOOD[:1], width=16),
    ),
    "lights.median_cut/one_row": (
        hl.median_cut,
        "envmap",
        lambda: hl.median_cut(GOOD[:1], n_lights=4, width=16),
    ),
    "lights.detect_image/narrow": (
        hl.detect_image,
        "image",
        lambda: hl.detect_image(GOOD[:, :2], width=16),
    ),
    "tonemap/rank2": (hdrjax.tonemap, "rgb", lambda: hdrjax.tonemap(GOOD[..., 0])),
    "tonemap/unknown_parameter": (
        hdrjax.tonemap,
        "kee",  # as the user wrote it (**params)
        lambda: hdrjax.tonemap(GOOD, "reinhard2002", kee=0.18),
    ),
    "make_operator/unknown_parameter": (
        hdrjax.make_operator,
        "kee",
        lambda: hdrjax.make_operator("reinhard2002", kee=0.18),
    ),
    "study.sweep/rank2": (
        hdrjax.study.sweep,
        "image",
        lambda: hdrjax.study.sweep("reinhard2002", GOOD[..., 0], {"key": [0.1, 0.2]}),
    ),
    "plot.tone_curve/rank2": (
        hdrjax.plot.tone_curve,
        "image",
        lambda: hdrjax.plot.tone_curve("reinhard2002", GOOD[..., 0]),
    ),
    "vision.simulate/effect": (
        hv.simulate,
        "effects",
        lambda: hv.simulate(GOOD, 30.0, {"glow"}, scale=1.0),
    ),
    "vision.simulate/view": (hv.simulate, "view", lambda: hv.simulate(GOOD, -5.0, scale=1.0)),
    "vision.HumanVision.build/view": (
        hv.HumanVision.build,
        "view",
        lambda: hv.HumanVision.build((8, 8), 200.0, ("glare",)),
    ),
}


@pytest.mark.parametrize("key", sorted(OUTSIDE))
def test_outside_the_table_messages_name_the_callers_argument(key):
    fn, arg, call = OUTSIDE[key]
    assert arg in parameters_of(fn) or arg == "kee", f"{key}: {arg!r} is no argument"
    with pytest.raises(ValueError) as err:
        call()
    check_message(str(err.value), arg)


def test_effect_names_are_checked_for_the_cli_option_too():
    from hdrjax.vision._simulate import effect_name

    with pytest.raises(ValueError) as err:
        effect_name("glow", "--with")
    check_message(str(err.value), "--with")


# -- operators: required parameters, for every registered operator ------------------------

REQUIRED = [
    (name, p)
    for name in hdrjax.operator_names()
    for p in required_parameters(hdrjax.get_operator(name))
]


def test_the_required_parameters_are_found():
    """Not vacuous: the tabulated operator's table is required, and nothing with a
    default is."""
    assert ("tabulated", "luminance") in REQUIRED and ("tabulated", "display") in REQUIRED
    assert not any(name == "reinhard2002" for name, _ in REQUIRED)


@pytest.mark.parametrize("via", ["tonemap", "make_operator"])
@pytest.mark.parametrize("name,param", REQUIRED)
def test_missing_required_parameter_is_a_one_line_value_error(name, param, via):
    cls = hdrjax.get_operator(name)
    expected = parameter_help(cls, param)
    assert expected, f"{name}.{param}: required but undocumented (Attributes: section)"
    # the other required parameters are given (a placeholder: the check comes first)
    given = {q: object() for q in required_parameters(cls) if q != param}
    for params in (given, {**given, param: None}):
        with pytest.raises(ValueError) as err:
            if via == "tonemap":
                hdrjax.tonemap(GOOD, method=name, **params)
            else:
                hdrjax.make_operator(name, **params)
        msg = str(err.value)
        check_message(msg, param)
        assert expected.split("; ")[0] in msg and name in msg, msg
