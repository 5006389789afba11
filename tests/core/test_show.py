"""Images in notebooks: hdrjax.show and the LayeredImage's own views (repr, HTML)."""

import base64
import io
import re

import numpy as np
import pytest
from PIL import Image

import hdrjax
from hdrjax.layers import LayeredImage

from ..conftest import DATA


@pytest.fixture(scope="module")
def cornell():
    return hdrjax.io.read(DATA / "cornell_box.exr")


def test_repr_is_one_short_line(cornell):
    text = repr(cornell)
    assert text == "LayeredImage('cornell_box.exr', 512×512, channels R,G,B, relative, sRGB)"
    with_layer = cornell.with_layer("depth", np.ones((512, 512), np.float32))
    assert repr(with_layer).endswith(", layers: depth)")
    assert len(repr(hdrjax.io.read(DATA / "XYZ.exr"))) < 120


def test_html_shows_a_thumbnail_and_the_metadata(cornell):
    from hdrjax.display import encode, quantize

    page = cornell.with_layer("depth", np.ones((512, 512), np.float32))._repr_html_()
    for needle in ("512 × 512", "R, G, B", "relative", "sRGB", "layer depth", "grid float32"):
        assert needle in page
    (uri,) = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    thumb = np.asarray(Image.open(io.BytesIO(base64.b64decode(uri))))
    assert thumb.shape == (256, 256, 3)
    # the thumbnail is Reinhard et al. 2002 of the image box-averaged 2 × 2, sRGB-encoded
    small = cornell.rgb().reshape(256, 2, 256, 2, 3).mean(axis=(1, 3))
    expect = quantize(encode(hdrjax.tonemap(small.astype(np.float32), "reinhard2002")), 8)
    assert np.abs(thumb.astype(int) - expect).max() <= 1


def test_show_puts_images_side_by_side(cornell):
    rgb = cornell.rgb()
    codes = (np.clip(rgb, 0, 1) * 255).astype(np.uint8)
    fig = hdrjax.show(cornell, rgb[..., 1], codes, titles=["file", "green", "8-bit"])
    axes = [ax for ax in fig.axes if ax.images]
    assert [ax.get_title() for ax in axes] == ["file", "green", "8-bit"]
    np.testing.assert_array_equal(axes[2].images[0].get_array(), codes)  # shown as it is
    assert hdrjax.show(cornell).axes[0].get_title() == "cornell_box.exr"
    nan = rgb.copy()
    nan[3, 4] = np.nan
    shown = hdrjax.show(nan, size=None).axes[0].images[0].get_array()
    assert shown.dtype == np.uint8 and (shown[3, 4] == 0).all()


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: hdrjax.show(), "images: expected at least one"),
        (lambda: hdrjax.show(np.zeros((4, 4, 3)), titles=["a", "b"]), "titles: expected 1"),
        (lambda: hdrjax.show(np.zeros((4, 4, 5))), r"image: expected \(H, W\)"),
    ],
)
def test_show_errors_name_the_argument(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_an_image_without_rgb_still_describes_itself():
    img = LayeredImage(np.ones((4, 4, 2), np.float32), channels=("A", "B"))
    page = img._repr_html_()
    assert "no thumbnail" in page and "A, B" in page
