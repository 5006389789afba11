"""Every case of the conformance table on degenerate shapes: one pixel, one row, one column.

Split from ``test_images.py`` (same table, same families) so that the test workers, which
take whole files, share the conformance suite's time."""

import jax
import numpy as np
import pytest

from ..operators.cases import natural
from ._table import CASES, float_leaves
from .test_images import NAMES


@pytest.mark.parametrize("name", NAMES)
def test_degenerate_shapes(name):
    """(1, 1, 3), (1, W, 3), (H, 1, 3) natural images: finite outputs ((H, W, 3) is every
    family of test_hard_families)."""
    case = CASES[name]
    fn = jax.jit(case.fn) if case.jit else case.fn
    for shape in [(1, 1), (1, 9), (7, 1)]:
        img = natural(shape)
        try:
            out = fn(img)
        except ValueError as e:  # a documented minimum size, named with the expected form
            msg = str(e)
            assert "\n" not in msg, f"{name}: {shape}: {msg}"
            assert ("expected" in msg or "need" in msg) and ":" in msg, msg
            continue
        for leaf in float_leaves(out):
            assert np.all(np.isfinite(leaf)), f"{name}: non-finite output for {shape}"
