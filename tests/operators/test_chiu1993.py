"""chiu1993 (Chiu et al. 1993) against HDR Toolbox's ``ChiuTMO`` (GNU Octave, the fixtures
of fixtures/hdrtoolbox/make_chiu1993.py) and a float64 NumPy model that runs the Toolbox's
steps literally (500 passes of the 3 × 3 filter, the glare as a direct correlation).

Issue 21's parity criterion, per image: SSIM of the encoded luminance ≥ 0.97 and mean
absolute difference ≤ 0.02 (both outputs clipped to [0, 1], sRGB encoded; the SSIM of
tests/operators/test_durand2002.py). HDR Toolbox's outputs are display-linear. Measured,
float32: SSIM 1.0000 and mean difference ≤ 2.9e-6 on the three images, largest encoded
difference 2.5e-5 (float32 against the Toolbox's float64).
"""

import functools
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.ndimage import correlate, correlate1d

import hdrjax
import hdrjax.tile as T
from hdrjax.operators._chiu1993 import smooth

from ..conftest import RTOL64, enable_x64
from .test_ashikhmin2002 import check_image_gradient, taps
from .test_durand2002 import assert_parity

FIXTURES = Path(__file__).parent / "fixtures" / "hdrtoolbox" / "chiu1993.npz"
SSIM_TIGHT, MAD_TIGHT, MAX_TIGHT = 0.9999, 1e-5, 1e-4
"""Measured: SSIM 1.0000, mean ≤ 2.9e-6, largest encoded difference 2.5e-5."""
TILE_RTOL = 1e-10
"""Tiles against the whole image in float64 (the windows' DCTs and FFTs differ in size: in
float32 their rounding, relative to the image's largest values, reaches 3e-5 of a pixel)."""
REC709 = np.array(hdrjax.REC709_WEIGHTS)
H3 = np.array([[0.080, 0.113, 0.080], [0.113, 0.227, 0.113], [0.080, 0.113, 0.080]])


@functools.cache
def toolbox() -> dict[str, np.ndarray]:
    with np.load(FIXTURES) as d:
        return {k: d[k] for k in d.files}


@functools.cache
def outputs() -> np.ndarray:
    op = hdrjax.make_operator("chiu1993")
    return np.asarray(eqx.filter_jit(lambda o, x: o(x))(op, toolbox()["input"]))


def glare_reference(size=121, g=0.8, p=8.0):
    w = int(np.floor(size / 2 + 0.5))
    x = np.arange(-w, w + 1) / w
    r = np.hypot(x[:, None], x[None, :])
    k = np.where(r <= 1, np.abs(r - 1) ** p, 0.0)
    k[w, w] = 0
    k /= k.sum()
    k[w, w] = g
    return k


def chiu_reference(rgb, k=8.0, sigma=2.0, passes=500, g=0.8, p=8.0, size=121):
    """The steps of the module docstring, literally, in float64."""
    L = rgb @ REC709
    t = taps(5 * sigma)
    Lb = correlate1d(correlate1d(L, t, axis=0, mode="nearest"), t, axis=1, mode="nearest")
    with np.errstate(divide="ignore"):
        s = np.nan_to_num(1 / (k * Lb), posinf=0.0)
        if passes:
            s = np.minimum(s, np.nan_to_num(1 / L, posinf=0.0))
            for _ in range(passes):
                s = correlate(s, H3, mode="nearest")
    Ld = L * s
    if g > 0:
        Ld = correlate(Ld, glare_reference(size, g, p), mode="nearest")
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(rgb * (Ld / L)[..., None], nan=0.0, posinf=0.0)


@pytest.mark.parametrize("i", range(3), ids=["rooitou_park", "venice_sunset", "CandleGlass"])
def test_matches_hdrtoolbox(i):
    assert_parity(outputs()[i], toolbox()["output"][i], SSIM_TIGHT, MAD_TIGHT, MAX_TIGHT)


def test_follows_the_steps_in_float64():
    """float64 against the literal model, the defaults and other settings (fewer passes,
    no glare, a smaller and softer glare kernel, another k)."""
    settings = (
        {},
        dict(k=5.0, passes=37, glare=0.5, glare_power=4.0, glare_size=31),
        dict(passes=0, glare=0.0),
        dict(sigma=3.0, passes=3),
    )
    with enable_x64():
        x = toolbox()["input"][:2].astype(np.float64)
        for kw in settings:
            op = hdrjax.make_operator("chiu1993", **kw)
            got = np.asarray(eqx.filter_jit(lambda o, v: o(v))(op, x))
            names = dict(k="k", sigma="sigma", passes="passes", glare="g", glare_power="p",
                         glare_size="size")  # fmt: skip
            ref_kw = {names[n]: v for n, v in kw.items()}
            for img, out in zip(x, got, strict=True):
                ref = chiu_reference(img, **ref_kw)
                np.testing.assert_allclose(out, ref, rtol=RTOL64, atol=1e-12 * ref.max())


def test_smoothing_is_the_passes():
    """The DCT product equals ``n`` passes of the 3 × 3 filter with replicated edges."""
    with enable_x64():
        s = np.random.default_rng(0).uniform(0, 2, (13, 21))
        for n in (1, 2, 25):
            ref = s.copy()
            for _ in range(n):
                ref = correlate(ref, H3, mode="nearest")
            np.testing.assert_allclose(np.asarray(smooth(jnp.asarray(s), n)), ref, rtol=1e-12)


def test_default_blur_follows_the_image_size():
    """``sigma=None`` is HDR Toolbox's ``round(16 max(H, W) / 1024) + 1``: 2 pixels here."""
    x = toolbox()["input"][1]
    a = np.asarray(hdrjax.make_operator("chiu1993")(x))
    b = np.asarray(hdrjax.make_operator("chiu1993", sigma=2.0)(x))
    np.testing.assert_array_equal(a, b)
    assert hdrjax.make_operator("chiu1993").halo((2048, 1024, 3)) == (1024, 512)
    assert hdrjax.make_operator("chiu1993", sigma=33.0).halo((4096, 4096, 3)) == (643, 643)


def test_tiles_smaller_than_the_image():
    """With ``sigma`` given the halo is the blur's radius + the passes + the glare's radius
    (2 + 3 + 3 pixels here): 8-pixel tiles of a 48 × 64 image, windows of 24 × 24, give the
    whole image's result
    (float64, so that the rounding of the transforms does not hide a wrong halo)."""
    with enable_x64():
        x = toolbox()["input"][0].astype(np.float64)
        op = hdrjax.make_operator("chiu1993", sigma=1.0, passes=3, glare_size=5)
        assert op.halo(x.shape) == (8, 8)
        whole = np.asarray(op(x))
        tiled = T.apply(T.Tonemap(op), x, tile=8)
    np.testing.assert_allclose(tiled, whole, rtol=TILE_RTOL, atol=1e-12 * whole.max())


def test_black_and_uniform_images():
    """Black maps to black; a uniform field to ``0.999ⁿ (1 + g) / k`` of its colour ratio."""
    black = np.asarray(hdrjax.make_operator("chiu1993")(np.zeros((16, 24, 3), np.float32)))
    assert np.all(black == 0)
    flat = np.full((16, 24, 3), 7.0, np.float32)
    out = np.asarray(hdrjax.make_operator("chiu1993")(flat))
    np.testing.assert_allclose(out, 0.999**500 * 1.8 / 8.0, rtol=1e-4)


def test_image_gradient_matches_central_differences():
    """The image gradient, through the blur, the clamping, the passes and the glare."""
    check_image_gradient(hdrjax.make_operator("chiu1993"), toolbox()["input"][1][:24, :32])
