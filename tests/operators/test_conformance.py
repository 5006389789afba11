"""Registry-driven conformance: every registered operator, without anyone listing it.

Hard cases from the foundation issue and issue 10 (tests/operators/cases.py) in float16,
float32 and float64, degenerate shapes, finite gradients, jit == eager,
vmap == loop, batch-shape independence, and NaN/Inf isolation.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax.operators import AbstractLuminanceCurve, parameter_names

from ..conftest import RTOL32, enable_x64
from .cases import SINGLE_PIXEL, hard_cases, make, natural

NAMES = hdrjax.operator_names()
LOCAL = ("reinhard2002_local", "reinhard2002_auto")  # neighbourhoods: test_reinhard2002.py


def test_registry_has_the_required_operators():
    required = {
        "reinhard2002",
        "reinhard2002_local",
        "reinhard2002_auto",
        "tumblin_reinhard",
        "linear",
        "tabulated",
        "simple",
        "normalisation",
        "gamma",
        "logarithmic",
        "exponential",
        "logarithmic_mapping",
        "exponentiation_mapping",
        "schlick1994",
        "tumblin1999",
        "reinhard2004",
        "filmic",
    }
    assert required <= set(NAMES)


def _check_outputs(name, case, img, out):
    bad_in = ~np.all(np.isfinite(img), axis=-1)
    nan_in = np.any(np.isnan(img), axis=-1)
    assert np.all(np.isfinite(out[~bad_in])), f"{name}/{case}: non-finite output at finite pixels"
    assert np.all(np.isnan(out[nan_in])), f"{name}/{case}: NaN pixel lost"
    assert np.all(np.isfinite(out[bad_in & ~nan_in])), f"{name}/{case}: Inf pixel not mapped"
    if case == "zeros":  # no light in, no light out
        np.testing.assert_allclose(out, 0.0, atol=1e-6, err_msg=name)


@pytest.mark.parametrize("dtype", [np.float16, np.float32, np.float64])
@pytest.mark.parametrize("name", NAMES)
def test_hard_cases_stay_finite(name, dtype, request):
    if dtype == np.float64:
        request.getfixturevalue("x64")
    op = make(name)
    cases = hard_cases(dtype)
    batch = np.stack(list(cases.values()))  # one compile: frames are independent
    outs = np.asarray(eqx.filter_jit(lambda o, x: o(x))(op, batch))
    # half floats are computed and returned in the default float (float32 here)
    assert outs.dtype == (np.float32 if dtype == np.float16 else dtype)
    for (case, img), out in zip(cases.items(), outs, strict=True):
        _check_outputs(name, case, img, out)
    one = SINGLE_PIXEL.astype(dtype)
    _check_outputs(name, "single_pixel", one, np.asarray(op(one)))
    # +Inf luminance is white, -Inf black, a NaN channel makes the pixel NaN
    out = outs[-1]
    np.testing.assert_array_equal(out[1, 2], 1.0)
    np.testing.assert_array_equal(out[5, 5], 0.0)
    assert np.all(np.isnan(out[4, 5]))


@pytest.mark.parametrize("name", [n for n in NAMES if n not in LOCAL])
def test_bad_pixels_do_not_reach_statistics_or_neighbours(name):
    """An image with NaN/Inf pixels maps its finite pixels exactly as the same image whose
    bad pixels are replaced by a copy of a finite pixel, when both are mapped with the
    parameters measured on the finite pixels only."""
    op = make(name)
    img = hard_cases(np.float32)["nan_and_inf"]
    bad = ~np.all(np.isfinite(img), axis=-1)
    finite_only = img[~bad][None]  # (1, n, 3): order-free statistics
    measure = eqx.filter_jit(lambda o, x: o.measure(x))
    ref_op = measure(op, finite_only)
    got_op = measure(op, img)
    for (k, a), (_, b) in zip(
        ref_op.parameters().items(), got_op.parameters().items(), strict=True
    ):
        if isinstance(a, float):
            np.testing.assert_allclose(b, a, rtol=RTOL32, err_msg=f"{name}/{k}")
    patched = np.where(bad[..., None], img[~bad][0], img)
    apply = eqx.filter_jit(lambda o, x: o(x))
    out, ref = np.asarray(apply(ref_op, np.stack([img, patched])))
    np.testing.assert_allclose(out[~bad], ref[~bad], rtol=RTOL32, atol=1e-7)


@pytest.mark.parametrize("name", NAMES)
def test_gradients_are_finite(name):
    cases = hard_cases(np.float32)
    batch = jnp.asarray(
        np.stack([v for k, v in cases.items() if k != "nan_and_inf"] + [natural((8, 8))])
    )
    op = make(name)
    params, static = eqx.partition(op, eqx.is_inexact_array)

    def loss(p, x):
        out = eqx.combine(p, static)(x)
        return jnp.sum(jnp.where(jnp.isfinite(out), out, 0.0))

    gp, gx = jax.jit(jax.grad(loss, argnums=(0, 1)))(params, batch)
    for leaf in jax.tree_util.tree_leaves((gp, gx)):
        assert np.all(np.isfinite(np.asarray(leaf))), name
    assert np.any(np.asarray(gx[-1]) != 0), name  # the output depends on the image


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


@pytest.mark.parametrize("name", NAMES)
def test_jit_equals_eager_and_vmap_equals_loop(name):
    op = make(name)
    frames = np.stack([natural(seed=s) for s in range(3)])
    eager = np.stack([np.asarray(op(f)) for f in frames])
    jitted = np.asarray(eqx.filter_jit(lambda o, x: o(x))(op, frames))
    np.testing.assert_allclose(jitted, eager, rtol=RTOL32, atol=1e-6)
    # batch shape does not matter: (3, H, W, 3) vs (3, 1, H, W, 3)
    nested = np.asarray(op(frames[:, None]))[:, 0]
    np.testing.assert_allclose(nested, eager, rtol=RTOL32, atol=1e-6)
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
def test_parameters_are_declared(name):
    cls = hdrjax.get_operator(name)
    assert cls.name == name
    with pytest.raises(ValueError, match="valid"):
        hdrjax.make_operator(name, not_a_parameter=1.0)
    assert len(parameter_names(cls)) >= 1 or name == "simple"


CURVES = [n for n in NAMES if issubclass(hdrjax.get_operator(n), AbstractLuminanceCurve)]


@pytest.mark.parametrize("name", CURVES)
def test_global_curves_are_monotone_in_luminance(name):
    """hypothesis: for every global luminance curve, brighter grey pixels never get darker."""
    from hypothesis import given, settings, strategies as st

    op = eqx.filter_jit(lambda o, x: o.measure(x))(make(name), natural())
    f = jax.jit(lambda o, x: o(x))

    @settings(deadline=None, max_examples=15)
    @given(st.lists(st.floats(1e-4, 1e4), min_size=2, max_size=64))
    def check(values):
        L = np.sort(np.asarray(values, np.float32))
        grey = np.repeat(L[None, :, None], 3, axis=2)
        out = np.asarray(f(op, grey))[0, :, 1]
        assert np.all(np.diff(out) >= -1e-6 * np.maximum(np.abs(out[1:]), 1e-30)), name

    check()
