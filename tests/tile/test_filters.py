"""Tiled median and mean filters equal the whole-image filters bit for bit.

References: :func:`hdrjax.filters.median_filter` / :func:`mean_filter` on the whole image
(their own tests check them against SciPy and OpenCV), and SciPy's ``median_filter`` /
``maximum_filter`` directly for the channel median and a user-defined step.
"""

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.ndimage as ndi

import hdrjax.tile as T
from hdrjax.filters import mean_filter, median_filter

from ._images import crop


def _same(a, b) -> bool:
    """Bitwise equality, NaN included."""
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and np.array_equal(a.view(np.uint32), b.view(np.uint32))


@pytest.mark.parametrize(
    "size, criterion, mode, tile",
    [
        (3, "luminance", "nearest", (40, 32)),  # tiles divide 80×64... except the columns
        (5, "luminance", "reflect", (37, 29)),  # tiles that divide nothing
        (7, "channels", "mirror", (23, 64)),  # one tile column spanning the width
    ],
)
def test_median_rgb_bit_identical(size, criterion, mode, tile):
    x = crop(80, 64)
    ref = median_filter(x, size, criterion=criterion, mode=mode)
    got = T.apply(T.Median(size, criterion, mode=mode), x, tile=tile)
    assert _same(got, ref)


def test_median_luminance_ties_go_to_the_same_pixel():
    # three colours of equal luminance under weights (1/4, 1/2, 1/4): the chosen pixel
    # depends only on the tie-break by image position, at the replicated top edge too
    rng = np.random.default_rng(1)
    colours = np.array([[0.5, 0, 0.5], [0, 0.5, 0], [1, 0, 0]], np.float32)
    x = crop(48, 40, bad=False)
    x[:20, :30] = colours[rng.integers(0, 3, (20, 30))]
    w = (0.25, 0.5, 0.25)
    ref = median_filter(x, 5, weights=w)
    got = T.apply(T.Median(5, weights=w), x, tile=(7, 11))
    assert _same(got, ref)
    assert len(np.unique(np.asarray(ref[:18, :28]).reshape(-1, 3), axis=0)) > 1  # ties seen


def test_median_planes_two_passes_bit_identical():
    x = crop(80, 64)[..., 1]
    ref = median_filter(x, 5, passes=2, channel_axis=None)
    step = T.Median(5, passes=2, channel_axis=None)
    assert step.halo(x.shape) == (4, 4)
    assert _same(T.apply(step, x, tile=(33, 64)), ref)


def test_channel_median_matches_scipy():
    x = crop(50, 40, bad=False)
    got = T.apply(T.Median(3, "channels", mode="mirror"), x, tile=(16, 16))
    ref = np.stack([ndi.median_filter(x[..., c], 3, mode="mirror") for c in range(3)], -1)
    assert _same(got, ref)


@pytest.mark.parametrize(
    "size, mode, tile, passes", [(3, "nearest", (31, 17), 1), (7, "reflect", (20, 64), 2)]
)
def test_mean_bit_identical(size, mode, tile, passes):
    x = crop(80, 64)
    ref = mean_filter(x, size, mode=mode, passes=passes)
    got = T.apply(T.Mean(size, passes=passes, mode=mode), x, tile=tile)
    assert _same(got, ref)
    assert np.isnan(got).sum() > 4  # NaN spread inside its windows, exactly as whole-image


def test_mean_into_memmap(tmp_path):
    x = crop(60, 50)
    out = np.lib.format.open_memmap(tmp_path / "out.npy", "w+", np.float32, x.shape)
    T.apply(T.Mean(5, mode="mirror"), x, tile=(16, 32), out=out)
    out.flush()
    assert _same(np.load(tmp_path / "out.npy"), mean_filter(x, 5, mode="mirror"))


@pytest.mark.parametrize(
    "size, shape, tile",
    [
        (5, (80, 64), (16, 24)),  # halo 2: every later band reads two rows of the one before
        # halo 4, tile 8, 41 rows: the last band has 1 row, so its window (shifted inside
        # the image) reads 7 rows of the band before it and 8 of the one before that
        (9, (41, 30), (8, 8)),
        (3, (30, 20), (64, 64)),  # one tile for the image
    ],
)
def test_in_place_with_a_halo_equals_a_separate_output(size, shape, tile):
    x = crop(*shape)
    ref = T.apply(T.Mean(size, mode="reflect"), x, tile=tile)
    y = x.copy()
    got = T.apply(T.Mean(size, mode="reflect"), y, tile=tile, out=y)
    assert got is y
    assert _same(y, ref)
    assert _same(ref, mean_filter(x, size, mode="reflect"))


def test_in_place_with_a_halo_into_a_memmap(tmp_path):
    x = crop(60, 50)
    path = tmp_path / "image.npy"
    np.save(path, x)
    mm = np.load(path, mmap_mode="r+")
    T.apply(T.Median(5), mm, tile=(16, 16), out=mm)
    mm.flush()
    del mm
    assert _same(np.load(path), median_filter(x, 5))


def test_neighbourhood_step_matches_scipy():
    def max3(w):  # 3×3 maximum with replicated edges, written by a user
        p = jnp.pad(w, 1, mode="edge")
        h, wd = w.shape
        return jnp.max(jnp.stack([p[i : i + h, j : j + wd] for i in range(3) for j in range(3)]), 0)

    x = crop(45, 38, bad=False)[..., 0]
    got = T.apply(T.Neighbourhood(max3, 1), x, tile=(10, 9))
    assert _same(got, ndi.maximum_filter(x, 3, mode="nearest"))


def test_float64_and_integer_images_promote_like_the_filters():
    x = crop(40, 36, bad=False)
    got = T.apply(T.Mean(3), x.astype(np.float64), tile=16)
    assert got.dtype == np.float32 and _same(got, mean_filter(x, 3))
    q = (np.clip(x, 0, 1) * 255).astype(np.uint8)
    got = T.apply(T.Median(3, "channels"), q, tile=16)
    assert got.dtype == np.float32 and _same(got, median_filter(q, 3, criterion="channels"))
