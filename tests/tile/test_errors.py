"""Bad arguments raise ValueError with a message naming the argument and what was expected."""

import math

import dask.array as da
import numpy as np
import pytest

import hdrjax.tile as T
from hdrjax.operators import Gamma, Reinhard2002, Reinhard2002Local
from hdrjax.tile._layout import spans

X = np.zeros((40, 30, 3), np.float32)


@pytest.mark.parametrize("tile", [0, -4, (16, 0), (8,), (8, 8, 8), (True, 8), 2.5])
def test_tile_must_be_positive_integers(tile):
    with pytest.raises(ValueError, match="tile: expected 2 integers >= 1"):
        T.apply(T.Mean(3), X, tile=tile)
    with pytest.raises(ValueError, match="tile: expected 2 integers >= 1"):
        T.statistics(X, tile=tile)


def test_halo_bigger_than_tile():
    with pytest.raises(ValueError, match="tile: 4 rows is smaller than the step's halo of 6"):
        T.apply(T.Median(3, passes=6), X, tile=(4, 30))
    with pytest.raises(ValueError, match="halo of 39 rows"):
        T.apply(T.Tonemap(Reinhard2002Local()), np.zeros((100, 100, 3), np.float32), tile=32)
    # a tile spanning the image needs no halo there: one window, the whole image
    assert spans(40, 40, 100) == spans(40, 64, 100)


def test_halo_argument():
    with pytest.raises(ValueError, match=r"halo: the step reads \(2, 2\) pixels"):
        T.apply(T.Mean(5), X, tile=8, halo=1)
    with pytest.raises(ValueError, match="halo: expected one or two integers"):
        T.apply(T.Mean(5), X, tile=8, halo=(2, 2, 2))
    # a larger halo than needed changes nothing
    x = np.arange(1200, dtype=np.float32).reshape(40, 30)
    a = T.apply(T.Mean(3, channel_axis=None), x, tile=8)
    b = T.apply(T.Mean(3, channel_axis=None), x, tile=8, halo=(3, 5))
    assert np.array_equal(a, b)


def test_steps_reject_what_tiles_cannot_reproduce():
    with pytest.raises(ValueError, match="mode: tiles reproduce the edge modes"):
        T.Median(3, mode="wrap")
    with pytest.raises(ValueError, match="size: expected an odd integer"):
        T.Mean(4)
    with pytest.raises(ValueError, match="Glare: the full Spencer PSF spans the whole image"):
        T.apply(T.Glare(), X, tile=16)
    with pytest.raises(ValueError, match="step: expected an hdrjax.tile step"):
        T.apply(lambda w: w, X)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="operator: expected an hdrjax operator"):
        T.Tonemap(np.mean)  # type: ignore[arg-type]


def test_out_and_image_checks():
    with pytest.raises(ValueError, match=r"out: expected shape \(40, 30, 3\)"):
        T.apply(T.Mean(3), X, out=np.zeros((40, 30), np.float32))
    # in place is the image itself; another view of its memory is refused
    y = np.ascontiguousarray(X)
    with pytest.raises(ValueError, match="out: overlaps image without being image itself"):
        T.apply(T.Mean(3), y, out=y[::-1])
    with pytest.raises(ValueError, match=r"image: expected shape \(H, W\) or \(H, W, C\)"):
        T.apply(T.Mean(3), np.zeros(5, np.float32))
    with pytest.raises(ValueError, match="bins: expected an integer >= 2"):
        T.statistics(X, bins=1)
    with pytest.raises(ValueError, match="Reinhard2002|reinhard2002"):
        T.Tonemap(Reinhard2002()).bind(X.shape, None)


def test_tonemap_refuses_what_it_cannot_bind_or_tile():
    # the LuminanceStats summary cannot feed op.bind: the merged Statistics are needed
    with pytest.raises(ValueError, match=r"^stats: expected the merged Statistics reinhard2002"):
        T.Tonemap(Reinhard2002()).bind(X.shape, T.statistics(X, tile=40))
    # an operator that reads the whole image (an unbounded halo) cannot run on tiles

    class WholeImage(Gamma):
        def halo(self, shape):
            return math.inf, math.inf

    with pytest.raises(ValueError, match=r"^operator: gamma reads the whole image"):
        T.apply(T.Tonemap(WholeImage()), X, tile=16)


def test_dask_chunks_smaller_than_halo():
    d = da.zeros((64, 64, 3), chunks=(8, 32, 3), dtype=np.float32)
    with pytest.raises(ValueError, match="darr: chunks of 8 rows are smaller than the step's"):
        T.to_dask(T.Median(3, passes=10), d)
    with pytest.raises(ValueError, match="darr: expected a dask.array.Array"):
        T.to_dask(T.Mean(3), X)


def test_filter_layout_must_match_the_image():
    with pytest.raises(ValueError, match=r"image: expected shape \(H, W\) with channel_axis"):
        T.apply(T.Median(3, channel_axis=None), X)
    with pytest.raises(ValueError, match=r"image: expected shape \(H, W, C\) with channel_axis"):
        T.apply(T.Mean(3), X[..., 0])
