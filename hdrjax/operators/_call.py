"""Calling an operator on an image already known to be finite.

:meth:`AbstractOperator.__call__` checks every image for NaN/±Inf pixels and takes the
masked path only when it finds one. Callers that have checked the image themselves (a batch
frame read from a file, an image whose statistics were just measured) use
:func:`clean_operator_call` to take the finite-image path directly, without a second check.
"""

from jaxtyping import Array, Float

from .._colour import luminance
from ._base import AbstractOperator, Prepared


def clean_operator_call(op: AbstractOperator, rgb: Float[Array, "H W 3"]) -> Float[Array, "H W 3"]:
    """``op(rgb)`` for one image known to be finite: the operators' fast path, without the
    data-dependent check that chooses it (same result as ``op(rgb)`` on such an image):
    the operator measured on the image (``op.bind`` of its statistics, or the operator's own
    measurement where it has one, as mantiuk2008's curve), then mapped."""
    L = luminance(rgb, op.weights_)
    p = Prepared(rgb, L, L, clean=True)
    return op._measure(p)._apply(p)


__all__ = ["clean_operator_call"]
