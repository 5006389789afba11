"""hdrjax.filters: exactness against SciPy and NumPy references, NaN/Inf, edges, strips,
batches, gradients, and the ``hdrjax filter`` command."""

import functools
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.ndimage as ndi
from hypothesis import given, settings, strategies as st

from hdrjax import luminance
from hdrjax.filters import CRITERIA, MODES, mean_filter, median_filter
from hdrjax.filters._median_core import argmedian_plane, pair_network, pixel_network
from hdrjax.filters._network import Network
from hdrjax.filters._strips import map_index

from .conftest import DATA, enable_x64, shared_file

RNG = np.random.default_rng(20220919)


def _sorted_median(x: np.ndarray, k: int, mode: str) -> np.ndarray:
    """NumPy reference: sort each edge-mapped window (NaN last, as numpy.sort), take the middle."""
    h, w = x.shape
    r = k // 2
    rows = map_index(np.arange(-r, h + r), h, mode)
    cols = map_index(np.arange(-r, w + r), w, mode)
    win = np.lib.stride_tricks.sliding_window_view(x[rows][:, cols], (k, k)).reshape(h, w, -1)
    return np.sort(win, axis=-1)[..., (k * k - 1) // 2]


def _ref_argmedian(lum: np.ndarray, k: int, mode: str) -> np.ndarray:
    """The luminance criterion by definition: sort each window by (luminance, flat position)
    with NaN last, take the middle; returns flat source indices."""
    h, w = lum.shape
    r = k // 2
    ys = map_index(np.arange(-r, h + r), h, mode)
    xs = map_index(np.arange(-r, w + r), w, mode)
    L, P = lum[ys][:, xs], ys[:, None] * w + xs[None, :]
    out = np.zeros((h, w), np.int64)
    for y in range(h):
        for x in range(w):
            lv, pv = L[y : y + k, x : x + k].ravel(), P[y : y + k, x : x + k].ravel()
            order = np.lexsort((pv, np.where(np.isnan(lv), 0, lv), np.isnan(lv)))
            out[y, x] = pv[order[(k * k - 1) // 2]]
    return out


def _ref_vector(img: np.ndarray, k: int, mode: str) -> np.ndarray:
    """Vector median by definition (float64 distances), first minimum in window order."""
    h, w, _ = img.shape
    r = k // 2
    ys = map_index(np.arange(-r, h + r), h, mode)
    xs = map_index(np.arange(-r, w + r), w, mode)
    P = img[ys][:, xs].astype(np.float64)
    out = np.zeros_like(img)
    for y in range(h):
        for x in range(w):
            win = P[y : y + k, x : x + k].reshape(-1, img.shape[2])
            ok = np.all(np.isfinite(win), axis=1)
            safe = np.where(ok[:, None], win, 0)
            d = np.sqrt(((safe[:, None] - safe[None]) ** 2).sum(-1))
            s = np.where(ok[None], d, 0).sum(1)
            s = np.where(ok, s, np.inf)
            out[y, x] = win[np.argmin(s)] if np.isfinite(s).any() else win[(k * k) // 2]
    return out


# --- the comparator networks -------------------------------------------------------------


@pytest.mark.parametrize("k", [3, 5, 7])
def test_networks_select_the_median_of_integer_windows_with_ties(k):
    m = (k * k - 1) // 2
    x = RNG.integers(0, 4, size=(2000, k, k + 1))  # many ties
    net, out = pixel_network(k)
    got = net.emit([out], lambda key: x[:, key[0], key[1]], np.minimum, np.maximum)[0]
    np.testing.assert_array_equal(got, np.sort(x[:, :, :k].reshape(2000, -1), 1)[:, m])
    net, outs = pair_network(k)  # leaves (column, row) over k + 1 rows
    y = x.transpose(0, 2, 1)  # (n, k + 1 rows, k columns)
    a, b = net.emit(list(outs), lambda key: y[:, key[1], key[0]], np.minimum, np.maximum)
    np.testing.assert_array_equal(a, np.sort(y[:, :k].reshape(2000, -1), 1)[:, m])
    np.testing.assert_array_equal(b, np.sort(y[:, 1:].reshape(2000, -1), 1)[:, m])


def test_network_sizes_are_the_documented_ones():
    net, out = pixel_network(5)
    assert net.size([out]) == 206
    net, outs = pair_network(5)
    assert net.size(list(outs)) == 216


def test_select_range_on_unequal_runs():
    net = Network()
    sizes = [3, 5, 2, 7]
    keys = [(i, j) for i, n in enumerate(sizes) for j in range(n)]
    runs = [net.sort([net.leaf((i, j)) for j in range(n)]) for i, n in enumerate(sizes)]
    outs = net.select_range(runs, 4, 9)
    x = RNG.normal(size=(500, len(keys)))
    col = {key: n for n, key in enumerate(keys)}
    got = np.array(net.emit(outs, lambda key: x[:, col[key]], np.minimum, np.maximum))
    np.testing.assert_array_equal(got.T, np.sort(x, axis=1)[:, 4:10])


# --- channel median: bit-identical to SciPy ----------------------------------------------


@pytest.mark.parametrize("mode", MODES)
def test_channel_median_is_bit_identical_to_scipy(mode):
    cases = (
        [(5, 71, 90, 8), (3, 66, 131, None)] if mode in ("nearest", "wrap") else [(5, 71, 90, 8)]
    )
    for k, h, w, rows in cases:
        x = RNG.normal(size=(h, w)).astype(np.float32)
        got = np.asarray(median_filter(x, k, mode=mode, channel_axis=None, strip_rows=rows))
        np.testing.assert_array_equal(got, ndi.median_filter(x, size=k, mode=mode))


@pytest.mark.parametrize("k", [7, 9, 15])
def test_large_windows_are_bit_identical_to_scipy(k):
    x = RNG.normal(size=(71, 90)).astype(np.float32)
    got = np.asarray(median_filter(x, k, channel_axis=None, strip_rows=8))
    np.testing.assert_array_equal(got, ndi.median_filter(x, size=k, mode="nearest"))


def test_tiny_and_degenerate_shapes():
    for h, w in [(1, 1), (1, 7), (7, 1), (2, 3), (4, 300)]:
        x = RNG.normal(size=(h, w)).astype(np.float32)
        for k in (3, 5):
            got = np.asarray(median_filter(x, k, channel_axis=None))
            np.testing.assert_array_equal(got, ndi.median_filter(x, size=k, mode="nearest"))
    x = RNG.normal(size=(8, 9, 3)).astype(np.float32)
    np.testing.assert_array_equal(np.asarray(median_filter(x, 1)), x)
    np.testing.assert_array_equal(np.asarray(median_filter(x, 5, passes=0)), x)


def test_strip_size_does_not_change_the_result():
    """Bounded memory: any strip height gives exactly the whole-image result."""
    x = RNG.lognormal(0, 3, size=(203, 160)).astype(np.float32)
    ref = np.asarray(median_filter(x, 5, channel_axis=None, strip_rows=203))
    got = np.asarray(median_filter(x, 5, channel_axis=None, strip_rows=6))
    np.testing.assert_array_equal(got, ref)
    # a small plane called eagerly skips the strips (two compiled stages): same bits as the
    # strips, and as the one computation a caller's jit gets (odd interior height here)
    for k, mode in ((5, "mirror"), (3, "wrap")):
        strips = median_filter(x, k, mode=mode, channel_axis=None, strip_rows=6)
        eager = median_filter(x, k, mode=mode, channel_axis=None)
        traced = jax.jit(functools.partial(median_filter, size=k, mode=mode, channel_axis=None))
        np.testing.assert_array_equal(np.asarray(eager), np.asarray(strips))
        np.testing.assert_array_equal(np.asarray(eager), np.asarray(traced(x)))
    mref = np.asarray(mean_filter(x, 5, channel_axis=None, strip_rows=203))
    got = np.asarray(mean_filter(x, 5, channel_axis=None, strip_rows=7))
    np.testing.assert_array_equal(got, mref)
    # the default for small windows is one fused pass: the same sums in the same order
    for mode in ("nearest", "wrap"):
        strips = mean_filter(x, 7, mode=mode, channel_axis=None, strip_rows=7)
        one_pass = mean_filter(x, 7, mode=mode, channel_axis=None)
        np.testing.assert_array_equal(np.asarray(one_pass), np.asarray(strips))


def test_median_float64_is_bit_identical_to_scipy():
    with enable_x64():
        x = RNG.normal(size=(70, 81))
        got = median_filter(x, 5, channel_axis=None, strip_rows=10)
        assert got.dtype == jnp.float64
        np.testing.assert_array_equal(np.asarray(got), ndi.median_filter(x, 5, mode="nearest"))
        small = median_filter(x, 5, channel_axis=None)  # no strips: complex128 pairs
        assert small.dtype == jnp.float64
        np.testing.assert_array_equal(np.asarray(small), ndi.median_filter(x, 5, mode="nearest"))


# --- NaN, Inf, zeros, negatives ----------------------------------------------------------


def test_nan_inf_zero_negative_follow_numpy_sort_and_stay_in_their_window():
    vals = np.array([np.nan, np.inf, -np.inf, 0.0, -1.5, 2.0, 1e30, -1e-30], np.float32)
    x = RNG.choice(vals, size=(60, 70), p=[0.15, 0.1, 0.1, 0.2, 0.15, 0.1, 0.1, 0.1])
    x = x.astype(np.float32)
    for k in (3, 5):
        got = np.asarray(median_filter(x, k, channel_axis=None, strip_rows=6))
        ref = _sorted_median(x, k, "nearest")
        np.testing.assert_array_equal(got, ref)  # NaN positions equal too
    # a NaN never reaches outside its window; an isolated NaN is replaced
    y = RNG.random((40, 50)).astype(np.float32)
    y[10, 10] = np.nan
    out = np.asarray(median_filter(y, 5, channel_axis=None))
    assert np.isfinite(out).all()
    y[5:30, 5:30] = np.nan
    out = np.asarray(median_filter(y, 5, channel_axis=None))
    near = ndi.binary_dilation(np.isnan(y), np.ones((5, 5), bool))
    assert not np.isnan(out[~near]).any()
    assert np.isnan(out[12:23, 12:23]).all()


def test_mean_nan_spreads_exactly_over_its_window_and_infinities():
    x = RNG.random((30, 40)).astype(np.float32)
    x[10, 12] = np.nan
    out = np.asarray(mean_filter(x, 5, channel_axis=None))
    near = ndi.binary_dilation(np.isnan(x), np.ones((5, 5), bool))
    np.testing.assert_array_equal(np.isnan(out), near)
    x[10, 12] = np.inf
    out = np.asarray(mean_filter(x, 3, channel_axis=None))
    assert np.isposinf(out[9:12, 11:14]).all() and np.isfinite(out[13:, :]).all()
    x[20, 30] = -np.inf
    x[20, 31] = np.inf
    out = np.asarray(mean_filter(x, 3, channel_axis=None))
    assert np.isnan(out[20, 30])  # +Inf and -Inf in one window: undefined mean


# --- luminance and vector criteria -------------------------------------------------------


@pytest.mark.parametrize("k", [3, 5, 9])
def test_luminance_median_matches_the_numpy_definition(k):
    h, w = (23, 29) if k == 9 else (31, 37)
    rgb = RNG.integers(0, 3, size=(h, w, 3)).astype(np.float32)  # equal luminances: ties
    rgb[RNG.random((h, w)) < 0.05] = np.nan
    for mode in ("nearest", "wrap"):
        got = np.asarray(median_filter(rgb, k, mode=mode, strip_rows=6))
        idx = _ref_argmedian(np.asarray(luminance(rgb)), k, mode)
        np.testing.assert_array_equal(got, rgb.reshape(-1, 3)[idx])  # whole pixels


def test_luminance_median_uses_the_given_weights():
    rgb = RNG.random((30, 30, 3)).astype(np.float32)
    wts = (0.7, 0.2, 0.1)
    got = np.asarray(median_filter(rgb, 3, weights=wts))
    idx = _ref_argmedian(np.asarray(luminance(rgb, wts)), 3, "nearest")
    np.testing.assert_array_equal(got, rgb.reshape(-1, 3)[idx])
    lum = np.asarray(luminance(rgb, wts))
    idx2 = np.asarray(jax.jit(functools.partial(argmedian_plane, k=3, mode="nearest"))(lum))
    np.testing.assert_array_equal(idx2, idx)


def test_vector_median_matches_the_numpy_definition():
    img = RNG.random((18, 21, 3)).astype(np.float32)
    img[4, 5] = [np.nan, 0, 0]
    img[9, 9] = [np.inf, 1, 1]
    got = np.asarray(median_filter(img, 3, criterion="vector", strip_rows=5))
    np.testing.assert_array_equal(got, _ref_vector(img, 3, "nearest"))
    got5 = np.asarray(median_filter(img, 5, criterion="vector", mode="reflect"))
    np.testing.assert_array_equal(got5, _ref_vector(img, 5, "reflect"))


# --- mean: accuracy against float64 ------------------------------------------------------


@pytest.mark.parametrize(
    "k, mode",
    [(3, "nearest"), (3, "reflect"), (3, "mirror"), (3, "wrap"), (5, "nearest"), (15, "wrap")],
)
def test_mean_float32_error_below_1e6_relative_on_hdr_data(k, mode):
    x = RNG.lognormal(0, 4, size=(64, 75)).astype(np.float32)  # ~40 stops
    ref = ndi.uniform_filter(x.astype(np.float64), size=k, mode=mode)
    for rows in (9, None):  # row strips, and the default (one fused pass for k <= 7)
        got = np.asarray(mean_filter(x, k, mode=mode, channel_axis=None, strip_rows=rows))
        assert np.max(np.abs(got - ref) / ref) < 1e-6


def test_mean_on_the_repository_image_matches_scipy():
    from hdrjax import io as hio

    rgb = hio.read(DATA / "cornell_box.exr").rgb()[:160, :200]
    got = np.asarray(mean_filter(rgb, 5))
    ref = ndi.uniform_filter(rgb.astype(np.float64), size=(5, 5, 1), mode="nearest")
    scale = ndi.uniform_filter(np.abs(rgb.astype(np.float64)), size=(5, 5, 1), mode="nearest")
    # the file has small negative values: error relative to the mean magnitude in the window
    assert np.max(np.abs(got - ref) / np.where(scale > 0, scale, 1.0)) < 1e-6
    twice = np.asarray(mean_filter(mean_filter(rgb, 5), 5))
    np.testing.assert_array_equal(np.asarray(mean_filter(rgb, 5, passes=2)), twice)


# --- batches, channels, jit, vmap --------------------------------------------------------


def test_batches_and_channels_equal_per_plane_results():
    x = RNG.random((2, 3, 20, 24, 3)).astype(np.float32)
    for crit in CRITERIA:
        got = np.asarray(median_filter(x, 3, criterion=crit))
        for b in np.ndindex(2, 3):
            one = np.asarray(median_filter(x[b], 3, criterion=crit))
            np.testing.assert_array_equal(got[b], one)
    ch = np.asarray(median_filter(x, 3, criterion="channels"))
    for c in range(3):
        ref = ndi.median_filter(x[1, 2, :, :, c], 3, mode="nearest")
        np.testing.assert_array_equal(ch[1, 2, :, :, c], ref)
    vm = jax.jit(jax.vmap(lambda im: mean_filter(im, 3)))(x.reshape(6, 20, 24, 3))
    np.testing.assert_allclose(
        np.asarray(vm).reshape(x.shape), np.asarray(mean_filter(x, 3)), rtol=1e-6
    )


def test_passes_repeat_the_filter():
    x = RNG.random((25, 30, 3)).astype(np.float32)
    twice = median_filter(median_filter(x, 3), 3)
    np.testing.assert_array_equal(np.asarray(median_filter(x, 3, passes=2)), np.asarray(twice))


# --- gradients ---------------------------------------------------------------------------


def test_median_gradient_goes_to_the_selected_pixel():
    x = jnp.asarray(RNG.permutation(20 * 22).reshape(20, 22).astype(np.float32))  # distinct
    c = jnp.asarray(RNG.random((20, 22)).astype(np.float32))
    for crit in ("channels", "luminance", "vector"):
        img = jnp.stack([x, x, x], -1)

        def f(im, crit=crit):
            return jnp.sum(median_filter(im, 3, criterion=crit)[..., 0] * c)

        g = np.asarray(jax.grad(f)(img))[..., 0]
        out = np.asarray(median_filter(img, 3, criterion=crit))[..., 0]
        # each output is one input value: the gradient puts c there (x values are distinct)
        ref = np.zeros((20 * 22,), np.float32)
        np.add.at(ref, np.asarray(out, np.int64).ravel(), np.asarray(c).ravel())
        np.testing.assert_allclose(g.ravel(), ref[np.asarray(x, np.int64).ravel()], rtol=1e-6)


def test_mean_gradient_is_the_adjoint_filter():
    x = jnp.asarray(RNG.random((15, 17)).astype(np.float32))
    c = jnp.asarray(RNG.random((15, 17)).astype(np.float32))
    g = jax.grad(lambda a: jnp.sum(mean_filter(a, 3, channel_axis=None, mode="wrap") * c))(x)
    # wrap-mode box filter is symmetric: its adjoint is itself
    np.testing.assert_allclose(
        np.asarray(g), ndi.uniform_filter(np.asarray(c), 3, mode="wrap"), rtol=1e-5
    )


# --- invariants --------------------------------------------------------------------------


@settings(deadline=None, max_examples=25)
@given(
    st.sampled_from([(9, 11), (37, 23)]),  # few shapes: each new one compiles
    st.sampled_from(MODES[:2]),
    st.integers(0, 2**31 - 1),
)
def test_median_commutes_with_monotone_maps_and_lies_between_min_and_max(shape, mode, seed):
    k = 3
    x = np.random.default_rng(seed).lognormal(0, 2, size=shape).astype(np.float32)
    med = np.asarray(median_filter(x, k, mode=mode, channel_axis=None))
    f = lambda v: v * np.float32(3) + np.float32(1)  # noqa: E731 — monotone, same floats
    np.testing.assert_array_equal(
        np.asarray(median_filter(f(x), k, mode=mode, channel_axis=None)), f(med)
    )
    assert (med >= ndi.minimum_filter(x, k, mode=mode)).all()
    assert (med <= ndi.maximum_filter(x, k, mode=mode)).all()
    mean = np.asarray(mean_filter(x, k, mode=mode, channel_axis=None))
    assert (mean >= ndi.minimum_filter(x, k, mode=mode) * (1 - 1e-6)).all()


# --- arguments ---------------------------------------------------------------------------


def test_bad_arguments_raise_value_error():
    x = np.zeros((10, 10, 3), np.float32)
    for kwargs in (
        {"size": 4},
        {"size": 0},
        {"mode": "edge"},
        {"criterion": "max"},
        {"passes": -1},
        {"channel_axis": 0},
        {"strip_rows": 0},
    ):
        with pytest.raises(ValueError):
            median_filter(x, **{"size": 3, **kwargs})
    with pytest.raises(ValueError, match="3 channels"):
        median_filter(np.zeros((10, 10, 4), np.float32), 3)
    with pytest.raises(ValueError):
        mean_filter(np.zeros((10,), np.float32), 3)


# --- shared data and the command line ----------------------------------------------------


def test_channel_median_on_a_shared_photograph():
    from hdrjax import io as hio

    rgb = hio.read(shared_file("Desk.exr")).rgb()[:200, :260]
    got = np.asarray(median_filter(rgb, 5, criterion="channels"))
    for c in range(3):
        np.testing.assert_array_equal(
            got[..., c], ndi.median_filter(rgb[..., c], 5, mode="nearest")
        )


def test_filter_command_writes_the_library_result(tmp_path):
    from hdrjax import io as hio
    from hdrjax.cli import main

    out = tmp_path / "f.exr"
    assert main(["filter", str(DATA / "cornell_box.exr"), "-o", str(out), "--median", "3"]) == 0
    img = hio.read(DATA / "cornell_box.exr")
    ref = np.asarray(median_filter(img.rgb(), 3, weights=img.luminance_weights))
    np.testing.assert_array_equal(hio.read(out).rgb(), ref)
    with pytest.raises(SystemExit) as e:
        main(["filter", str(DATA / "cornell_box.exr"), "-o", str(out), "--mean", "4"])
    assert e.value.code == 2
    assert main(["filter", str(tmp_path / "missing.exr"), "-o", str(out), "--mean", "3"]) == 1
    assert (
        main(
            ["filter", str(DATA / "cornell_box.exr"), "-o", str(tmp_path / "g.png"), "--mean", "3"]
        )
        == 2
    )
    assert not os.path.exists(tmp_path / "g.png")


@pytest.mark.parametrize("criterion", ["luminance", "channels"])
def test_batched_and_vmapped_medians_of_strip_sized_images_equal_a_loop(criterion):
    # ≥ 64 rows takes the strip path, whose dynamic slices once mixed int32/int64 under vmap
    x = np.random.default_rng(3).lognormal(0, 2, (2, 130, 96, 3)).astype(np.float32)
    loop = np.stack([np.asarray(median_filter(a, 5, criterion=criterion)) for a in x])
    batched = np.asarray(median_filter(x, 5, criterion=criterion))
    vmapped = np.asarray(jax.vmap(lambda a: median_filter(a, 5, criterion=criterion))(x))
    np.testing.assert_array_equal(batched, loop)
    np.testing.assert_array_equal(vmapped, loop)
    ref = ndi.median_filter(x[0, ..., 1], size=5, mode="nearest")
    if criterion == "channels":
        np.testing.assert_array_equal(loop[0, ..., 1], ref)


def test_xla_compiler_options_are_still_accepted(monkeypatch):
    # The filters compile with XLA flags by name (hdrjax/filters/_xla_options.py; JAX has no
    # public API for them). XLA rejects a name it no longer knows, so an upgrade that drops
    # or renames one fails here, naming it, rather than in every filter call.
    from hdrjax.filters import _api
    from hdrjax.filters._xla_options import CPU_COMPILER_OPTIONS

    x = jnp.arange(6.0).reshape(2, 3)
    want = 2 * np.arange(6.0).reshape(2, 3) + 1
    for name, value in CPU_COMPILER_OPTIONS.items():
        out = jax.jit(lambda v: v * 2.0 + 1.0, compiler_options={name: value})(x)
        np.testing.assert_array_equal(np.asarray(out), want, err_msg=name)
    # the check means something: an unknown name is an error, not ignored; and the filters
    # compile with the options of that one place (on the CPU, at top level)
    if jax.default_backend() != "cpu":
        return
    bogus = {**CPU_COMPILER_OPTIONS, "xla_cpu_no_such_option": 1}
    monkeypatch.setattr(_api, "CPU_COMPILER_OPTIONS", bogus)
    _api.compiled.cache_clear()
    try:
        with pytest.raises(jax.errors.JaxRuntimeError, match="No such compile option"):
            mean_filter(np.ones((8, 8, 3), np.float32), 3)
    finally:
        _api.compiled.cache_clear()
