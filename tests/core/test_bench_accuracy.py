"""The error computations of benchmarks/bench_accuracy.py and the slope of bench_scaling.py,
checked on tiny inputs against hand values and independent NumPy references."""

import sys
from types import SimpleNamespace

import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax

from ..conftest import REPO

sys.path.insert(0, str(REPO / "benchmarks"))
import bench_accuracy as B  # noqa: E402
import bench_scaling as S  # noqa: E402


def lognormal_rgb(shape, seed=0):
    rng = np.random.default_rng(seed)
    L = rng.lognormal(0.0, 2.5, shape)
    return (L[..., None] * rng.uniform(0.5, 1.5, shape + (3,))).astype(np.float32)


def test_histogram_percentile_error_is_measured_and_within_the_bound():
    # 10001 pixels: q (n - 1) / 100 is an integer for every q in QS, so numpy.percentile is
    # an order statistic and the library's bound (one bin) applies to it exactly
    rgb = lognormal_rgb((73, 137))
    recs = B.percentile_curve({"synthetic": rgb}, bins=(64, 256), repeats=1)
    L64 = rgb.astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])
    ref = np.percentile(L64, B.QS)
    by = {r["setting"].split(" (")[0]: r for r in recs}  # "histogram 64 bins (8/octave)"
    assert {r["setting"] for r in recs} >= {"histogram 64 bins (8/octave)"}
    for bins in (64, 256):
        rec = by[f"histogram {bins} bins"]
        vals, bound = hdrjax.stats.percentile(jnp.asarray(L64, jnp.float32), B.QS, bins=bins)
        expected = np.max(np.abs(np.asarray(vals, np.float64) - ref) / ref)
        assert rec["error"] == pytest.approx(expected, rel=1e-3, abs=1e-7)
        assert 0 < rec["error"] <= rec["extra"]["rel_error_bound"]
        assert rec["extra"]["rel_error_bound"] == pytest.approx(float(bound), rel=1e-6)
        assert rec["extra"]["within_bound"]
    assert by["exact"]["error"] < 1e-5  # float32 sort vs float64 numpy
    assert by["histogram 64 bins"]["error"] > by["histogram 256 bins"]["error"]
    assert not any(r["default"] for r in recs)  # 8192 bins (the default) not in this run


def test_reference_is_numpy_percentile_of_finite_positive_values(x64):
    L = np.array([np.nan, -1.0, 0.0, np.inf, 3.0, 1.0, 7.0, 2.0, 5.0])
    qs = (1.0, 50.0, 90.0)
    ref = B.percentile_reference(L, qs)
    np.testing.assert_allclose(ref, np.percentile([3.0, 1.0, 7.0, 2.0, 5.0], qs), rtol=1e-15)
    # the library's exact method in float64 has the same definition
    exact, _ = hdrjax.stats.percentile(jnp.asarray(L), qs, method="exact")
    np.testing.assert_allclose(np.asarray(exact), ref, rtol=1e-12)


def test_error_metrics_hand_values():
    assert B.max_rel_error([1.1, 2.0], [1.0, 2.5]) == pytest.approx(0.2)
    assert B.max_rel_error([0.5], [0.0]) == pytest.approx(0.5)  # absolute where ref is 0
    # clipped to [0, 1]: 1.5 vs 1.0 is no error; NaN in both is no error; NaN in one is 1
    assert B.display_error([1.5, 0.5, np.nan], [1.0, 0.25, np.nan]) == pytest.approx(0.25)
    assert B.display_error([0.2, np.nan], [0.2, 0.3]) == 1.0
    assert B.angle_deg([1.0, 0.0, 0.0], [0.0, 2.0, 0.0]) == pytest.approx(90.0)


def fake_lights(directions, energies):
    k = len(directions)
    pad = 4 - k
    e = np.array(list(energies) + [0.0] * pad)
    return SimpleNamespace(
        valid=np.array([True] * k + [False] * pad),
        direction=np.array(list(directions) + [[0.0, 0.0, 0.0]] * pad, np.float64),
        energy=e,
        energy_share=e / 10.0,
        count=k,
    )


def test_light_errors_position_and_energy():
    c, s = np.cos(np.radians(2.0)), np.sin(np.radians(2.0))
    ref = fake_lights([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [5.0, 2.0, 0.05])  # 3rd: 0.5 % share
    found = fake_lights([[c, s, 0], [0, 1, 0]], [4.0, 2.0])
    e = B.light_errors(found, ref)
    assert e["position_deg"] == pytest.approx(2.0, abs=1e-9)  # the 0.5 % light is ignored
    assert e["energy_rel_error"] == pytest.approx(0.2)
    assert (e["count"], e["ref_count"]) == (2, 3)


def test_median_references_against_brute_force():
    rng = np.random.default_rng(3)
    rgb = rng.uniform(0, 4, (6, 7, 3))
    rgb[2, 3] = rgb[2, 4]  # a luminance tie: the earlier pixel (row-major) wins
    k, r = 3, 1
    pad = np.pad(rgb, ((r, r), (r, r), (0, 0)), mode="edge")
    w = np.array([0.2126, 0.7152, 0.0722])
    lum_ref = np.empty_like(rgb)
    ch_ref = np.empty_like(rgb)
    for i in range(6):
        for j in range(7):
            win = pad[i : i + k, j : j + k].reshape(-1, 3)
            lum = win @ w
            order = sorted(range(k * k), key=lambda t, lum=lum: (lum[t], t))
            lum_ref[i, j] = win[order[k * k // 2]]
            ch_ref[i, j] = np.sort(win, axis=0)[k * k // 2]
    np.testing.assert_array_equal(B.luminance_median_reference(rgb, k), lum_ref)
    np.testing.assert_array_equal(B.channels_median_reference(rgb, k), ch_ref)


def test_loglog_slope():
    px = np.array([256, 1024, 4096, 15000], float) ** 2
    assert S.loglog_slope(px, 3e-9 * px) == pytest.approx(1.0, abs=1e-12)
    assert S.loglog_slope(px, 1e-12 * px**1.5) == pytest.approx(1.5, abs=1e-12)
    assert np.isnan(S.loglog_slope([4.0], [1.0]))


def test_tiled_fills_and_crops():
    base = np.arange(2 * 3 * 3, dtype=np.float32).reshape(2, 3, 3)
    t = S.tiled(base, 5)
    assert t.shape == (5, 5, 3)
    np.testing.assert_array_equal(t[4, 4], base[0, 1])  # row 4 % 2, column 4 % 3
