"""Exposure fusion (Mertens, Kautz & Van Reeth 2007) against OpenCV's MergeMertens on the
same synthetic brackets; batching, input forms, bad input."""

import cv2
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.merge as hm
from hdrjax.io import read

from ..conftest import DATA

# measured on the four scenes (128 × 192): p99 2.1e-5, max 2.2e-3. The max is where every
# exposure's weight is ~1e-12 and the epsilon decides: OpenCV's saturation is
# sqrt(Σ (I_c − μ)²), the paper's (and ours) the standard deviation, √3 smaller.
P99_TOL = 1e-4
MAX_TOL = 5e-3
FLOAT32_TOL = 2e-5  # codes / 255 rounded in NumPy or in XLA: measured 8.7e-6
SCENES = ["rooitou_park_1k.hdr", "Carrots.exr", "MtTamNorth.exr", "cornell_box.exr"]


def scene(name, h=128, w=192):
    img = np.asarray(read(DATA / name).rgb())
    step = max(1, min(img.shape[0] // h, img.shape[1] // w))
    return img[::step, ::step][:h, :w]


@pytest.fixture(scope="module")
def brackets():
    return np.stack([hm.simulate_bracket(scene(n)).codes for n in SCENES])


def opencv(codes, weights=(1.0, 1.0, 1.0)):
    # OpenCV's default exposure weight is 0 (the paper's and ours 1): pass all three. Its grey
    # is COLOR_RGB2GRAY of whatever order it is given, so hand it RGB.
    return np.clip(cv2.createMergeMertens(*weights).process(list(codes)), 0.0, 1.0)


def test_matches_opencv_mergemertens(brackets):
    ours = np.asarray(jax.vmap(hm.fuse)(jnp.asarray(brackets)))
    assert ours.shape == (len(SCENES), 128, 192, 3) and ours.dtype == np.float32
    for codes, out in zip(brackets, ours, strict=True):
        d = np.abs(out - opencv(codes))
        assert np.percentile(d, 99) < P99_TOL and d.max() < MAX_TOL
        # vmap over brackets gives what one call gives
        np.testing.assert_allclose(np.asarray(hm.fuse(codes)), out, atol=FLOAT32_TOL)


@pytest.mark.parametrize("weights", [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)])
def test_each_measure_alone_matches_opencv(brackets, weights):
    c, s, e = weights
    out = np.asarray(hm.fuse(brackets[1], contrast=c, saturation=s, exposedness=e))
    np.testing.assert_allclose(out, opencv(brackets[1], weights), atol=1e-5)


def test_input_forms_agree(brackets):
    codes = brackets[0]
    ref = np.asarray(hm.fuse(codes))
    assert ref.min() >= 0.0 and ref.max() <= 1.0
    unit = codes.astype(np.float32) / 255.0
    np.testing.assert_allclose(np.asarray(hm.fuse(unit)), ref, atol=FLOAT32_TOL)
    np.testing.assert_allclose(np.asarray(hm.fuse(list(unit))), ref, atol=FLOAT32_TOL)
    wide = codes.astype(np.uint16) * 257  # the same values on 16 bits
    # / 65535 rounds otherwise than / 255; where every weight is ~1e-12 (the darkest pixels
    # of every exposure) that decides: measured 2.6e-4 at one pixel, 3e-5 elsewhere
    d = np.abs(np.asarray(hm.fuse(wide)) - ref)
    assert np.percentile(d, 99) < FLOAT32_TOL and d.max() < MAX_TOL
    # a one-level pyramid is a per-pixel weighted average of the exposures
    flat = np.asarray(hm.fuse(codes, levels=1))
    assert np.all(flat >= unit.min(0) - 1e-6) and np.all(flat <= unit.max(0) + 1e-6)


def test_differentiable_in_the_exposures(brackets):
    unit = jnp.asarray(brackets[0, :, 40:56, 60:84], jnp.float32) / 255.0
    g = jax.grad(lambda x: jnp.sum(hm.fuse(x, contrast=0.5, levels=3)))(unit)
    assert g.shape == unit.shape and bool(jnp.all(jnp.isfinite(g)))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"contrast": -1.0}, "contrast"),
        ({"saturation": float("nan")}, "saturation"),
        ({"exposedness": "high"}, "exposedness"),
        ({"sigma": 0.0}, "sigma"),
        ({"levels": 0}, "levels"),
    ],
)
def test_bad_settings_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        hm.fuse(np.zeros((2, 8, 8, 3), np.uint8), **kwargs)


@pytest.mark.parametrize(
    "images",
    [
        np.full((2, 8, 8, 3), 1.5, np.float32),
        np.zeros((2, 8, 8), np.float32),
        np.zeros((2, 8, 8, 3), np.int32),
        [np.zeros((8, 8, 3), np.float32), np.zeros((8, 9, 3), np.float32)],
        jnp.zeros((8, 8, 3)),
    ],
)
def test_bad_images_are_named(images):
    with pytest.raises(ValueError, match="images"):
        hm.fuse(images)
