"""An eager call of one image compiles only the branch it takes (clean or masked:
hdrjax/operators/_base.py, ``dispatch`` and ``DECIDE_FIRST_PIXELS``) and maps exactly as
the traced function, which compiles both."""

import equinox as eqx
import jax
import numpy as np
import pytest

from hdrjax.operators import _base

from .cases import make, natural


@pytest.mark.parametrize("name", ["reinhard2002", "drago2003", "mantiuk2008", "gamma"])
def test_eager_calls_trace_only_the_branch_taken(name, monkeypatch):
    traced = []
    prepare = _base.prepare
    monkeypatch.setattr(_base, "prepare", lambda *a: traced.append(1) or prepare(*a))
    op = make(name)
    clean = natural((9, 13))  # a shape no other test of this file compiles
    bad = clean.copy()
    bad[2, 3, 1], bad[4, 5] = np.nan, np.inf
    out = np.asarray(op(clean))
    assert not traced, "a clean image compiled the masked path"
    out_bad = np.asarray(op(bad))
    assert traced, "the masked path was not taken for NaN/Inf pixels"
    both = jax.jit(lambda v: op(v))  # traced: both branches under lax.cond
    # rounding only; mantiuk2008's iteration stops when its curve settles, so the rounding
    # of the luminance it was given can move the last step: 1.1e-4 relative on one CPU,
    # 2.2e-4 absolute at dark pixels (0 in one, 2.2e-4 in the other) on another (the code
    # XLA:CPU generates differs between processors): 5e-4 of the display's range, an
    # eighth of an 8-bit code value
    rtol = 5e-4 if name == "mantiuk2008" else 1e-5
    atol = 5e-4 if name == "mantiuk2008" else 1e-6
    np.testing.assert_allclose(out, np.asarray(both(clean)), rtol=rtol, atol=atol)
    ref = np.asarray(both(bad))
    np.testing.assert_array_equal(np.isnan(out_bad), np.isnan(ref))
    ok = ~np.isnan(ref)
    np.testing.assert_allclose(out_bad[ok], ref[ok], rtol=rtol, atol=atol)


def test_large_images_run_the_whole_function(monkeypatch):
    """Above DECIDE_FIRST_PIXELS the separate pass would cost more per call than it saves
    in compile time: one program with both branches."""
    monkeypatch.setattr(_base, "DECIDE_FIRST_PIXELS", 50)
    calls = []
    whole = _base._apply_whole_jit
    monkeypatch.setattr(_base, "_apply_whole_jit", lambda *a: calls.append(1) or whole(*a))
    op = make("reinhard2002")
    np.asarray(op(natural((8, 8))))  # 64 pixels > 50
    assert calls
    calls.clear()
    np.asarray(op(natural((5, 9))))  # 45 pixels
    assert not calls


@pytest.mark.parametrize("name", ["reinhard2002", "mantiuk2008"])
def test_eager_measure_traces_only_the_branch_taken(name, monkeypatch):
    traced = []
    prepare = _base.prepare
    monkeypatch.setattr(_base, "prepare", lambda *a: traced.append(1) or prepare(*a))
    op = make(name)
    clean = natural((11, 7))
    measured = op.measure(clean)
    assert not traced, "measuring a clean image compiled the masked path"
    bad = clean.copy()
    bad[1, 1] = np.nan
    measured_bad = op.measure(bad)
    assert traced
    both = eqx.filter_jit(lambda o, v: o.measure(v))  # traced: both branches
    for got, img in ((measured, clean), (measured_bad, bad)):
        ref = both(op, img)
        for (k, a), (_, b) in zip(got.parameters().items(), ref.parameters().items(), strict=True):
            if isinstance(a, float):
                np.testing.assert_allclose(a, b, rtol=1e-5, err_msg=f"{name}/{k}")
