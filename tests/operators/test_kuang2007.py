"""kuang2007 (iCAM06, Kuang et al. 2007) against HDR Toolbox's ``KuangTMO`` (GNU Octave, the
fixtures of fixtures/hdrtoolbox/make_kuang2007.py) and a float64 NumPy model of the module
docstring's steps 2–7 (step 1, the bilateral filter, is durand2002's, tested there).

Issue 21's parity criterion, per image: SSIM of the encoded luminance ≥ 0.97 and mean
absolute difference ≤ 0.02 (both outputs clipped to [0, 1], sRGB encoded; the SSIM of
tests/operators/test_durand2002.py). ``KuangTMO``'s outputs are display-linear. The peer
is the Toolbox with its bilateral domain fixed to the paper's log10 (the fixture script
says how); the Toolbox as shipped filters linear values (module docstring of
``hdrjax.operators._kuang2007``), which :func:`test_the_shipped_toolbox_skips_the_detail`
measures. Measured, float32, against the fixed Toolbox: SSIM 0.9981, 0.9982, 0.9909,
mean differences 0.0102, 0.0067, 0.0091 and largest differences 0.064, 0.081, 0.095
(rooitou_park, venice_sunset, MtTamWest; the Toolbox filters the channels jointly and
blurs the white on an image downsampled by 8).
"""

import functools
import math
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.ndimage import correlate1d

import hdrjax
from hdrjax.operators._ashikhmin2002 import gaussian_taps
from hdrjax.operators._durand2002 import bilateral_base
from hdrjax.operators._kuang2007 import (
    D65_XYZ,
    M_CAT02,
    M_D65,
    M_HPE,
    M_IPT,
    luminance_factor,
    white_blur,
)

from ..conftest import enable_x64
from .test_durand2002 import assert_parity, criterion

FIXTURES = Path(__file__).parent / "fixtures" / "hdrtoolbox" / "kuang2007.npz"
SSIM_MIN = 0.97
"""Issue 21's criterion (with a mean difference ≤ 0.02: ``assert_parity``)."""
SSIM_TIGHT, MAD_TIGHT = 0.985, 0.013
"""Measured: SSIM ≥ 0.9909, mean difference ≤ 0.0102 (the module docstring)."""
RTOL_MODEL = 1e-9
"""float64 against the NumPy model (the same operations in another order)."""
RTOL_GRAD = 1e-5
"""float64 image gradient against a central difference of relative step 1e-6."""
IDS = ["rooitou_park", "venice_sunset", "MtTamWest"]
SRGB_TO_XYZ = np.array(
    [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]
)
"""IEC 61966-2-1's RGB → XYZ matrix (HDR Toolbox's ``ConvertRGBtoXYZ``)."""


@functools.cache
def toolbox() -> dict[str, np.ndarray]:
    with np.load(FIXTURES) as d:
        return {k: d[k] for k in d.files}


@functools.cache
def outputs() -> np.ndarray:
    op = hdrjax.make_operator("kuang2007")
    return np.asarray(eqx.filter_jit(lambda o, x: o(x))(op, toolbox()["input"]))


@pytest.mark.parametrize("i", range(3), ids=IDS)
def test_matches_hdrtoolbox(i):
    assert_parity(outputs()[i], toolbox()["output"][i], SSIM_TIGHT, MAD_TIGHT)


def test_the_shipped_toolbox_skips_the_detail():
    """HDR Toolbox as shipped filters linear XYZ with the log-unit ``σ_r`` (a misspelt
    domain): its detail layer is about 1, and on MtTamWest (fine foliage) its result is
    far from the paper's (SSIM 0.906 against this operator, 0.918 against the fixed
    Toolbox; this operator against the fixed Toolbox: 0.991), so parity is
    with the fixed one and this operator follows the paper."""
    s_fixed = criterion(outputs()[2], toolbox()["output"][2])[0]
    s_shipped = criterion(outputs()[2], toolbox()["output_shipped"][2])[0]
    assert s_shipped < SSIM_MIN < s_fixed
    # the two Toolbox runs differ as much
    s_peers = criterion(toolbox()["output_shipped"][2], toolbox()["output"][2])[0]
    assert s_peers < SSIM_MIN


def _spow(x, e):
    return np.sign(x) * np.abs(x) ** e


def _F_L(L_A):
    k = 1 / (5 * L_A + 1)
    return 0.2 * k**4 * 5 * L_A + 0.1 * (1 - k**4) ** 2 * np.cbrt(5 * L_A)


def kuang_model(rgb, base_log, L_peak=20000.0, p=0.75, gamma=1.0):
    """Steps 2–7 of the module docstring in float64, literally, from the image and the
    bilateral filter's log10 base layer (``(H, W, 3)``)."""
    m = SRGB_TO_XYZ
    x = rgb * (L_peak / (rgb @ m[1]).max())
    XYZ = x @ m.T
    H, W = XYZ.shape[:2]
    t = gaussian_taps(5 * 0.5 * max(H, W))
    white = correlate1d(correlate1d(XYZ, t, axis=0, mode="nearest"), t, axis=1, mode="nearest")
    base = 10**base_log
    detail = (XYZ + 1e-6) / base
    Y_W = white[..., 1]
    L_A = 0.2 * Y_W
    D = (1 - np.exp(-(L_A + 42) / 92) / 3.6)[..., None]
    rgb_w = white @ M_CAT02.T
    rgb_c = (base @ M_CAT02.T) * (D * (M_CAT02 @ D65_XYZ) / rgb_w + 1 - D)
    adapted = rgb_c @ np.linalg.inv(M_CAT02).T
    F_L = _F_L(L_A)[..., None]
    tt = _spow(F_L * (adapted @ M_HPE.T) / Y_W[..., None], p)
    cones = 400 * tt / (27.13 + np.abs(tt)) + 0.1
    S_t = adapted[..., 1] / Y_W.max()
    L_LS = 5 * L_A
    j = 1e-5 / (L_LS + 1e-5)
    F_LS = 3800 * j**2 * L_LS + 0.2 * (1 - j**2) ** 4 * L_LS ** (1 / 6)
    B_S = 0.5 / (1 + 0.3 * (L_LS * S_t) ** 0.3) + 0.5 / (1 + 5 * L_LS)
    ts = (F_LS * S_t) ** p
    A_S = 3.05 * B_S * 400 * ts / (27.13 + ts) + 0.3
    tc = (cones + A_S[..., None]) @ np.linalg.inv(M_HPE).T
    F_L2 = _F_L(0.2 * base[..., 1])
    xyz = tc * detail ** ((F_L2 + 0.8) ** 0.25)[..., None]
    ipt = _spow(xyz @ M_D65.T, 0.43) @ M_IPT.T
    C = np.hypot(ipt[..., 1], ipt[..., 2])
    hunt = (F_L2 + 1) ** 0.2 * (1.29 * C**2 - 0.27 * C + 0.42) / (C**2 - 0.31 * C + 0.42)
    ipt[..., 1:] *= hunt[..., None]
    I_max = ipt[..., 0].max()
    ipt[..., 0] = _spow(ipt[..., 0] / I_max, gamma) * I_max
    out = _spow(ipt @ np.linalg.inv(M_IPT).T, 1 / 0.43) @ np.linalg.inv(M_D65).T
    out = out @ np.linalg.inv(m).T
    v = np.sort(out.reshape(-1))
    lo = v[max(math.floor(v.size * 0.01 + 0.5), 1) - 1]
    hi = v[max(math.floor(v.size * 0.99 + 0.5), 1) - 1]
    return (out - lo) / (hi - lo)


_bilateral = jax.jit(bilateral_base, static_argnames=("sigma_s", "max_segments"))


def _base_log(rgb, L_peak=20000.0, sigma_r=0.35):
    """Step 1 by hdrjax's bilateral filter (durand2002's, tested there), float64: each
    channel alone, the nodes spanning the log values of all three."""
    m = SRGB_TO_XYZ
    XYZ = (rgb * (L_peak / (rgb @ m[1]).max())) @ m.T
    logs = np.log10(XYZ + 1e-6)
    sigma_s = 0.02 * min(rgb.shape[:2])
    return np.stack(
        [
            np.asarray(
                _bilateral(
                    jnp.asarray(logs[..., c]),
                    jnp.ones(logs.shape[:2], bool),
                    jnp.asarray(logs.min()),
                    jnp.asarray(logs.max()),
                    jnp.asarray(math.sqrt(2) * sigma_r),
                    sigma_s=math.pi * sigma_s,
                    max_segments=64,
                )
            )
            for c in range(3)
        ],
        axis=-1,
    )


@functools.cache
def _weights() -> np.ndarray:
    return np.random.default_rng(1).uniform(0.5, 1.5, (2, 48, 96, 3))


def _output_and_derivative(op, x, v):
    """``(op(x), Σ w · ∂op(x)/∂x · v)``, forward mode: the float64 tests' one compiled
    program."""
    out, tangent = jax.jvp(op, (x,), (v,))
    return out, jnp.sum(tangent * _weights())


_float64_run = eqx.filter_jit(_output_and_derivative)


def test_follows_the_steps_in_float64():
    """float64 against :func:`kuang_model` on two fixture images, the defaults and
    another ``L_peak`` and ``p`` (parameters are traced: one compile)."""
    with enable_x64():
        x = toolbox()["input"][:2].astype(np.float64)
        for kw in (dict(), dict(L_peak=5000.0, p=0.65)):
            op = hdrjax.make_operator("kuang2007", **kw)
            got = np.asarray(_float64_run(op, x, np.zeros_like(x))[0])
            for img, out in zip(x, got, strict=True):
                ref = kuang_model(img, _base_log(img, kw.get("L_peak", 20000.0)), **kw)
                np.testing.assert_allclose(out, ref, rtol=RTOL_MODEL, atol=RTOL_MODEL)


def test_image_gradient_matches_central_differences():
    """float64: the image derivative of ``Σ w · op(x)`` along a random direction (forward
    mode, as ``jax.grad`` transposes it; tests/operators/test_conformance_grad.py runs the
    reverse mode) against a central difference of relative step 1e-6 of each pixel (the
    percentiles and maxima keep their pixels)."""
    with enable_x64():
        x = toolbox()["input"][:2].astype(np.float64)
        v = np.random.default_rng(2).normal(size=x.shape) * x
        op = hdrjax.make_operator("kuang2007")
        d = float(_float64_run(op, x, v)[1])
        h = 1e-6
        plus, minus = (
            float(np.sum(np.asarray(_float64_run(op, x + s * h * v, v)[0]) * _weights()))
            for s in (1.0, -1.0)
        )
        np.testing.assert_allclose(d, (plus - minus) / (2 * h), rtol=RTOL_GRAD)


def test_white_is_the_toolbox_blur():
    """The adapting white: a Gaussian of σ = max(H, W) / 2 pixels truncated at 2.5 σ
    (MATLAB's ``fspecial``), edges replicated, equal to SciPy's ``mode="nearest"``."""
    with enable_x64():
        x = np.random.default_rng(0).uniform(0, 5, (7, 12, 3))
        t = gaussian_taps(5 * 0.5 * 12)
        ref = correlate1d(correlate1d(x, t, axis=0, mode="nearest"), t, axis=1, mode="nearest")
        np.testing.assert_allclose(np.asarray(white_blur(jnp.asarray(x))), ref, rtol=1e-12)


def test_constants_are_the_published_ones():
    """CAT02, Hunt–Pointer–Estévez and IPT's matrices as colour-science holds them;
    ``F_L`` as CIECAM02's."""
    from colour.adaptation import CAT_CAT02
    from colour.appearance import ciecam02
    from colour.models import ipt

    np.testing.assert_array_equal(M_CAT02, CAT_CAT02)
    np.testing.assert_array_equal(M_D65, ipt.MATRIX_IPT_XYZ_TO_LMS)
    np.testing.assert_array_equal(M_IPT, ipt.MATRIX_IPT_LMS_P_TO_IPT)
    np.testing.assert_array_equal(M_HPE, ciecam02.MATRIX_XYZ_TO_HPE)
    L_A = np.array([0.1, 4.0, 318.31, 2e4])
    want = ciecam02.luminance_level_adaptation_factor(L_A)
    with enable_x64():
        np.testing.assert_allclose(np.asarray(luminance_factor(jnp.asarray(L_A))), want, rtol=1e-12)
