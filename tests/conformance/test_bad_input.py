"""Bad input gets a clear error: every case of the conformance table (``_table.py``) is fed an
image of the wrong rank, the wrong channel count, a wrong dtype and no rows or no columns,
and every out-of-range parameter the table lists for it.

A bad form must raise a one-line ``ValueError`` that starts with the argument's name and
states the expected form (``rgb: expected shape (..., H, W, 3), got shape (8, 8)``), before
anything is compiled — the checks of ``hdrjax/_check.py`` read only static shapes, dtypes and
Python numbers. A form a case accepts by design (``Case.accepts``: elementwise formulas take
any shape, filters and resamplers any channel count; ``PROMOTED``: integer and bool images are
promoted to float) must instead give the reference result the table names for it.
"""

import inspect
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from ..conftest import RTOL32
from ..operators.cases import natural
from ._table import (
    BAD_INPUTS,
    CASES,
    EMPTY_FORMS,
    PROMOTED,
    channels_of,
    float_leaves,
    per_value,
)
from .test_coverage import public_callables
from .test_messages import case_parameters

GOOD = natural((8, 8))
"""The good image the bad forms are made from: float32 (8, 8, 3), positive, 17 stops."""

SHAPE_FORMS = ("rank2", "rank1", "channels4", "channels1", *EMPTY_FORMS)

PROMOTION_VALUES = {
    # one traced case per promotion path (compiles: the others are traced, not compiled)
    "luminance",  # hdrjax._colour
    "estimate.log_average",  # operators/_base.as_float_image
    "vision.glare",  # _photometry.check_rgb
    "filters.mean_filter[nearest]",  # filters/_api.float_image
    "panorama.sample_bilinear",  # arithmetic with float weights
    "encode_srgb",  # display/_encode
    "targets.MeanLuminance",  # targets/_display
}
"""Traced cases whose integer/bool results are compared value by value with the float32
results; for the other traced cases ``jax.eval_shape`` checks the promoted output dtypes
and shapes without compiling (the promotion itself is shared: one line at each entry)."""


def _parameter_names() -> set[str]:
    """Every parameter name of a public callable (functions, constructors, methods)."""
    names = {"shape"}  # HumanVision.build's image size
    for obj in public_callables().values():
        fns = [obj]
        if inspect.isclass(obj):
            fns = [getattr(obj, m, None) for m in ("__init__", "__call__", "residuals", "build")]
        for f in fns:
            try:
                names |= set(inspect.signature(f).parameters)
            except (TypeError, ValueError):
                continue
    return names


PARAMETER_NAMES = _parameter_names()


TRACEABLE = {n for n, c in CASES.items() if c.jit} | {
    "batch.render_batch",  # compiled by itself (filter_jit); not vmapped by test_images
}
"""Cases ``jax.eval_shape`` can trace (structure checks without a compile)."""


def _structs(tree):
    """(shape, dtype) of every leaf of an ``eval_shape`` result, floats only."""
    leaves = jax.tree_util.tree_leaves(tree)
    return [(v.shape, v.dtype) for v in leaves if jnp.issubdtype(v.dtype, jnp.floating)]


def _call(case, x):
    return case.fn(jnp.asarray(x)) if case.jit else case.fn(x)


def _check_message(
    msg: str, name: str | None, kind: str | None = None, case: str | None = None
) -> None:
    """One line, ``name: expected <form>, got <what>`` (or ``name ... needs ...``); with
    ``case``, the name is an argument of the callables that case calls (test_messages.py)."""
    assert "\n" not in msg, f"not one line: {msg!r}"
    first = re.match(r"^(\w+)[: ]", msg)
    assert first, f"does not start with the argument's name: {msg!r}"
    if name is None:
        assert first[1] in PARAMETER_NAMES, f"{first[1]!r} is no argument name: {msg!r}"
    else:
        assert name in msg, f"does not name {name!r}: {msg!r}"
    if case is not None:
        own = case_parameters(case)
        assert first[1] in own, f"{first[1]!r} is no argument of {case}: {msg!r}"
        assert name is None or first[1] == name, f"does not start with {name!r}: {msg!r}"
    assert re.search(r"\b(expect(s|ed)?|needs?|must|valid)\b", msg), f"no expected form: {msg!r}"
    assert "got" in msg or "valid" in msg, f"does not say what it got: {msg!r}"
    if kind in SHAPE_FORMS:
        assert re.search(r"\(.*\)", msg), f"no shape form: {msg!r}"
    elif kind is not None:
        assert "real" in msg or "float" in msg, f"no dtype form: {msg!r}"
    if kind in EMPTY_FORMS:  # says what it needs, and the empty shape it got
        assert re.search(r"non-empty|>= ?[12]|at least", msg), f"no minimum size: {msg!r}"
        assert re.search(r"got (shape )?\((\d+, )*0(, \d+)*\)", msg), f"no empty shape: {msg!r}"


def _assert_same(got, want, what):
    got = [np.asarray(v, np.float64) for v in got]
    want = [np.asarray(v, np.float64) for v in want]
    assert len(got) == len(want), f"{what}: {len(got)} outputs, expected {len(want)}"
    for g, w in zip(got, want, strict=True):
        assert g.shape == w.shape, f"{what}: shape {g.shape}, expected {w.shape}"
        np.testing.assert_allclose(g, w, rtol=RTOL32, atol=1e-6, equal_nan=True, err_msg=what)


@pytest.mark.parametrize("kind", list(BAD_INPUTS))
@pytest.mark.parametrize("name", sorted(CASES))
def test_bad_input_form(name, kind):
    case = CASES[name]
    bad = BAD_INPUTS[kind](GOOD)
    if kind in case.accepts and case.accepts[kind][1] is None and name in TRACEABLE:
        # SAME_PATH: the values are checked on another form or case; the structure here
        got = _structs(jax.eval_shape(case.fn, jax.ShapeDtypeStruct(bad.shape, bad.dtype)))
        good = _structs(jax.eval_shape(case.fn, jax.ShapeDtypeStruct(GOOD.shape, GOOD.dtype)))
        want = [(channels_of(np.empty(s), kind).shape, d) for s, d in good]
        assert got == want, f"{name}/{kind}: {got} != {want}"
    elif kind in case.accepts:
        _reason, reference = case.accepts[kind]
        want = (reference or per_value)(case.fn, GOOD, kind)
        _assert_same(float_leaves(_call(case, bad)), want, f"{name}/{kind}")
    elif kind in PROMOTED and name in TRACEABLE and name not in PROMOTION_VALUES:
        got = jax.eval_shape(case.fn, jax.ShapeDtypeStruct(bad.shape, bad.dtype))
        want = jax.eval_shape(case.fn, jax.ShapeDtypeStruct(bad.shape, np.float32))
        assert jax.tree_util.tree_structure(got) == jax.tree_util.tree_structure(want)
        assert _structs(got) == _structs(want), f"{name}/{kind}: {got} != {want}"
    elif kind in PROMOTED:
        want = float_leaves(_call(case, bad.astype(np.float32)))
        out = float_leaves(_call(case, bad))
        if case.jit:  # promoted to the default float (NumPy-side functions: their own)
            assert all(v.dtype == np.float32 for v in out), f"{name}: {[v.dtype for v in out]}"
        _assert_same(out, want, f"{name}/{kind}")
    else:
        with pytest.raises(ValueError) as err:
            _call(case, bad)
        _check_message(str(err.value), None, kind, case=name)


PARAMS = [(n, i) for n in sorted(CASES) for i in range(len(CASES[n].params))]


@pytest.mark.parametrize("name,index", PARAMS)
def test_bad_parameter(name, index):
    arg, call = CASES[name].params[index]
    with pytest.raises(ValueError) as err:
        call(jnp.asarray(GOOD))
    _check_message(str(err.value), arg, case=name)


def test_every_form_is_swept():
    """The sweep is not vacuous: most cases reject most forms, and the accepted forms are
    declared with a reason."""
    rejected = sum(
        k not in c.accepts and k not in PROMOTED for c in CASES.values() for k in BAD_INPUTS
    )
    assert rejected > 3 * len(CASES)
    for name, case in CASES.items():
        for kind, (reason, _) in case.accepts.items():
            assert kind in BAD_INPUTS and reason, (name, kind)
    assert len(PARAMS) > len(CASES)
