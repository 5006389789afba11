"""hypothesis properties the conformance issue asks for that other test files do not already
state: scale invariance of the auto-exposed operators, desaturate_highlights at T = L_max,
bit-exact (or format-precision) round trips of every file format with hard values, and the
inverse pairs of the colour/brightness transforms.

Already elsewhere (not repeated): monotone tone curves (tests/operators/test_conformance.py,
test_reinhard2002.py, test_linear_tabulated.py), direction-convention round trips
(tests/lights/test_geometry.py), saturation never increasing (tests/display/test_desaturate.py).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp

import hdrjax
import hdrjax.io as hio
import hdrjax.vision as hv
from hdrjax.display import srgb_decode, srgb_encode

from ..conftest import enable_x64
from ..operators.cases import make, natural

# Operators that declare themselves scale invariant: every statistic is measured from the
# image and enters only as a ratio L / (image statistic), so the scene's scale must not
# matter. (tumblin*, filmic, gamma, logarithmic*, simple, reinhard2004 and tabulated use
# absolute or fixed levels by design.)
AUTO_EXPOSED = [n for n in hdrjax.operator_names() if hdrjax.get_operator(n).scale_invariant]


def test_the_scale_invariant_operators_are_declared():
    """Not vacuous: the eight operators this test covered by name before the declaration."""
    assert set(AUTO_EXPOSED) >= {
        "exponential",
        "exponentiation_mapping",
        "linear",
        "normalisation",
        "reinhard2002",
        "reinhard2002_auto",
        "reinhard2002_local",
        "schlick1994",
    }


@pytest.mark.parametrize("name", AUTO_EXPOSED)
def test_auto_exposed_operators_are_scale_invariant(name):
    assert name in hdrjax.operator_names()
    kw = (
        {"delta": 0.0}
        if "delta" in hdrjax.operators.parameter_names(hdrjax.get_operator(name))
        else {}
    )
    op = make(name, **kw)
    img = natural()
    f = eqx.filter_jit(lambda o, x: o(x))
    ref = np.asarray(f(op, img))

    # k from 2^-40 to 2^40 (any mantissa): far beyond any exposure a file would hold
    @settings(deadline=None, max_examples=12)
    @given(st.floats(-40.0, 40.0))
    def check(log2k):
        k = np.float32(2.0**log2k)
        out = np.asarray(f(op, img * k))
        # histogram percentiles may move by one bin when ln(k L) rounds differently
        np.testing.assert_allclose(out, ref, rtol=1e-3, atol=1e-4, err_msg=f"{name}, k={k}")

    check()


_images = hnp.arrays(
    np.float32,
    st.tuples(st.integers(1, 5), st.integers(1, 6), st.just(3)),
    # normal floats: XLA:CPU flushes subnormal inputs to zero
    elements=st.floats(0.0, 1e4, width=32, allow_subnormal=False),
)


@settings(deadline=None, max_examples=15)
@given(_images)
def test_desaturate_highlights_at_threshold_max_is_identity_and_idempotent(img):
    """T = L_max: nothing is above the threshold (module docstring), so the step is the
    identity, hence idempotent."""
    T = float(np.max(np.asarray(hdrjax.luminance(img))))
    once = np.asarray(hdrjax.desaturate_highlights(img, T))
    np.testing.assert_array_equal(once, img)
    twice = np.asarray(hdrjax.desaturate_highlights(once, T))
    np.testing.assert_array_equal(twice, once)


# file round trips: shapes down to 1×1 and the hard values each format can store
_hard32 = st.one_of(
    st.floats(width=32, allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-42, 65504.0, 3.4e38, -1e-30]),
)


def _arrays(elements, max_side=6):
    return hnp.arrays(
        np.float32,
        st.tuples(st.integers(1, max_side), st.integers(1, max_side), st.just(3)),
        elements=elements,
    )


def _same(a, b):
    """Bit-identical, NaN payloads aside."""
    a, b = np.asarray(a, np.float32), np.asarray(b, np.float32)
    assert a.shape == b.shape
    nan = np.isnan(a)
    np.testing.assert_array_equal(np.isnan(b), nan)
    np.testing.assert_array_equal(a[~nan].view(np.uint32), b[~nan].view(np.uint32))


@settings(deadline=None, max_examples=20)
@given(_arrays(_hard32))
def test_pfm_and_float_exr_round_trips_are_bit_exact(tmp_path_factory, img):
    d = tmp_path_factory.mktemp("rt")
    for name, kw in (("a.pfm", {}), ("a.exr", {"pixel_type": "float"})):
        back = hio.read(hio.write(d / name, img, **kw), sidecars=False).image
        _same(back, img)


@settings(deadline=None, max_examples=20)
@given(_arrays(st.floats(width=16, allow_nan=True, allow_infinity=True)))
def test_half_exr_round_trip_is_exact_for_half_values(tmp_path_factory, img):
    back = hio.read(
        hio.write(tmp_path_factory.mktemp("rt") / "h.exr", img, pixel_type="half"),
        sidecars=False,
    ).image
    _same(back, img)


@settings(deadline=None, max_examples=20)
@given(_arrays(st.floats(0.0, float(np.float32(1e30)), width=32)))
def test_radiance_round_trip_within_rgbe_precision(tmp_path_factory, img):
    """RGBE keeps 8 mantissa bits relative to the largest channel ``m``: with
    ``2^(e-1) <= m < 2^e`` every channel is truncated to a multiple of ``2^(e-8)`` (OpenCV's
    convention, which hdrjax follows: no half-step on decoding), so it is within one step
    below its value; values below RGBE's smallest exponent come back black."""
    back = hio.read(hio.write(tmp_path_factory.mktemp("rt") / "r.hdr", img), sidecars=False).image
    assert back.shape == img.shape and back.dtype == np.float32
    m = np.max(img, axis=-1, keepdims=True).astype(np.float64)
    lit = m[..., 0] >= 2.0**-120
    step = 2.0 ** (np.floor(np.log2(np.where(m > 0, m, 1.0))) + 1 - 8)
    err = img.astype(np.float64) - back
    assert np.all(err[lit] >= -1e-6 * np.broadcast_to(m, img.shape)[lit])
    assert np.all(err[lit] <= np.broadcast_to(step, img.shape)[lit] * 1.0001)
    assert np.all(back[~lit] <= 2.0**-120)


@settings(deadline=None, max_examples=15)
@given(st.lists(st.floats(0.0, 1.0, width=32), min_size=1, max_size=32))
def test_srgb_decode_inverts_encode(values):
    x = jnp.asarray(values, jnp.float32)
    np.testing.assert_allclose(srgb_decode(srgb_encode(x)), x, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(srgb_encode(srgb_decode(x)), x, rtol=1e-5, atol=1e-7)


@settings(deadline=None, max_examples=30)
@given(
    st.lists(st.floats(float(np.float32(1e-4)), 1e6, width=32), min_size=1, max_size=16),
    st.floats(1e-3, 1e4),
)
def test_fechner_luminance_inverts_brightness(values, L_a):
    L = jnp.asarray(values, jnp.float32)
    back = hv.fechner_luminance(hv.fechner_brightness(L, L_a), L_a)
    np.testing.assert_allclose(back, L, rtol=1e-4)


@settings(deadline=None, max_examples=20)
@given(
    hnp.arrays(np.float64, (4, 3), elements=st.floats(1e-2, 1e4)),
    st.floats(1.0, 1e3),
)
def test_cone_opponent_space_round_trip(xyz, Yb):
    """ConeOpponentSpace.inverse(forward(XYZ)) = XYZ at the same background."""
    space = hv.ConeOpponentSpace()
    with enable_x64():
        bg = tuple(jnp.asarray(v) for v in (0.95 * Yb, Yb, 1.09 * Yb))
        XYZ = tuple(jnp.asarray(xyz[:, i]) for i in range(3))
        back = space.inverse(space.forward(XYZ, bg), bg)
        # a and b are differences of cube roots: cancellation costs a few digits
        np.testing.assert_allclose(np.stack(back, -1), xyz, rtol=1e-7)
