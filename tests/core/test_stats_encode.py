"""Statistics (histogram percentiles with their bound, exact mode, exclusion of bad pixels),
luminance weights from primaries, and display encoding."""

import colour
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax._stats import (
    measure,
    percentile,
    percentile_by_selection,
    selection_range,
    summarise,
    summarise_histogram,
)
from hdrjax.display import encode, gamma_encode, quantize, srgb_decode, srgb_encode

from ..tile.test_stats import trimmed_log_bound


@pytest.mark.parametrize("sigma", [0.5, 3.0, 6.0])
def test_histogram_percentiles_within_stated_bound(sigma):
    rng = np.random.default_rng(1)
    L = rng.lognormal(0, sigma, 200_000).astype(np.float32)
    q = np.array([1.0, 5.0, 50.0, 90.0, 99.0])
    vals, bound = percentile(L, q)
    # the bound is on the order statistic x_(floor(q (n-1))) (numpy's "lower"): the
    # fixed grid's bins are at most a factor 1 + 2^-10 wide (default 8192 bins: m = 10)
    lower = np.percentile(L.astype(np.float64), q, method="lower")
    err = np.abs(np.asarray(vals) / lower - 1)
    assert float(bound) == 2.0**-10 and np.all(err <= float(bound) + 1e-6), (err, float(bound))
    ref = np.percentile(L.astype(np.float64), q)
    exact, zero = percentile(L, q, method="exact")
    np.testing.assert_allclose(exact, ref, rtol=1e-5)
    assert float(zero) == 0.0
    more, tighter = percentile(L, q, bins=65536)  # 2^13 bins per octave
    assert float(tighter) == 2.0**-13
    assert np.all(np.abs(np.asarray(more) / lower - 1) <= 2.0**-13 + 1e-6)


def test_percentiles_skip_bad_and_non_positive_values():
    L = np.array([np.nan, np.inf, -np.inf, -3.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0], np.float32)
    vals, _ = percentile(L, np.array([0.0, 50.0, 100.0]), method="exact")
    np.testing.assert_allclose(vals, [1.0, 3.0, 5.0])
    vals, b = percentile(L, np.array([0.0, 50.0, 100.0]))
    np.testing.assert_allclose(vals, [1.0, 3.0, 5.0], rtol=float(b))
    empty, _ = percentile(np.zeros(5, np.float32), np.array([50.0]))
    assert np.isnan(np.asarray(empty)).all()


def test_percentiles_at_the_float_maximum():
    """Pixels at float32's largest value: every percentile is that value (the histogram
    path took the logarithm of the extrema and back: exp(ln max) rounds to +Inf, NaN out)."""
    big = np.finfo(np.float32).max
    # the shapes of the test above: its compiled steps are reused
    L = np.full(10, big, np.float32)
    L[:2] = 1.0
    q = np.array([0.0, 50.0, 100.0])
    vals, err = percentile(L, q)  # within the stated bound, finite
    np.testing.assert_allclose(vals, [1.0, big, big], rtol=float(err))
    assert np.all(np.asarray(vals) <= big)
    # a constant image: min = max = the float maximum, exact
    const, _ = percentile(np.full(10, big, np.float32), q)
    np.testing.assert_array_equal(const, [big, big, big])


def test_quantiles_of_merged_statistics_and_the_single_pass():
    """``Statistics.quantile``: the histogram percentiles of the pixels the statistics saw,
    from merged parts as from the whole (same counts and extrema), without a pass; and
    ``summarise_histogram`` (desaturation's single pass): ``summarise`` without the log sum
    for a finite image, a NaN pixel reported by ``finite``."""
    L = np.random.default_rng(5).lognormal(0, 3, (8, 8)).astype(np.float32)
    L[0, :3] = [0.0, -1.0, np.nan]  # not positive / not finite: left out
    q = np.array([0.0, 0.1, 0.5, 0.9, 1.0], np.float32)

    @jax.jit  # one program (eager statistics compile every step)
    def stats(L):
        whole = summarise(L)[1].without_source()
        merged = summarise(L[:4])[1].merge(summarise(L[4:])[1])
        finite, single = summarise_histogram(L)
        quantiles = (whole.quantile(q), merged.quantile(q), single.quantile(q)[0])
        return quantiles, merged.quantile(0.5)[0], percentile(L, 100 * q), whole, finite, single

    ((got, err), (got_m, err_m), _), one, (want, bound), _, finite, _ = stats(L)
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(got_m, want)
    assert float(err) == float(err_m) == float(bound) == 2.0**-10
    # against NumPy's order statistics of the 61 positive pixels, within the bound
    pos = L[np.isfinite(L) & (L > 0)].astype(np.float64)
    lower = np.percentile(pos, 100 * q, method="lower")
    assert np.all(np.abs(np.asarray(want) / lower - 1) <= 2.0**-10 + 1e-6)
    assert one.shape == () and float(one) == float(want[2])  # a scalar q gives a scalar
    assert not bool(finite)
    # a finite image: the single pass holds summarise's counts, extrema and histogram
    L[0, 2] = 2.0
    (_, _, got_1), _, (want, _), ref, finite, st = stats(L)
    assert bool(finite)
    for f in ("n_pixels", "n_finite", "n_positive", "min", "max", "min_positive", "counts"):
        np.testing.assert_array_equal(getattr(st, f), getattr(ref, f), err_msg=f)
    assert np.isnan(float(st.log_sum)) and st.source is None and st.m == ref.m
    np.testing.assert_array_equal(got_1, want)
    ((none, err0), *_), *_ = stats(np.zeros((8, 8), np.float32))  # no positive pixel
    assert np.isnan(np.asarray(none)).all() and float(err0) == 0.0
    with pytest.raises(ValueError, match="^statistics: quantiles need histogram"):
        jax.eval_shape(lambda L: summarise(L, method="exact")[1].quantile(q), L)
    with pytest.raises(ValueError, match="^q: expected numbers in"):
        jax.eval_shape(lambda L: summarise(L)[1].quantile(50.0), L)


def test_percentile_by_selection_is_the_exact_percentile():
    """Partial selection (the fit's percentile targets): the exact method's values, with and
    without a mask, and the sort for a q outside the selection it was sized for."""
    L = np.random.default_rng(7).lognormal(0, 2, (8, 8)).astype(np.float32)
    L[0, :2] = [0.0, np.nan]
    mask = np.ones((8, 8), bool)
    mask[1] = False
    q = np.array([2.0, 95.0], np.float32)
    select = selection_range(q)
    assert select == (2.0, 95.0) and selection_range([50.0]) == (None, 50.0)

    @jax.jit
    def both(L, q, where):
        got = (percentile_by_selection(L, q, select=select, where=w) for w in (None, where))
        want = (percentile(L, q, method="exact", where=w)[0] for w in (None, where))
        return tuple(got), tuple(want)

    for qq in (q, np.array([2.0, 60.0], np.float32)):  # 60 lies outside the selection: sorted
        got, want = both(L, qq, mask)
        np.testing.assert_allclose(got, want, rtol=1e-6)  # the final interpolation's rounding
    ref = np.percentile(L[np.isfinite(L) & (L > 0)], q)
    np.testing.assert_allclose(both(L, q, mask)[0][0], ref, rtol=1e-6)


def test_measure_against_numpy(x64):
    rng = np.random.default_rng(2)
    L = rng.lognormal(0, 2, (64, 64))
    L[0, 0], L[0, 1], L[1, 1] = np.nan, np.inf, -0.5
    st = jax.jit(lambda x: measure(x, method="exact"))(L)
    ok = np.isfinite(L)
    f = L[ok]
    pos = f[f > 0]
    assert int(st.n_nonfinite) == 2 and int(st.n_positive) == pos.size
    np.testing.assert_allclose(
        float(st.log_average), np.exp(np.mean(np.log(1e-6 + np.maximum(f, 0)))), rtol=1e-9
    )
    np.testing.assert_allclose(float(st.max), f.max())
    np.testing.assert_allclose(float(st.min), -0.5)
    np.testing.assert_allclose(float(st.min_positive), pos.min())
    p1, p99 = np.percentile(pos, [1, 99])
    np.testing.assert_allclose([float(st.p01), float(st.p99)], [p1, p99], rtol=1e-9)
    np.testing.assert_allclose(
        float(st.log_average_trimmed), np.exp(np.mean(np.log(pos[pos <= p99]))), rtol=1e-9
    )
    np.testing.assert_allclose(float(st.dynamic_range_stops), np.log2(f.max() / pos.min()))


def test_luminance_weights_from_primaries():
    # ACES AP0 (Carrots.exr): Y weights with a negative blue (SOURCES.md)
    ap0 = (0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.077, 0.32168, 0.33767)
    np.testing.assert_allclose(
        hdrjax.luminance_weights(ap0), [0.34397, 0.72817, -0.07213], atol=5e-6
    )
    assert hdrjax.luminance_weights(None) == (0.2126, 0.7152, 0.0722)
    with pytest.raises(ValueError, match="chromaticities"):
        hdrjax.luminance_weights((0.1, 0.2))
    with pytest.raises(ValueError, match="degenerate"):
        hdrjax.luminance_weights((0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3127, 0.329))
    rgb = np.random.default_rng(0).uniform(0, 1, (4, 5, 3))
    np.testing.assert_allclose(
        hdrjax.luminance(rgb, ap0 and hdrjax.luminance_weights(ap0)),
        rgb @ np.array(hdrjax.luminance_weights(ap0)),
        rtol=1e-5,
    )


def test_srgb_matches_colour_science(x64):
    x = np.linspace(0, 1, 1001)
    np.testing.assert_allclose(srgb_encode(x), colour.cctf_encoding(x, "sRGB"), atol=1e-12)
    np.testing.assert_allclose(srgb_decode(srgb_encode(x)), x, atol=1e-12)
    np.testing.assert_allclose(gamma_encode(x, 2.2), x ** (1 / 2.2), atol=1e-12)


def test_encoding_clips_and_quantizes():
    x = jnp.array([-1.0, 0.0, 0.5, 1.0, 7.0, jnp.nan, jnp.inf])
    enc = np.asarray(encode(x, "linear"))
    np.testing.assert_array_equal(enc, [0, 0, 0.5, 1, 1, 0, 1])
    np.testing.assert_array_equal(quantize(enc, 8), [0, 0, 128, 255, 255, 0, 255])
    assert quantize(enc, 16).dtype == np.uint16 and quantize(enc, 16)[3] == 65535
    with pytest.raises(ValueError, match="bits"):
        quantize(enc, 12)
    with pytest.raises(ValueError, match="transfer"):
        encode(x, "pq")
    g = jax.grad(lambda v: jnp.sum(srgb_encode(v)))(jnp.array([0.0, 0.001, 0.5, 2.0]))
    assert np.all(np.isfinite(np.asarray(g)))


@pytest.mark.parametrize(
    "chroma",
    [
        (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290),  # Rec.709 / D65
        (0.640, 0.330, 0.290, 0.600, 0.150, 0.060, 1 / 3, 1 / 3),  # Radiance's standard
        (0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.077, 0.32168, 0.33767),  # ACES AP0
        (0.680, 0.320, 0.265, 0.690, 0.150, 0.060, 0.3127, 0.3290),  # Display P3
    ],
)
def test_primary_matrix_equals_colour_science(chroma):
    import colour

    from hdrjax._colour import normalised_primary_matrix

    c = np.asarray(chroma)
    ref = colour.normalised_primary_matrix(c[:6].reshape(3, 2), c[6:])
    np.testing.assert_allclose(normalised_primary_matrix(c), ref, rtol=1e-12, atol=1e-15)


def _hard_image(shape, seed, dirty):
    L = np.random.default_rng(seed).lognormal(0, 2, shape)
    if dirty:  # every masked case: NaN, ±Inf, negative, zero
        L.flat[[3, 50, 777, 4100, 9000, 10001]] = [np.nan, np.inf, -np.inf, -0.5, 0.0, 0.0]
    return L


@pytest.mark.parametrize("dirty", [False, True, "tail"])
def test_blocked_passes_against_numpy(monkeypatch, dirty):
    # small blocks, so a 150×201 image spans many blocks and a ragged tail (the code paths
    # a 4096² image takes: the one-pass lanes, and the masked pass for bad pixels);
    # "tail": the only bad pixels are in the ragged tail, which the lanes never see.
    # NumPy float64 is the reference
    import hdrjax._stats as S

    monkeypatch.setattr(S, "BLOCK", 4096)
    monkeypatch.setattr(S, "LANES", 4096)  # 7 blocks of lanes + a tail of 1478
    L = _hard_image((150, 201), 5, dirty is True).astype(np.float32)
    if dirty == "tail":
        L.flat[[29000, 30001, 30100]] = [np.nan, 0.0, -2.0]
    finite, st = jax.jit(S.measure_checked)(L)
    assert bool(finite) == (not dirty)
    # the histogram on the bit-pattern grid, bin by bin (NaN, ±Inf, negatives: past the end)
    counts = np.asarray(jax.jit(lambda x: S._one_pass(x, 10, None)[0])(L))
    bits = L.reshape(-1).view(np.uint32) >> 13
    grid = S.grid_size(10)
    np.testing.assert_array_equal(counts, np.bincount(bits[bits < grid], minlength=grid))
    f = L[np.isfinite(L)].astype(np.float64)
    pos = f[f > 0]
    assert int(st.n_nonfinite) == L.size - f.size and int(st.n_positive) == pos.size
    assert float(st.min) == f.min() and float(st.max) == f.max()
    assert float(st.min_positive) == pos.min()
    lavg = np.exp(np.mean(np.log(1e-6 + np.maximum(f, 0))))
    np.testing.assert_allclose(float(st.log_average), lavg, rtol=1e-5)
    bound = float(st.rel_error_bound)
    assert bound == 2.0**-10  # fixed grid, 1024 bins per octave (module docstring)
    for q, got in ((1, st.p01), (99, st.p99)):
        ref = np.percentile(pos, q, method="lower")  # the order statistic x_(floor(q(n-1)))
        assert abs(float(got) / ref - 1) <= bound + 1e-6, (q, float(got), ref)
    kept = pos[pos <= float(st.p99)]
    err = abs(np.log(float(st.log_average_trimmed)) - np.mean(np.log(kept)))
    assert err <= trimmed_log_bound(pos, float(st.p99)) + 1e-6
    vals, b = jax.jit(lambda x: percentile(x, np.array([10.0, 90.0])))(L)
    for q, got in zip([10, 90], vals, strict=True):
        assert abs(float(got) / np.percentile(pos, q, method="lower") - 1) <= float(b) + 1e-6


@pytest.mark.parametrize("dirty", [False, True])
def test_measure_gradients_follow_the_formulas(x64, dirty):
    # d/dL of each statistic, by hand: extrema pick their pixel; log-averages
    # exp(mean ln(.)) spread over the pixels they average
    L = _hard_image((90, 120), 6, dirty)
    st = measure(L)
    ok = np.isfinite(L)
    f = np.where(ok, L, 0.0)
    n = ok.sum()

    def grad(name):
        return np.asarray(jax.grad(lambda x: getattr(measure(x), name))(L))

    for name, value, mask in (
        ("min", np.min(L[ok]), ok),
        ("max", np.max(L[ok]), ok),
        ("min_positive", np.min(L[ok & (f > 0)]), ok & (f > 0)),
    ):
        expect = np.where(mask & (f == value), 1.0, 0.0)
        np.testing.assert_allclose(grad(name), expect / expect.sum(), atol=1e-12, err_msg=name)
    lavg = float(st.log_average)
    slope = np.where(f > 0, 1.0, np.where(f == 0, 0.5, 0.0))  # JAX's max(x, 0) at 0: 1/2
    expect = np.where(ok, lavg / n * slope / (1e-6 + np.maximum(f, 0)), 0.0)
    np.testing.assert_allclose(grad("log_average"), expect, rtol=1e-9, atol=1e-15)
    kept = ok & (f > 0) & (f <= float(st.p99))
    trimmed = float(st.log_average_trimmed)
    expect = np.where(kept, trimmed / kept.sum() / np.where(kept, f, 1.0), 0.0)
    np.testing.assert_allclose(grad("log_average_trimmed"), expect, rtol=1e-9, atol=1e-15)
