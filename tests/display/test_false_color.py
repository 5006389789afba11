"""False colour: colours against matplotlib, special values, bands, iso-lines, legends."""

import jax
import jax.numpy as jnp
import matplotlib
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp

from hdrjax.display import FalseColorScale, false_color, false_color_scale, render_figure

from ..conftest import DATA

RNG = np.random.default_rng(5)


def _cm(name, t):
    """matplotlib's colour at t (nearest of its 256 entries)."""
    return np.asarray(matplotlib.colormaps[name](np.asarray(t, np.float64)))[..., :3]


def _cm_lerp(name, t):
    """The documented mapping: matplotlib's 256-entry table, interpolated linearly."""
    lut = matplotlib.colormaps[name](np.linspace(0, 1, 256))[:, :3]
    x = np.clip(np.asarray(t, np.float64), 0, 1) * 255
    return np.stack([np.interp(x, np.arange(256), lut[:, c]) for c in range(3)], axis=-1)


def test_linear_and_log_scales_take_the_colormap_colour():
    v = np.array([[0.0, 2.5, 5.0, 7.5, 10.0]], np.float32)
    fc = false_color(v, vmin=0, vmax=10, cmap="viridis", legend=False)
    # the 256-entry table is interpolated linearly: equal to matplotlib at its nodes
    np.testing.assert_allclose(
        np.asarray(fc.image)[0, [0, 2, 4]], _cm("viridis", [0, 0.5, 1]), atol=3e-3
    )
    lv = np.array([[1.0, 10.0, 100.0, 1000.0]], np.float32)
    fl = false_color(lv, vmin=1, vmax=1000, log=True, cmap=["black", "white"], legend=False)
    np.testing.assert_allclose(np.asarray(fl.image)[0, :, 0], [0, 1 / 3, 2 / 3, 1], atol=1e-6)


def test_special_values_get_their_documented_colours():
    v = np.array([[np.nan, np.inf, -np.inf, -1.0, 0.0, 0.5, 2.0]], np.float32)
    img = np.asarray(false_color(v, vmin=0.1, vmax=1, log=True, legend=False).image)[0]
    expect = {0: [1, 0, 1], 1: [0, 1, 1], 2: [0, 0, 0.5], 3: [0, 0, 0], 4: [0, 0, 0], 6: [1, 1, 1]}
    for i, c in expect.items():
        np.testing.assert_allclose(img[i], c, atol=2e-3, err_msg=f"pixel {i}")
    custom = false_color(
        v, vmin=0, vmax=1, under="red", over="#00ff00", nan=(0.5, 0.5, 0.5), legend=False
    )
    img = np.asarray(custom.image)[0]
    np.testing.assert_allclose(img[[3, 6, 0]], [[1, 0, 0], [0, 1, 0], [0.5, 0.5, 0.5]])


def test_bands_are_flat_and_isolines_follow_the_level():
    y, x = np.mgrid[0:40, 0:50].astype(np.float32)
    v = x * 2.0  # 0..98, increasing to the right
    fc = false_color(v, levels=[0, 25, 50, 75, 100], bands=True, cmap="turbo", legend=False)
    img = np.asarray(fc.image)
    cols = [_cm_lerp("turbo", (j + 0.5) / 4) for j in range(4)]
    np.testing.assert_allclose(img[5, 5], cols[0], atol=3e-3)  # v = 10
    np.testing.assert_allclose(img[5, 30], cols[2], atol=3e-3)  # v = 60
    assert len({tuple(np.round(c, 4)) for c in img[:, :12].reshape(-1, 3)}) == 1
    iso = np.asarray(
        false_color(v, vmin=0, vmax=100, isolines=[41], isoline_color="red", legend=False).image
    )
    line = np.all(np.isclose(iso, [1, 0, 0]), axis=-1)
    assert line[:, 20].all() and line.sum() == 40  # v crosses 41 between x = 20 and 21


def test_automatic_range_min_max_and_percentiles():
    v = RNG.lognormal(0, 1, size=(30, 40)).astype(np.float32)
    v[0, 0] = 1e6  # an outlier
    s = false_color(v, legend=False).scale
    assert (s.vmin, s.vmax) == (float(v.min()), float(v.max()))
    p = false_color(v, percentiles=(1, 99), log=True, legend=False).scale
    # hdrjax.stats.percentile: within one histogram bin of the order statistic x_(floor(q(n-1)))
    lo, hi = np.percentile(v, [1, 99], method="lower")
    np.testing.assert_allclose([p.vmin, p.vmax], [lo, hi], rtol=3e-3)


def test_legend_figure_has_label_unit_and_ticks():
    v = RNG.random((20, 30)).astype(np.float32) * 100
    v[3, 3] = np.nan
    fc = false_color(v, name="illuminance", unit="lx", ticks=[0, 25, 50, 100], vmin=0, vmax=100)
    cax = fc.legend.axes[0]
    assert cax.get_ylabel() == "illuminance [lx]"
    np.testing.assert_allclose(cax.get_yticks(), [0, 25, 50, 100])
    assert [t.get_text() for t in fc.legend.legends[0].get_texts()] == ["NaN"]  # only NaN occurs
    arr = render_figure(fc.legend)
    assert arr.shape == (400, 160, 3) and arr.min() >= 0 and arr.max() <= 1
    comp = fc.composite()
    assert comp.shape == (300, 30 + 150, 3)
    np.testing.assert_allclose(comp[:20, :30], np.asarray(fc.image), atol=1e-6)


def test_scale_reuses_on_other_images_and_batches():
    scale = false_color_scale(vmin=1, vmax=100, log=True, cmap="inferno")
    assert isinstance(scale, FalseColorScale)
    batch = RNG.lognormal(1, 1, size=(2, 8, 9)).astype(np.float32)
    out = np.asarray(jax.jit(lambda b: scale(b))(batch))
    np.testing.assert_allclose(out[1], np.asarray(scale(batch[1])), atol=1e-7)


def test_bad_arguments_raise_but_data_never_does():
    v = np.ones((5, 5), np.float32)
    for kw in (
        {"cmap": "no-such-map"},
        {"vmin": 2, "vmax": 1},
        {"log": True, "vmin": 0, "vmax": 1},
        {"bands": True, "levels": [1]},
        {"bands": True, "levels": [2, 1]},
        {"cmap": ["red"]},
        {"percentiles": (50, 10)},
    ):
        with pytest.raises(ValueError):
            false_color(v, legend=False, **kw)
    for data in (
        np.full((4, 4), np.nan),
        np.zeros((4, 4)),
        -np.ones((4, 4)),
        np.full((4, 4), np.inf),
    ):
        for log in (False, True):
            fc = false_color(data.astype(np.float32), log=log)
            assert np.isfinite(np.asarray(fc.image)).all()


@settings(deadline=None, max_examples=40)
@given(
    hnp.arrays(
        np.float32, (5, 6), elements=st.floats(width=32, allow_nan=True, allow_infinity=True)
    ),
    st.booleans(),
)
def test_any_values_give_colours_in_the_unit_cube(values, log):
    fc = false_color(values, log=log, legend=False, isolines=[0.0, 1.0])
    img = np.asarray(fc.image)
    assert img.shape == (5, 6, 3) and np.isfinite(img).all()
    assert img.min() >= 0 and img.max() <= 1


def test_cornell_box_luminance_in_false_colour():
    from hdrjax import io as hio, luminance

    img = hio.read(DATA / "cornell_box.exr")
    L = luminance(jnp.asarray(img.rgb()), img.luminance_weights)
    fc = false_color(L, vmin=0.01, vmax=1.0, log=True, legend=False)
    out = np.asarray(fc.image)
    Ln = np.asarray(L)
    np.testing.assert_allclose(out[Ln > 1.0], 1.0)  # the light: above the range, white
    inside = (Ln > 0.01) & (Ln < 1.0)
    t = (np.log(Ln[inside]) - np.log(0.01)) / (np.log(1.0) - np.log(0.01))
    np.testing.assert_allclose(out[inside], _cm_lerp("viridis", t), atol=2e-5)
