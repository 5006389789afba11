"""Statistics over 10^8 float32 pixels keep their documented accuracy.

One image of exactly 10^8 pixels (400 MB, allocated once): 10^4 rows, each the same 10^4
lognormal values in a different order (a rotation). Naive float32 summation — one running
accumulator, as a loop or ``cumsum`` does — stops growing once the sum is 2^24 times the
addend, so it returns the wrong mean here (checked below, so the case is known to be hard);
hdrjax's statistics must not. The references are exact: every value occurs exactly 10^4
times, so means, extrema and order statistics follow from the 10^4 distinct values in
float64.

Documented errors (hdrjax._stats): log-averages and counts from (blocked) float32 sums with
error near ``sqrt(n) · eps`` — asserted as 1e-5 relative; extrema exact; histogram
percentiles within the returned ``rel_error_bound``.
"""

import jax
import numpy as np

from hdrjax import stats

N_SIDE = 10_000


def test_statistics_over_1e8_pixels():
    rng = np.random.default_rng(7)
    v = rng.lognormal(3.0, 2.5, N_SIDE).astype(np.float32)  # ln L mostly > 0: sums grow
    v[0] = 0.0  # a black pixel in every row: counts, log-average with delta
    img = np.empty((N_SIDE, N_SIDE), np.float32)
    for r in range(N_SIDE):
        img[r] = np.roll(v, r)
    st = jax.jit(stats.measure)(img)
    vals, bound = jax.jit(lambda x: stats.percentile(x, np.array([1.0, 50.0, 99.0])))(img)
    st, vals, bound = jax.device_get((st, vals, bound))

    v64 = v.astype(np.float64)
    n = N_SIDE * N_SIDE
    assert int(st.n_pixels) == n and int(st.n_nonfinite) == 0
    assert int(st.n_positive) == n - N_SIDE
    log_avg = np.exp(np.mean(np.log(1e-6 + v64)))
    np.testing.assert_allclose(float(st.log_average), log_avg, rtol=1e-5)
    assert float(st.max) == v.max() and float(st.min_positive) == v[v > 0].min()

    # order statistics of the positive values, each repeated N_SIDE times
    pos = np.sort(v64[v64 > 0])
    m = pos.size * N_SIDE

    def order_stat(q):
        k = int(np.floor(q / 100 * (m - 1)))
        return pos[k // N_SIDE]

    for q, got in zip([1.0, 50.0, 99.0], vals, strict=True):
        ref = order_stat(q)
        assert abs(got / ref - 1) <= float(bound) + 1e-6, (q, got, ref, float(bound))
    assert float(bound) < 5e-3

    # the same data defeat naive float32 summation: a running float32 sum of the log-terms,
    # in pixel order (row by row, carrying the accumulator)
    acc = np.zeros(1, np.float32)
    logv = np.log(1e-6 + v64).astype(np.float32)
    for r in range(N_SIDE):
        acc = np.cumsum(np.concatenate([acc, np.roll(logv, r)]), dtype=np.float32)[-1:]
    naive = np.exp(float(acc[0]) / n)
    assert abs(naive / log_avg - 1) > 1e-2, "the case no longer breaks naive summation"
