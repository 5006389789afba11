"""hdrjax.estimate: each automatic estimate equals what the operators use internally and an
independent float64 NumPy computation of the published formula (written here)."""

import equinox as eqx
import jax
import numpy as np
import pytest

import hdrjax
from hdrjax import estimate as E
from hdrjax.operators import Reinhard2002, Reinhard2002Local, TumblinReinhard

from ..conftest import DATA, RTOL32, RTOL64

W = np.array([0.2126, 0.7152, 0.0722])


def _box(rgb, fy, fx):
    h, w = rgb.shape[0] // fy, rgb.shape[1] // fx
    return rgb[: h * fy, : w * fx].reshape(h, fy, w, fx, 3).mean(axis=(1, 3))


@pytest.fixture(scope="module")
def images():
    """Real images box-filtered to 32 × 64 (float64 NumPy; one shape, so each estimate
    compiles once): the Cornell box (29.8 stops) and Venice sunset (25.9 stops); plus a
    narrow-range ramp, where the white point's guard applies."""
    cornell = np.asarray(hdrjax.io.read(DATA / "cornell_box.exr").rgb(), np.float64)
    venice = np.asarray(hdrjax.io.read(DATA / "venice_sunset_1k.hdr").rgb(), np.float64)
    ramp = np.linspace(1.0, 3.0, 32 * 64).reshape(32, 64, 1) * np.array([1.0, 0.9, 1.1])
    return {"cornell": _box(cornell, 16, 8), "venice": _box(venice, 16, 16), "ramp": ramp}


_measure = eqx.filter_jit(lambda op, x: op.measure(x))


def _finite_L(rgb):
    L = rgb @ W
    return L[np.all(np.isfinite(rgb), axis=-1)]


def jgt_numpy(rgb, delta=1e-6):
    """JGT 2002 Eqs. 4–5 (with hdritools' guard in scaled units: Eq. 5's white against the
    trimmed log-average times ``key / lbar``) and Reinhard 2002 Eq. 1, float64 NumPy."""
    L = _finite_L(rgb)
    pos = L[L > 0]
    l1, l99 = np.percentile(pos, [1, 99])
    lbar_t = np.exp(np.mean(np.log(pos[pos <= l99])))
    key = 0.18 * 4 ** ((2 * np.log2(lbar_t) - np.log2(l1) - np.log2(l99)) / np.log2(l99 / l1))
    lbar = np.exp(np.mean(np.log(delta + np.maximum(L, 0))))
    zones = np.log2(pos.max()) - np.log2(pos.min())
    guard = 1.5 * 2 ** (zones - 5) <= lbar_t * key / lbar  # ⇔ zones ≤ log2(·) + 4.415037
    white = 1.5 * pos.max() * key / lbar if guard else 1.5 * 2 ** (zones - 5)
    return dict(key=key, white=white, lbar=lbar, l1=l1, l99=l99, lbar_t=lbar_t, zones=zones,
                guard=guard)  # fmt: skip


@pytest.mark.parametrize("name", ["cornell", "venice", "ramp"])
def test_jgt_estimates_match_operator_and_numpy(images, name, x64):
    rgb = images[name]
    ref = jgt_numpy(rgb)
    key = E.jgt_key(rgb, percentile_method="exact")
    white = E.jgt_white(rgb, percentile_method="exact")
    lbar = E.log_average(rgb)
    # independent: the published formulas in NumPy
    np.testing.assert_allclose(float(key.value), ref["key"], rtol=RTOL64)
    np.testing.assert_allclose(float(white.value), ref["white"], rtol=RTOL64)
    np.testing.assert_allclose(float(lbar.value), ref["lbar"], rtol=RTOL64)
    st = key.statistics
    np.testing.assert_allclose(
        [st["p01"], st["p99"], st["log_average_trimmed"]],
        [ref["l1"], ref["l99"], ref["lbar_t"]],
        rtol=RTOL64,
    )
    assert float(st["rel_error_bound"]) == 0.0
    np.testing.assert_allclose(float(white.statistics["zones"]), ref["zones"], rtol=RTOL64)
    assert bool(white.statistics["guard"]) == ref["guard"]
    np.testing.assert_allclose(
        float(white.statistics["scale"]), ref["key"] / ref["lbar"], rtol=RTOL64
    )
    assert int(lbar.statistics["n_pixels"]) == rgb.shape[0] * rgb.shape[1]
    # the operators use exactly these values (histogram default and exact percentiles)
    for method in ("exact", "histogram"):
        op = _measure(Reinhard2002(percentile_method=method), rgb)
        k = E.jgt_key(rgb, percentile_method=method)
        w = E.jgt_white(rgb, percentile_method=method)
        np.testing.assert_allclose(float(op.key), float(k.value), rtol=1e-12)
        np.testing.assert_allclose(float(op.L_white), float(w.value), rtol=1e-12)
        np.testing.assert_allclose(float(op.log_average), float(lbar.value), rtol=1e-12)
        local = _measure(Reinhard2002Local(percentile_method=method), rgb)
        np.testing.assert_allclose(float(local.key), float(k.value), rtol=1e-12)


def test_guard_branch_is_exercised(images):
    assert jgt_numpy(images["ramp"])["guard"] and not jgt_numpy(images["cornell"])["guard"]


@pytest.mark.parametrize("k", [2.0**-20, 1 / 16, 1.0, 2.0**20])
def test_white_is_scale_invariant(images, k, x64):
    """The white point of ``k ×`` the ramp is the ramp's: its guard compares Eq. 5's white
    with the trimmed log-average in scaled units. hdritools' comparison with the
    log-average in image units switches to Eq. 5 (a white 5× lower) for k ≤ 1/16."""
    rgb = images["ramp"] * k
    ref = jgt_numpy(rgb, delta=0.0)  # delta > 0 makes L̄_w itself scale dependent
    assert ref["guard"]
    np.testing.assert_allclose(
        ref["white"], jgt_numpy(images["ramp"], delta=0.0)["white"], rtol=1e-12
    )
    if k <= 1 / 16:  # the case that motivates the scaled units
        assert ref["zones"] > np.log2(ref["lbar_t"]) + 4.415037
    w = E.jgt_white(rgb, percentile_method="exact", delta=0.0)
    assert bool(w.statistics["guard"])
    np.testing.assert_allclose(float(w.value), ref["white"], rtol=RTOL64)
    op = _measure(Reinhard2002(delta=0.0), rgb)  # histogram percentiles: key moves slightly
    np.testing.assert_allclose(float(op.L_white), ref["white"], rtol=1e-3)


def test_white_with_given_key_and_log_average_and_delta(images, x64):
    rgb = images["venice"]
    # a user key/log-average changes the guard's scale; delta is the operator's field
    w = E.jgt_white(images["ramp"], key=0.3, log_average=2.0, percentile_method="exact")
    op = _measure(Reinhard2002(key=0.3, log_average=2.0, percentile_method="exact"), images["ramp"])
    np.testing.assert_allclose(float(w.value), float(op.L_white), rtol=1e-12)
    L_max = float((images["ramp"] @ W).max())
    np.testing.assert_allclose(float(w.value), 1.5 * L_max * 0.3 / 2.0, rtol=RTOL64)
    lb = E.log_average(rgb, delta=1e-2)
    np.testing.assert_allclose(float(lb.value), jgt_numpy(rgb, delta=1e-2)["lbar"], rtol=RTOL64)
    op = _measure(Reinhard2002(delta=1e-2), rgb)
    np.testing.assert_allclose(float(op.log_average), float(lb.value), rtol=1e-12)


@pytest.mark.parametrize("name", ["cornell", "venice"])
def test_adaptation_luminance_matches_tumblin_and_numpy(images, name, x64):
    rgb = images[name]
    L = _finite_L(rgb)
    plain = E.adaptation_luminance(rgb)
    # colour-hdri / HDR Toolbox: exp(mean(ln(L + 2.3e-5)))
    np.testing.assert_allclose(float(plain.value), np.exp(np.mean(np.log(L + 2.3e-5))), rtol=RTOL64)
    assert float(plain.statistics["eps"]) == pytest.approx(2.3e-5)
    np.testing.assert_allclose(float(_measure(TumblinReinhard(), rgb).L_wa), float(plain.value),
                               rtol=1e-12)  # fmt: skip
    robust = E.adaptation_luminance(rgb, robust=True)
    st = robust.statistics
    pos = np.sort(L[L > 0])
    # histogram percentiles (hdrjax.stats): within the stated bound of the bin holding
    # order statistic x_(floor(q (n − 1))), interpolated towards the next one
    bound = float(st["rel_error_bound"])
    assert 0 < bound < 0.01
    for name, q in (("p01", 0.01), ("p99", 0.99)):
        k = int(np.floor(q * (pos.size - 1)))
        assert pos[k] * (1 - bound) <= float(st[name]) <= pos[k + 1] * (1 + bound)
    kept = pos[(pos >= float(st["p01"])) & (pos <= float(st["p99"]))]
    assert int(st["n_pixels"]) == kept.size
    np.testing.assert_allclose(float(robust.value), np.exp(np.mean(np.log(kept))), rtol=RTOL64)
    op = _measure(TumblinReinhard(adaptation="trimmed"), rgb)
    np.testing.assert_allclose(float(op.L_wa), float(robust.value), rtol=1e-12)


@pytest.mark.parametrize("name", ["cornell", "venice"])
def test_desaturation_threshold_is_twice_the_90th_percentile(images, name):
    # float32, as the display module is used (its x64 tracing was broken when written)
    rgb = images[name].astype(np.float32)
    L = _finite_L(rgb.astype(np.float64))
    est = E.desaturation_threshold(rgb, method="exact")
    np.testing.assert_allclose(float(est.value), 2 * np.percentile(L, 90), rtol=RTOL32)
    np.testing.assert_allclose(float(est.statistics["L90"]), np.percentile(L, 90), rtol=RTOL32)
    T, _ = hdrjax.display.highlight_threshold(rgb, method="exact")
    assert float(T) == float(est.value)
    # the desaturation step uses this threshold: pixels below it are unchanged
    out = np.asarray(hdrjax.desaturate_highlights(rgb, method="exact"))
    below = (rgb @ W.astype(np.float32)) < float(est.value)
    assert 0 < below.sum() < below.size
    np.testing.assert_array_equal(out[below], rgb[below])
    fast = E.desaturation_threshold(rgb)
    b = float(fast.statistics["rel_error_bound"])
    s = np.sort(L)  # histogram: the bin of x_(floor(q (n − 1))), towards the next one
    k = int(np.floor(0.9 * (s.size - 1)))
    assert s[k] * (1 - b) <= float(fast.statistics["L90"]) <= s[k + 1] * (1 + b)


def test_desaturation_threshold_at_the_float_maximum():
    """``T = 2 · L₉₀`` is clamped to the largest float; ``L90`` is the percentile itself
    (it was reported as ``T / 2``, +Inf for these images)."""
    big = np.finfo(np.float32).max
    for level in (1.0, 0.75):
        # the images' shape (32 × 64, float32): the compiled estimate is reused
        est = E.desaturation_threshold(np.full((32, 64, 3), level * big, np.float32))
        assert float(est.value) == big
        L90, err = float(est.statistics["L90"]), float(est.statistics["rel_error_bound"])
        np.testing.assert_allclose(L90, level * big, rtol=err)
        assert L90 <= big


def test_nan_pixels_are_left_out_like_the_operators(images, x64):
    rgb = images["cornell"].copy()
    rgb[3, 4] = np.nan
    rgb[5, 6, 1] = np.inf
    ref = jgt_numpy(rgb)
    key = E.jgt_key(rgb, percentile_method="exact")
    np.testing.assert_allclose(float(key.value), ref["key"], rtol=RTOL64)
    np.testing.assert_allclose(float(E.log_average(rgb).value), ref["lbar"], rtol=RTOL64)
    assert int(E.log_average(rgb).statistics["n_pixels"]) == rgb.shape[0] * rgb.shape[1] - 2
    op = _measure(Reinhard2002(percentile_method="exact"), rgb)
    np.testing.assert_allclose(float(op.key), float(key.value), rtol=1e-12)


def test_estimates_vmap_over_frames(images, x64):
    frames = np.stack([images["venice"], 3.0 * images["venice"]])
    est = jax.vmap(E.log_average)(frames)
    assert est.value.shape == (2,)
    np.testing.assert_allclose(est.value, [jgt_numpy(f)["lbar"] for f in frames], rtol=RTOL64)


def test_bad_arguments_name_the_argument():
    with pytest.raises(ValueError, match="image"):
        E.jgt_key(np.ones((2, 4, 4, 3)))
    with pytest.raises(ValueError, match="percentile_method"):
        E.jgt_key(np.ones((4, 4, 3)), percentile_method="sort")
    with pytest.raises(ValueError, match="weights"):
        E.log_average(np.ones((4, 4, 3)), weights=(1.0, 0.0))


def test_info_prints_each_estimate_with_its_statistics(images, tmp_path, capsys):
    from hdrjax.cli import main

    rgb = images["venice"].astype(np.float32)
    path = tmp_path / "venice_small.exr"
    hdrjax.io.write(path, rgb)
    assert main(["info", str(path), "--exact"]) == 0
    text = capsys.readouterr().out
    lines = {ln.split(":")[0].strip(): ln for ln in text.splitlines() if ln.startswith("  ")}
    ref = jgt_numpy(rgb.astype(np.float64))

    def value(name):
        return float(lines[name].split(":")[1].split()[0])

    np.testing.assert_allclose(value("jgt_key"), ref["key"], rtol=1e-5)
    np.testing.assert_allclose(value("jgt_white"), ref["white"], rtol=1e-5)
    np.testing.assert_allclose(value("log_average"), ref["lbar"], rtol=1e-5)
    assert f"p99 {ref['l99']:.6g}" in lines["jgt_key"] and "guard no" in lines["jgt_white"]
    L = _finite_L(rgb.astype(np.float64))
    np.testing.assert_allclose(value("desaturation_threshold"), 2 * np.percentile(L, 90), rtol=1e-5)
    for name in ("adaptation_luminance", "adaptation_luminance_robust"):
        assert "n_pixels" in lines[name]
    assert "reinhard2002: key: " in text  # the earlier per-operator lines stay
