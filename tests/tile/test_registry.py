"""Every registered operator with a finite halo runs on tiles (issue 17): the tiled
``Tonemap`` equals the whole-image operator bound to the whole image's statistics, and the
tiles' merged statistics equal ``op.statistics(whole)``.

Reference: the operator itself on the whole image, ``op.bind(op.statistics(x))(x)`` (the
mergeable statistics; for Tumblin et al. 1999 the trimmed adaptation is the histogram
estimate either way). Counts, extrema and the histogram merge exactly; the log sum is a
float64 sum of per-tile float32 sums (``LOG_SUM_RTOL``) and the outputs agree to float32
rounding of the parameters computed from it (``OUT_RTOL``). Per operator: one compile of
its bind, and of its bound curve on the whole image and on the 39×39 windows of the 2×2
tiles (the local operators' windows, tile plus halo, are the whole image).
"""

import numpy as np
import pytest

import hdrjax
import hdrjax.tile as T

from ..operators.cases import make, natural

SHAPE = (78, 78, 3)
"""One image for every operator (the statistics compile once per setting): the local
Reinhard operators' halo of 39 pixels fits a 39-pixel tile."""
TILE = 39
NAMES = [n for n in hdrjax.operator_names() if np.all(np.isfinite(make(n).halo(SHAPE)))]
EXACT = ("n_pixels", "n_finite", "n_positive", "min", "max", "min_positive", "counts")
LOG_SUM_RTOL = 1e-6
OUT_RTOL = 2e-5


def _image(h: int, w: int) -> np.ndarray:
    x = natural((h, w), seed=3)
    x[0, 0] = 1e-4  # a wide range (reinhard2002_auto's local branch)
    x[h // 2, w // 3] = 5e3
    x[1, w - 2, 1] = np.nan  # a bad pixel: left out of the statistics, kept in place
    return x


@pytest.mark.parametrize("name", NAMES)
def test_tiled_tonemap_equals_the_whole_image(name):
    op = make(name)
    assert max(op.halo(SHAPE)) <= TILE  # 2×2 tiles, each at least the halo
    x = _image(*SHAPE[:2])
    tile = TILE
    whole = op.statistics(x)
    merged = T.operator_statistics(op, x, tile=tile)
    if whole is None:
        assert merged is None
        ref = np.asarray(op(x))
    else:
        for f in EXACT:
            np.testing.assert_array_equal(getattr(merged, f), getattr(whole, f), err_msg=f)
        np.testing.assert_allclose(merged.log_sum, whole.log_sum, rtol=LOG_SUM_RTOL)
        if whole.channel_sum is not None:
            np.testing.assert_allclose(merged.channel_sum, whole.channel_sum, rtol=1e-6)
        ref = np.asarray(T.Tonemap(op).bind(x.shape, whole).operator(x))  # op.bind(whole)
    got = T.apply(T.Tonemap(op), x, tile=tile)  # its own first pass over the tiles
    assert np.array_equal(np.isnan(got), np.isnan(ref)), name
    ok = ~np.isnan(ref)
    np.testing.assert_allclose(got[ok], ref[ok], rtol=OUT_RTOL, atol=1e-6, err_msg=name)
