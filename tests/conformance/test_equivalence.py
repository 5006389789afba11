"""Cases that compute the same thing another way equal it on every hard family: tiled
processing (``hdrjax.tile``) equals the whole-image function, the batch pipeline on arrays
equals its operator (``Case.equals`` in ``_table.py``). The whole-image functions are the
references (their own cases and tests check them against NumPy/SciPy)."""

import numpy as np
import pytest

from ..operators.cases import hard_cases, natural
from ._table import CASES, float_leaves

EQUIVALENT = sorted(n for n, c in CASES.items() if c.equals is not None)


@pytest.mark.parametrize("name", EQUIVALENT)
def test_equals_the_whole_image_function(name):
    case = CASES[name]
    whole, rtol, atol = case.equals
    images = dict(hard_cases(np.float32), natural=natural((8, 8)))
    for family, img in images.items():
        got = [np.asarray(v, np.float64) for v in float_leaves(case.fn(img))]
        want = [np.asarray(v, np.float64) for v in float_leaves(whole(img))]
        assert len(got) == len(want), f"{name}/{family}: {len(got)} outputs vs {len(want)}"
        for g, w in zip(got, want, strict=True):
            assert g.shape == w.shape, f"{name}/{family}: shape {g.shape} vs {w.shape}"
            assert np.array_equal(np.isnan(g), np.isnan(w)), f"{name}/{family}: NaN moved"
            fin = np.isfinite(w)
            assert np.array_equal(g[~fin & ~np.isnan(w)], w[~fin & ~np.isnan(w)]), family
            scale = np.max(np.abs(w[fin]), initial=0.0)
            np.testing.assert_allclose(
                g[fin], w[fin], rtol=rtol, atol=atol * max(scale, 1.0), err_msg=f"{name}/{family}"
            )
