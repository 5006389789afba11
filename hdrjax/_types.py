"""Shared type aliases (jaxtyping) for hdrjax's public signatures."""

from jaxtyping import Array, ArrayLike, Float

RGB = Float[Array, "*batch H W 3"]
"""Linear-light RGB image, channels last."""

Luminance = Float[Array, "*batch H W"]
"""Per-pixel luminance (cd/m² for absolute images, relative otherwise)."""

Scalar = Float[ArrayLike, ""]
"""A scalar parameter: Python float or 0-d array."""

__all__ = ["RGB", "Luminance", "Scalar"]
