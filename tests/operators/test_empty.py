"""Empty images, for every registered operator (policy of ``hdrjax/_check.py``).

An image with no rows or no columns is a ``ValueError`` naming ``rgb`` and the shape, raised
while tracing (``jax.eval_shape`` compiles nothing), from ``__call__``, ``measure`` and
``hdrjax.tonemap``; a batch of zero frames is not an error: it gives zero frames. (The other
public functions: the empty forms of ``tests/conformance/_table.py``'s ``BAD_INPUTS``.)
"""

import jax
import numpy as np
import pytest

import hdrjax

from .cases import EXTRA, make, natural
from .test_conformance import LOCAL

NAMES = hdrjax.operator_names()
GOOD = natural((8, 8))
EMPTY = {"empty_rows": GOOD[:0], "empty_cols": GOOD[:, :0]}


def _struct(x):
    return jax.ShapeDtypeStruct(x.shape, x.dtype)


def _check_empty_message(msg, shape):
    assert "\n" not in msg, msg
    assert msg.startswith("rgb: expected a non-empty image (..., H, W, 3) with H, W >= 1"), msg
    assert msg.endswith(f"got shape {shape}"), msg


@pytest.mark.parametrize("kind", list(EMPTY))
@pytest.mark.parametrize("name", NAMES)
def test_empty_image_is_a_value_error(name, kind):
    op, img = make(name), EMPTY[kind]
    calls = {
        "traced": lambda: jax.eval_shape(op, _struct(img)),
        "eager": lambda: op(img),
        "measure": lambda: op.measure(img),
        "tonemap": lambda: hdrjax.tonemap(img, name, **EXTRA.get(name, {})),
    }
    for what, call in calls.items():
        try:
            call()
        except ValueError as err:
            _check_empty_message(str(err), img.shape)
        else:
            pytest.fail(f"{name}/{kind}: {what} did not raise")


@pytest.mark.parametrize("name", [n for n in NAMES if n not in LOCAL])
def test_empty_batch_gives_empty_batch(name):
    """Traced, not compiled (the neighbourhood operators take the same batch path, in
    ``AbstractOperator.__call__``, and are slow to trace)."""
    frames = np.zeros((0, 8, 8, 3), np.float32)
    out = jax.eval_shape(make(name), _struct(frames))
    assert (out.shape, out.dtype) == ((0, 8, 8, 3), np.float32)


def test_empty_batch_runs():
    """The zero-frame batch runs as traced (one cheap operator: the others share the path)."""
    out = make("linear")(np.zeros((0, 4, 8, 3), np.float32))
    assert out.shape == (0, 4, 8, 3) and out.dtype == np.float32
