"""Pinhole (rectilinear) views of spherical panoramas, in JAX.

The frame is the panorama module's (Y up, the viewer looks along −Z, +X to the right;
:mod:`hdrjax.panorama`). A view is a pinhole camera at the centre of the sphere:

- **Orientation**: ``yaw_deg`` turns the camera to the right (the azimuth of its axis, as
  the equirectangular map's azimuth: 0 straight ahead, 90 looks along +X), ``pitch_deg``
  tilts it up (the elevation of its axis), ``roll_deg`` turns it clockwise about its axis
  as the photographer sees it (the scene then appears turned counter-clockwise). The
  camera's axis, right and up vectors are

  ``f = (cos p sin y, sin p, −cos p cos y)``, ``r₀ = (cos y, 0, sin y)``, ``u₀ = r₀ × f``,
  ``r = cos ρ r₀ − sin ρ u₀``, ``u = sin ρ r₀ + cos ρ u₀``

  (``y``, ``p``, ``ρ`` the yaw, pitch and roll), so yaw = pitch = roll = 0 is the
  equirectangular map's centre with +X to the right and +Y up.
- **Projection**: the horizontal field of view ``fov_deg`` spans the image width; the
  focal length in pixels is ``F = (W / 2) / tan(fov / 2)`` and square pixels give the
  vertical field ``2 atan((H / 2) / F)``. Pixel ``(i, j)`` (centre ``(i + ½, j + ½)``,
  row 0 at the top) looks along ``a r + b u + f`` with ``a = (i + ½ − W/2) / F`` and
  ``b = (H/2 − j − ½) / F``: the gnomonic (rectilinear) projection, straight lines of the
  scene stay straight (Snyder, *Map Projections — A Working Manual*, USGS Professional
  Paper 1395, 1987, p. 164, doi:10.3133/pp1395).

Sampling is bilinear with the seam wrapped (:func:`~hdrjax.panorama.sample_equirect`), so a
NaN or Inf pixel of the panorama reaches only the view pixels whose four neighbours include
it, and the view is linear in the panorama (its gradient with respect to the image is the
transposed resampling). The angles may be traced (``jax.grad`` with respect to them works
wherever no sample sits exactly on a pixel boundary); the output size is static.
"""

import functools

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from ._projections import sample_equirect


def _check_view(height: int, width: int, fov_deg, yaw_deg, pitch_deg, roll_deg) -> None:
    _check.integer(height, "height")
    _check.integer(width, "width")
    _check.positive(fov_deg, "fov_deg")
    _check.in_range(fov_deg, "fov_deg", 0.0, 179.999)
    for v, n in ((yaw_deg, "yaw_deg"), (pitch_deg, "pitch_deg"), (roll_deg, "roll_deg")):
        _check.in_range(v, n, -1e6, 1e6)  # finite numbers


def camera_basis(
    yaw_deg: Float[ArrayLike, ""], pitch_deg: Float[ArrayLike, ""], roll_deg: Float[ArrayLike, ""]
) -> Float[Array, "3 3"]:
    """The camera's right, up and forward unit vectors (rows), in the panorama's frame
    (module docstring)."""
    dt = jnp.result_type(yaw_deg, pitch_deg, roll_deg, float)
    y, p, rho = (jnp.deg2rad(jnp.asarray(v, dt)) for v in (yaw_deg, pitch_deg, roll_deg))
    cy, sy, cp, sp = jnp.cos(y), jnp.sin(y), jnp.cos(p), jnp.sin(p)
    f = jnp.stack([cp * sy, sp, -cp * cy])
    r0 = jnp.stack([cy, jnp.zeros_like(cy), sy])
    u0 = jnp.cross(r0, f)
    cr, sr = jnp.cos(rho), jnp.sin(rho)
    return jnp.stack([cr * r0 - sr * u0, sr * r0 + cr * u0, f])


@functools.partial(jax.jit, static_argnames=("height", "width"))
def _directions(height: int, width: int, fov_deg, yaw_deg, pitch_deg, roll_deg) -> Array:
    basis = camera_basis(yaw_deg, pitch_deg, roll_deg)
    dt = basis.dtype
    focal = (width / 2.0) / jnp.tan(jnp.deg2rad(jnp.asarray(fov_deg, dt)) / 2.0)
    a = (jnp.arange(width, dtype=dt) + 0.5 - width / 2.0) / focal
    b = (height / 2.0 - jnp.arange(height, dtype=dt) - 0.5) / focal
    a, b = jnp.broadcast_arrays(a[None, :], b[:, None])
    d = jnp.einsum("hwk,kc->hwc", jnp.stack([a, b, jnp.ones_like(a)], axis=-1), basis)
    return d / jnp.linalg.norm(d, axis=-1, keepdims=True)


def perspective_directions(
    height: int,
    width: int,
    *,
    fov_deg: Float[ArrayLike, ""] = 90.0,
    yaw_deg: Float[ArrayLike, ""] = 0.0,
    pitch_deg: Float[ArrayLike, ""] = 0.0,
    roll_deg: Float[ArrayLike, ""] = 0.0,
) -> Float[Array, "H W 3"]:
    """Unit directions of the pixel centres of a ``height × width`` pinhole view.

    Args:
        height: rows of the view.
        width: columns of the view.
        fov_deg: horizontal field of view, degrees, in (0, 180).
        yaw_deg: azimuth of the view axis, degrees (positive to the right).
        pitch_deg: elevation of the view axis, degrees (positive up).
        roll_deg: clockwise turn of the camera about its axis, degrees.

    Returns:
        ``(height, width, 3)`` unit vectors in the panorama's frame (module docstring).
    """
    _check_view(height, width, fov_deg, yaw_deg, pitch_deg, roll_deg)
    return _directions(height, width, fov_deg, yaw_deg, pitch_deg, roll_deg)


@functools.partial(jax.jit, static_argnames=("height", "width"))
def _view(img, height: int, width: int, fov_deg, yaw_deg, pitch_deg, roll_deg):
    d = _directions(height, width, fov_deg, yaw_deg, pitch_deg, roll_deg)
    return sample_equirect(img, d.astype(jnp.result_type(img.dtype, jnp.float32)))


def equirect_to_perspective(
    img: Float[ArrayLike, "H W C"],
    height: int,
    width: int,
    *,
    fov_deg: Float[ArrayLike, ""] = 90.0,
    yaw_deg: Float[ArrayLike, ""] = 0.0,
    pitch_deg: Float[ArrayLike, ""] = 0.0,
    roll_deg: Float[ArrayLike, ""] = 0.0,
) -> Float[Array, "height width C"]:
    """A pinhole view of an equirectangular panorama (module docstring).

    Args:
        img: ``(H, W, C)`` equirectangular map, any units (linear values: the view
            interpolates them bilinearly, seam wrapped).
        height, width, fov_deg, yaw_deg, pitch_deg, roll_deg: the view, as for
            :func:`perspective_directions`.

    Returns:
        ``(height, width, C)`` in the units of ``img``; the view's centre pixel looks along
        the azimuth ``yaw_deg`` and elevation ``pitch_deg``.
    """
    _check.shape(img, "img", channels=None, ndim=3)
    _check_view(height, width, fov_deg, yaw_deg, pitch_deg, roll_deg)
    img = jnp.asarray(img)
    return _view(img, height, width, fov_deg, yaw_deg, pitch_deg, roll_deg)


__all__ = [
    "camera_basis",
    "equirect_to_perspective",
    "perspective_directions",
]
