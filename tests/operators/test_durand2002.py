"""durand2002 (Durand & Dorsey 2002) against pfstmo 2.2.0's ``pfstmo_durand02`` and a NumPy
model of the paper's piecewise-linear bilateral filter.

Fixtures: fixtures/pfstmo/durand2002.npz, written by fixtures/pfstmo/make_durand2002.py
(its docstring: the commands, the pfstmo version, how the inputs were cropped and
downscaled from the repository's ``data/``; the test rebuilds the inputs the same way and
checks their sums). pfstmo tags its output ``LUMINANCE=RELATIVE`` (checked by the script):
display-linear, so both outputs are clipped to [0, 1] and sRGB-encoded alike.

Issue 21's parity criterion, per image: SSIM of the encoded luminance ≥ 0.97 and mean
absolute difference ≤ 0.02. SSIM: Wang et al. 2004 with a Gaussian window (σ = 1.5 pixels,
truncated at 3.5 σ, SciPy's ``gaussian_filter``), ``C1 = 0.01²``, ``C2 = 0.03²``, data
range 1, the mean over the image (written here; scikit-image is not installed). Encoded
luminance: the sRGB encoding of the Rec.709 luminance of the output clipped to [0, 1].
Measured, float32 (SSIM / mean / 99th percentile of the absolute difference):
rooitou_park 0.9975 / 0.0112 / 0.017, venice_sunset 0.9995 / 0.0059 / 0.026, MtTamNorth
0.9980 / 0.0068 / 0.022, cornell_box 0.9993 / 0.0090 / 0.022. The differences come from the
operator's deviations (module docstring of hdrjax.operators._durand2002): pfstmo's
anisotropic, circular FFT blur and its base-layer percentiles; a NumPy copy of pfstmo's own
steps reproduces its output to 0.0012 mean absolute difference, so the fixtures read as
described.

Where pfstmo is wrong: ``cornell_box`` has pixels with a channel at exactly 0, which
pfstools' XYZ round trip makes slightly negative and pfstmo's colour correction raises to a
fractional power: NaN (7184 of its 32768 pixels). The paper's colour ratios there are 0 (a
black channel stays black): the operator's output is finite and its channel is 0.
"""

import dataclasses
import functools
import math
import sys
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.ndimage import convolve1d, gaussian_filter

import hdrjax
import hdrjax.tile as T
from hdrjax._srgb import srgb_encode
from hdrjax.operators._durand2002 import (
    _kernel,
    bilateral_base,
    gaussian_blur,
    spatial_radius,
    spatial_sigma,
)

from ..conftest import DATA

HERE = Path(__file__).resolve().parent
FIXTURES = HERE / "fixtures" / "pfstmo" / "durand2002.npz"
sys.path.insert(0, str(HERE / "fixtures"))
from peers import downscaled  # noqa: E402

sys.path.pop(0)

IMAGES = (
    ("rooitou_park_1k.hdr", 4),
    ("venice_sunset_1k.hdr", 4),
    ("MtTamNorth.exr", 4),
    ("cornell_box.exr", 2),
)
"""The fixture script's images and box factors (128 × 256 each)."""
SHAPE = (128, 256)
REC709 = np.array([0.2126, 0.7152, 0.0722])
SSIM_MIN, MAD_MAX = 0.97, 0.02
"""Issue 21's criterion."""
SSIM_TIGHT, MAD_TIGHT = 0.996, 0.013
"""Tighter bounds, just outside the measured worst (0.9975, 0.0112)."""
RTOL64 = 1e-6
TILE_RTOL = 2e-5
"""Tiles against the whole image, float32: XLA may order or contract the sums differently
for another shape."""


@functools.cache
def fixtures() -> dict[str, np.ndarray]:
    with np.load(FIXTURES) as f:
        return {k: f[k] for k in f.files}


@functools.cache
def inputs() -> np.ndarray:
    return np.stack([downscaled(DATA / n, SHAPE, k) for n, k in IMAGES])


@functools.cache
def outputs() -> np.ndarray:
    """The operator (pfstmo's defaults) on the four inputs, one compiled program."""
    op = hdrjax.make_operator("durand2002")
    return np.asarray(eqx.filter_jit(lambda o, x: o(x))(op, inputs()))


def encoded_luminance(rgb_or_y: np.ndarray) -> np.ndarray:
    y = rgb_or_y if rgb_or_y.ndim == 2 else np.clip(rgb_or_y, 0.0, 1.0) @ REC709
    return np.asarray(srgb_encode(jnp.asarray(np.clip(y, 0.0, 1.0)))).astype(np.float64)


def ssim(a: np.ndarray, b: np.ndarray) -> float:
    """Mean SSIM (Wang et al. 2004) of two images in [0, 1], Gaussian window σ = 1.5."""
    c1, c2 = 0.01**2, 0.03**2
    g = functools.partial(gaussian_filter, sigma=1.5, truncate=3.5)
    ma, mb = g(a), g(b)
    va, vb, cov = g(a * a) - ma**2, g(b * b) - mb**2, g(a * b) - ma * mb
    s = ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma**2 + mb**2 + c1) * (va + vb + c2))
    return float(s.mean())


def criterion(got: np.ndarray, want: np.ndarray) -> tuple[float, float, float]:
    """Issue 21's comparison of two renditions: SSIM, mean and largest absolute difference
    of their luminances clipped to [0, 1] and sRGB-encoded."""
    a = encoded_luminance(np.asarray(got, np.float64))
    b = encoded_luminance(np.asarray(want, np.float64))
    d = np.abs(a - b)
    return ssim(a, b), float(d.mean()), float(d.max())


def assert_parity(got, want, ssim_tight: float, mad_tight: float, max_tight: float = 1.0):
    """Issue 21's criterion (SSIM ≥ 0.97, mean ≤ 0.02) and a test's tighter bounds."""
    s, mad, top = criterion(got, want)
    assert s >= 0.97 and mad <= 0.02, (s, mad)
    assert s >= ssim_tight and mad <= mad_tight and top <= max_tight, (s, mad, top)


def test_inputs_are_the_fixtures():
    sums = [float(np.sum(x, dtype=np.float64)) for x in inputs()]
    np.testing.assert_allclose(sums, fixtures()["input_sum"], rtol=1e-12)


@pytest.mark.parametrize("i", range(len(IMAGES)), ids=[n for n, _ in IMAGES])
def test_matches_pfstmo(i):
    ref = fixtures()["luminance"][i].astype(np.float64)
    ok = ~np.isnan(ref)
    got = encoded_luminance(outputs()[i].astype(np.float64))
    want = np.where(ok, encoded_luminance(np.where(ok, ref, 0.0)), got)  # pfstmo's NaN: ours
    s, mad = ssim(got, want), float(np.abs(got - want)[ok].mean())
    assert s >= SSIM_MIN and mad <= MAD_MAX, (s, mad)
    assert s >= SSIM_TIGHT and mad <= MAD_TIGHT, (s, mad)


def test_pfstmo_nan_pixels_are_black_channels_here():
    """pfstmo writes NaN where a channel is 0 (module docstring); the paper's ratio is 0."""
    i = [n for n, _ in IMAGES].index("cornell_box.exr")
    nan = np.isnan(fixtures()["luminance"][i])
    assert nan.sum() == fixtures()["nan_pixels"][i] > 1000
    x, out = inputs()[i], outputs()[i]
    assert np.all(np.isfinite(out))
    assert np.all((x[nan] == 0) <= (out[nan] == 0))  # a black channel stays black
    assert np.all(np.any(x[nan] == 0, axis=-1))  # every NaN pixel of pfstmo has one


def numpy_base(I, valid, sigma_r, sigma_s):
    """The paper's piecewise-linear bilateral filter in float64 NumPy (nodes from the
    image's own range): per node, the Gaussian-weighted normalised convolution of the
    range-weighted values, interpolated linearly between the two nodes around each pixel."""
    lo, hi = I[valid].min(), I[valid].max()
    n = max(1, math.ceil((hi - lo) / sigma_r))
    step = (hi - lo) / n
    r = spatial_radius(sigma_s)
    x = np.arange(-r, r + 1)
    k = np.exp(-0.5 * (x / spatial_sigma(sigma_s)) ** 2)
    k /= k.sum()

    def blur(a):
        a = convolve1d(a, k, axis=0, mode="constant")
        return convolve1d(a, k, axis=1, mode="constant")

    out = np.zeros_like(I)
    for j in range(n + 1):
        i_j = lo + j * step
        G = np.exp(-(((I - i_j) / sigma_r) ** 2)) * valid
        J = i_j + blur(G * (I - i_j)) / blur(G)
        out += np.clip(1.0 - np.abs(I - i_j) / step, 0.0, 1.0) * J
    return out


def test_bilateral_matches_numpy_model(x64):
    rng = np.random.default_rng(1)
    I = np.cumsum(rng.normal(0, 0.3, (24, 40)), axis=1)  # edges and ramps, about 10 ln units
    valid = np.ones(I.shape, bool)
    valid[5, 7] = False
    ref = numpy_base(I, valid, 0.4, 15.0)
    got = bilateral_base(
        jnp.asarray(I),
        jnp.asarray(valid),
        jnp.asarray(I[valid].min()),
        jnp.asarray(I[valid].max()),
        jnp.asarray(0.4),
        sigma_s=15.0,
        max_segments=64,
    )
    np.testing.assert_allclose(np.asarray(got)[valid], ref[valid], rtol=RTOL64)


@pytest.mark.parametrize("shape", [(8, 8), (1, 9), (7, 1), (50, 45), (90, 130)])
def test_blur_cuts_its_kernel_to_the_image(shape, x64):
    """``gaussian_blur`` keeps only the taps an axis can use (``min(r, size − 1)``: 8 of
    the 40 for an 8-pixel axis) and its column strips no wider than the image, and equals
    the whole kernel (``r = 39`` for ``σ_s = 40``) applied densely with zeros outside."""
    sigma_s = 40.0
    r = spatial_radius(sigma_s)
    x = np.random.default_rng(3).lognormal(0.0, 1.0, (2, *shape))
    k = np.exp(-0.5 * (np.arange(r + 1) / (sigma_s / np.pi)) ** 2)
    k /= k[0] + 2.0 * k[1:].sum()

    def dense(n):  # (n, n): weight of input j at output i, zero beyond the radius
        d = np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])
        return np.where(d <= r, k[np.minimum(d, r)], 0.0)

    ref = dense(shape[0]) @ x @ dense(shape[1]).T
    got = gaussian_blur(jnp.asarray(x), sigma_s, jnp.asarray(True))
    np.testing.assert_allclose(np.asarray(got), ref, rtol=RTOL64, atol=1e-300)
    (vertical, horizontal), strip = _kernel(sigma_s, shape)
    assert (len(vertical), len(horizontal)) == (min(r, shape[0] - 1) + 1, min(r, shape[1] - 1) + 1)
    assert strip == min(64, shape[1])


def test_tiles_equal_the_whole_image():
    """hdrjax.tile with tiles of 40 pixels (halo 20 for sigma_s = 20): the whole image's
    result to float rounding, statistics merged from the tiles."""
    x = inputs()[1][:80, :120].copy()
    x[10, 20] = np.nan
    op = hdrjax.make_operator("durand2002", sigma_s=20.0)
    assert op.halo(x.shape) == (20, 20)
    whole = np.asarray(op.bind(op.statistics(x))(x))
    tiled = T.apply(T.Tonemap(op), x, tile=40)
    assert np.array_equal(np.isnan(tiled), np.isnan(whole))
    ok = ~np.isnan(whole)
    np.testing.assert_allclose(tiled[ok], whole[ok], rtol=TILE_RTOL, atol=1e-7)


def test_output_range_follows_base_contrast():
    """Two flat halves (intensity 1 and 100): the bright half maps to 1 (``L_high``), the
    dark one to ``e^-base_contrast`` (``L_low``), as pfstmo_durand02 2.2.0 gives them."""
    x = np.ones((32, 64, 3), np.float32)
    x[:, 32:] = 100.0
    for bc in (5.0, 3.0):
        out = np.asarray(hdrjax.tonemap(x, "durand2002", base_contrast=bc, sigma_s=20.0))
        np.testing.assert_allclose(out[:, :8], math.exp(-bc), rtol=1e-4)
        np.testing.assert_allclose(out[:, -8:], 1.0, rtol=1e-4)


PARAMS = ("sigma_r", "base_contrast", "saturation", "L_min", "L_max", "L_low", "L_high")
FD_STEP = 1e-6
"""Relative step of the central differences (float64)."""


def test_gradients_match_finite_differences(x64):
    """Every parameter and the image (one random direction), one compiled gradient."""
    rng = np.random.default_rng(2)
    x = jnp.asarray(inputs()[1][40:52, 100:116].astype(np.float64))
    w = jnp.asarray(rng.uniform(0.5, 1.5, x.shape))
    op = hdrjax.make_operator("durand2002", sigma_s=10.0).measure(x)
    # off the kinks: the measured L_min and L_max are pixels' own values, where the
    # clamp max(L, L_min) and the node range's ends meet those pixels
    op = dataclasses.replace(op, L_min=op.L_min * 0.8, L_max=op.L_max * 1.2)

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
