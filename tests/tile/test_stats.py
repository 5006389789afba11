"""The tiled first pass equals :func:`hdrjax._stats.measure` on the whole image.

Exact (bit for bit): pixel counts, extrema and the percentiles' error bound (the same
global histogram grid). The 1st/99th percentiles come from the same histogram bins; the
final interpolation inside the bin is compiled apart from ``measure``'s (XLA may contract
a multiply-add differently), so they agree to ``PCT_ULP`` ulp. The log-average is a sum of
per-tile float32 sums, so it agrees with the whole-image float32 reduction to
``LOGAVG_RTOL``; the trimmed log-average is the same function of the same merged histogram.
A NumPy float64 computation checks the values independently (the trimmed log-average
within its hand-derived histogram bound, :func:`trimmed_log_bound`).
"""

import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.tile as T
from hdrjax._colour import luminance
from hdrjax._stats import measure
from hdrjax.operators._base import prepare

from ._images import crop

LOGAVG_RTOL = 1e-5
"""float32 sums of ~10⁴ log terms in another order: a few ulp of the mean."""

PCT_ULP = 2

EXACT = ("n_pixels", "n_nonfinite", "n_positive", "min", "min_positive", "max")


def _lum_plane(x):
    """Luminance with NaN at non-finite pixels, computed once (the shared input)."""
    return np.array(prepare(jnp.asarray(x), (0.2126, 0.7152, 0.0722)).L_stats)


@pytest.mark.parametrize("tile", [(37, 50), 300])
def test_plane_statistics_equal_measure(tile):
    L = _lum_plane(crop(120, 100))
    L[5:9, 0] = 0.0  # zeros: finite, not positive
    ref = measure(L)
    got = T.statistics(L, tile=tile)
    for name in EXACT + ("rel_error_bound",):
        assert np.asarray(getattr(got, name)) == np.asarray(getattr(ref, name)), name
    for name in ("p01", "p99"):
        np.testing.assert_array_max_ulp(getattr(got, name), getattr(ref, name), PCT_ULP)
    for name in ("log_average", "log_average_trimmed"):
        np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=LOGAVG_RTOL)


def test_statistics_against_numpy_float64():
    L = _lum_plane(crop(120, 100))
    st = T.statistics(L, tile=(37, 50))
    f = L[np.isfinite(L)].astype(np.float64)
    pos = f[f >= np.finfo(np.float32).tiny]
    assert int(st.n_nonfinite) == L.size - f.size == 4  # NaN×3 and the +Inf channel
    assert int(st.n_positive) == pos.size
    assert float(st.min) == f.min() < 0 and float(st.max) == f.max()
    lavg = np.exp(np.mean(np.log(1e-6 + np.maximum(f, 0))))
    np.testing.assert_allclose(float(st.log_average), lavg, rtol=LOGAVG_RTOL)
    for q, v in ((1, st.p01), (99, st.p99)):  # within the histogram's stated error bound
        exact = np.percentile(pos, q, method="lower")
        assert abs(float(v) / exact - 1) <= float(st.rel_error_bound) * 1.01
    trimmed = np.exp(np.mean(np.log(pos[pos <= float(st.p99)])))
    bound = trimmed_log_bound(pos, float(st.p99))
    assert abs(np.log(float(st.log_average_trimmed) / trimmed)) <= bound + 1e-6


def trimmed_log_bound(pos: np.ndarray, p99: float, m: int = 10) -> float:
    """Bound on |ln(histogram trimmed log-average / exact)|, derived by hand (NumPy float64):
    pixels of the full bins below p99's bin count at their bin's geometric centre (at most
    half a bin, ln(1 + 2^-m) / 2); the boundary bin's c_b pixels may be counted in or out,
    each moving the mean by at most (a + 2 w - ln min) / N_F (a, w: the bin's lower edge and
    width in ln, N_F the pixels of the full bins)."""
    bins = pos.astype(np.float32).view(np.uint32) >> np.uint32(23 - m)
    b = np.float32(p99).view(np.uint32) >> np.uint32(23 - m)
    edge = lambda k: float(np.array([k << (23 - m)], np.uint32).view(np.float32)[0])  # noqa: E731
    a, w = np.log(edge(int(b))), np.log(edge(int(b) + 1) / edge(int(b)))
    c_b, n_f = np.sum(bins == b), np.sum(bins < b)
    return np.log1p(2.0**-m) / 2 + c_b * (a + 2 * w - np.log(pos.min())) / n_f


def test_rgb_statistics_match_operator_statistics():
    # the RGB path computes luminance inside each tile; XLA may fuse w·RGB with an FMA,
    # moving a luminance by an ulp, so a bin boundary pixel may move: compare to 1e-5
    x = crop(120, 100)
    ref = measure(_lum_plane(x))
    got = T.statistics(x, tile=(37, 50))
    for name in ("n_pixels", "n_nonfinite", "n_positive"):
        assert int(getattr(got, name)) == int(getattr(ref, name)), name
    for name in ("min", "min_positive", "max", "p01", "p99", "log_average", "rel_error_bound"):
        np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-5)


def test_no_positive_pixels_equal_measure():
    L = np.full((30, 20), -1.0, np.float32)
    L[3, 4] = np.nan
    ref, got = measure(L), T.statistics(L, tile=8)
    for name in EXACT + ("p01", "p99", "rel_error_bound", "log_average_trimmed"):
        assert np.asarray(getattr(got, name)) == np.asarray(getattr(ref, name)), name
    # 599 equal terms ln(1e-6): the float64 merge is the closer one to 1e-6
    np.testing.assert_allclose(got.log_average, ref.log_average, rtol=LOGAVG_RTOL)
    np.testing.assert_allclose(got.log_average, 1e-6, rtol=1e-6)


def test_image_at_the_float_maximum_equals_measure():
    """Every pixel at float32's largest value: the log-averages are clamped below it as
    ``measure`` clamps them (``exp`` of the rounded mean of logarithms was +Inf)."""
    big = np.finfo(np.float32).max
    L = np.full((30, 20), big, np.float32)  # the shapes above: their compiles are reused
    ref, got = measure(L), T.statistics(L, tile=8)
    for name in EXACT + ("p01", "p99", "rel_error_bound"):
        assert np.asarray(getattr(got, name)) == np.asarray(getattr(ref, name)), name
    for name in ("log_average", "log_average_trimmed"):
        np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=LOGAVG_RTOL)
        np.testing.assert_allclose(getattr(got, name), big, rtol=1e-4)
    assert float(got.p99) == big


def test_luminance_of_one_channel_image():
    x = crop(40, 30, bad=False)
    L = np.asarray(luminance(x))
    a = T.statistics(L[..., None], tile=16)
    b = T.statistics(L, tile=16)
    assert float(a.p99) == float(b.p99) and int(a.n_positive) == int(b.n_positive)
