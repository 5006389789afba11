"""Light detection on cube maps, through :func:`hdrjax.panorama.cubemap_to_equirect`.

The six faces (OpenGL order +X, −X, +Y, −Y, +Z, −Z, laid out as in
:mod:`hdrjax.panorama`) are resampled (bilinear) to an equirectangular map of
``height × 2·height`` — ``2 S`` rows for ``S``-pixel faces by default, which keeps about one
equirectangular pixel per face pixel at the face centres — and :func:`~hdrjax.lights.detect`
runs on it. The cube map's frame is hdrjax's (Y-up, −Z ahead), so the lights' directions
are directions in the cube map's world; pixel positions refer to the resampled map.
Bilinear resampling spreads a non-finite face pixel over its neighbours: they are excluded.
"""

import functools
import math
from typing import Any

import jax
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from ..panorama import cubemap_to_equirect
from ._loghin2019 import detect
from ._result import Lights


@functools.partial(jax.jit, static_argnames=("height",))
def _to_equirect(faces: Array, height: int) -> Array:
    lead = faces.shape[:-4]
    flat = faces.reshape((math.prod(lead),) + faces.shape[-4:])
    out = jax.vmap(lambda f: cubemap_to_equirect(f, height))(flat)
    return out.reshape(lead + out.shape[1:])


def cubemap_equirect(
    faces: Float[ArrayLike, "*batch 6 S S 3"], height: int | None = None
) -> Float[Array, "*batch h w 3"]:
    """The equirectangular map :func:`detect_cubemap` searches (``height`` default ``2 S``)."""
    shape = _check.cube(faces, "faces")
    h = 2 * int(shape[-2]) if height is None else int(height)
    if h < 2:
        raise ValueError(f"height: expected an integer >= 2, got {height!r}")
    return _to_equirect(faces, h)


def detect_cubemap(
    faces: Float[ArrayLike, "*batch 6 S S 3"], *, height: int | None = None, **options: Any
) -> Lights:
    """Find the light sources of a cube map (module docstring).

    Args:
        faces: ``(..., 6, S, S, 3)`` linear RGB faces in OpenGL order.
        height: rows of the intermediate equirectangular map (default ``2 S``).
        **options: as :func:`~hdrjax.lights.detect` (``width``, ``threshold``, ...).

    Returns:
        :class:`~hdrjax.lights.Lights` of the resampled map (``input_shape`` is its size).
    """
    _check.real(faces, "faces")
    return detect(cubemap_equirect(faces, height), **options)


__all__ = ["cubemap_equirect", "detect_cubemap"]
