"""analyze/simulate: selection rules on synthetic and real scenes, the no-trace guarantee,
transformations, hard cases, and the refusal to guess absolute luminance."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.vision as hv

from ..conftest import DATA, RTOL32, shared_file

TINT = np.array([1.0, 0.85, 0.7])


def scene(h, w, lo, hi, seed=0):
    rng = np.random.default_rng(seed)
    return (10 ** rng.uniform(np.log10(lo), np.log10(hi), (h, w, 1)) * TINT).astype(np.float32)


def daylight():
    return scene(96, 192, 300.0, 3000.0)  # 10:1, bright


def night_street():
    return scene(256, 512, 0.02, 0.5)  # 25:1 (no veil), mesopic; 40° over 512 px


def dark_room_with_lamp():
    img = scene(96, 192, 0.05, 0.5)
    img[40:44, 90:94] = 2e4  # a bright lamp: range > 90:1
    return img


# -- selection ---------------------------------------------------------------------------


def test_daylight_selects_nothing_and_costs_nothing():
    img = daylight()
    out, rep = hv.simulate(img, 40.0, scale=1.0)
    assert rep.selected == ()
    np.testing.assert_array_equal(np.asarray(out), img)  # nothing applied (nor compiled)
    for d in rep.decisions.values():
        assert not d.applies and d.reason
    assert rep.luminance_p05 >= hv.TOP_MESOPIC
    assert rep.adaptation_global > 79.4


def test_night_street_selects_colour_loss_and_acuity_but_no_veil():
    rep = hv.analyze(night_street(), 40.0, scale=1.0)
    assert {"acuity", "colour_loss", "blue_shift", "contrast"} <= set(rep.selected)
    assert "glare" not in rep.selected
    a = rep.decisions["acuity"]
    assert a.value == pytest.approx(float(hv.acuity(rep.luminance_p05)), rel=RTOL32)
    assert a.threshold == pytest.approx(rep.view.samples_per_degree) and a.value < a.threshold
    assert rep.decisions["glare"].value == pytest.approx(math.log(25.0), abs=0.05)
    assert rep.glare_variant == "mesopic"


def test_dark_room_with_lamp_selects_glare():
    rep = hv.analyze(dark_room_with_lamp(), 40.0, scale=1.0)
    assert "glare" in rep.selected
    assert rep.luminance_max == pytest.approx(2e4, rel=RTOL32)
    assert rep.dynamic_range == pytest.approx(math.log(rep.luminance_max / rep.luminance_min))
    text = str(rep)
    assert "glare" in text and "90:1" in text


@pytest.mark.parametrize("level, colour", [(5.60, True), (5.65, False), (5.62e-3, True)])
def test_mesopic_threshold_of_the_colour_rule(level, colour):
    img = np.full((16, 32, 3), level, np.float32)
    rep = hv.analyze(img, 40.0, scale=1.0)
    assert rep.luminance_p05 == pytest.approx(level, rel=RTOL32)
    assert ("colour_loss" in rep.selected) is colour


@pytest.mark.parametrize("ratio, veil", [(85.0, False), (95.0, True)])
def test_90_to_1_rule_of_the_veil(ratio, veil):
    img = np.full((32, 64, 3), 10.0, np.float32)
    img[:, 32:] *= ratio  # two halves, whole foveal blocks on each side
    rep = hv.analyze(img, 40.0, scale=1.0)
    assert rep.dynamic_range == pytest.approx(math.log(ratio), rel=RTOL32)
    assert ("glare" in rep.selected) is veil
    assert math.exp(4.5) == pytest.approx(90.0, rel=1e-3)


def np_samples(Y, block):
    """pcond's samples as documented: 1° block means + every (b//4)-th pixel."""
    H, W = Y.shape
    by, bx = block
    hb, wb = -(-H // by), -(-W // bx)
    fov = np.array(
        [
            [Y[i * by : (i + 1) * by, j * bx : (j + 1) * bx].mean() for j in range(wb)]
            for i in range(hb)
        ]
    )
    sy, sx = max(1, by // 4), max(1, bx // 4)
    return fov, Y[sy // 2 :: sy, sx // 2 :: sx]


def test_adaptation_is_pcond_mean_brightness():
    img = scene(40, 60, 0.1, 100.0, seed=4).astype(np.float64)
    rep = hv.analyze(img, 40.0, scale=1.0)
    Y = img @ np.array([0.2126, 0.7152, 0.0722])
    fov, sub = np_samples(Y, rep.view.fovea_block)
    expect = math.exp(0.5 * np.log(fov).mean() + 0.5 * np.log(sub).mean())
    assert rep.adaptation_global == pytest.approx(expect, rel=RTOL32)
    np.testing.assert_allclose(rep.adaptation_foveal, fov, rtol=RTOL32)
    assert rep.to_dict()["selected"] == list(rep.selected)


def test_effect_overrides():
    img = night_street()
    _, rep = hv.simulate(img[:32, :64], 40.0, {"glare": True, "contrast": False}, scale=1.0)
    from hdrjax.vision._simulate import select_effects

    assert select_effects({"glare": True, "contrast": False}, rep) == (
        "glare",
        "colour_loss",
        "blue_shift",
    )
    assert select_effects("all", rep) == hv.EFFECTS
    assert select_effects(["Color-Loss", "acuity"], rep) == ("acuity", "colour_loss")
    with pytest.raises(ValueError, match="unknown effect"):
        select_effects({"bloom": True}, rep)


def test_report_selects_what_simulate_applied():
    """issue 16: ``report.selected`` is what ``simulate`` applied, for every form of
    ``effects``; the image is compared with the named effects applied alone (an explicit
    set, whose report must name exactly that set), so a report that lists a disabled
    effect gives another image."""
    img = night_street()[:32, :64]  # test_effect_overrides' shape: its analysis compile
    img[12:14, 30:32] = 2e4  # a lamp: glare, besides the night effects
    rules = hv.analyze(img, 40.0, scale=1.0).selected
    assert rules[0] == "glare" and {"colour_loss", "contrast"} <= set(rules)

    given = set(rules[1:])  # the night effects without glare (one compile less below)
    out, rep = hv.simulate(img, 40.0, given, scale=1.0)
    assert rep.selected == rules[1:]  # the set given, in application order
    assert f"effects simulated: {', '.join(rules[1:])} (" in str(rep)  # not the rules'
    out, rep = hv.simulate(img, 40.0, "none", scale=1.0)
    assert rep.selected == ()
    np.testing.assert_array_equal(np.asarray(out), img)
    outs = {}
    for effects, want in (("auto", rules), ({"glare": False}, rules[1:])):
        out, rep = hv.simulate(img, 40.0, effects, scale=1.0)
        assert rep.selected == want, effects
        alone, _ = hv.simulate(img, 40.0, set(rep.selected), scale=1.0)
        np.testing.assert_array_equal(np.asarray(out), np.asarray(alone))
        assert rep.decisions["glare"].applies  # the rules' verdict stays in the report
        outs[str(effects)] = np.asarray(out)
    assert "effects simulated" not in str(hv.simulate(img, 40.0, scale=1.0)[1])
    assert not np.allclose(outs["auto"], outs["{'glare': False}"])  # glare made a difference


# -- what gets compiled ------------------------------------------------------------------


def _lowered(step, img):
    return jax.jit(lambda x: step(x)).lower(img).as_text()


def test_unselected_effects_are_not_traced():
    img = jnp.asarray(night_street()[:64, :128])
    none = hv.HumanVision.build(img.shape, 40.0, ())
    text = _lowered(none, img)
    assert "fft" not in text and "atan" not in text and "log" not in text
    glare = _lowered(hv.HumanVision.build(img.shape, 40.0, ("glare",)), img)
    assert "fft" in glare and "atan" not in glare
    colour = _lowered(hv.HumanVision.build(img.shape, 40.0, ("colour_loss",)), img)
    assert "fft" not in colour and "atan" not in colour
    acuity = _lowered(hv.HumanVision.build(img.shape, 40.0, ("acuity",)), img)
    assert "atan" in acuity and "fft" not in acuity
    every = _lowered(hv.HumanVision.build(img.shape, 40.0, hv.EFFECTS), img)
    assert len(every) > 3 * len(text)


# -- transformations ---------------------------------------------------------------------


def test_human_vision_jit_vmap_grad():
    imgs = jnp.stack(
        [jnp.asarray(dark_room_with_lamp()[:32, :48]), jnp.asarray(night_street()[:32, :48])]
    )
    imgs = imgs.at[0, 3, 3, 0].set(jnp.nan)
    step = hv.HumanVision.build((32, 48), 20.0, hv.EFFECTS, acuity_levels=2)
    loop = [np.asarray(step(x)) for x in imgs]  # step(x) is jit-compiled once for both
    batched = np.asarray(eqx.filter_jit(lambda s, x: jax.vmap(s)(x))(step, imgs))
    for i in range(2):
        np.testing.assert_allclose(batched[i], loop[i], rtol=RTOL32, equal_nan=True)
    nan = np.zeros(batched.shape, bool)
    nan[0, 3, 3, 0] = True
    assert np.isnan(batched[nan]).all() and np.isfinite(batched[~nan]).all()
    g = jax.jit(jax.grad(lambda x: jnp.sum(jnp.nan_to_num(step(x)))))(imgs[0])
    assert np.isfinite(np.asarray(g)).all() and np.abs(np.asarray(g)).sum() > 0


def test_simulate_float64_under_x64(x64):
    img = dark_room_with_lamp()[:24, :40].astype(np.float64)
    out, rep = hv.simulate(img, 20.0, "all", scale=1.0)
    assert out.dtype == np.float64 and np.isfinite(np.asarray(out)).all()


def test_simulate_refuses_under_trace():
    with pytest.raises(ValueError, match="HumanVision"):
        jax.jit(lambda x: hv.simulate(x, 40.0, scale=1.0)[0])(jnp.ones((8, 8, 3)))


# -- hard cases ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "shape, view",
    [
        ((1, 1, 3), 40.0),
        ((1, 37, 3), 40.0),
        ((16, 64, 3), hv.View(hfov=360.0, vfov=90.0, projection="equiangular")),
        ((16, 16, 3), hv.View(pixel_deg=1e-4)),
    ],
)
def test_shapes_and_fields_of_view(shape, view):
    img = np.asarray(scene(shape[0], shape[1], 0.01, 1e4, seed=7))
    out, rep = hv.simulate(img, view, "all", scale=1.0)
    assert out.shape == shape and np.isfinite(np.asarray(out)).all()
    assert set(rep.decisions) == set(hv.EFFECTS)


@pytest.mark.parametrize("fill", ["mixed", "zeros", "tiny"])
def test_hard_values(fill):
    img = scene(24, 32, 0.01, 1.0, seed=8)
    if fill == "mixed":  # negative values, NaN, Inf and a huge value in one image
        img[::3] *= -1.0
        img[5, 6] = np.nan
        img[7, 8, 2] = np.inf
        img[10, 10] = 1e30
    elif fill == "zeros":
        img[:] = 0.0
    elif fill == "tiny":
        img *= 1e-30
    out, rep = hv.simulate(img, 40.0, "all", scale=1.0)
    out = np.asarray(out)
    finite_in = np.isfinite(img).all(axis=-1)
    assert np.isfinite(out[finite_in]).all()
    np.testing.assert_array_equal(out[~finite_in], img[~finite_in])
    if fill == "zeros":
        # the rules call for nothing in the dark; "all" applied every effect (to zeros)
        assert not any(d.applies for d in rep.decisions.values()) and not np.any(out)
        assert rep.selected == hv.EFFECTS
        assert "no pixel" in rep.decisions["glare"].reason
    if fill == "mixed":
        assert rep.n_nonfinite == 2
        assert rep.luminance_max < 1e5  # 1e30 is beyond pcond's visible range


# -- units -------------------------------------------------------------------------------


class FakeLayered:
    def __init__(self, rgb, unit, white=None):
        self._rgb, self.unit, self.white_luminance, self.chromaticities = rgb, unit, white, None

    def rgb(self):
        return self._rgb


def test_relative_images_need_a_stated_scale():
    img = night_street()[:16, :16]
    with pytest.raises(ValueError, match="scale"):
        hv.analyze(img)
    with pytest.raises(ValueError, match="relative"):
        hv.analyze(FakeLayered(img, None))
    with pytest.raises(ValueError, match="illuminance"):
        hv.analyze(FakeLayered(img, "lx"))
    a = hv.analyze(FakeLayered(img, "cd/m²"))
    b = hv.analyze(img * 100, scale=0.01)
    assert a.luminance_p05 == pytest.approx(b.luminance_p05, rel=RTOL32)
    c = hv.analyze(FakeLayered(img / 179.0, "W/(sr·m²)"))  # Radiance radiance units
    assert c.luminance_p05 == pytest.approx(a.luminance_p05, rel=RTOL32)
    d = hv.analyze(FakeLayered(img / 50.0, None, white=50.0))  # EXR whiteLuminance
    assert d.luminance_p05 == pytest.approx(a.luminance_p05, rel=RTOL32)


# -- real images -------------------------------------------------------------------------


def test_real_image_cornell_box_with_a_stated_scale():
    from hdrjax.io import read

    img = read(DATA / "cornell_box.exr")
    Y = np.asarray(img.luminance(), np.float64)
    # a relative render, stated as a lit interior and as a night scene
    for scale in (1e4, 0.01):
        rep = hv.analyze(img, 50.0, scale=scale)
        _, sub = np_samples(Y * scale, rep.view.fovea_block)
        p05 = np.percentile(sub[(sub > 1e-7) & (sub < 1e5)], 5)
        assert rep.luminance_p05 == pytest.approx(p05, rel=2e-3)
        assert ("colour_loss" in rep.selected) == (p05 < 5.62)
        assert "glare" in rep.selected  # the lamp against the shadows
    assert {"colour_loss", "acuity"} <= set(rep.selected)  # the night one
    # energy: the glare output holds the input light minus what scatters past the border
    out, rep = hv.simulate(img, 50.0, ("glare",), scale=100.0, glare_radius_deg=8.0)
    rgb = np.asarray(img.rgb(), np.float64) * 100.0
    ones = np.ones(rgb.shape, np.float32)
    kappa = np.asarray(hv.glare(ones, 50.0, variant=rep.glare_variant, radius_deg=8.0))
    expect = (np.maximum(rgb, 0) * kappa).sum() + np.minimum(rgb, 0).sum()
    assert np.asarray(out, np.float64).sum() == pytest.approx(expect, rel=1e-4)


def test_real_image_tree_in_absolute_units():
    from hdrjax.io import read

    img = read(shared_file("Tree.exr"))
    assert img.white_luminance == pytest.approx(621.0)
    rep = hv.analyze(img)  # whiteLuminance makes it absolute: no scale needed
    assert rep.luminance_max == pytest.approx(621 * 10.62, rel=5e-3)
    assert "glare" in rep.selected  # a bright sky behind dark branches
    out, rep2 = hv.simulate(img, 40.0, ("glare",), glare_radius_deg=5.0)
    rgb = np.asarray(img.rgb(), np.float64) * 621.0
    ones = np.ones(rgb.shape, np.float32)
    kappa = np.asarray(hv.glare(ones, 40.0, variant=rep2.glare_variant, radius_deg=5.0))
    got = np.asarray(out, np.float64)
    np.testing.assert_allclose(got.sum(), (np.maximum(rgb, 0) * kappa).sum(), rtol=1e-4)


# -- composition with every tone-mapping operator -----------------------------------------


def test_composes_with_operators():
    """simulate returns a plain finite, non-negative float32 image of the input's shape: the
    domain every registered operator is tested on (tests/operators/test_conformance.py runs
    each over hard finite images), so three operators of different kinds stand for them all
    here (each one compiled is ~1 s of the suite)."""
    import hdrjax

    from ..operators.cases import natural

    img = natural() * 0.05  # (12, 16) lognormal scene, as a dim interior in cd/m²
    out, rep = hv.simulate(img, 10.0, ("acuity", "glare", "colour_loss"), scale=1.0)
    assert isinstance(out, jax.Array) and out.shape == img.shape and out.dtype == np.float32
    assert np.isfinite(out).all() and (np.asarray(out) >= 0).all()
    for name in ("reinhard2002", "drago2003", "durand2002"):
        shown = np.asarray(hdrjax.tonemap(out, name))
        assert shown.shape == img.shape and np.isfinite(shown).all(), name
        assert 0.0 < shown.mean() < 1.0, name
