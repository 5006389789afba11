"""Panorama and goniometric projections with bilinear sampling, in JAX.

Conventions (chosen once; jit-, vmap- and grad-friendly; output sizes are static Python
ints):

- **Directions**: right-handed, **Y up**, the viewer looks along **−Z**, **+X** is to the
  right. Azimuth ``az = atan2(d_x, −d_z)`` (0 straight ahead, positive to the right),
  elevation ``el = asin(d_y)``.
- **Pixels**: pixel ``(i, j)`` (column, row) covers ``[i, i+1) × [j, j+1)``; its centre is
  ``(i + 0.5, j + 0.5)``. Row 0 is the top.
- **Equirectangular** ``(H, W)``: ``x = (az / 2π + 0.5) W``, ``y = (0.5 − el / π) H``, so
  the image centre looks ahead (−Z), ``x = 3W/4`` looks right (+X), the top row is the
  zenith (+Y): at pixel centres ``az = 360 (x + 0.5) / W − 180``,
  ``el = 90 − 180 (y + 0.5) / H``. Sampling wraps around the left/right seam.
- **Cube map**: faces ``(6, S, S, C)`` in the OpenGL order +X, −X, +Y, −Y, +Z, −Z, each
  face as OpenGL's ``GL_TEXTURE_CUBE_MAP`` table lays it out (face coordinates
  ``u, v ∈ [−1, 1]``, ``v`` down): +X ``(1, −v, −u)``, −X ``(−1, −v, u)``, +Y ``(u, 1, v)``,
  −Y ``(u, −1, −v)``, +Z ``(u, −v, 1)``, −Z ``(−u, −v, −1)``.
- **Fisheye**: equidistant lens (``r = f θ``) looking along −Z with +Y up; the image
  circle of diameter ``min(H, W)`` covers ``fov_deg``.
- **Polar (goniometric sensor)**: columns are the azimuth ``φ`` over [0°, 360°) (column
  ``i`` centred on ``φ = 360 (i + 0.5) / W``), rows the polar angle ``θ`` from 0 (top row
  edge) to ``theta_max_deg`` (bottom edge). The Cartesian view is a disc with ``θ = 0``
  at the centre, radius proportional to ``θ``, ``φ = 0`` pointing right and ``φ``
  increasing counter-clockwise; pixels outside the disc get ``fill``.
"""

import functools
import math

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .. import _check
from .._interp import lerp


@functools.partial(jax.jit, static_argnames=("wrap_x",))
def sample_bilinear(
    img: Float[ArrayLike, "H W C"],
    x: Float[ArrayLike, "*S"],
    y: Float[ArrayLike, "*S"],
    *,
    wrap_x: bool = False,
) -> Float[Array, "*S C"]:
    """Bilinear sample of ``img`` at continuous pixel coordinates (pixel centres at +0.5).

    Args:
        img: ``(H, W, C)`` image.
        x: column coordinates (edge convention: pixel ``i`` spans ``[i, i+1)``).
        y: row coordinates, same shape as ``x``.
        wrap_x: wrap columns around (panoramas); otherwise clamp to the edge.

    Returns:
        ``x.shape + (C,)`` samples.
    """
    _check.shape(img, "img", channels=None, ndim=3)
    img = jnp.asarray(img)
    if img.dtype in (jnp.float16, jnp.bfloat16):  # half floats are computed in float32
        img = img.astype(jnp.result_type(float))
    h, w = img.shape[0], img.shape[1]
    xc = jnp.asarray(x) - 0.5
    yc = jnp.clip(jnp.asarray(y) - 0.5, 0.0, h - 1.0)
    x0 = jnp.floor(xc)
    y0 = jnp.floor(yc)
    fx = (xc - x0)[..., None]
    fy = (yc - y0)[..., None]
    x0 = x0.astype(jnp.int32)
    y0 = y0.astype(jnp.int32)
    x1 = x0 + 1
    y1 = jnp.minimum(y0 + 1, h - 1)
    if wrap_x:
        x0, x1 = x0 % w, x1 % w
    else:
        fx = jnp.where((xc < 0.0)[..., None], 0.0, fx)
        fx = jnp.where((xc > w - 1.0)[..., None], 1.0, fx)
        x0 = jnp.clip(x0, 0, w - 1)
        x1 = jnp.clip(x1, 0, w - 1)
    # each blend stays between its two neighbours (no +Inf from neighbours at the float
    # maximum; a NaN/Inf neighbour with zero weight does not reach the sample)
    top = lerp(img[y0, x0], img[y0, x1], fx)
    bottom = lerp(img[y1, x0], img[y1, x1], fx)
    return lerp(top, bottom, fy)


def _centres(n: int) -> Array:
    return jnp.arange(n, dtype=jnp.float32) + 0.5


@functools.partial(jax.jit, static_argnames=("height", "width"))
def equirect_directions(height: int, width: int) -> Float[Array, "H W 3"]:
    """Unit directions of the pixel centres of an ``(height, width)`` equirectangular map."""
    az = (_centres(width) / width - 0.5) * (2 * math.pi)
    el = (0.5 - _centres(height) / height) * math.pi
    az, el = az[None, :], el[:, None]
    ce = jnp.cos(el)
    return jnp.stack(
        jnp.broadcast_arrays(ce * jnp.sin(az), jnp.sin(el), -ce * jnp.cos(az)), axis=-1
    )


@functools.partial(jax.jit, static_argnames=("height", "width"))
def direction_to_equirect(
    d: Float[ArrayLike, "*S 3"], height: int, width: int
) -> tuple[Float[Array, "*S"], Float[Array, "*S"]]:
    """Continuous pixel coordinates ``(x, y)`` of directions ``d`` in an equirect map."""
    d = jnp.asarray(d)
    n = jnp.linalg.norm(d, axis=-1)
    safe = jnp.where(n > 0, n, 1.0)
    az = jnp.arctan2(d[..., 0], -d[..., 2])
    el = jnp.arcsin(jnp.clip(d[..., 1] / safe, -1.0, 1.0))
    return (az / (2 * math.pi) + 0.5) * width, (0.5 - el / math.pi) * height


@jax.jit
def sample_equirect(
    img: Float[ArrayLike, "H W C"], d: Float[ArrayLike, "*S 3"]
) -> Float[Array, "*S C"]:
    """Bilinear lookup of an equirectangular map in directions ``d`` (seam wrapped)."""
    _check.shape(d, "d", min_ndim=1)
    _check.shape(img, "img", channels=None, ndim=3)
    img = jnp.asarray(img)
    x, y = direction_to_equirect(d, img.shape[0], img.shape[1])
    return sample_bilinear(img, x, y, wrap_x=True)


def _face_uv(size: int) -> tuple[Array, Array]:
    t = _centres(size) / size * 2.0 - 1.0
    return t[None, :], t[:, None]  # u along columns, v down the rows


@functools.partial(jax.jit, static_argnames=("size",))
def cubemap_directions(size: int) -> Float[Array, "6 S S 3"]:
    """Unit directions of the pixel centres of the six ``size``-square cube faces."""
    u, v = _face_uv(size)
    one = jnp.ones((size, size), jnp.float32)
    u = u * one
    v = v * one
    faces = [
        (one, -v, -u),  # +X
        (-one, -v, u),  # -X
        (u, one, v),  # +Y
        (u, -one, -v),  # -Y
        (u, -v, one),  # +Z
        (-u, -v, -one),  # -Z
    ]
    d = jnp.stack([jnp.stack(f, axis=-1) for f in faces])
    return d / jnp.linalg.norm(d, axis=-1, keepdims=True)


@functools.partial(jax.jit, static_argnames=("size",))
def equirect_to_cubemap(img: Float[ArrayLike, "H W C"], size: int) -> Float[Array, "6 S S C"]:
    """Resample an equirectangular map into six ``size × size`` cube faces (OpenGL order)."""
    _check.integer(size, "size")
    _check.shape(img, "img", channels=None, ndim=3)
    return sample_equirect(img, cubemap_directions(size))


@functools.partial(jax.jit, static_argnames=("height",))
def cubemap_to_equirect(faces: Float[ArrayLike, "6 S S C"], height: int) -> Float[Array, "H W C"]:
    """Resample cube faces into an equirectangular map of ``height × 2 height``."""
    _check.integer(height, "height")
    _check.cube(faces, "faces", channels=None, batch=False)
    faces = jnp.asarray(faces)
    size = faces.shape[1]
    d = equirect_directions(height, 2 * height)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    ax, ay, az = jnp.abs(x), jnp.abs(y), jnp.abs(z)
    use_x = (ax >= ay) & (ax >= az)
    use_y = ~use_x & (ay >= az)
    # face index and (u, v) on that face (inverse of cubemap_directions)
    face = jnp.where(
        use_x,
        jnp.where(x > 0, 0, 1),
        jnp.where(use_y, jnp.where(y > 0, 2, 3), jnp.where(z > 0, 4, 5)),
    )
    ma = jnp.where(use_x, ax, jnp.where(use_y, ay, az))
    u = (
        jnp.select([face == 0, face == 1, face == 2, face == 3, face == 4], [-z, z, x, x, x], -x)
        / ma
    )
    v = (
        jnp.select([face == 0, face == 1, face == 2, face == 3, face == 4], [-y, -y, z, -z, -y], -y)
        / ma
    )
    fx = (u + 1.0) * 0.5 * size - 0.5
    fy = (v + 1.0) * 0.5 * size - 0.5
    fx = jnp.clip(fx, 0.0, size - 1.0)
    fy = jnp.clip(fy, 0.0, size - 1.0)
    x0 = jnp.floor(fx).astype(jnp.int32)
    y0 = jnp.floor(fy).astype(jnp.int32)
    x1 = jnp.minimum(x0 + 1, size - 1)
    y1 = jnp.minimum(y0 + 1, size - 1)
    wx = (fx - x0)[..., None]
    wy = (fy - y0)[..., None]
    top = lerp(faces[face, y0, x0], faces[face, y0, x1], wx)
    bottom = lerp(faces[face, y1, x0], faces[face, y1, x1], wx)
    return lerp(top, bottom, wy)


@functools.partial(jax.jit, static_argnames=("height", "width", "fov_deg"))
def fisheye_directions(
    height: int, width: int, *, fov_deg: float = 180.0
) -> tuple[Float[Array, "H W 3"], Array]:
    """Directions of fisheye pixel centres and a mask of the pixels inside the circle."""
    r_img = min(height, width) / 2.0
    u = (_centres(width)[None, :] - width / 2.0) / r_img
    v = (_centres(height)[:, None] - height / 2.0) / r_img
    r = jnp.sqrt(u * u + v * v)
    theta = r * math.radians(fov_deg) / 2.0
    psi = jnp.arctan2(-v, u)
    st = jnp.sin(theta)
    d = jnp.stack(
        jnp.broadcast_arrays(st * jnp.cos(psi), st * jnp.sin(psi), -jnp.cos(theta)), axis=-1
    )
    return d, r <= 1.0


@functools.partial(jax.jit, static_argnames=("size", "fov_deg", "fill"))
def equirect_to_fisheye(
    img: Float[ArrayLike, "H W C"], size: int, *, fov_deg: float = 180.0, fill: float = 0.0
) -> Float[Array, "S S C"]:
    """An equidistant fisheye view (``size × size``, looking along −Z) of an equirect map."""
    _check.positive(fov_deg, "fov_deg")
    _check.integer(size, "size")
    _check.shape(img, "img", channels=None, ndim=3)
    d, inside = fisheye_directions(size, size, fov_deg=fov_deg)
    out = sample_equirect(img, d)
    return jnp.where(inside[..., None], out, jnp.asarray(fill, out.dtype))


@functools.partial(jax.jit, static_argnames=("height", "fov_deg", "fill"))
def fisheye_to_equirect(
    img: Float[ArrayLike, "H W C"], height: int, *, fov_deg: float = 180.0, fill: float = 0.0
) -> Float[Array, "Ho Wo C"]:
    """Resample an equidistant fisheye image into a ``height × 2 height`` equirect map.

    Directions outside the fisheye's field of view get ``fill``.
    """
    _check.positive(fov_deg, "fov_deg")
    _check.integer(height, "height")
    _check.shape(img, "img", channels=None, ndim=3)
    img = jnp.asarray(img)
    h, w = img.shape[0], img.shape[1]
    d = equirect_directions(height, 2 * height)
    theta = jnp.arccos(jnp.clip(-d[..., 2], -1.0, 1.0))
    psi = jnp.arctan2(d[..., 1], d[..., 0])
    half = math.radians(fov_deg) / 2.0
    r = theta / half * (min(h, w) / 2.0)
    x = w / 2.0 + r * jnp.cos(psi)
    y = h / 2.0 - r * jnp.sin(psi)
    out = sample_bilinear(img, x, y)
    return jnp.where((theta <= half)[..., None], out, jnp.asarray(fill, out.dtype))


@functools.partial(jax.jit, static_argnames=("size", "theta_max_deg", "theta_view_deg", "fill"))
def polar_to_cartesian(
    img: Float[ArrayLike, "H W C"],
    size: int,
    *,
    theta_max_deg: float = 90.0,
    theta_view_deg: float | None = None,
    fill: float = 0.0,
) -> Float[Array, "S S C"]:
    """A ``size × size`` disc view of a polar (azimuth × polar angle) sensor image.

    Args:
        img: ``(H, W, C)``: rows are the polar angle θ from 0 (top edge) to
            ``theta_max_deg`` (bottom edge), columns the azimuth φ over [0°, 360°).
        size: output side in pixels; the disc touches the borders.
        theta_max_deg: the polar angle of the input's bottom edge, degrees.
        theta_view_deg: the polar angle shown at the disc's rim (default
            ``theta_max_deg``); angles beyond the input get ``fill``.
        fill: value outside the disc and beyond the input.

    Returns:
        The disc: centre ``θ = 0``, radius ∝ θ, ``φ = 0`` to the right, counter-clockwise.
    """
    _check.integer(size, "size")
    _check.shape(img, "img", channels=None, ndim=3)
    if not theta_max_deg > 0:  # static arguments: checked at trace time
        raise ValueError(f"theta_max_deg must be > 0, got {theta_max_deg}")
    view = theta_max_deg if theta_view_deg is None else float(theta_view_deg)
    if not view > 0:
        raise ValueError(f"theta_view_deg must be > 0, got {theta_view_deg}")
    img = jnp.asarray(img)
    h, w = img.shape[0], img.shape[1]
    u = _centres(size)[None, :] / size * 2.0 - 1.0
    v = _centres(size)[:, None] / size * 2.0 - 1.0
    rho = jnp.sqrt(u * u + v * v)
    phi = jnp.mod(jnp.arctan2(-v, u), 2 * math.pi)
    theta_frac = rho * (view / theta_max_deg)  # 1 at the input's bottom edge
    x = jnp.broadcast_to(phi / (2 * math.pi) * w, (size, size))
    y = jnp.broadcast_to(theta_frac * h, (size, size))
    out = sample_bilinear(img, x, y, wrap_x=True)
    keep = (rho <= 1.0) & (theta_frac <= 1.0)
    return jnp.where(keep[..., None], out, jnp.asarray(fill, out.dtype))


__all__ = [
    "cubemap_directions",
    "cubemap_to_equirect",
    "direction_to_equirect",
    "equirect_directions",
    "equirect_to_cubemap",
    "equirect_to_fisheye",
    "fisheye_directions",
    "fisheye_to_equirect",
    "polar_to_cartesian",
    "sample_bilinear",
    "sample_equirect",
]
