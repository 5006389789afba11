"""Display encodings beyond sRGB (PQ, HLG, BT.1886, Display P3), gamut mapping and the
BT.2390 EETF, against colour-science, the standards' equations in float64 NumPy, and a real
file (openexr-images' Chromaticities/XYZ.exr)."""

import functools

import colour
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax import REC709_WEIGHTS, spaces
from hdrjax.display import (
    DEFAULT_GAMUT,
    DISPLAYS,
    HLG_REFERENCE_WHITE,
    bt2390_eetf,
    encode,
    gamut_map,
    get_display,
)

from ..conftest import RTOL32, RTOL64, enable_x64, shared_file

ATOL64 = 1e-6  # against colour-science, on signals in [0, 1]: a 16-bit code is 1.5e-5
F32_MAX = float(np.finfo(np.float32).max)
EXTREMES = [0.0, 1e-38, 1e-20, 1e-6, 0.5, 1.0, 3.0, 1e6, F32_MAX, -1e-20, -0.3, -4.0]
EXTREMES += [-F32_MAX, np.nan, np.inf, -np.inf]
GRID = np.array(np.meshgrid(EXTREMES, EXTREMES, EXTREMES, indexing="ij"), np.float32)
GRID = GRID.reshape(3, -1).T  # every combination of extreme channels: (4096, 3)
BT2020 = "ITU-R BT.2020"
F32_STEP = 1e-7  # a few float32 ulps of a signal near 1: rounding, not a trend
# light decoded from a float32 PQ signal: the curve's steep top multiplies the signal's
# rounding (7.5e-5 at most measured)
RTOL_PQ_LIGHT = 2e-4


# The suite is compile-bound: one compiled function per configuration, reused across tests
# with arrays of a few shapes (options that are numbers, such as peak, are passed traced)
@functools.cache
def _encoder(**config):
    return jax.jit(functools.partial(encode, **config))


@jax.jit
def _gamut_maps(rgb):
    methods = ("clip", "luminance", "compress")
    out = {m: gamut_map(rgb, m) for m in methods}
    return out | {f"{m}, unbounded": gamut_map(rgb, m, upper=None) for m in methods}


_eetf = jax.jit(bt2390_eetf)


def _rng(seed: int = 7) -> np.random.Generator:
    return np.random.default_rng(seed)  # per test: each is reproducible run alone


def _in_gamut(n: int = 256) -> np.ndarray:
    return _rng().uniform(0.0, 1.0, (n, 3))


# -- curves against colour-science -------------------------------------------------------


def test_pq_is_st2084_of_white_at_the_peak():
    rgb = _in_gamut()
    rgb[:2] = [[1.0] * 3, [0.203] * 3]
    with enable_x64():
        got = {p: np.asarray(_encoder(display="PQ", space=BT2020)(rgb, peak=p)) for p in (1e3, 4e3)}
    for peak, signal in got.items():
        want = colour.models.eotf_inverse_ST2084(rgb * peak)
        np.testing.assert_allclose(signal, want, rtol=0, atol=ATOL64)
    # BT.2408's anchors: 1000 cd/m² at 0.7518, reference white (203 cd/m²) at 0.58
    np.testing.assert_allclose(got[1e3][:2, 0], [0.75183, 0.58069], atol=1e-5)


def test_hlg_is_the_bt2100_oetf_of_the_relative_scene_signal():
    rgb = _in_gamut()
    scene = rgb * 3.7  # up to the top of HLG's range (E = 0.98)
    scene[:2] = [[1.0] * 3, [0.18] * 3]
    with enable_x64():
        got = np.asarray(_encoder(display="ITU-R BT.2100 HLG", space=BT2020)(rgb))
        got_scene = _encoder(display="HLG", space=BT2020, scene_referred=True)(scene)
    with np.errstate(invalid="ignore"):  # colour evaluates both branches' logarithms
        want = colour.models.oetf_BT2100_HLG(rgb)
        want_scene = colour.models.oetf_BT2100_HLG(scene * HLG_REFERENCE_WHITE)
    np.testing.assert_allclose(got, want, rtol=0, atol=ATOL64)
    np.testing.assert_allclose(np.asarray(got_scene), want_scene, rtol=0, atol=ATOL64)
    # BT.2408: reference white at 75 %, the 18 % grey card at 38 % of the HLG signal
    np.testing.assert_allclose(np.asarray(got_scene)[:2, 0], [0.75, 0.3783], atol=1e-4)
    with pytest.raises(ValueError, match="^peak: .*HLG"):
        encode(rgb, display="HLG", peak=1000.0)


def test_bt2020_is_the_inverse_of_bt1886_with_zero_black():
    rgb = _in_gamut()
    with enable_x64():
        got = np.asarray(_encoder(display="BT2020", space=BT2020)(rgb))
    want = colour.models.eotf_inverse_BT1886(rgb, L_B=0.0, L_W=1.0)
    np.testing.assert_allclose(got, want, rtol=0, atol=ATOL64)
    np.testing.assert_allclose(got, rgb ** (1 / 2.4), rtol=RTOL64)


def test_display_p3_is_colour_science_conversion_then_the_srgb_curve():
    rgb = _in_gamut()  # sRGB lies inside P3: no gamut mapping
    rgb[0] = [1.0, 0.0, 0.0]
    with enable_x64():
        got = np.asarray(_encoder(display="Display P3")(rgb))
    p3 = colour.RGB_to_RGB(rgb, "sRGB", "Display P3")
    np.testing.assert_allclose(got, colour.cctf_encoding(p3, "sRGB"), rtol=0, atol=ATOL64)
    # not the identity: pure sRGB red lies inside P3's red, some green in it
    assert got[0, 0] < 0.95 and got[0, 1] > 0.2


def test_sdr_displays_with_clipping_are_the_old_per_value_encodings():
    # equal but for the display path's flush of |values| < 1e-15 to 0 (1.3e-19 in sRGB)
    got = _encoder(display="sRGB", gamut="clip")(GRID)
    np.testing.assert_allclose(np.asarray(got), np.asarray(_encoder()(GRID)), rtol=0, atol=1e-15)
    got = _encoder(display="gamma", gamma=2.6, gamut="clip")(GRID)
    want = _encoder(transfer="gamma", gamma=2.6)(GRID)  # the flush: (1e-15)^(1/2.6) = 1.7e-6
    np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=0, atol=2e-6)
    assert get_display("gamma", 2.6).gamma == 2.6 and "sRGB" in DISPLAYS


# -- BT.2390 EETF ------------------------------------------------------------------------


def _eetf_reference(E, L_B, L_W, L_min, L_max):
    """ITU-R BT.2390-4 section 5.4.1, transcribed in float64."""
    pq = colour.models.eotf_inverse_ST2084
    span = pq(L_W) - pq(L_B)
    E1 = (E - pq(L_B)) / span
    min_lum = (pq(L_min) - pq(L_B)) / span
    max_lum = (pq(L_max) - pq(L_B)) / span
    KS = 1.5 * max_lum - 0.5
    T = (E1 - KS) / (1 - KS)
    P = (
        (2 * T**3 - 3 * T**2 + 1) * KS
        + (T**3 - 2 * T**2 + T) * (1 - KS)
        + (-2 * T**3 + 3 * T**2) * max_lum
    )
    E2 = np.where(E1 < KS, E1, P)
    E3 = E2 + min_lum * (1 - E2) ** 4
    return E3 * span + pq(L_B)


def test_eetf_is_the_reports_equations():
    pq = colour.models.eotf_inverse_ST2084
    for L_B, L_W, L_min, L_max in [
        (0.0, 10000.0, 0.0, 1000.0),
        (0.005, 4000.0, 0.05, 600.0),
        (0.0, 1000.0, 0.1, 100.0),
    ]:
        E = np.linspace(pq(L_B), pq(L_W), 2001)
        kw = dict(source_peak=L_W, target_peak=L_max, source_black=L_B, target_black=L_min)
        with enable_x64():
            got = np.asarray(_eetf(E, **kw))
        np.testing.assert_allclose(got, _eetf_reference(E, L_B, L_W, L_min, L_max), atol=1e-12)
        # monotone, and the source black lands on the target black; without a black lift,
        # the source peak lands exactly on the target peak (the lift moves it a little)
        assert np.all(np.diff(got) >= 0)
        np.testing.assert_allclose(got[0], pq(L_min), atol=1e-12)
        if L_min == 0:
            np.testing.assert_allclose(got[-1], pq(L_max), atol=1e-12)


def test_eetf_is_the_identity_below_the_knee_and_clips_beyond_the_source():
    pq = colour.models.eotf_inverse_ST2084
    E = np.linspace(pq(0.0), 1.0, 4001).astype(np.float32)
    got = np.asarray(_eetf(E, source_peak=4000.0, target_peak=1000.0))
    knee = pq(4000.0) * (1.5 * pq(1000.0) / pq(4000.0) - 0.5)  # KS, normalised (black 0)
    below = E < knee
    np.testing.assert_allclose(got[below], E[below], rtol=RTOL32)
    assert np.all(got[~below] <= E[~below] + 1e-6)
    assert np.all(np.diff(got) >= -F32_STEP)  # monotone to float32 rounding
    np.testing.assert_allclose(got[E >= pq(4000.0)], pq(1000.0), rtol=RTOL32)
    # a target as bright as the source: nothing to roll off (up to the source peak)
    same = np.asarray(_eetf(E, source_peak=1000.0, target_peak=1000.0))
    np.testing.assert_allclose(same, np.minimum(E, pq(1000.0)), rtol=RTOL32)
    # a target below a third of the source in PQ (KS < 0): still monotone, still on the peak
    dim = np.asarray(_eetf(E, source_peak=10000.0, target_peak=5.0))
    assert np.all(np.diff(dim) >= -F32_STEP) and abs(dim[-1] - pq(5.0)) < 1e-5
    with pytest.raises(ValueError, match="^target_black: expected a value below"):
        bt2390_eetf(E, source_peak=1000.0, target_peak=100.0, target_black=100.0)


def test_scene_referred_pq_rolls_highlights_onto_the_peak_keeping_hue():
    pq, pq_eotf = colour.models.eotf_inverse_ST2084, colour.models.eotf_ST2084
    img = _rng(1).lognormal(-1.0, 1.0, (24, 32, 3)).astype(np.float32)
    img[0, 0] = [50.0, 20.0, 5.0]  # the source peak: 50 × 203 = 10150 → 10000 cd/m²
    img[0, 1] = [0.18, 0.18, 0.18]
    hot = img.copy()
    hot[5, 5] = [np.inf, np.inf, np.inf]
    batch = np.stack([img, img * 0.02, hot])  # leading axes are a batch of images
    config = dict(display="PQ", space=BT2020, scene_referred=True)
    out, dim, got_hot = np.array(_encoder(**config)(batch))
    # mid grey is below the knee: exactly 0.18 × 203 cd/m²
    np.testing.assert_allclose(out[0, 1], pq(0.18 * 203.0), rtol=RTOL32)
    # the brightest channel reaches the peak; one gain for the pixel keeps its ratios
    np.testing.assert_allclose(out[0, 0, 0], pq(1000.0), rtol=RTOL32)
    light = pq_eotf(out[0, 0].astype(np.float64))
    np.testing.assert_allclose(light / light[0], img[0, 0] / img[0, 0, 0], rtol=RTOL_PQ_LIGHT)
    # the curve through each pixel's largest channel is the EETF of its PQ signal
    hi = img.max(-1).ravel()
    got = pq_eotf(out.max(-1).ravel().astype(np.float64))
    want = pq_eotf(_eetf_reference(pq(np.minimum(hi * 203.0, 10000.0)), 0, 10000, 0, 1000))
    np.testing.assert_allclose(got, want, rtol=RTOL_PQ_LIGHT)
    # an image no brighter than the display, in the same batch: plain scaling
    np.testing.assert_allclose(dim, pq(img * 0.02 * 203.0), rtol=RTOL32, atol=1e-6)
    # an infinite pixel is no source peak: it lands on the peak and nothing else moves
    np.testing.assert_allclose(got_hot[5, 5], pq(1000.0), rtol=RTOL32)
    others = np.ones(img.shape[:2], bool)
    others[5, 5] = False
    np.testing.assert_array_equal(got_hot[others], out[others])
    # vmap over the images: the same per-image source peaks
    mapped = jax.jit(jax.vmap(functools.partial(encode, **config)))(batch)
    np.testing.assert_allclose(np.asarray(mapped), np.stack([out, dim, got_hot]), atol=1e-6)
    # a given source peak (10 × white, 2030 cd/m²): values above it land on the display peak
    capped = np.asarray(_encoder(**config)(batch, scene_max=10.0))[0].max(-1)
    np.testing.assert_allclose(capped[img.max(-1) >= 10], pq(1000.0), rtol=RTOL32)
    assert np.all(capped[img.max(-1) < 9] < pq(1000.0) - 1e-5)
    assert np.sum(img.max(-1) >= 10) > 1


# -- gamut mapping -----------------------------------------------------------------------


def test_gamut_mapping_is_never_nan_and_lands_in_the_gamut():
    for method, out in _gamut_maps(GRID).items():
        out = np.asarray(out)
        assert np.all(np.isfinite(out)) and out.min() >= 0.0, method
        assert "unbounded" in method or out.max() <= 1.0, method
    # NaN channels are 0, +Inf the top: a pixel of NaN is black, one of +Inf white
    nan_px, inf_px = np.all(np.isnan(GRID), -1), np.all(GRID == np.inf, -1)
    out = np.asarray(_gamut_maps(GRID)["luminance"])
    np.testing.assert_array_equal(out[nan_px | inf_px], [[0, 0, 0], [1, 1, 1]])


def test_in_gamut_colours_are_unchanged():
    rgb = _in_gamut(len(GRID)).astype(np.float32)
    maps = _gamut_maps(rgb)
    for method in ("clip", "luminance"):
        np.testing.assert_array_equal(np.asarray(maps[method]), rgb)
    # compress leaves every channel whose distance from the achromatic axis is below its
    # threshold (ACES: 0.815, 0.803, 0.880) exactly as it was
    dist = (rgb.max(-1, keepdims=True) - rgb) / rgb.max(-1, keepdims=True)
    core = dist < np.array([0.815, 0.803, 0.880])
    assert core.all(-1).sum() > 100 and (~core).sum() > 100
    out = np.asarray(maps["compress"])
    np.testing.assert_array_equal(out[core], rgb[core])
    # beyond it, compressed towards the axis: raised (visibly so 0.01 past the threshold)
    assert np.all(out[~core] >= rgb[~core] - F32_STEP)  # at the threshold: 1 ulp
    past = dist > np.array([0.815, 0.803, 0.880]) + 0.01
    assert np.all(out[past] > rgb[past])


def test_luminance_mapping_keeps_luminance_and_hue():
    w = np.asarray(REC709_WEIGHTS)
    rgb = _rng(2).uniform(-0.5, 1.0, (len(GRID), 3))
    rgb[:3] = [[2.0, 1.0, 0.5], [3.0, -0.2, 0.5], [0.1, -1.0, 0.2]]
    with enable_x64():
        out = np.asarray(_gamut_maps(rgb)["luminance"])
    Y = (rgb @ w)[:, None]
    fits = (rgb.min(-1) < 0) & (Y[:, 0] > 0.01) & (out.max(-1) < 1.0)  # not scaled down
    assert fits.sum() > 300
    np.testing.assert_allclose((out @ w)[fits], Y[fits, 0], rtol=RTOL64)
    np.testing.assert_array_equal(out[fits].min(-1), 0.0)  # just far enough
    # towards its own grey: out − Y = t (rgb − Y) with one t in (0, 1) per pixel
    t = (out - Y)[fits] / (rgb - Y)[fits]
    np.testing.assert_allclose(t, t[:, :1].repeat(3, 1), rtol=RTOL64)
    assert np.all((t > 0) & (t < 1))
    # above 1: scaled, so every ratio between channels (hue and saturation) is kept
    np.testing.assert_allclose(out[0], [1.0, 0.5, 0.25], rtol=RTOL64)
    y1 = Y[1, 0]  # first towards grey (red 2.32, blue 0.55), then down to red = 1
    moved = y1 * (rgb[1] + 0.2) / (y1 + 0.2)
    np.testing.assert_allclose(out[1], moved / moved[0], rtol=RTOL64)
    # no grey of its luminance (Y ≤ 0): black
    np.testing.assert_array_equal(out[2], 0.0)


def _rgc_reference(rgb):
    """ACES 1.3 LMT.Academy.ReferenceGamutCompress's compression in float64 (its constants)."""
    lim = np.array([1.147, 1.264, 1.312])
    thr = np.array([0.815, 0.803, 0.880])
    pwr = 1.2
    ach = rgb.max(-1, keepdims=True)
    dist = np.where(ach == 0, 0.0, (ach - rgb) / np.abs(np.where(ach == 0, 1, ach)))
    scl = (lim - thr) / (((1.0 - thr) / (lim - thr)) ** -pwr - 1.0) ** (1.0 / pwr)
    nd = np.maximum(dist - thr, 0) / scl
    compressed = np.where(dist < thr, dist, thr + scl * nd / (1.0 + nd**pwr) ** (1.0 / pwr))
    return ach - compressed * np.abs(ach)


def test_compress_is_the_aces_reference_gamut_compression():
    rgb = _rng(3).uniform(-0.3, 1.0, (len(GRID), 3))
    rgb[0] = [1.0, -2.0, 0.5]  # farther out than ACES's limits
    want = _rgc_reference(rgb)
    with enable_x64():
        got = np.asarray(_gamut_maps(rgb)["compress"])
    inside = (want.min(-1) >= 0) & (want.max(-1) <= 1) & (rgb.max(-1) > 0)
    assert inside.sum() > 1000 and np.any(rgb[inside] < 0)
    np.testing.assert_allclose(got[inside], want[inside], rtol=0, atol=1e-12)
    # beyond the limits the curve leaves a channel negative: finished towards grey (its
    # luminance kept), not clipped
    assert want[0].min() < 0 and got[0].min() == 0.0
    w = np.asarray(REC709_WEIGHTS)
    np.testing.assert_allclose(got[0] @ w, want[0] @ w, rtol=RTOL64)


def test_on_a_real_file_only_out_of_gamut_colours_move():
    """Chromaticities/XYZ.exr of openexr-images (CIE XYZ primaries) in sRGB has a few
    colours outside the gamut: "luminance" (the default) moves only them; "compress" also
    moves in-gamut ones (the measurement behind the default)."""
    img = hdrjax.io.read(shared_file("XYZ.exr")).image
    rgb = np.asarray(spaces.convert_to(img, spaces.XYZ_CHROMATICITIES, "sRGB")).reshape(-1, 3)
    neg = rgb.min(-1) < 0
    inside = ~neg & (rgb.max(-1) <= 1)
    assert 100 < neg.sum() < 0.01 * len(rgb)  # 319 of 247660
    assert DEFAULT_GAMUT == "luminance"
    maps = _gamut_maps(rgb)
    out = np.asarray(maps["luminance"])
    np.testing.assert_array_equal(out[inside], rgb[inside])
    w = np.asarray(REC709_WEIGHTS, np.float32)
    fixed = neg & (rgb.max(-1) <= 1)
    np.testing.assert_allclose(out[fixed] @ w, rgb[fixed] @ w, rtol=RTOL32)
    assert np.all(out[fixed].min(-1) == 0)
    moved = np.any(np.asarray(maps["compress"]) != rgb, axis=-1)
    assert (moved & inside).mean() > 0.01  # 4.6 % of the image, all inside the gamut


# -- differentiability, transformations, errors ------------------------------------------

# every display once, every gamut mapping on at least two of them
_CONFIGS = [
    dict(display="sRGB"),
    dict(display="Display P3", gamut="compress"),
    dict(display="ITU-R BT.2020", gamut="clip"),
    dict(display="ITU-R BT.2100 PQ"),
    dict(display="ITU-R BT.2100 HLG", gamut="clip"),
    dict(display="linear"),
    dict(display="gamma", gamut="clip"),
    dict(display="PQ", scene_referred=True, gamut="compress"),
    dict(display="HLG", scene_referred=True),
]


@jax.jit
def _values_and_gradients(x):
    # one program for all configurations: a third faster to compile than one each
    return [jax.value_and_grad(lambda v, c=c: jnp.sum(encode(v, **c)))(x) for c in _CONFIGS]


def test_gradients_are_finite_for_every_display_and_jit_equals_eager():
    assert {c["display"] for c in _CONFIGS[:7]} == {*DISPLAYS, "gamma"}
    x = jnp.asarray(np.concatenate([GRID, [[0.5, 0.5, 0.5], [0.0, 0.0, 0.0]]]))
    results = _values_and_gradients(x)
    for config, (value, grad) in zip(_CONFIGS, results, strict=True):
        assert np.isfinite(float(value)) and np.all(np.isfinite(np.asarray(grad))), config
    # a value a wrong gradient would miss: sRGB at grey 0.5, d/dx 1.055 x^(1/2.4 − 1) / 2.4
    grad_srgb = np.asarray(results[0][1])
    np.testing.assert_allclose(grad_srgb[-2], 1.055 / 2.4 * 0.5 ** (1 / 2.4 - 1), rtol=RTOL32)
    # the compiled function computes what the eager one does, up to rounding (fused
    # operations round differently)
    eager = encode(x, **_CONFIGS[8])
    np.testing.assert_allclose(_encoder(**_CONFIGS[8])(x), eager, rtol=RTOL32, atol=1e-6)


def test_misuse_raises_with_the_argument_named():
    x = np.full((2, 3), 0.5, np.float32)
    cases = [
        ("transfer", lambda: encode(x, "srgb", display="sRGB")),
        ("transfer", lambda: encode(x, "pq")),
        ("display", lambda: encode(x, display="cinema")),
        ("gamut", lambda: encode(x, display="sRGB", gamut="perceptual")),
        ("scene_referred", lambda: encode(x, display="sRGB", scene_referred=True)),
        ("scene_max", lambda: encode(x, display="HLG", scene_referred=True, scene_max=4.0)),
        ("peak", lambda: encode(x, display="PQ", peak=20000.0)),
        ("peak", lambda: encode(x, peak=1000.0)),
        ("linear", lambda: encode(x[:, :2], display="PQ")),
        ("weights", lambda: gamut_map(x, weights=(0.3, 0.3, 0.3))),
        ("method", lambda: gamut_map(x, "hue")),
    ]
    for name, call in cases:
        with pytest.raises(ValueError, match=f"^{name}: "):
            call()
    # names are case- and separator-insensitive
    assert get_display("itu-r bt.2100 pq") is get_display("PQ")
    np.testing.assert_array_equal(np.asarray(gamut_map(x * 3 - 1, "Clip")), [[0.5] * 3] * 2)
