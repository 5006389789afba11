"""Equirectangular geometry: pixel ↔ direction under several renderer conventions.

Image coordinates: ``u, v ∈ [0, 1]`` with ``v = 0`` the **top** row; pixel ``(x, y)`` (column,
row; integers at pixel centres) sits at ``u = (x + 0.5) / W``, ``v = (y + 0.5) / H``.
Azimuth and elevation:
``az = 360° · u − 180°`` (0 at the image centre, positive to the right) and
``el = 90° − 180° · v``.

hdrjax's own convention (``"hdrjax"``, the one of :mod:`hdrjax.panorama`) is **Y-up,
right-handed, looking along −Z with +X to the right**::

    d = (cos el · sin az, sin el, −cos el · cos az)

Other renderers map the same pixel to other directions (read from their sources: Blender
Cycles' ``direction_to_equirectangular_range``, pbrt-v3's ``InfiniteAreaLight``, Mitsuba 3's
``envmap`` emitter, OpenEXR's ``Imf::LatLongMap``):

- ``"blender"`` (Cycles, Z-up): image centre +X, right −Y:
  ``d = (cos el cos az, −cos el sin az, sin el)``;
- ``"pbrt"`` (Z-up): ``φ = 2πu``, ``θ = πv``, ``d = (sinθ cosφ, sinθ sinφ, cosθ)``;
- ``"mitsuba"`` (Y-up): ``φ = 2πu``, ``θ = πv``, ``d = (sinφ sinθ, cosθ, −cosφ sinθ)``;
- ``"openexr"`` (Y-up, ``Imf::LatLongMap``): ``lon = −2π(u − ½)``, ``lat = π(½ − v)``,
  ``d = (sin lon cos lat, sin lat, cos lon cos lat)`` (OpenEXR puts the first and last pixel
  centres on the image edges; here ``u, v`` are the continuous coordinates above).

:func:`convert_direction` maps a direction between two conventions through the pixel it
comes from. :func:`to_z_up` / :func:`to_y_up` only change the up axis (a rotation about X:
``(x, y, z) → (x, −z, y)`` and back), for a Z-up scene that keeps hdrjax's horizontal
layout (ahead becomes +Y, right stays +X).
"""

import math
from typing import Literal

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

Convention = Literal["hdrjax", "blender", "pbrt", "mitsuba", "openexr"]
CONVENTIONS: tuple[str, ...] = ("hdrjax", "blender", "pbrt", "mitsuba", "openexr")
"""Names accepted by the ``convention`` arguments."""


def _check(convention: str) -> str:
    c = str(convention).lower()
    if c not in CONVENTIONS:
        raise ValueError(f"convention: expected one of {CONVENTIONS}, got {convention!r}")
    return c


def azel_to_direction(az: ArrayLike, el: ArrayLike) -> Array:
    """hdrjax unit vectors from azimuth and elevation in **radians** (module docstring)."""
    ce = jnp.cos(el)
    return jnp.stack([ce * jnp.sin(az), jnp.sin(el) + 0 * ce, -ce * jnp.cos(az)], axis=-1)


def _float(x: ArrayLike) -> Array:
    x = jnp.asarray(x)
    if not jnp.issubdtype(x.dtype, jnp.floating) or x.dtype in (jnp.float16, jnp.bfloat16):
        x = x.astype(jnp.result_type(float))
    return x


def uv_to_direction(
    uv: Float[ArrayLike, "*N 2"], convention: Convention = "hdrjax"
) -> Float[Array, "*N 3"]:
    """Unit direction for equirectangular image coordinates.

    Args:
        uv: ``(u, v)`` in [0, 1], ``v = 0`` at the top row (see module docstring).
        convention: which renderer's mapping (module docstring).

    Returns:
        Unit vectors, shape ``uv.shape[:-1] + (3,)``.

    >>> uv_to_direction([0.5, 0.5]).round(6).tolist()  # image centre: ahead, -Z
    [0.0, 0.0, -1.0]
    """
    c = _check(convention)
    uv = _float(uv)
    u, v = uv[..., 0], uv[..., 1]
    if c == "hdrjax":
        return azel_to_direction(2 * math.pi * (u - 0.5), math.pi * (0.5 - v))
    if c == "blender":
        az, el = 2 * math.pi * (u - 0.5), math.pi * (0.5 - v)
        ce = jnp.cos(el)
        return jnp.stack([ce * jnp.cos(az), -ce * jnp.sin(az), jnp.sin(el)], axis=-1)
    if c == "pbrt":
        phi, theta = 2 * math.pi * u, math.pi * v
        st = jnp.sin(theta)
        return jnp.stack([st * jnp.cos(phi), st * jnp.sin(phi), jnp.cos(theta)], axis=-1)
    if c == "mitsuba":
        phi, theta = 2 * math.pi * u, math.pi * v
        st = jnp.sin(theta)
        return jnp.stack([jnp.sin(phi) * st, jnp.cos(theta), -jnp.cos(phi) * st], axis=-1)
    lon, lat = -2 * math.pi * (u - 0.5), math.pi * (0.5 - v)  # openexr
    cl = jnp.cos(lat)
    return jnp.stack([jnp.sin(lon) * cl, jnp.sin(lat), jnp.cos(lon) * cl], axis=-1)


def direction_to_uv(
    d: Float[ArrayLike, "*N 3"], convention: Convention = "hdrjax"
) -> Float[Array, "*N 2"]:
    """Equirectangular image coordinates of a direction (inverse of :func:`uv_to_direction`).

    Args:
        d: directions (need not be normalised; the zero vector maps to the image centre
            row at ``u = 0.5``).
        convention: which renderer's mapping.

    Returns:
        ``(u, v)`` with ``u ∈ [0, 1)`` and ``v ∈ [0, 1]``.
    """
    c = _check(convention)
    d = _float(d)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    tau = 2 * math.pi
    if c == "hdrjax":
        az, el = jnp.arctan2(x, -z), jnp.arctan2(y, jnp.hypot(x, z))
        u, v = az / tau + 0.5, 0.5 - el / math.pi
    elif c == "blender":
        az, el = jnp.arctan2(-y, x), jnp.arctan2(z, jnp.hypot(x, y))
        u, v = az / tau + 0.5, 0.5 - el / math.pi
    elif c == "pbrt":
        u, v = jnp.arctan2(y, x) / tau, jnp.arctan2(jnp.hypot(x, y), z) / math.pi
    elif c == "mitsuba":
        u, v = jnp.arctan2(x, -z) / tau, jnp.arctan2(jnp.hypot(x, z), y) / math.pi
    else:
        lon, lat = jnp.arctan2(x, z), jnp.arctan2(y, jnp.hypot(x, z))
        u, v = 0.5 - lon / tau, 0.5 - lat / math.pi
    u = u - jnp.floor(u)
    return jnp.stack([jnp.where(u >= 1.0, 0.0, u), v], axis=-1)


def convert_direction(
    d: Float[ArrayLike, "*N 3"], source: Convention, target: Convention
) -> Float[Array, "*N 3"]:
    """Direction in ``target``'s world that the same env-map pixel as ``d`` in ``source`` has.

    >>> convert_direction([0.0, 0.0, -1.0], "hdrjax", "mitsuba").round(6).tolist()
    [0.0, 0.0, 1.0]
    """
    return uv_to_direction(direction_to_uv(d, source), target)


def to_z_up(d: Float[ArrayLike, "*N 3"]) -> Float[Array, "*N 3"]:
    """hdrjax (Y-up) directions in a Z-up right-handed frame: ``(x, y, z) → (x, −z, y)``.

    >>> to_z_up([0.0, 1.0, 0.0]).tolist()  # up
    [0.0, 0.0, 1.0]
    """
    d = _float(d)
    return jnp.stack([d[..., 0], -d[..., 2], d[..., 1]], axis=-1)


def to_y_up(d: Float[ArrayLike, "*N 3"]) -> Float[Array, "*N 3"]:
    """Inverse of :func:`to_z_up`: Z-up ``(x, y, z) → (x, z, −y)`` (hdrjax, Y-up)."""
    d = _float(d)
    return jnp.stack([d[..., 0], d[..., 2], -d[..., 1]], axis=-1)


def azimuth_elevation(
    d: Float[ArrayLike, "*N 3"],
) -> tuple[Float[Array, "*N"], Float[Array, "*N"]]:
    """hdrjax azimuth and elevation in degrees (module docstring) of directions."""
    d = _float(d)
    az = jnp.degrees(jnp.arctan2(d[..., 0], -d[..., 2]))
    el = jnp.degrees(jnp.arctan2(d[..., 1], jnp.hypot(d[..., 0], d[..., 2])))
    return az, el


def angle_between(a: Float[ArrayLike, "*N 3"], b: Float[ArrayLike, "*N 3"]) -> Float[Array, "*N"]:
    """Angle between two directions in degrees (``atan2(|a×b|, a·b)``: accurate near 0)."""
    a, b = _float(a), _float(b)
    cross = jnp.linalg.norm(jnp.cross(a, b), axis=-1)
    return jnp.degrees(jnp.arctan2(cross, jnp.sum(a * b, axis=-1)))


__all__ = [
    "CONVENTIONS",
    "Convention",
    "angle_between",
    "azel_to_direction",
    "azimuth_elevation",
    "convert_direction",
    "direction_to_uv",
    "to_y_up",
    "to_z_up",
    "uv_to_direction",
]
