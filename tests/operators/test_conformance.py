"""Registry-driven conformance: every registered operator, without anyone listing it.

Hard cases from the foundation issue and issues 10 and 16 (tests/operators/cases.py:
hard values, one kind of bad pixel at a time, every brightness scale of the dtype) in
float16, float32 and float64, degenerate shapes, finite gradients (image and parameters,
bad pixels and scales included), jit == eager, vmap == loop, batch-shape independence, and
NaN/Inf isolation.
"""

import equinox as eqx
import jax
import numpy as np
import pytest

import hdrjax
from hdrjax.operators import AbstractLuminanceCurve, parameter_names

from ..conftest import RTOL32
from .cases import (
    SINGLE_PIXEL,
    families,
    hard_cases,
    make,
    natural,
    scale_cases,
)

NAMES = hdrjax.operator_names()
# neighbourhood operators (a finite halo; tested against NumPy models in their own files)
LOCAL = tuple(n for n in NAMES if 0 < max(make(n).halo((64, 64, 3))) < float("inf"))


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
    """Every family (hard values, bad pixels, every scale from the smallest normal to the
    largest finite value of the dtype): finite where the input is finite."""
    if dtype == np.float64:
        request.getfixturevalue("x64")
    op = make(name)
    cases = families(dtype)
    batch = np.stack(list(cases.values()))  # one compile: frames are independent
    # called as users call it: float16 is promoted before the operator's compiled function,
    # which the float32 case then reuses (the same shape)
    outs = np.asarray(op(batch))
    # half floats are computed and returned in the default float (float32 here)
    assert outs.dtype == (np.float32 if dtype == np.float16 else dtype)
    failed = []
    for (case, img), out in zip(cases.items(), outs, strict=True):
        try:
            _check_outputs(name, case, img, out)
        except AssertionError as e:  # every failing family, not only the first
            failed.append(str(e).splitlines()[0])
    assert not failed, f"{len(failed)} families: " + "; ".join(failed)
    if dtype == np.float64:  # float16/32: the float32 program, test_conformance_shapes.py
        one = SINGLE_PIXEL.astype(dtype)
        _check_outputs(name, "single_pixel", one, np.asarray(op(one)))
    # +Inf luminance is white, -Inf black, a NaN channel makes the pixel NaN
    out = outs[list(cases).index("nan_and_inf")]
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
        # one row of 64 pixels whatever the example's length (the brightest repeated): the
        # measured operator maps each pixel by itself, and one shape is one compile
        L = np.pad(L, (0, 64 - L.size), mode="edge")
        grey = np.repeat(L[None, :, None], 3, axis=2)
        out = np.asarray(f(op, grey))[0, :, 1]
        assert np.all(np.diff(out) >= -1e-6 * np.maximum(np.abs(out[1:]), 1e-30)), name

    check()


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize(
    "name,params", [("logarithmic", dict(q=3.0, k=2.0)), ("schlick1994", dict(p=20.0))]
)
def test_dim_and_bright_images_keep_their_values(name, params, dtype, request):
    """Issue 16.2: logarithmic and Schlick give colour-hdri's values (the formulas in
    float64 NumPy, as in test_colour_hdri_parity.py) for the natural image at every scale
    of the dtype, not only where ``1 + k L_max`` differs from 1 (logarithmic) or the
    luminance floor is far below ``L_max`` (Schlick). Compared at the pixels whose channels
    are normal floats (XLA:CPU flushes subnormals to zero); logarithmic up to L = 1e37 in
    float32 (above, its ratio ``L_d / L`` is below the smallest normal float: the shared
    mapping's concern, whose outputs the scale families check)."""
    if dtype == np.float64:
        request.getfixturevalue("x64")
    frames = scale_cases(dtype, 0, float("inf"))
    batch = np.stack(list(frames.values()))
    outs = np.asarray(eqx.filter_jit(lambda o, x: o(x))(make(name, **params), batch))
    w = np.asarray(hdrjax.REC709_WEIGHTS)
    fi = np.finfo(dtype)
    compared = 0
    for family, img, out in zip(frames, batch, outs, strict=True):
        x = img.astype(np.float64)
        L = x @ w
        L_max = L.max()
        if name == "logarithmic":
            with np.errstate(over="ignore"):  # 3 L beyond float64's range: ln 3 + ln L
                num = np.where(L < 1, np.log1p(3 * L), np.log(L) + np.log(3 + 1 / L))
            Ld = num / (
                np.log(L_max) + np.log(2 + 1 / L_max) if L_max >= 1 else np.log1p(2 * L_max)
            )
            keep = L < (1e37 if dtype == np.float32 else 1e300)
        else:
            r = L / L_max
            Ld = 20 * r / (19 * r + 1)
            keep = np.ones(L.shape, bool)
        keep &= np.all(x * w >= fi.tiny, axis=-1)  # every term of the luminance normal
        if not keep.any():  # the frame at finfo.tiny: flushed to black
            continue
        compared += 1
        ref = x * (Ld / L)[..., None]
        np.testing.assert_allclose(
            out[keep], ref[keep], rtol=RTOL32 if dtype == np.float32 else 1e-12, err_msg=family
        )
    assert compared >= len(frames) - 2  # all but the frames at (and next to) tiny
