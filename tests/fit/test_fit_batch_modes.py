"""hdrjax.fit.fit_batch: the vmapped and the sequential (lax.map) solves give each frame the
result of fitting it alone, with and without a per-frame target."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax import fit as hf, targets as ht

from ..conftest import RTOL32


def _frames():
    rng = np.random.default_rng(7)
    base = np.exp(rng.normal(0.0, 1.5, (16, 16, 3)))
    return jnp.asarray(np.stack([base * s for s in (0.5, 1.0, 4.0)]), jnp.float32)


@pytest.mark.parametrize("vectorize", [True, False])
def test_batch_modes_equal_separate_fits(vectorize):
    frames = _frames()
    op = hdrjax.make_operator("linear", L_max=5.0)
    tgt = ht.MeanLuminance(0.25)
    batch = hf.fit_batch(op, frames, tgt, params="L_max", vectorize=vectorize)
    assert batch.success.shape == (3,) and bool(jnp.all(batch.success))
    for i in range(3):
        one = hf.fit(op, frames[i], tgt, params="L_max")
        np.testing.assert_allclose(batch.params["L_max"][i], one.params["L_max"], rtol=RTOL32)
        assert int(batch.steps[i]) == int(one.steps)
    # Linear is L / L_max and the frames are scaled copies: L_max scales with them
    np.testing.assert_allclose(
        np.asarray(batch.params["L_max"]) / float(batch.params["L_max"][1]), [0.5, 1, 4], rtol=1e-3
    )


@pytest.mark.parametrize("vectorize", [True, False])
def test_batch_modes_with_a_target_per_frame(vectorize):
    frames = _frames()
    true_L_max = np.array([8.0, 12.0, 60.0])
    # Linear is rgb / L_max; 0.1 % noise keeps the loss above 0 (an exact float32 zero
    # loss is reported as a non-finite solve by optimistix: noted for the lead)
    noise = 1 + 1e-3 * np.random.default_rng(1).standard_normal(frames.shape[1:])
    refs = jnp.stack([frames[i] / true_L_max[i] * noise for i in range(3)])
    op = hdrjax.make_operator("linear", L_max=5.0)
    tgt = jax.vmap(ht.Reference)(refs)  # one reference per frame (leading axis)
    batch = hf.fit_batch(
        op, frames, tgt, params="L_max", max_size=None, batch_target=True, vectorize=vectorize
    )
    assert bool(jnp.all(batch.success))
    np.testing.assert_allclose(batch.params["L_max"], true_L_max, rtol=2e-3)
