"""fattal2002 (Fattal, Lischinski & Werman 2002) against pfstmo 2.2.0's ``pfstmo_fattal02``
and a float64 NumPy model of the paper's steps.

Fixtures: fixtures/pfstmo/fattal2002.npz, written by fixtures/pfstmo/make_fattal2002.py
(its docstring: the commands, the pfstmo version and its default configuration, the DCT
Poisson solver; how the inputs were cropped and downscaled from the repository's
``data/``; the test rebuilds the inputs the same way and checks their sums). pfstmo tags its
output ``LUMINANCE=RELATIVE`` (checked by the script): display-linear, so both outputs are
clipped to [0, 1] and sRGB-encoded alike.

Issue 21's parity criterion, per image: SSIM of the encoded luminance ≥ 0.97 and mean
absolute difference ≤ 0.02, the SSIM and encoding of tests/operators/test_durand2002.py.
Measured, float32 (SSIM / mean / 99th percentile / maximum of the absolute difference):
rooitou_park 0.99999 / 0.00018 / 0.0005 / 0.0011, venice_sunset 0.99999 / 0.00007 / 0.0003
/ 0.0010, MtTamNorth 0.99999 / 0.00007 / 0.0003 / 0.0004, cornell_box 0.99994 / 0.00016 /
0.0003 / 0.016 (the maximum at a few pixels darker than 10⁻⁴, where pfstmo's colour ratios
use its absolute floor). The differences come from the operator's deviations (module docstring of
hdrjax.operators._fattal2002): the type-II transform's boundaries against pfstmo's type-I,
the colour ratios without pfstmo's absolute floor of 10⁻⁴, the interpolated percentiles.
"""

import dataclasses
import functools
import math
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.fft import dct

import hdrjax
import hdrjax.tile as T
from hdrjax.operators._fattal2002 import (
    blur_downsample,
    dct2_last,
    idct2_last,
    levels,
    solve_poisson_neumann,
    upsample_blur,
)

from .test_durand2002 import IMAGES, encoded_luminance, inputs, ssim

HERE = Path(__file__).resolve().parent
FIXTURES = HERE / "fixtures" / "pfstmo" / "fattal2002.npz"
"""The images and their 128 × 256 inputs are those of the durand2002 fixtures."""
SSIM_MIN, MAD_MAX = 0.97, 0.02
"""Issue 21's criterion."""
SSIM_TIGHT, MAD_TIGHT = 0.9998, 0.0005
"""Tighter bounds, just outside the measured worst (0.99994, 0.00018)."""
RTOL64 = 1e-6


@functools.cache
def fixtures() -> dict[str, np.ndarray]:
    with np.load(FIXTURES) as f:
        return {k: f[k] for k in f.files}


@functools.cache
def outputs() -> np.ndarray:
    """The operator (pfstmo's defaults) on the four inputs, one compiled program."""
    op = hdrjax.make_operator("fattal2002")
    return np.asarray(eqx.filter_jit(lambda o, x: o(x))(op, inputs()))


def test_inputs_are_the_fixtures():
    sums = [float(np.sum(x, dtype=np.float64)) for x in inputs()]
    np.testing.assert_allclose(sums, fixtures()["input_sum"], rtol=1e-12)


@pytest.mark.parametrize("i", range(len(IMAGES)), ids=[n for n, _ in IMAGES])
def test_matches_pfstmo(i):
    want = encoded_luminance(fixtures()["luminance"][i].astype(np.float64))
    got = encoded_luminance(outputs()[i].astype(np.float64))
    s, mad = ssim(got, want), float(np.abs(got - want).mean())
    assert s >= SSIM_MIN and mad <= MAD_MAX, (s, mad)
    assert s >= SSIM_TIGHT and mad <= MAD_TIGHT, (s, mad)


def numpy_blur(a):
    """The ``[1 2 1] / 4`` blur along both axes, edge pixels repeated."""
    p = np.pad(a, 1, mode="edge")
    a = (p[1:-1, :-2] + 2 * p[1:-1, 1:-1] + p[1:-1, 2:]) / 4
    p = np.pad(a, 1, mode="edge")
    return (p[:-2, 1:-1] + 2 * p[1:-1, 1:-1] + p[2:, 1:-1]) / 4


def numpy_luminance(Y, alpha, beta, gamma, noise, detail_level, black, white):
    """The module docstring's steps 1–6 in float64 NumPy, written out plainly: the blur and
    the resampling separately, the Laplacian as a dense Kronecker sum solved by least
    squares (the constant mode left to ``lstsq``'s minimum norm), the percentiles by
    ``np.percentile`` (linear)."""

    H = np.log(100 * (Y - Y.min()) / (Y.max() - Y.min()) + 1e-4)
    pyramid = [H]
    while min(pyramid[-1].shape) // 2 >= 8:
        b = numpy_blur(pyramid[-1])
        h, w = b.shape[0] // 2, b.shape[1] // 2
        pyramid.append(b[: 2 * h, : 2 * w].reshape(h, 2, w, 2).mean(axis=(1, 3)))
    n = len(pyramid)
    phi = np.ones(pyramid[-1].shape)
    for k in range(n - 1, -1, -1):
        if k >= detail_level or k == n - 1:
            p = np.pad(pyramid[k], 1, mode="edge")
            g = np.hypot(p[1:-1, 2:] - p[1:-1, :-2], p[2:, 1:-1] - p[:-2, 1:-1]) / 2 ** (k + 1)
            a = alpha * g.mean()
            phi = phi * np.where(g > 1e-4, a / (g + noise) * ((g + noise) / a) ** beta, 1.0)
        if k > 0:
            shape = pyramid[k - 1].shape
            ys = np.minimum(np.arange(shape[0]) // 2, phi.shape[0] - 1)
            xs = np.minimum(np.arange(shape[1]) // 2, phi.shape[1] - 1)
            phi = numpy_blur(phi[ys][:, xs])
    h, w = H.shape
    gx = np.zeros((h, w))
    gy = np.zeros((h, w))
    gx[:, :-1] = np.diff(H, axis=1) * (phi[:, 1:] + phi[:, :-1]) / 2
    gy[:-1] = np.diff(H, axis=0) * (phi[1:] + phi[:-1]) / 2
    div = gx + gy
    div[:, 1:] -= gx[:, :-1]
    div[1:] -= gy[:-1]

    def lap1(m):  # 1-D Laplacian, zero-flux Neumann (I(-1) = I(0))
        d = -2 * np.eye(m) + np.eye(m, k=1) + np.eye(m, k=-1)
        d[0, 0] = d[-1, -1] = -1
        return d

    A = np.kron(lap1(h), np.eye(w)) + np.kron(np.eye(h), lap1(w))
    I = np.linalg.lstsq(A, div.reshape(-1), rcond=None)[0].reshape(h, w)
    lo, hi = np.percentile(I, [black, 100 - white])
    L = (np.exp(gamma * I) - np.exp(gamma * lo)) / (np.exp(gamma * hi) - np.exp(gamma * lo))
    return np.maximum(L, 1e-4)


def test_matches_numpy_model(x64):
    """Non-default parameters (every level attenuated), a 20 × 36 crop: 2 levels."""
    x = inputs()[0][50:70, 100:136].astype(np.float64)
    values = dict(alpha=0.8, beta=0.85, gamma=0.9, noise=0.01, detail_level=0)
    pct = dict(black_point=1.0, white_point=2.0)
    op = hdrjax.make_operator("fattal2002", saturation=1.0, **values, **pct)
    Y = x @ np.array([0.2126, 0.7152, 0.0722])
    want = numpy_luminance(Y, **values, black=1.0, white=2.0)
    got = np.asarray(op(x))
    # saturation 1: the colour ratios are kept, so the output's luminance is L
    np.testing.assert_allclose(got @ np.array([0.2126, 0.7152, 0.0722]), want, rtol=RTOL64)


@pytest.mark.parametrize("n", [1, 2, 7, 8, 33])
def test_dct_is_scipys_type_2(x64, n):
    x = np.random.default_rng(n).normal(size=(3, n))
    X = np.asarray(dct2_last(jnp.asarray(x)))
    np.testing.assert_allclose(2 * X, dct(x, type=2), rtol=RTOL64, atol=1e-12)
    np.testing.assert_allclose(np.asarray(idct2_last(jnp.asarray(X))), x, atol=1e-12)


@pytest.mark.parametrize("shape", [(1, 1), (5, 1), (9, 14), (16, 7)])
def test_poisson_solution_has_the_laplacian(x64, shape):
    f = np.random.default_rng(sum(shape)).normal(size=shape)
    u = np.asarray(solve_poisson_neumann(jnp.asarray(f)))
    p = np.pad(u, 1, mode="edge")
    lap = p[:-2, 1:-1] + p[2:, 1:-1] + p[1:-1, :-2] + p[1:-1, 2:] - 4 * u
    np.testing.assert_allclose(lap, f - f.mean(), atol=1e-10)
    assert abs(u.sum()) < 1e-9


@pytest.mark.parametrize("shape", [(8, 8), (9, 13), (16, 7), (3, 2)])
def test_resampling_is_blur_then_box_and_repeat_then_blur(x64, shape):
    x = np.random.default_rng(1).normal(size=shape)

    h, w = shape[0] // 2, shape[1] // 2
    box = numpy_blur(x)[: 2 * h, : 2 * w].reshape(h, 2, w, 2).mean(axis=(1, 3))
    np.testing.assert_allclose(np.asarray(blur_downsample(jnp.asarray(x))), box, atol=1e-14)
    c = x[:h, :w]
    up = np.repeat(np.repeat(c, 2, 0), 2, 1)
    up = np.pad(up, ((0, shape[0] - 2 * h), (0, shape[1] - 2 * w)), mode="edge")
    got = np.asarray(upsample_blur(jnp.asarray(c), shape))
    np.testing.assert_allclose(got, numpy_blur(up), atol=1e-14)


def test_levels_follow_pfstmo():
    """Halvings of the smaller side while it is at least 8 (pfstmo's DCT setting)."""
    assert [levels(s) for s in [(128, 256), (1024, 2048), (8, 9), (7, 100), (1, 1)]] == [
        5,
        8,
        1,
        1,
        1,
    ]


def test_whole_image_only():
    """The Poisson solve couples every pixel: an infinite halo, which hdrjax.tile refuses."""
    op = hdrjax.make_operator("fattal2002")
    assert op.halo((64, 64, 3)) == (math.inf, math.inf)
    with pytest.raises(ValueError, match="whole image"):
        T.apply(T.Tonemap(op), inputs()[0], tile=64)


PARAMS = ("alpha", "beta", "gamma", "saturation", "noise")
FD_STEP = 1e-6
"""Relative step of the central differences (float64)."""


def test_gradients_match_finite_differences(x64):
    """Every parameter and the image (one random direction), through the DCT solve and the
    percentiles, one compiled gradient."""
    rng = np.random.default_rng(2)
    x = jnp.asarray(inputs()[1][40:60, 100:132].astype(np.float64))
    w = jnp.asarray(rng.uniform(0.5, 1.5, x.shape))
    values = dict(alpha=1.2, beta=0.85, gamma=0.7, saturation=0.6, noise=0.01)
    op = hdrjax.make_operator("fattal2002", detail_level=1, **values)

    def loss(o, img):
        return jnp.sum(w * jnp.sqrt(o(img) + 1e-3))

    value = eqx.filter_jit(loss)
    g_op, g_x = eqx.filter_jit(eqx.filter_grad(lambda ox: loss(*ox)))((op, x))
    d = jnp.asarray(rng.normal(size=x.shape)) * x
    analytic = [float(getattr(g_op, n)) * float(getattr(op, n)) for n in PARAMS]
    analytic.append(float(jnp.vdot(g_x, d)))
    numeric = []
    for n in PARAMS:
        v = getattr(op, n)
        up = value(dataclasses.replace(op, **{n: v * (1 + FD_STEP)}), x)
        down = value(dataclasses.replace(op, **{n: v * (1 - FD_STEP)}), x)
        numeric.append(float(up - down) / (2 * FD_STEP))
    numeric.append(float(value(op, x + FD_STEP * d) - value(op, x - FD_STEP * d)) / (2 * FD_STEP))
    assert all(abs(v) > 1e-3 for v in numeric), numeric  # each parameter has an effect
    np.testing.assert_allclose(analytic, numeric, rtol=1e-5)


def test_bad_pixel_stays_and_the_rest_is_finite():
    x = inputs()[2][:32, :64].copy()
    x[10, 20] = np.nan
    x[3, 4] = (np.inf, 1.0, 1.0)
    out = np.asarray(hdrjax.tonemap(x, "fattal2002"))
    assert np.all(np.isnan(out[10, 20]))
    np.testing.assert_array_equal(out[3, 4], 1.0)
    ok = np.ones(x.shape[:2], bool)
    ok[10, 20] = ok[3, 4] = False
    assert np.all(np.isfinite(out[ok]))
