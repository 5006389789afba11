"""Finite in, finite out near the largest float for the vision effects (issue 16, point 3):
weighted sums, colour matrices and contrast scales that overflowed float32 although the
result is representable (or, for a contrast scale above 1, saturates). 8×8 images."""

import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.vision as hv

from .conftest import RTOL32, enable_x64
from .operators.cases import natural

MAX32 = float(np.finfo(np.float32).max)


def test_veil_of_a_uniform_image_near_the_float_maximum():
    """Each foveal sample's weighted sum of its surround overflowed (NaN everywhere); the
    veil of a uniform image is the image itself (0.92 L + 0.08 L)."""
    img = np.full((2, 8, 8, 3), 1e36, np.float32)
    img[1] = 1e38
    for x in img:
        np.testing.assert_allclose(np.asarray(hv.veil(x)), x, rtol=RTOL32)


def test_blue_shift_of_a_lamp_near_the_float_maximum():
    """XYZ of a 3e38 cd/m² pixel overflowed (+Inf pixel). Above 4 cd/m² the pixel keeps its
    colour, so the lamp comes out as the same lamp 2^80 times dimmer, times 2^80."""
    img = natural((8, 8))
    img[5, 7] = (3e38, 2e38, 1e38)
    dim = img.copy()
    dim[5, 7] *= np.float32(2.0**-80)
    out = np.asarray(hv.blue_shift(jnp.asarray(np.stack([img, dim]))))
    assert np.all(np.isfinite(out))
    np.testing.assert_array_equal(out[0, 5, 7], out[1, 5, 7] * np.float32(2.0**80))
    others = np.delete(out.reshape(2, 64, 3), 5 * 8 + 7, axis=1)
    np.testing.assert_array_equal(others[0], others[1])
    np.testing.assert_allclose(out[0, 5, 7], img[5, 7], rtol=1e-3)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_blue_shift_of_a_pixel_at_the_float_maximum(dtype):
    """RGB = (max, max, max): the colour matrix and its inverse round the pixel past the
    float maximum (+Inf in two channels before). Above 4 cd/m² the pixel keeps its colour:
    it comes out at the maximum, within round-off; the other pixels keep their bits."""
    top = np.finfo(dtype).max
    img = natural((8, 8)).astype(dtype)
    lamp = img.copy()
    lamp[2, 3] = top
    with enable_x64(dtype == np.float64):
        out = np.asarray(hv.blue_shift(jnp.asarray(np.stack([img, lamp]))))
    assert out.dtype == dtype
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out[1, 2, 3], top, rtol=1e-6)
    others = np.delete(out.reshape(2, 64, 3), 2 * 8 + 3, axis=1)
    np.testing.assert_array_equal(others[1], others[0])


def test_simulate_scale_saturates_at_the_float_maximum():
    """``scale=`` (cd/m² per stored unit) takes stored values near the float maximum past
    it: they saturate (+Inf before, and the effects' outputs then non-finite); the other
    values are exactly ``x · scale``."""
    img = natural((8, 8))
    img[3, 4] = MAX32
    img[5, 1] = (1e36, 3e35, 2e38)
    out = np.asarray(hv.simulate(img, 30.0, "none", scale=100.0)[0])
    over = img.astype(np.float64) * 100.0 > MAX32
    assert over.sum() == 4
    np.testing.assert_array_equal(out[over], MAX32)
    np.testing.assert_array_equal(out[~over], img[~over] * np.float32(100.0))


def test_contrast_saturates_at_the_float_maximum():
    """A dim adaptation scales by m > 1: values past the float maximum saturate (+Inf
    before); the others are exactly ``x · m``."""
    img = natural((8, 8))
    img = img / img.max() * np.float32(MAX32 * 0.999)
    m = np.float32(hv.contrast_scale(0.01))
    assert m > 1
    out = np.asarray(hv.contrast(img, 0.01))
    over = img.astype(np.float64) * m > MAX32
    assert over.any() and not over.all()
    np.testing.assert_array_equal(out[over], MAX32)
    np.testing.assert_array_equal(out[~over], img[~over] * m)
