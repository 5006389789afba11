"""merge and the weighting functions: accuracy on simulated brackets of real HDR images
(against the truth and against OpenCV's MergeDebevec, called directly), the pixels no
exposure measured, masks, jit/vmap, validation."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.merge as hm
from hdrjax.io import read
from hdrjax.merge._merge import _merge_jit, merge_codes
from hdrjax.merge._weights import granados2010_weight

from ..conftest import DATA, RTOL32, RTOL64, enable_x64

cv2 = pytest.importorskip("cv2")

SHAPE = (96, 144)
IMAGES = ("venice_sunset_1k.hdr", "cornell_box.exr", "MtTamNorth.exr")
CURVES = ("srgb", "scurve", "per_channel")
MEDIAN_REL_ERROR = 0.02
"""Issue 23: merged radiance within 2 % median relative error of the truth."""
MEASURED_TRUE = 0.018
"""Measured worst median error with the true response and the default hat weights: 0.0177
(MtTamNorth, S-curve; 0.0107 with the triangle); the others 0.0043–0.0082."""


@functools.cache
def scene(name: str) -> np.ndarray:
    """A real HDR image subsampled to :data:`SHAPE` (every k-th pixel), float64."""
    img = np.asarray(read(DATA / name).rgb(), np.float64)
    sy, sx = max(img.shape[0] // SHAPE[0], 1), max(img.shape[1] // SHAPE[1], 1)
    return img[::sy, ::sx][: SHAPE[0], : SHAPE[1]]


@functools.cache
def bracket(name: str, curve: str) -> hm.Bracket:
    """8-bit, 5 exposures 2 EV apart (the simulator's default bracket)."""
    return hm.simulate_bracket(scene(name), curve=curve)


def median_rel_error(x, truth, match=False) -> float:
    """Median relative error over the pixels with light; ``match``: after the one scale (the
    median ratio) that matches a response defined up to a factor."""
    x = np.asarray(x, np.float64)
    ok = truth > 0
    s = np.median(truth[ok] / np.maximum(x[ok], 1e-30)) if match else 1.0
    return float(np.median(np.abs(x[ok] * s - truth[ok]) / truth[ok]))


def opencv_merge(b: hm.Bracket, response=None) -> np.ndarray:
    """OpenCV MergeDebevec (RGB out); ``response``: a linear (levels, 3) table, else its own
    CalibrateDebevec."""
    bgr = [np.ascontiguousarray(c[..., ::-1]) for c in b.codes]
    t = b.exposure_times.astype(np.float32)
    if response is None:
        lin = cv2.createCalibrateDebevec().process(bgr, t)
    else:
        lin = np.asarray(response, np.float32)[:, None, ::-1].copy()
    return cv2.createMergeDebevec().process(bgr, t, lin)[..., ::-1]


def true_linear_table(b: hm.Bracket) -> np.ndarray:
    """The true response as OpenCV's linear table; code 0 (zero exposure, −inf in log) gets
    half of code 1's value, since OpenCV's triangle gives code 0 a weight and would take its
    logarithm."""
    tab = np.exp(b.response)
    tab[0] = tab[1] / 2
    return tab


@pytest.mark.parametrize("name", IMAGES)
def test_true_response_merge_is_within_2_percent_and_beats_opencv(name):
    for curve in CURVES:
        b = bracket(name, curve)
        ours = hm.merge(b.codes, b.exposure_times, b.response)
        assert ours.dtype == jnp.float32 and ours.shape == (*SHAPE, 3)
        err = median_rel_error(ours, b.radiance)
        assert err <= MEASURED_TRUE <= MEDIAN_REL_ERROR, (curve, err)
        # the bar: no worse than OpenCV with its own recovered response
        assert err <= median_rel_error(opencv_merge(b), b.radiance, match=True), curve
        # same weights (Debevec & Malik's triangle) and the same true response as OpenCV
        tri = median_rel_error(
            hm.merge(b.codes, b.exposure_times, b.response, "triangle"), b.radiance
        )
        assert tri <= median_rel_error(opencv_merge(b, true_linear_table(b)), b.radiance), curve


@pytest.mark.parametrize("curve", ["srgb", "per_channel"])
def test_recovered_response_merge_beats_opencv_own(curve):
    """Both recover the response from the bracket (Debevec & Malik 1997) and merge with it.
    (On the S-curve hdrjax's recovered response gives 0.010–0.012 against OpenCV's
    0.009–0.010: not asserted.)"""
    for name in IMAGES:
        b = bracket(name, curve)
        ours = hm.merge(b.codes, b.exposure_times, "debevec", "triangle")
        err = median_rel_error(ours, b.radiance, match=True)
        assert err <= MEDIAN_REL_ERROR
        assert err <= median_rel_error(opencv_merge(b), b.radiance, match=True), name


def test_response_given_by_name_file_or_table_agree(tmp_path):
    b = bracket("venice_sunset_1k.hdr", "srgb")
    g = hm.recover_response(b.codes, b.exposure_times, method="robertson")
    by_name = hm.merge(b.codes, b.exposure_times, "Robertson")
    np.testing.assert_allclose(by_name, hm.merge(b.codes, b.exposure_times, g), rtol=RTOL32)
    path = tmp_path / "g.json"
    hm.save_response(path, g)
    np.testing.assert_allclose(hm.merge(b.codes, b.exposure_times, str(path)), by_name, rtol=RTOL32)


def test_linear_response_on_linear_16bit_and_granados_on_noisy_raw():
    """``"linear"`` is exact on linear data up to quantisation; with shot and read noise
    matching its default camera, Granados et al.'s inverse-variance weights beat the
    per-code ones (measured median error 0.0063 against hat 0.0093, triangle 0.0067)."""
    img = scene("venice_sunset_1k.hdr")
    clean = hm.simulate_bracket(img, curve="linear", bits=16)
    e = hm.merge(clean.codes, clean.exposure_times, "linear")
    assert median_rel_error(e, clean.radiance) < 1e-4
    noisy = hm.simulate_bracket(
        img, curve="linear", bits=16, shot_noise=1 / 20000, read_noise=3 / 20000, seed=1
    )
    errs = {
        w: median_rel_error(
            hm.merge(noisy.codes, noisy.exposure_times, "linear", w), noisy.radiance
        )
        for w in hm.WEIGHTS
    }
    assert errs["granados2010"] == min(errs.values()), errs
    assert errs["granados2010"] < 0.0075


def test_weight_functions_are_the_papers():
    z = np.arange(256) / 255.0
    np.testing.assert_allclose(hm.weight_function("hat"), 1 - (2 * z - 1) ** 12, rtol=RTOL32)
    np.testing.assert_allclose(hm.weight_function("Triangle"), 1 - np.abs(2 * z - 1), atol=1e-6)
    c = 127.5
    np.testing.assert_allclose(
        hm.weight_function("gaussian"), np.exp(-4 * (np.arange(256) - c) ** 2 / c**2), rtol=RTOL32
    )
    assert hm.weight_function("hat", 65536).shape == (65536,)
    with pytest.raises(ValueError, match="granados2010"):
        hm.weight_function("granados2010")
    # Granados et al. (2010): inverse variance t² / (K z_max t E + σ_R²)
    w = granados2010_weight(np.array([1.0, 4.0]), 0.1, gain=0.5, read_noise=2.0, levels=256)
    np.testing.assert_allclose(
        w, [1 / (0.5 * 255 * 0.1 + 4), 16 / (0.5 * 255 * 0.4 + 4)], rtol=RTOL32
    )


def extreme_bracket():
    """A scene with a patch too bright for the shortest exposure and a black patch."""
    img = scene("cornell_box.exr").copy()
    img[:10, :10] = 1e6
    img[-10:, -10:] = 0.0
    return hm.simulate_bracket(img, curve="srgb")


def test_pixels_saturated_or_black_everywhere():
    b = extreme_bracket()
    assert np.all(b.codes[:, :10, :10] == 255) and np.all(b.codes[:, -10:, -10:] == 0)
    t_min, t_max = b.exposure_times.min(), b.exposure_times.max()
    g_rec = np.asarray(hm.recover_response(b.codes, b.exposure_times))
    for w in (*hm.WEIGHTS, np.ones(256), np.ones((256, 3))):
        for response in (b.response, g_rec, "linear"):
            e = np.asarray(hm.merge(b.codes, b.exposure_times, response, w))
            assert np.all(np.isfinite(e)) and np.all(e >= 0), (w, response)
            top = np.asarray(b.response if isinstance(response, str) else response)[255]
            # saturated everywhere: the shortest exposure's value, a lower bound (g(top) = 0)
            np.testing.assert_allclose(
                e[:10, :10], np.broadcast_to(np.exp(top) / t_min, (10, 10, 3)), rtol=RTOL32
            )
        # black everywhere: the longest exposure's value (0 where g(0) = −inf)
        e = np.asarray(hm.merge(b.codes, b.exposure_times, b.response, w))
        assert np.all(e[-10:, -10:] == 0)
        e = np.asarray(hm.merge(b.codes, b.exposure_times, g_rec, w))
        np.testing.assert_allclose(
            e[-10:, -10:], np.broadcast_to(np.exp(g_rec[0]) / t_max, (10, 10, 3)), rtol=RTOL32
        )


def test_mask_drops_members_and_all_masked_pixels_take_the_middle_exposure():
    b = bracket("venice_sunset_1k.hdr", "srgb")
    codes = b.codes.copy()
    rng = np.random.default_rng(0)
    codes[1, 20:40, 30:60] = rng.integers(0, 256, (20, 30, 3))  # a ghost in member 1
    mask = np.ones(codes.shape[:3], bool)
    mask[1, 20:40, 30:60] = False
    mask[:, 0:5, 0:5] = False
    e = np.asarray(hm.merge(codes, b.exposure_times, b.response, mask=mask))
    keep = [0, 2, 3, 4]
    without = np.asarray(hm.merge(b.codes[keep], b.exposure_times[keep], b.response))
    np.testing.assert_allclose(e[20:40, 30:60], without[20:40, 30:60], rtol=RTOL32)
    plain = np.asarray(hm.merge(b.codes, b.exposure_times, b.response))
    np.testing.assert_allclose(e[50:, 70:], plain[50:, 70:], rtol=RTOL32)
    mid = np.exp(b.response[b.codes[2, 0:5, 0:5], np.arange(3)]) / b.exposure_times[2]
    np.testing.assert_allclose(e[0:5, 0:5], mid, rtol=RTOL32)


def test_vmap_over_brackets_equals_the_loop_and_one_compile_per_shape():
    bs = [bracket(n, "srgb") for n in IMAGES]
    codes = np.stack([b.codes for b in bs])
    log_t = np.log(np.stack([b.exposure_times * (1 + k) for k, b in enumerate(bs)]))
    w = hm.weight_function("hat")
    batched = jax.jit(jax.vmap(merge_codes, in_axes=(0, 0, None, None)))(
        codes, log_t, bs[0].response, w
    )
    for k in range(len(bs)):
        loop = hm.merge(codes[k], np.exp(log_t[k]), bs[0].response)
        np.testing.assert_allclose(batched[k], loop, rtol=RTOL32)
    # same shapes, other values (times, response, weights, image): no new compile
    before = _merge_jit._cache_size()
    hm.merge(codes[1], np.exp(log_t[0]) * 3, bs[1].response, np.linspace(0, 1, 256))
    hm.merge(codes[2], np.exp(log_t[2]), bs[2].response, "gaussian")
    assert _merge_jit._cache_size() == before


def test_float64_under_x64():
    b = bracket("venice_sunset_1k.hdr", "per_channel")
    with enable_x64():
        e = hm.merge(b.codes, b.exposure_times, b.response, "triangle")
        assert e.dtype == jnp.float64
        assert hm.weight_function("hat").dtype == jnp.float64
        # float64 NumPy reference of Debevec & Malik's eq. 6 (triangle, censored ends)
        z = b.codes.astype(np.int64)
        w = 1 - np.abs(2 * z / 255 - 1)
        g = np.take_along_axis(
            np.broadcast_to(b.response, (5, 1, 256, 3)), z.reshape(5, 1, -1, 3), 2
        )
        g = g.reshape(z.shape)
        w = np.where((z > 0) & (z < 255), w, 0.0)
        num = np.sum(w * (np.where(w > 0, g, 0) - np.log(b.exposure_times)[:, None, None, None]), 0)
        den = np.sum(w, 0)
        ok = den > 0
        np.testing.assert_allclose(np.asarray(e)[ok], np.exp(num[ok] / den[ok]), rtol=RTOL64)


def one_line_value_error(match, *args, **kwargs):
    with pytest.raises(ValueError, match=match) as info:
        hm.merge(*args, **kwargs)
    assert "\n" not in str(info.value)


def test_bad_input_is_a_one_line_value_error_naming_the_argument():
    b = bracket("venice_sunset_1k.hdr", "srgb")
    c, t, g = b.codes, b.exposure_times, b.response
    one_line_value_error("^images", c.astype(np.float32), t, g)
    one_line_value_error("^exposure_times", c, t[:3], g)
    one_line_value_error("^exposure_times", c, None, g)
    one_line_value_error("^response", c, t, g[:100])
    one_line_value_error("^response", c, t, np.full((256, 3), np.nan))
    one_line_value_error("^response", c, t, "devebec")
    one_line_value_error("^weights", c, t, g, "box")
    one_line_value_error("^weights", c, t, g, np.ones(10))
    one_line_value_error("^weights", c, t, g, -np.ones(256))
    one_line_value_error("^mask", c, t, g, mask=np.ones((5, 3, 3), bool))
    one_line_value_error("^mask", c, t, g, mask=np.ones(c.shape[:3], np.uint8))
    one_line_value_error("^gain", c, t, g, "hat", gain=1.0)
    one_line_value_error("^gain", c, t, g, "granados2010", gain=-1.0)
    with pytest.raises(ValueError, match="^levels"):
        hm.weight_function("hat", 1)


def test_kernel_gradients_match_finite_differences():
    """d/d ln t₀ and d/d g of the summed radiance (x64), through the jitted kernel."""
    b = bracket("cornell_box.exr", "srgb")
    with enable_x64():
        g = jnp.asarray(b.response).at[0].set(b.response[1] - 1.0)  # finite everywhere
        w = hm.weight_function("hat")
        log_t = jnp.log(jnp.asarray(b.exposure_times))

        @jax.jit
        def total(g, log_t):
            return jnp.sum(merge_codes(b.codes, log_t, g, w))

        dg, dt = jax.grad(total, argnums=(0, 1))(g, log_t)
        assert bool(jnp.all(jnp.isfinite(dg))) and bool(jnp.all(jnp.isfinite(dt)))
        h = 1e-6
        step = jnp.zeros(5).at[0].set(h)
        fd = (total(g, log_t + step) - total(g, log_t - step)) / (2 * h)
        assert float(dt[0]) == pytest.approx(float(fd), rel=1e-5)
        step = jnp.zeros_like(g).at[128, 1].set(h)
        fd = (total(g + step, log_t) - total(g - step, log_t)) / (2 * h)
        assert float(dg[128, 1]) == pytest.approx(float(fd), rel=1e-5)


@pytest.mark.parametrize(
    "bad",
    [
        np.zeros((100, 3)),
        np.full((256, 3), np.nan),
        np.full((256, 3), np.inf),
        np.full((256, 3), -np.inf),
        np.zeros((256, 2)),
    ],
    ids=["levels", "nan", "+inf", "no-finite", "channels"],
)
def test_one_response_check_for_merge_ghosts_and_saving(bad, tmp_path):
    """merge, ghost_mask and save_response reject a bad response table with the same
    one-line message (one checker)."""
    b = bracket("cornell_box.exr", "srgb")
    messages = []
    calls = [
        lambda: hm.merge(b.codes, b.exposure_times, bad),
        lambda: hm.ghost_mask(b.codes, b.exposure_times, bad),
    ]
    if len(bad) == 256:  # save_response takes any number of levels
        calls.append(lambda: hm.save_response(tmp_path / "r.json", bad))
    for call in calls:
        with pytest.raises(ValueError, match="^response: expected a \\(") as info:
            call()
        messages.append(str(info.value))
    assert len(set(messages)) == 1, messages
    assert not (tmp_path / "r.json").exists()
