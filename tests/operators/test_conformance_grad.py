"""Every registered operator: finite gradients for every bad-pixel and scale family.

Split from ``test_conformance.py`` (same registry, same cases) so that the test workers,
which take whole files, share the conformance suite's time."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from .cases import gradient_families, make, natural
from .test_conformance import NAMES


@pytest.mark.parametrize("name", NAMES)
def test_gradients_are_finite(name):
    """Gradients of the sum of the finite outputs with respect to the image and to every
    parameter are finite, at every finite pixel, for every family: bad pixels (NaN only,
    +Inf only, -Inf only, mixed) and the scales of ``cases.GRAD_SCALES`` included."""
    cases = {**gradient_families(), "natural": natural((8, 8))}
    batch = jnp.asarray(np.stack(list(cases.values())))
    op = make(name)
    params, static = eqx.partition(op, eqx.is_inexact_array)

    def loss(p, x):
        out = eqx.combine(p, static)(x)
        return jnp.sum(jnp.where(jnp.isfinite(out), out, 0.0))

    # one compile; per frame, so a failure names its family
    grad = jax.jit(jax.vmap(jax.grad(loss, argnums=(0, 1)), in_axes=(None, 0)))
    gp, gx = grad(params, batch)
    gx = np.asarray(gx)
    failed = []
    for i, (family, img) in enumerate(cases.items()):
        finite = np.all(np.isfinite(img), axis=-1)
        if not np.all(np.isfinite(gx[i][finite])):
            failed.append(f"{family}: image")
        for path, leaf in jax.tree_util.tree_leaves_with_path(gp):
            if not np.all(np.isfinite(np.asarray(leaf)[i])):
                failed.append(f"{family}: {jax.tree_util.keystr(path)}")
    assert not failed, f"{name}: non-finite gradients: " + "; ".join(failed)
    assert np.any(gx[-1] != 0), name  # the output depends on the image
