"""PU21 (Mantiuk & Azimi 2021) and the PSNR/SSIM on it, log PSNR and mPSNR, each against a
float64 NumPy model of the published formulas (written in this file)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import ndimage

import hdrjax.metrics as hm

from ..conftest import RTOL32, RTOL64

LUMINANCES = np.array([1e-4, 0.005, 0.01, 0.1, 1.0, 10.0, 100.0, 1000.0, 10000.0, 1e5])
"""cd/m²: both clamps, and every decade of the encoding's range."""


def pu21_numpy(L, p):
    Y = np.clip(np.asarray(L, np.float64), 0.005, 10000.0)
    V = p[6] * (((p[0] + p[1] * Y ** p[3]) / (1 + p[2] * Y ** p[3])) ** p[4] - p[5])
    return np.maximum(V, 0.0)


@pytest.mark.parametrize("params", sorted(hm.PU21_PARAMETERS))
def test_pu21_matches_the_published_formula(params, x64):
    p = hm.PU21_PARAMETERS[params]
    got = np.asarray(hm.pu21_encode(LUMINANCES, params=params))
    np.testing.assert_allclose(got, pu21_numpy(LUMINANCES, p), rtol=RTOL64)


def test_pu21_properties():
    """100 cd/m² ↦ about 256 (the SDR range, Mantiuk & Azimi 2021), monotone, clamped."""
    v = np.asarray(hm.pu21_encode(LUMINANCES))
    assert abs(float(hm.pu21_encode(100.0)) - 256) < 10
    assert np.all(np.diff(v[1:-1]) > 0)
    assert v[0] == v[1] and v[-1] == v[-2]
    with pytest.raises(ValueError, match="^params: expected one of"):
        hm.pu21_encode(1.0, params="pu08")


def _pair(seed=0, shape=(2, 24, 31, 3)):
    rng = np.random.default_rng(seed)
    ref = rng.lognormal(3.0, 2.0, shape)
    test = ref * rng.lognormal(0.0, 0.2, shape)
    return test, ref


def test_pu_psnr(x64):
    test, ref = _pair()
    p = hm.PU21_PARAMETERS["banding_glare"]
    mse = ((pu21_numpy(test, p) - pu21_numpy(ref, p)) ** 2).mean(axis=(1, 2, 3))
    np.testing.assert_allclose(hm.pu_psnr(test, ref), 10 * np.log10(256**2 / mse), rtol=RTOL64)


def _ssim_numpy(a, b, L=256.0):
    """Wang et al. (2004) with MATLAB ssim's conventions: 11×11 Gaussian σ 1.5, edges
    replicated, per channel, mean over pixels and channels."""
    x = np.arange(11) - 5.0
    w = np.exp(-(x[:, None] ** 2 + x[None] ** 2) / 4.5)
    w /= w.sum()
    c1, c2 = (0.01 * L) ** 2, (0.03 * L) ** 2
    out = []
    for c in range(3):
        u, v = a[..., c], b[..., c]

        def f(t):
            return ndimage.correlate(t, w, mode="nearest")

        mu, mv = f(u), f(v)
        su, sv, suv = f(u * u) - mu**2, f(v * v) - mv**2, f(u * v) - mu * mv
        out.append(((2 * mu * mv + c1) * (2 * suv + c2)) / ((mu**2 + mv**2 + c1) * (su + sv + c2)))
    return np.mean(out)


def test_pu_ssim(x64):
    test, ref = _pair(1)
    p = hm.PU21_PARAMETERS["banding"]
    want = [_ssim_numpy(pu21_numpy(t, p), pu21_numpy(r, p)) for t, r in zip(test, ref, strict=True)]
    np.testing.assert_allclose(hm.pu_ssim(test, ref, params="banding"), want, rtol=RTOL64)
    np.testing.assert_allclose(hm.pu_ssim(ref, ref), 1.0, rtol=RTOL64)


def test_log_psnr(x64):
    test, ref = _pair(2)
    a, b = np.log10(np.maximum(test, 1e-5)), np.log10(np.maximum(ref, 1e-5))
    peak = b.max(axis=(1, 2, 3)) + 5
    want = 10 * np.log10(peak**2 / ((a - b) ** 2).mean(axis=(1, 2, 3)))
    np.testing.assert_allclose(hm.log_psnr(test, ref), want, rtol=RTOL64)


def mpsnr_numpy(ref, dist):
    """HDR Toolbox's mPSNR.m, as read: exposures from the two images' luminance range,
    those whose reference rendition has a mean in (0.1, 0.9) counted, MSEs summed."""
    w = np.array([0.2126, 0.7152, 0.0722])
    L1, L2 = ref @ w, dist @ w
    lo = min(L1[L1 > 0].min(), L2[L2 > 0].min())
    hi = max(L1.max(), L2.max())
    e_min, e_max = -round(np.log2(hi)), -round(np.log2(lo))
    if e_min == e_max:
        e_min, e_max = e_min - 1, e_max + 1
    total, used = 0.0, 0
    for e in range(int(e_min), int(e_max) + 1):

        def q(x, e=e):
            return np.clip(np.round(255 * (x * 2.0**e) ** (1 / 2.2)), 0, 255)

        if 0.1 < (q(ref) / 255).mean() < 0.9:
            total += ((q(ref) - q(dist)) ** 2).mean()
            used += 1
    return 20 * np.log10(255 / np.sqrt(total)) if used else -1.0


def test_mpsnr(x64):
    test, ref = _pair(3)
    want = [mpsnr_numpy(r, t) for t, r in zip(test, ref, strict=True)]
    np.testing.assert_allclose(hm.mpsnr(test, ref), want, rtol=RTOL64)


def test_identical_black_and_nan_pairs():
    """Identical images: PSNRs +inf, SSIM 1, ΔE 0, all with finite (zero) gradients; NaN
    pixels are left out; a black pair is identical."""
    rng = np.random.default_rng(4)
    img = rng.lognormal(2.0, 1.5, (2, 16, 16, 3)).astype(np.float32)
    img[1] = 0.0
    nan = img.copy()
    nan[0, 2, 3, 0] = np.nan
    fns = {
        "pu_psnr": hm.pu_psnr,
        "log_psnr": hm.log_psnr,
        "mpsnr": hm.mpsnr,
        "pu_ssim": hm.pu_ssim,
        "delta_e_itp": lambda a, b: jnp.mean(hm.delta_e_itp(a, b), axis=(-2, -1)),
    }
    for name, f in fns.items():
        for x in (img, nan):
            v = np.asarray(f(x, x))
            if name == "mpsnr":
                assert np.all((v == np.inf) | (v == -1.0)), (name, v)
            elif name == "pu_ssim":
                np.testing.assert_allclose(v, 1.0, rtol=RTOL32)
            elif name == "delta_e_itp":
                np.testing.assert_array_equal(v, 0.0)
            else:
                assert np.all(v == np.inf), (name, v)
            g = jax.grad(lambda a, f=f, x=x: jnp.sum(jnp.where(jnp.isfinite(f(a, x)), f(a, x), 0)))
            assert np.all(np.isfinite(g(x))), name
        distorted = np.asarray(f(nan * 1.1, nan))
        assert np.all(np.isfinite(distorted[0])), name  # the NaN pixel is left out


def test_input_errors():
    with pytest.raises(ValueError, match="^reference: expected the shape of test"):
        hm.pu_psnr(np.ones((4, 4, 3)), np.ones((4, 5, 3)))
    with pytest.raises(ValueError, match="^floor: expected a positive number"):
        hm.log_psnr(np.ones((4, 4, 3)), np.ones((4, 4, 3)), floor=0.0)
    with pytest.raises(ValueError, match="^span: expected a positive integer"):
        hm.mpsnr(np.ones((4, 4, 3)), np.ones((4, 4, 3)), span=0)
