"""Every registered operator: degenerate shapes, float16 and float64 inputs, and jit and
vmap equal to eager calls.

Split from ``test_conformance.py`` (same registry, same cases) so that the test workers,
which take whole files, share the conformance suite's time."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax.operators._call import clean_operator_call

from ..conftest import RTOL32, enable_x64
from .cases import make, natural
from .test_conformance import NAMES


@pytest.mark.parametrize("name", NAMES)
def test_degenerate_shapes(name):
    """One pixel, one row, one column: finite, same shape (issue 10's shape list)."""
    op = make(name)
    for shape in [(1, 1), (1, 9), (7, 1)]:
        img = natural(shape)
        out = np.asarray(op(img))
        assert out.shape == img.shape and np.all(np.isfinite(out)), f"{name}: {shape}"


@pytest.mark.parametrize("name", NAMES)
def test_float16_input(name):
    img = natural().astype(np.float16)
    out = hdrjax.tonemap(
        img,
        name,
        **({} if name != "tabulated" else dict(luminance=[0.01, 1, 100], display=[0.02, 0.5, 1])),
    )
    assert out.dtype == jnp.float32
    ref = hdrjax.tonemap(
        img.astype(np.float32),
        name,
        **({} if name != "tabulated" else dict(luminance=[0.01, 1, 100], display=[0.02, 0.5, 1])),
    )
    np.testing.assert_allclose(out, ref, rtol=RTOL32)


NESTED = sorted(
    {"reinhard2002", "reinhard2002_local", "mantiuk2006", "fattal2002"}
    | {n for n in NAMES if hdrjax.get_operator(n).frames_in_sequence}
)
"""Operators whose nested batches are checked: :meth:`AbstractOperator.__call__` maps the
leading axes of every operator alike (``vmap``, or ``lax.map`` where
``frames_in_sequence``); a global curve, a local operator and two solvers stand for the
``vmap`` kind (a nested batch is one more compiled program an operator, about 3 s)."""


def test_nested_batches_cover_both_ways_of_mapping_frames():
    assert set(NESTED) <= set(NAMES)
    kinds = {hdrjax.get_operator(n).frames_in_sequence for n in NESTED}
    assert kinds == {True, False}


@pytest.mark.parametrize("name", NAMES)
def test_jit_equals_eager_and_vmap_equals_loop(name):
    op = make(name)
    frames = np.stack([natural(seed=s) for s in range(3)])
    eager = np.stack([np.asarray(op(f)) for f in frames])
    jitted = np.asarray(eqx.filter_jit(lambda o, x: o(x))(op, frames))
    atol = max(1e-6, op.rounding)  # budak2005: its colour transforms' conditioning
    np.testing.assert_allclose(jitted, eager, rtol=RTOL32, atol=atol)
    # batch shape does not matter: (3, H, W, 3) vs (3, 1, H, W, 3) (the base class's
    # recursion over batch axes: checked for each way it maps frames, NESTED)
    if name in NESTED:
        nested = np.asarray(op(frames[:, None]))[:, 0]
        np.testing.assert_allclose(nested, eager, rtol=RTOL32, atol=atol)
    # and each frame's statistics are its own
    assert not np.allclose(eager[0], np.asarray(op(frames[1])))


@pytest.mark.parametrize("name", NAMES)
def test_float64_agrees_with_float32(name):
    img = natural()
    out32 = np.asarray(make(name)(img))
    with enable_x64():
        out64 = np.asarray(make(name)(img.astype(np.float64)))
    assert out32.dtype == np.float32 and out64.dtype == np.float64
    np.testing.assert_allclose(out32, out64, rtol=2e-3, atol=1e-5)


@pytest.mark.parametrize("name", NAMES)
def test_clean_call_equals_the_checked_call(name):
    """The path batches and vision take for frames known to be finite (no check for bad
    pixels) maps as a plain call does: it once skipped mantiuk2008's own measurement, and
    every frame of ``hdrjax batch --method mantiuk2008`` failed."""
    op = make(name)
    img = natural()  # the shape of the tests above: op(img) is compiled already
    clean = np.asarray(eqx.filter_jit(clean_operator_call)(op, img))
    atol = max(1e-6, op.rounding)
    np.testing.assert_allclose(clean, np.asarray(op(img)), rtol=RTOL32, atol=atol)
