"""Each vision effect against a float64 NumPy reference, plus its NaN/overflow policy."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

import hdrjax.vision as hv
from hdrjax._photometry import rgb_to_xyz_matrix

from ..conftest import RTOL32, RTOL64


def night_scene(h=48, w=96, seed=0, lo=0.01, hi=0.3):
    rng = np.random.default_rng(seed)
    tint = np.array([1.0, 0.8, 0.6])
    return rng.uniform(lo, hi, (h, w, 1)) * tint


def np_cielum(rgb):
    X, Y, Z = np.moveaxis(rgb @ rgb_to_xyz_matrix().T, -1, 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        V = np.where(X > 0, Y * (1.33 * (1 + (Y + Z) / X) - 1.68), 0.0)
    return X, Y, Z, np.maximum(V, 0.0)


def np_upsample(a, fy, fx, H, W):
    """Centre-aligned bilinear upsampling holding edge values (float64 reference)."""

    def up(a, f, n):
        u = np.clip((np.arange(n) + 0.5) / f - 0.5, 0, a.shape[0] - 1)
        i0 = np.minimum(np.floor(u).astype(int), max(a.shape[0] - 2, 0))
        w = (u - i0) if a.shape[0] > 1 else np.zeros(n)
        i1 = np.minimum(i0 + 1, a.shape[0] - 1)
        w = w.reshape((-1,) + (1,) * (a.ndim - 1))
        return a[i0] * (1 - w) + a[i1] * w

    return np.swapaxes(up(np.swapaxes(up(a, fy, H), 0, 1), fx, W), 0, 1)


# -- glare -----------------------------------------------------------------------------


@pytest.mark.usefixtures("x64")
def test_glare_equals_direct_linear_convolution():
    img = night_scene(24, 40)
    img[10, 20] = 1e4
    view = hv.View(hfov=30.0).resolve(24, 40)
    for variant in ("photopic", "scotopic"):
        k = hv.glare_kernel(view, variant)
        out = np.asarray(hv.glare(img, view, variant=variant))
        ref = np.stack(
            [scipy.signal.convolve(img[..., c], k[min(c, len(k) - 1)], "same") for c in range(3)],
            axis=-1,
        )
        np.testing.assert_allclose(out, ref, rtol=1e-9, atol=1e-12 * img.max())


def test_glare_conserves_energy():
    # a source far from the border with a kernel that fits: nothing leaves the image
    img = np.zeros((64, 64, 3), np.float32)
    img[30:33, 31:34] = [5e3, 4e3, 3e3]
    view = hv.View(pixel_deg=0.1).resolve(64, 64)
    out = np.asarray(hv.glare(img, view, variant="mesopic", radius_deg=2.5), np.float64)
    np.testing.assert_allclose(out.sum(axis=(0, 1)), img.sum(axis=(0, 1)), rtol=RTOL32)
    assert (out >= 0).all()
    # full kernel: what is missing is exactly the light scattered past the border
    scene = night_scene(40, 80).astype(np.float32)
    scene[5, 70] = 2e4
    v2 = hv.View(hfov=40.0).resolve(40, 80)
    full = np.asarray(hv.glare(scene, v2), np.float64)
    inside = np.asarray(hv.glare(np.ones_like(scene), v2), np.float64)
    np.testing.assert_allclose(full.sum(), (scene * inside).sum(), rtol=RTOL32)
    assert full.sum() < scene.sum()


def test_glare_nan_stays_in_its_pixel_and_gradients_are_finite():
    img = night_scene(20, 30).astype(np.float32)
    img[8, 8] = 1e3
    bad = img.copy()
    bad[3, 4, 1] = np.nan
    bad[15, 20] = np.inf
    view = hv.View(hfov=20.0).resolve(20, 30)
    out = np.asarray(hv.glare(bad, view))
    assert np.isnan(out[3, 4, 1]) and np.isinf(out[15, 20]).all()
    clean = img.copy()
    clean[3, 4] = 0.0  # the pixel with a NaN channel is left out entirely
    clean[15, 20] = 0.0
    ref = np.asarray(hv.glare(clean, view))
    mask = np.ones(out.shape[:2], bool)
    mask[3, 4] = mask[15, 20] = False
    np.testing.assert_allclose(out[mask], ref[mask], rtol=RTOL32)
    g = jax.grad(lambda x: jnp.sum(hv.glare(x, view)[5:10]))(jnp.asarray(bad))
    assert np.isfinite(np.asarray(g)).all()


@pytest.mark.parametrize("value", [1e30, 3e38])
def test_glare_huge_values_do_not_overflow(value):
    img = np.full((16, 16, 3), 1.0, np.float32)
    img[8, 8] = value
    out = np.asarray(hv.glare(img, hv.View(hfov=10.0), radius_deg=1.0))
    assert np.isfinite(out).all()
    k = hv.glare_kernel(hv.View(hfov=10.0).resolve(16, 16), radius_deg=1.0)[0]
    assert out[8, 8, 0] == pytest.approx(value * k[k.shape[0] // 2, k.shape[1] // 2], rel=1e-3)


@pytest.mark.usefixtures("x64")
def test_glare_float32_error_is_bounded_by_total_light():
    img = night_scene(64, 128)
    img[30:32, 60:62] = 1e5
    view = hv.View(hfov=40.0).resolve(64, 128)
    ref = np.asarray(hv.glare(img, view))
    out32 = hv.glare(img.astype(np.float32), view)  # float32 in, float32 throughout
    assert out32.dtype == np.float32
    out = np.asarray(out32, np.float64)
    # FFT round-off: absolute error a few 1e-8 of the image's total light per pixel
    assert np.abs(out - ref).max() <= 1e-7 * img.sum()
    assert np.median(np.abs(out - ref) / ref) < RTOL32


# -- pcond veil ------------------------------------------------------------------------


@pytest.mark.usefixtures("x64")
def test_pcond_veil_against_dense_formula():
    img = night_scene(20, 36)
    img[4:8, 30:34] = 500.0
    view = hv.View(pixel_deg=0.5).resolve(20, 36)  # 2×2-pixel foveal blocks
    by, bx = view.fovea_block
    assert (by, bx) == (2, 2)
    fov = img.reshape(10, 2, 18, 2, 3).mean(axis=(1, 3))
    yy, xx = np.mgrid[0:10, 0:18]
    pts = np.stack([yy.ravel(), xx.ravel()], 1) * 1.0  # degrees (1 sample = 1°)
    th = np.deg2rad(np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1)))
    c = np.cos(th)
    with np.errstate(divide="ignore"):
        w = np.where((c > 1e-6) & (th > 0), 0.5 * c / (1 - c), 0.0)
    veil = 0.08 * (w @ fov.reshape(-1, 3)) / w.sum(1, keepdims=True)
    veil = veil.reshape(10, 18, 3)
    out = np.asarray(hv.veil(img, view))
    np.testing.assert_allclose(out, 0.92 * img + np_upsample(veil, 2, 2, 20, 36), rtol=1e-6)


@pytest.mark.usefixtures("x64")
def test_pcond_veil_of_a_uniform_image_at_the_float64_maximum():
    """Issue 16.3: FFT round-off put the weighted mean of a uniform image at the float64
    maximum a few ulps above it, and 0.92·RGB + 0.08·mean rounded past the maximum (+Inf
    pixels); the veil of a uniform image is the image (a blend stays between its values)."""
    top = np.finfo(np.float64).max
    out = np.asarray(hv.veil(np.full((8, 8, 3), top)))
    assert out.dtype == np.float64
    np.testing.assert_allclose(out, top, rtol=1e-12)


# -- colour ------------------------------------------------------------------------------


@pytest.mark.usefixtures("x64")
def test_colour_loss_is_pcond_scotscan():
    rng = np.random.default_rng(1)
    rgb = 10.0 ** rng.uniform(-4, 2, (200, 1)) * rng.uniform(0.05, 1.0, (200, 3))
    _, Y, _, V = np_cielum(rgb)
    c = np.clip((Y - 5.62e-3) / (5.62 - 5.62e-3), 0, 1)[:, None]
    expect = c * rgb + (1 - c) * (V / 2.26)[:, None]
    np.testing.assert_allclose(hv.colour_loss(rgb), expect, rtol=RTOL64, atol=1e-300)
    # photopic pixels keep their colour; scotopic ones are grey
    assert np.allclose(np.asarray(hv.colour_loss(rgb[Y > 5.62])), rgb[Y > 5.62])
    grey = np.asarray(hv.colour_loss(rgb[Y < 5.62e-3]))
    np.testing.assert_allclose(grey, grey[:, :1].repeat(3, 1), rtol=RTOL64)


@pytest.mark.usefixtures("x64")
def test_blue_shift_is_jensen2001():
    rng = np.random.default_rng(2)
    rgb = 10.0 ** rng.uniform(-3, 1.5, (200, 1)) * rng.uniform(0.05, 1.0, (200, 3))
    X, Y, Z, V = np_cielum(rgb)
    x = np.clip((np.log10(Y) + 2) / 2.6, 0, 1)
    s = 3 * x**2 - 2 * x**3
    tot = X + Y + Z
    cx = (1 - s) * 0.25 + s * X / tot
    cy = (1 - s) * 0.25 + s * Y / tot
    Yn = 0.4468 * (1 - s) * V + s * Y
    xyz = np.stack([cx * Yn / cy, Yn, (1 - cx - cy) * Yn / cy], -1)
    expect = xyz @ np.linalg.inv(rgb_to_xyz_matrix()).T
    np.testing.assert_allclose(hv.blue_shift(rgb), expect, rtol=1e-6, atol=1e-12)
    # fully scotopic pixels land on the blue-shift white (0.25, 0.25)
    dark = np.asarray(hv.blue_shift(rgb[Y < 0.01])) @ rgb_to_xyz_matrix().T
    np.testing.assert_allclose(dark[:, 0] / dark.sum(1), 0.25, rtol=1e-6)
    np.testing.assert_allclose(dark[:, 1] / dark.sum(1), 0.25, rtol=1e-6)


def test_per_pixel_effects_hard_values():
    rgb = np.array(
        [[0, 0, 0], [-1e-3, 0.01, 0.02], [np.nan, 1, 1], [np.inf, 0, 0], [1e30, 1e30, 1e30]],
        np.float32,
    )
    for f in (hv.colour_loss, hv.blue_shift):
        out = np.asarray(f(rgb))
        assert np.isfinite(out[[0, 1, 4]]).all(), f
        np.testing.assert_array_equal(out[2:4], rgb[2:4])  # passed through
        g = jax.grad(lambda x, f=f: jnp.sum(f(x)))(jnp.asarray(rgb))
        assert np.isfinite(np.asarray(g)).all(), f


# -- acuity ------------------------------------------------------------------------------


def np_acuity_loss(rgb, view, levels):
    """float64 NumPy transcription of pcond's acuity sampling (see _acuity.py)."""
    H, W, _ = rgb.shape
    by, bx = view.fovea_block
    Y = rgb @ np.array([0.2126, 0.7152, 0.0722])
    hb, wb = -(-H // by), -(-W // bx)
    fov = np.zeros((hb, wb))
    for i in range(hb):
        for j in range(wb):
            fov[i, j] = Y[i * by : (i + 1) * by, j * bx : (j + 1) * bx].mean()
    ppd = 1 / math.sqrt(view.pixel_deg_x * view.pixel_deg_y)
    s_fov = ppd / (17.25 * np.arctan(1.4 * np.log10(np.maximum(fov, 1e-7)) + 0.35) + 25.72)

    def up2(a, fy, fx):
        return np_upsample(a, fy, fx, H, W)

    s = np.clip(np.maximum(up2(s_fov, by, bx), 1.0), 1, 2.0**levels)
    out = np.zeros_like(rgb)
    for k in range(levels + 1):
        f = 2**k
        hk, wk = -(-H // f), -(-W // f)
        lvl = np.zeros((hk, wk, 3))
        for i in range(hk):
            for j in range(wk):
                lvl[i, j] = rgb[i * f : (i + 1) * f, j * f : (j + 1) * f].mean(axis=(0, 1))
        upk = up2(lvl, f, f)
        if k == 0:
            w = np.clip(2 - s, 0, 1)
        else:
            w = np.where(
                s <= f, np.clip((s - f / 2) / (f / 2), 0, 1), np.clip((2 * f - s) / f, 0, 1)
            )
        if k == levels:
            w = np.where(s >= f, 1.0, w)
        out += w[..., None] * upk
    return out


@pytest.mark.usefixtures("x64")
def test_acuity_loss_matches_pcond_transcription():
    img = night_scene(37, 53, lo=1e-4, hi=0.05)
    img[:, 20:] *= 100.0  # bright right part: sharper there
    view = hv.View(hfov=12.0).resolve(37, 53)
    out = np.asarray(hv.acuity_loss(img, view, levels=4))
    np.testing.assert_allclose(out, np_acuity_loss(img, view, 4), rtol=1e-9)
    # the dark side is blurred more (less variance left) than the bright side
    d = np.asarray(out) / img.mean(axis=(0, 1))
    assert d[:, :15].std() < d[:, 30:].std()


def test_acuity_loss_leaves_bright_or_uniform_images_alone():
    view = hv.View(hfov=60.0).resolve(32, 64)  # 1 pixel ≈ 1°: the eye resolves it all
    rng = np.random.default_rng(3)
    day = rng.uniform(100, 1000, (32, 64, 3)).astype(np.float32)
    np.testing.assert_allclose(np.asarray(hv.acuity_loss(day, view)), day, rtol=RTOL32)
    flat = np.full((32, 64, 3), 1e-3, np.float32)
    np.testing.assert_allclose(np.asarray(hv.acuity_loss(flat, 0.5)), flat, rtol=RTOL32)


def test_acuity_loss_keeps_nan_in_its_pixel():
    img = night_scene(24, 24).astype(np.float32)
    img[5, 5] = np.nan
    out = np.asarray(hv.acuity_loss(img, 2.0, levels=3))
    assert (
        np.isnan(out[5, 5]).all()
        and np.isfinite(np.delete(out.reshape(-1, 3), 5 * 24 + 5, 0)).all()
    )
    # gradients through acuity_loss: test_simulate.py::test_human_vision_jit_vmap_grad


# -- contrast ----------------------------------------------------------------------------


@pytest.mark.usefixtures("x64")
def test_contrast_scales_by_tvi_ratio():
    rgb = night_scene(4, 5)
    out = np.asarray(hv.contrast(rgb, 0.1))
    m = float(hv.tvi(100 / math.sqrt(32))) / float(hv.tvi(0.1))
    np.testing.assert_allclose(out, m * rgb, rtol=RTOL64)
