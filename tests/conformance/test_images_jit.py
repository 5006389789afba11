"""Every traced case of the conformance table: eager calls equal one compiled vmap of the frames.

Split from ``test_images.py`` (same table, same families) so that the test workers, which
take whole files, share the conformance suite's time."""

import jax
import numpy as np
import pytest

from ..conftest import RTOL32
from ..operators.cases import natural
from ._table import CASES, float_leaves
from .test_images import TRACED


@pytest.mark.parametrize("name", TRACED)
def test_jit_equals_eager_and_vmap_equals_loop(name):
    case = CASES[name]
    frames = np.stack([natural((8, 8), seed=s) for s in range(3)])
    # called as users call it, frame by frame (the function's own compiled paths, or op by
    # op), against one compiled vmap of all frames: the traced function equals the eager
    # one and batches frame by frame (a separate unbatched jit would add one compile of
    # the whole function per case and prove nothing the vmap does not)
    loop = [float_leaves(case.fn(x)) for x in frames]
    vmapped = float_leaves(jax.jit(jax.vmap(case.fn))(frames))
    assert len(vmapped) == len(loop[0]), f"{name}: outputs differ"
    for k, v in enumerate(vmapped):
        ref = np.stack([e[k] for e in loop])
        np.testing.assert_allclose(v, ref, rtol=RTOL32, atol=1e-6, err_msg=f"{name}: jit/vmap")
