"""ferradans2011 (Ferradans et al. 2011) against pfstmo 2.2.0's ``pfstmo_ferradans11`` and a
float64 NumPy model of the paper's two stages as pfstmo runs them.

Fixtures: fixtures/pfstmo/ferradans2011.npz, written by
fixtures/pfstmo/make_ferradans2011.py (its docstring: the commands, the pfstmo version, how
the inputs were cropped and downscaled from the repository's ``data/``; the test rebuilds
the inputs the same way and checks their sums). pfstmo's result is sRGB-encoded, which
pfstools decodes: both outputs are display-linear, clipped to [0, 1] and sRGB-encoded
alike (issue 21's criterion, :func:`tests.operators.test_durand2002.assert_parity`).

Measured, float32 (SSIM / mean / largest absolute difference of the encoded luminance):
rooitou_park 0.999999 / 2.7e-5 / 1.5e-4, venice_sunset 0.999999 / 3.5e-5 / 1.6e-4,
MtTamNorth 0.999999 / 3.4e-5 / 1.6e-4, cornell_box 0.999998 / 4.5e-5 / 1.7e-4 (mostly the
float16 fixture's rounding, 2⁻¹¹ relative): the same stopping iteration as pfstmo (6, 7, 8
and 9 iterations) and its convolutions at these sizes. pfstmo's stopping rule is part of
the parity, so it is the default: the scheme iterated to convergence (``tol=1e-6``) is
SSIM 0.894 / 0.939 / 0.980 / 0.971 and mean 0.044 / 0.036 / 0.019 / 0.020 away from
pfstmo, outside issue 21's criterion on three of the four images.

Where pfstmo is wrong: on a flat image its contrast term is 0 everywhere and it divides it
by its largest magnitude, 0: the NaN never meets its stopping test and
``pfstmo_ferradans11`` runs forever (checked by hand on an 8 × 8 image of 5 cd/m²). The
paper's scheme has no contrast to enhance there: the operator's output is finite.
"""

import functools
import math
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax.operators import _ferradans2011 as F

from . import test_durand2002 as durand

HERE = Path(__file__).resolve().parent
FIXTURES = HERE / "fixtures" / "pfstmo" / "ferradans2011.npz"
IMAGES, SHAPE = durand.IMAGES, durand.SHAPE
"""The fixture script's images and box factors (128 × 256 each): durand2002's."""
inputs = durand.inputs
SSIM_TIGHT, MAD_TIGHT, MAX_TIGHT = 0.99995, 1e-4, 5e-4
"""Tighter bounds than issue 21's, outside the measured worst (0.999998, 4.5e-5, 1.7e-4)."""
RTOL64 = 1e-6
GRAD_RTOL = 1e-5
"""Central differences (relative step 1e-6, float64) against ``jax.grad``."""


@functools.cache
def fixtures() -> dict[str, np.ndarray]:
    with np.load(FIXTURES) as f:
        return {k: f[k] for k in f.files}


@functools.cache
def outputs() -> np.ndarray:
    """The operator (pfstmo's defaults) on the four inputs, one compiled program."""
    op = hdrjax.make_operator("ferradans2011")
    return np.asarray(eqx.filter_jit(lambda o, x: o(x))(op, inputs()))


def test_inputs_are_the_fixtures():
    sums = [float(np.sum(x, dtype=np.float64)) for x in inputs()]
    np.testing.assert_allclose(sums, fixtures()["input_sum"], rtol=1e-12)
    assert list(fixtures()["nan_pixels"]) == [0, 0, 0, 0]


@pytest.mark.parametrize("i", range(len(IMAGES)), ids=[n for n, _ in IMAGES])
def test_matches_pfstmo(i):
    want = fixtures()["luminance"][i].astype(np.float64)
    durand.assert_parity(outputs()[i], want, SSIM_TIGHT, MAD_TIGHT, MAX_TIGHT)


# --- float64 NumPy model: pfstmo's steps as the module docstring lists them -------------


def numpy_model(rgb: np.ndarray, rho: float, inv_alpha: float, tol: float) -> np.ndarray:
    """Both stages in float64 with full-size circular FFT convolutions and the exact lower
    median (inputs whose median is far from its neighbours, so that the operator's pixel
    nearest the histogram's median is the same)."""
    H, W, _ = rgb.shape
    I0 = np.empty((3, H, W))
    for c, K in enumerate((100 / 1.85, 100 / 1.85, 100 / 8.7)):
        I = np.maximum(rgb[..., c], 0.0) + 1e-6
        med = np.sort(I.ravel())[(I.size - 1) // 2]
        mu = math.sqrt(I.mean() * med)
        mu *= 10 ** (-0.37 * (math.log10(mu) + 4 - rho) + 1.9)
        I_r, i0 = 100 * mu, mu / 10**1.2
        join = I_r**0.74 / (I_r**0.74 + mu**0.74) - K * math.log10(I_r + i0)
        r = np.where(I <= I_r, K * np.log10(I + i0) + join, I**0.74 / (I**0.74 + mu**0.74))
        r -= r.min()
        I0[c] = r / (r.max() + 1e-12)
    sigma = min(H, W) / inv_alpha
    dh = np.minimum(np.arange(H), H - np.arange(H))
    dw = np.minimum(np.arange(W), W - np.arange(W))
    g = np.exp(-(dh[:, None] ** 2 + dw[None, :] ** 2) / (2 * sigma**2))
    g -= np.exp(-((H // 2) ** 2 + (W // 2) ** 2) / (2 * sigma**2))
    G = np.fft.rfft2(g / g.sum())
    coef = {1: 3.7891, 3: -11.013, 5: 15.836, 7: -7.7456}
    a, u = 255 / 253, I0.copy()
    for _ in range(100):
        new = np.empty_like(u)
        for c in range(3):
            M = [np.fft.irfft2(np.fft.rfft2(u[c] ** k) * G, s=(H, W)) for k in range(8)]
            R = sum(
                ck * sum(math.comb(k, j) * u[c] ** (k - j) * (-1) ** j * M[j] for j in range(k + 1))
                for k, ck in coef.items()
            )
            R = np.clip(R, -1, 1)
            R /= np.abs(R).max()
            step = u[c] + 0.2 * (I0[c] + 0.5 * R + a * I0[c].mean())
            new[c] = np.clip(step / (1 + 0.2 * (1 + a)), 0, 1)
        change = np.abs(new - u).mean(axis=(1, 2)).sum()
        u = new
        if change <= tol:
            break
    u = (u - u.min(axis=(1, 2), keepdims=True)) / np.ptp(u, axis=(1, 2), keepdims=True)
    y = np.moveaxis(u, 0, -1)
    return np.where(y <= 0.04045, y / 12.92, ((y + 0.055) / 1.055) ** 2.4)


def spread_image(shape, seed):
    """Positive RGB whose values are all ``1.35×`` apart (a well-separated median)."""
    rng = np.random.default_rng(seed)
    n = shape[0] * shape[1]
    steps = np.stack([rng.permutation(n) for _ in range(3)], axis=-1)
    return (10.0 ** (-2 + 6 * steps / n)).reshape(*shape, 3)


def test_matches_numpy_model(x64):
    """An odd number of pixels (the median is one of them), odd sides (periodic
    distances), pfstmo's stopping rule and a non-default ``rho`` and ``inv_alpha``."""
    x = spread_image((15, 21), 0)
    op = hdrjax.make_operator("ferradans2011", rho=-1.0, inv_alpha=4.0)
    got = np.asarray(op(jnp.asarray(x)))
    np.testing.assert_allclose(got, numpy_model(x, -1.0, 4.0, op.tol), rtol=RTOL64, atol=1e-9)


def test_flat_image_is_finite_where_pfstmo_never_stops(x64):
    """Module docstring: pfstmo's contrast term is 0 / 0 on a flat image (the model's
    operator and shape: no new compile)."""
    op = hdrjax.make_operator("ferradans2011", rho=-1.0, inv_alpha=4.0)
    out = np.asarray(op(jnp.full((15, 21, 3), 5.0)))
    assert np.all(np.isfinite(out))
    np.testing.assert_array_equal(out, 0.0)  # a flat first stage is 0 and stays there


# --- gradients, tiles -------------------------------------------------------------------


def test_gradients_match_central_differences(x64):
    """rho, inv_alpha and the image (a random direction) through both stages and 3
    iterations (full-size convolutions: the coarse grid's box means and interpolation are
    linear, and compile ten times slower under ``grad``): ``jax.grad`` against central
    differences of the same compiled function, float64. The stages are called directly
    (the operator's call adds the masked path for bad pixels, and its compile time);
    tests/fit/test_gradients.py checks rho and inv_alpha through the operator, and
    tests/operators/test_conformance_shapes.py vmap against a loop."""
    x0 = jnp.asarray(spread_image((16, 24), 1)) * 0.01
    rng = np.random.default_rng(2)
    w = jnp.asarray(rng.normal(size=(3, 16, 24)))
    v = jnp.asarray(rng.normal(size=x0.shape)) * x0

    def loss(theta):  # rho, inv_alpha, step along v
        I0 = F.adapted(x0 + theta[2] * v, theta[0])
        u, _ = F.enhance(I0, theta[1], tol=0.0, max_iterations=3, kernel_grid=256)
        return jnp.sum(w * u)

    f = jax.jit(jax.value_and_grad(loss))
    theta = jnp.asarray([-1.5, 4.0, 0.0])
    _, grad = f(theta)
    for k, h in enumerate((1.5e-6, 4e-6, 1e-6)):
        e = jnp.zeros(3).at[k].set(h)
        fd = (f(theta + e)[0] - f(theta - e)[0]) / (2 * h)
        np.testing.assert_allclose(grad[k], fd, rtol=GRAD_RTOL)
        assert grad[k] != 0


def test_coarse_grid_contrast_term():
    """The contrast term on box factors 2 × 3 against full-size convolutions (one small
    compile), and the phase layout's round trip. σ = 16 / 1.5 pixels here, so the
    grid's widening of the Gaussian (module docstring) shows: measured 0.0065 at most, on
    values up to 0.81."""
    u = jnp.asarray(spread_image((16, 24), 5)[..., 0].reshape(1, 16, 24))
    u = (jnp.log10(u) + 2.0) / 6.0  # [0, 1]
    sigma = jnp.asarray(16 / 1.5, u.dtype)

    def term(u, factors):
        p = F.to_phases(u, factors)
        return F.contrast_term(p, F.contrast_coefficients(p, sigma, (16, 24)))

    @jax.jit
    def both(u):
        return tuple(term(u, f) for f in ((1, 1), (2, 3)))

    full, coarse = both(u)
    np.testing.assert_array_equal(F.from_phases(F.to_phases(u, (2, 3))), u)
    ref = np.asarray(F.from_phases(full))
    np.testing.assert_allclose(np.asarray(F.from_phases(coarse)), ref, atol=0.01)
    assert np.abs(ref).max() > 0.5


def test_halo_is_the_whole_image():
    op = hdrjax.make_operator("ferradans2011")
    assert op.halo((4000, 6000)) == (math.inf, math.inf)
