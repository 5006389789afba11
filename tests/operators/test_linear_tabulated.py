"""Linear operator (direct, ISO 12232 exposure, EV100) and the tabulated curve."""

import json

import numpy as np
import pytest
from colour_hdri.exposure import dsc as cx
from hypothesis import given, settings, strategies as st
from scipy.interpolate import PchipInterpolator

import hdrjax
from hdrjax.operators import Q_FACTOR, Linear, Tabulated

from .cases import natural


def test_q_factor_matches_colour_hdri():
    np.testing.assert_allclose(Q_FACTOR, cx.q_factor(), rtol=1e-12)


def test_exposure_saturates_at_iso12232_luminance(x64):
    t, N, S = 1 / 125, 8.0, 200.0
    L_sat = 78 * N**2 / (Q_FACTOR * S * t)
    # colour-hdri: H_SBS = H S / 78 is 1 at saturation for focus at infinity, no flare
    H = cx.arithmetic_mean_focal_plane_exposure(L_sat, N, t)
    np.testing.assert_allclose(H * S / 78, 1.0, rtol=1e-9)
    op = Linear(exposure_time=t, f_number=N, iso=S).measure(np.ones((2, 2, 3)))
    np.testing.assert_allclose(float(op.L_max), L_sat, rtol=1e-12)
    # EV100 route agrees, and with colour-hdri's Lagarde 2014 scale factor
    ev = float(cx.exposure_value_100(N, t, S))
    op_ev = Linear(ev100=ev).measure(np.ones((2, 2, 3)))
    np.testing.assert_allclose(float(op_ev.L_max), L_sat, rtol=1e-9)
    np.testing.assert_allclose(
        1 / float(op_ev.L_max), cx.photometric_exposure_scale_factor_Lagarde2014(ev), rtol=1e-9
    )


@pytest.mark.parametrize(
    "kw", [{}, {"ev100": 3.0}, {"exposure_time": 0.01, "f_number": 4.0, "iso": 100.0}]
)
def test_measured_linear_has_a_curve(kw):
    """Once measured, the curve is there whichever way L_max was given: the exposure
    settings left unset only derive L_max (they once made ``curve`` refuse, and with it
    ``hdrjax.plot.tone_curve``)."""
    op = Linear(**kw).measure(natural())
    L = np.array([0.0, 1.0, 10.0], np.float32)
    np.testing.assert_allclose(np.asarray(op.curve(L)), L / float(op.L_max), rtol=1e-6)
    with pytest.raises(ValueError, match="unset parameters: L_max"):
        Linear().curve(L)


def test_linear_maps_L_max_to_white(x64):
    rgb = natural(dtype=np.float64)
    out = np.asarray(hdrjax.tonemap(rgb, "linear", L_max=7.0))
    np.testing.assert_allclose(out, rgb / 7.0, rtol=1e-12)
    auto = np.asarray(hdrjax.tonemap(rgb, "linear"))
    np.testing.assert_allclose((auto @ np.array(hdrjax.REC709_WEIGHTS)).max(), 1.0, rtol=1e-12)


@pytest.mark.parametrize(
    "kw",
    [
        dict(exposure_time=0.01),
        dict(L_max=2.0, ev100=3.0),
        dict(exposure_time=0.01, f_number=2, iso=100, L_max=3.0),
    ],
)
def test_linear_rejects_inconsistent_parameters(kw):
    with pytest.raises(ValueError, match="linear"):
        Linear(**kw)


TABLE = dict(luminance=[0.01, 0.1, 1.0, 10.0, 100.0], display=[0.0, 0.1, 0.45, 0.8, 1.0])


@pytest.mark.parametrize("method", ["pchip", "linear"])
def test_tabulated_interpolates_in_log_luminance(x64, method):
    L = np.logspace(-2, 2, 200)
    rgb = np.repeat(L[None, :, None], 3, axis=2)
    out = np.asarray(hdrjax.tonemap(rgb, "tabulated", interpolation=method, **TABLE))[0, :, 0]
    x = np.log10(TABLE["luminance"])
    if method == "pchip":
        ref = PchipInterpolator(x, TABLE["display"])(np.log10(L))
    else:
        ref = np.interp(np.log10(L), x, TABLE["display"])
    np.testing.assert_allclose(out, ref, atol=1e-12)
    # outside the table: linear ramp to 0 below, last value above
    ends = np.array([[[0.005] * 3, [1000.0] * 3]])
    e = np.asarray(hdrjax.tonemap(ends, "tabulated", **TABLE))[0, :, 0]
    np.testing.assert_allclose(e, [0.0 * 0.5, 1.0], atol=1e-12)


@settings(deadline=None, max_examples=20)
@given(st.lists(st.floats(0.0, 1.0), min_size=2, max_size=8))
def test_tabulated_is_monotone(steps):
    display = np.cumsum(steps)
    lum = np.logspace(-1, 3, len(display))
    L = np.logspace(-2, 4, 300)
    rgb = np.repeat(L[None, :, None], 3, axis=2).astype(np.float32)
    out = np.asarray(hdrjax.tonemap(rgb, "tabulated", luminance=lum, display=display))[0, :, 0]
    # rgb · Ld/L rounds each output in float32; allow a few ulps of the value, not of 1.
    tol = 4 * np.finfo(np.float32).eps * np.abs(out[1:])
    assert np.all(np.diff(out) >= -tol)


def test_table_files_round_trip_and_errors(tmp_path):
    op = Tabulated(**TABLE)
    for name in ("curve.csv", "curve.json"):
        p = tmp_path / name
        op.to_file(p)
        back = Tabulated.from_file(p)
        np.testing.assert_array_equal(np.asarray(back.luminance), np.asarray(op.luminance))
        np.testing.assert_array_equal(np.asarray(back.display), np.asarray(op.display))
    hand = tmp_path / "hand.csv"
    hand.write_text("# edited by hand\nluminance,display\n1,0.2\n10,0.9\n")
    np.testing.assert_allclose(np.asarray(Tabulated.from_file(hand).display), [0.2, 0.9])
    bad = {
        "empty.csv": "luminance,display\n",
        "down.csv": "luminance,display\n1,0.5\n10,0.2\n",
        "order.csv": "luminance,display\n10,0.5\n1,0.7\n",
        "zero.csv": "luminance,display\n0,0.1\n1,0.7\n",
        "words.csv": "luminance,display\n1,a\n",
        "bad.json": json.dumps({"lum": [1, 2]}),
    }
    for name, text in bad.items():
        p = tmp_path / name
        p.write_text(text)
        with pytest.raises(ValueError, match=name.replace(".", r"\.")):
            Tabulated.from_file(p)
    with pytest.raises(ValueError, match="non-monotone"):
        Tabulated(luminance=[1, 2, 3], display=[0.1, 0.5, 0.3])


def test_tabulated_knots_are_differentiable():
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    rgb = jnp.asarray(natural())
    op = Tabulated(**TABLE)
    g = jax.grad(lambda o: jnp.sum(o(rgb)))(op)
    assert np.all(np.isfinite(np.asarray(g.display))) and np.any(np.asarray(g.display) > 0)
    del eqx
