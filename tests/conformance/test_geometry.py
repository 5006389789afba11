"""Conformance of the public functions that take directions, angles or sizes instead of
images (hdrjax.lights geometry and sequences, hdrjax.panorama directions, vision kernels):
finite outputs for finite inputs (axes, poles, the zero vector, 1e-30 and 1e30 lengths,
subnormals), the documented dtype, jit == eager. Every convention of
``hdrjax.lights.CONVENTIONS`` is exercised."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
import hdrjax.lights as hl
import hdrjax.panorama as hp
import hdrjax.vision as hv

from ..conftest import enable_x64

# directions: axes, poles, tiny and huge lengths, the zero vector, a subnormal, a NaN row
DIRECTIONS = np.array(
    [
        [0, 0, -1],
        [1, 0, 0],
        [0, 1, 0],
        [0, -1, 0],
        [0.3, -0.2, 0.9],
        [1e-30, 2e-30, -1e-30],
        [1e30, -1e30, 3e30],
        [0, 0, 0],
        [1e-42, 0, 0],
        [np.nan, 0, 1],
    ]
)
UV = np.array([[0, 0], [1, 1], [0.5, 0.5], [0.25, 0.999], [-0.1, 1.2], [np.nan, 0.5]])
AZEL = np.array([[0, 0], [np.pi / 2, 0], [0, np.pi / 2], [1e30, -np.pi / 2], [np.nan, 0]])


def _conventions(d, uv, ae, *, c):
    """To and from convention ``c``, and its (u, v) mapping both ways."""
    return (
        hl.convert_direction(d, "hdrjax", c),
        hl.convert_direction(d, c, "hdrjax"),
        hl.direction_to_uv(d, c),
        hl.uv_to_direction(uv, c),
    )


# name -> (fn of (directions, uv, azel) arrays, public names covered); each returns arrays
# whose leading axis is the input row
ROW_CASES = {
    "angle_between": (
        lambda d, uv, ae: hl.angle_between(d, d[::-1]),
        ("hdrjax.lights.angle_between",),
    ),
    "azimuth_elevation": (
        lambda d, uv, ae: hl.azimuth_elevation(d),
        ("hdrjax.lights.azimuth_elevation",),
    ),
    "azel_to_direction": (
        lambda d, uv, ae: hl.azel_to_direction(ae[:, 0], ae[:, 1]),
        ("hdrjax.lights.azel_to_direction",),
    ),
    "to_y_up": (lambda d, uv, ae: hl.to_y_up(d), ("hdrjax.lights.to_y_up",)),
    "to_z_up": (lambda d, uv, ae: hl.to_z_up(d), ("hdrjax.lights.to_z_up",)),
    "direction_to_equirect": (
        lambda d, uv, ae: jnp.stack(hp.direction_to_equirect(d, 8, 16), -1),
        ("hdrjax.panorama.direction_to_equirect",),
    ),
    **{
        f"convention[{c}]": (
            functools.partial(_conventions, c=c),
            (
                "hdrjax.lights.convert_direction",
                "hdrjax.lights.direction_to_uv",
                "hdrjax.lights.uv_to_direction",
            ),
        )
        for c in hl.CONVENTIONS
    },
}

# name -> (fn() -> arrays from sizes only, covered names, documented range)
GENERATORS = {
    "halton": (lambda: hl.halton(17, 3), ("hdrjax.lights.halton",), (0, 1)),
    "hammersley": (lambda: hl.hammersley(17), ("hdrjax.lights.hammersley",), (0, 1)),
    "van_der_corput": (
        lambda: hl.van_der_corput(np.arange(0, 2**20, 997), 3),
        ("hdrjax.lights.van_der_corput",),
        (0, 1),
    ),
    "cubemap_directions": (
        lambda: hp.cubemap_directions(3),
        ("hdrjax.panorama.cubemap_directions",),
        (-1, 1),
    ),
    "equirect_directions": (
        lambda: hp.equirect_directions(1, 2),
        ("hdrjax.panorama.equirect_directions",),
        (-1, 1),
    ),
    "fisheye_directions": (
        lambda: hp.fisheye_directions(5, 5)[0],
        ("hdrjax.panorama.fisheye_directions",),
        (-1, 1),
    ),
    "perspective_directions": (
        lambda: hp.perspective_directions(3, 4, fov_deg=120.0, yaw_deg=-30.0, roll_deg=10.0),
        ("hdrjax.panorama.perspective_directions",),
        (-1, 1),
    ),
    "camera_basis": (
        lambda: hp.camera_basis(30.0, -20.0, 45.0),
        ("hdrjax.panorama.camera_basis",),
        (-1, 1),
    ),
    "glare_kernel": (
        lambda: hv.glare_kernel(hv.View(hfov=30.0).resolve(5, 7)),
        ("hdrjax.vision.glare_kernel",),
        (0, 1),
    ),
    "display_adaptation": (
        lambda: np.array([hv.display_adaptation(m) for m in ("pcond", "ward1994")]),
        ("hdrjax.vision.display_adaptation",),
        (0, 1e3),
    ),
    "luminance_weights": (
        lambda: np.array(
            hdrjax.luminance_weights((0.64, 0.33, 0.3, 0.6, 0.15, 0.06, 0.3127, 0.329))
        ),
        ("hdrjax.luminance_weights",),
        (0, 1),
    ),
}

COVERS = {n for _, c in ROW_CASES.values() for n in c} | {
    n for _, c, _ in GENERATORS.values() for n in c
}


def _leaves(out):
    return [np.asarray(v) for v in jax.tree_util.tree_leaves(out)]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("name", sorted(ROW_CASES))
def test_rows_finite_dtype_and_jit(name, dtype):
    fn = ROW_CASES[name][0]
    with enable_x64(dtype == np.float64):
        args = [jnp.asarray(a, dtype) for a in (DIRECTIONS, UV, AZEL)]
        eager = _leaves(fn(*args))
        jitted = _leaves(jax.jit(fn)(*args))
    ok_rows = {
        len(DIRECTIONS): np.all(np.isfinite(DIRECTIONS), -1),
        len(UV): np.all(np.isfinite(UV), -1),
        len(AZEL): np.all(np.isfinite(AZEL), -1),
    }
    if name == "angle_between":  # pairs a row with its mirror
        ok_rows[len(DIRECTIONS)] = ok_rows[len(DIRECTIONS)] & ok_rows[len(DIRECTIONS)][::-1]
    for e, j in zip(eager, jitted, strict=True):
        assert e.dtype == dtype, f"{name}: {dtype} in, {e.dtype} out"
        ok = ok_rows[e.shape[0]]
        assert np.all(np.isfinite(e[ok])), f"{name}: non-finite output for a finite row"
        np.testing.assert_allclose(j, e, rtol=1e-5, atol=1e-6, err_msg=name)


@pytest.mark.parametrize("name", sorted(GENERATORS))
def test_generators_are_finite_and_in_range(name):
    fn, _, (lo, hi) = GENERATORS[name]
    for leaf in _leaves(fn()):
        assert leaf.size and np.all(np.isfinite(leaf)), name
        assert np.all((leaf >= lo) & (leaf <= hi)), f"{name}: outside [{lo}, {hi}]"
