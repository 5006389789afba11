"""``simulate(..., then=op)`` (analysis and tone mapping in one call) against the two-call
composition ``op(simulate(...)[0])``, for every registered operator and every path (a
daylight scene: one program; a night scene: effects then the operator; bad pixels: the
masked analysis), and the deferred 5th percentile of its report against ``np.percentile``
and ``analyze``'s report."""

import math

import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
import hdrjax.vision as hv
from hdrjax.vision import _simulate
from hdrjax.vision._report import _selected_by_range, decide

from ..conftest import RTOL32
from ..operators.cases import make

TINT = np.array([1.0, 0.85, 0.7])
W709 = np.array([0.2126, 0.7152, 0.0722])


def scene(h, w, lo, hi, seed=0):
    rng = np.random.default_rng(seed)
    return (10 ** rng.uniform(np.log10(lo), np.log10(hi), (h, w, 1)) * TINT).astype(np.float32)


def daylight():
    return scene(48, 96, 300.0, 3000.0)


def night():
    img = scene(48, 96, 0.02, 0.5, seed=1)
    img[20:22, 40:42] = 2e4  # a lamp
    return img


def two_calls(img, name, **kw):
    out, rep = hv.simulate(img, 40.0, scale=1.0, **kw)
    return np.asarray(make(name)(jnp.asarray(out))), rep


@pytest.mark.parametrize("name", hdrjax.operator_names())
def test_daylight_then_equals_tonemap_of_simulate(name, monkeypatch):
    img = daylight()
    want, rep_want = two_calls(img, name)
    built = []
    monkeypatch.setattr(
        _simulate.HumanVision, "build", lambda *a, **k: built.append(a) or 1 / 0
    )  # no effect may even be prepared, let alone traced
    got, rep = hv.simulate(img, 40.0, scale=1.0, then=make(name))
    assert rep.selected == () and not built
    np.testing.assert_allclose(np.asarray(got), want, rtol=RTOL32, atol=1e-6)
    assert rep.to_dict() == rep_want.to_dict()


@pytest.mark.parametrize("name", ["reinhard2002", "exponential"])
def test_night_then_equals_tonemap_of_simulate(name):
    img = night()
    want, rep_want = two_calls(img, name)
    got, rep = hv.simulate(img, 40.0, scale=1.0, then=make(name))
    assert {"glare", "colour_loss", "contrast"} <= set(rep.selected)
    assert rep.selected == rep_want.selected
    np.testing.assert_allclose(np.asarray(got), want, rtol=RTOL32, atol=1e-6)


@pytest.mark.parametrize("bad", ["nan", "zero", "over"])
def test_bad_pixels_take_the_masked_analysis(bad):
    img = daylight()
    img[5, 7] = {"nan": np.nan, "zero": 0.0, "over": 2e5}[bad]
    want, rep_want = two_calls(img, "reinhard2002", effects={"glare": False})
    got, rep = hv.simulate(img, 40.0, {"glare": False}, scale=1.0, then="reinhard2002")
    assert rep.n_nonfinite == (1 if bad == "nan" else 0)
    np.testing.assert_allclose(np.asarray(got), want, rtol=RTOL32, atol=1e-6, equal_nan=True)
    assert rep.to_dict() == rep_want.to_dict()


def test_then_with_explicit_effects_and_none():
    img = daylight()
    got, _ = hv.simulate(img, 40.0, "none", scale=1.0, then="reinhard2002")
    want = hdrjax.tonemap(jnp.asarray(img), "reinhard2002")
    np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=RTOL32, atol=1e-6)
    want, _ = two_calls(img, "reinhard2002", effects=["acuity"])
    got, rep = hv.simulate(img, 40.0, iter(["acuity"]), scale=1.0, then="reinhard2002")
    assert rep.selected == ("acuity",)  # what was applied (the rules select nothing)
    assert not any(d.applies for d in rep.decisions.values())
    np.testing.assert_allclose(np.asarray(got), want, rtol=RTOL32, atol=1e-6)


def test_then_rejects_what_is_not_an_operator():
    with pytest.raises(ValueError, match="then: expected a tone-mapping operator"):
        hv.simulate(daylight(), 40.0, scale=1.0, then=lambda x: x)
    with pytest.raises(ValueError, match="unknown operator"):
        hv.simulate(daylight(), 40.0, scale=1.0, then="no-such-operator")


# -- the deferred 5th percentile -----------------------------------------------------------


def test_deferred_p05_is_numpys_percentile_and_analyze_s():
    img = scene(64, 128, 40.0, 4000.0, seed=3)
    _, rep = hv.simulate(img, 40.0, scale=1.0, then="linear")
    assert callable(rep.p05_source)  # the range decided: not computed yet
    by, bx = rep.view.fovea_block
    sy, sx = max(1, by // 4), max(1, bx // 4)
    sub = (np.asarray(img, np.float64) @ W709)[sy // 2 :: sy, sx // 2 :: sx]
    assert rep.luminance_p05 == pytest.approx(np.percentile(sub, 5), rel=RTOL32)
    assert rep.p05_source == rep.luminance_p05  # computed once; the luminance is let go
    ref = hv.analyze(img, 40.0, scale=1.0)
    assert not callable(ref.p05_source)
    assert rep.decisions == ref.decisions and rep.selected == ref.selected
    assert str(rep) == str(ref)


def test_range_straddling_a_threshold_computes_p05_at_once():
    img = scene(64, 128, 10.0, 40.0, seed=4)
    img[:2, :3] = 1.0  # 6 dark pixels: under 5.62 cd/m², fewer than 5 %
    _, rep = hv.simulate(img, 40.0, scale=1.0, then="reinhard2002")
    assert not callable(rep.p05_source)
    assert rep.luminance_min < hv.TOP_MESOPIC < rep.luminance_p05
    assert "colour_loss" not in rep.selected
    img[:, :16] = 1.0  # now an eighth of the image: the 5th percentile is 1 cd/m²
    _, rep = hv.simulate(img, 40.0, scale=1.0, then="reinhard2002")
    assert rep.luminance_p05 == pytest.approx(1.0, rel=RTOL32)
    assert {"colour_loss", "blue_shift"} <= set(rep.selected)


def test_selection_by_range_agrees_with_the_rules():
    """Whenever the range decides, every 5th percentile inside it gives the same verdicts
    as :func:`decide` (random scenes around each threshold, three views)."""
    rng = np.random.default_rng(7)
    decided = 0
    views = [
        hv.View(hfov=2.0).resolve(256, 512),
        hv.View(hfov=40.0).resolve(256, 512),
        hv.View(hfov=360.0, vfov=180.0, projection="equiangular").resolve(256, 512),
    ]
    for _ in range(3000):
        view = views[int(rng.integers(3))]
        lo = float(10 ** rng.uniform(-4, 2.5))
        hi = lo * float(10 ** rng.uniform(0, 3))
        La = float(10 ** rng.uniform(0.5, 3))
        got = _selected_by_range(view, La, lo, hi)
        if got is None:
            continue
        decided += 1
        for p05 in (lo, hi, lo + (hi - lo) * float(rng.uniform())):
            d = decide(view, La, p05, lo, hi, True)
            assert got == tuple(n for n, x in d.items() if x.applies)
    assert decided > 1000
    # and it declines where the percentile matters
    view = hv.View(hfov=40.0).resolve(256, 512)
    assert _selected_by_range(view, 100.0, 1.0, 50.0) is None
    assert math.isfinite(view.samples_per_degree)
