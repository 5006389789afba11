"""Directions, renderer conventions and low-discrepancy sequences (hdrjax.lights)."""

import math

import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import hdrjax.lights as hl
import hdrjax.panorama as pano
from hdrjax.lights import _loghin2019

ATOL = 1e-5

# formulas.md §6.2: (convention, (u, v), expected direction)
LANDMARKS = [
    ("hdrjax", (0.5, 0.5), (0, 0, -1)),  # centre looks ahead (-Z)
    ("hdrjax", (0.75, 0.5), (1, 0, 0)),  # right is +X
    ("hdrjax", (0.3, 0.0), (0, 1, 0)),  # top row is +Y
    ("blender", (0.5, 0.5), (1, 0, 0)),  # Cycles: centre +X
    ("blender", (0.25, 0.5), (0, 1, 0)),  # +Y at u = 0.25
    ("blender", (0.9, 0.0), (0, 0, 1)),
    ("pbrt", (0.0, 0.5), (1, 0, 0)),  # +X at s = 0
    ("pbrt", (0.25, 0.5), (0, 1, 0)),  # +Y at s = 0.25
    ("pbrt", (0.6, 0.0), (0, 0, 1)),
    ("mitsuba", (0.0, 0.5), (0, 0, -1)),  # u = 0 is -Z
    ("mitsuba", (0.25, 0.5), (1, 0, 0)),
    ("mitsuba", (0.5, 0.5), (0, 0, 1)),
    ("mitsuba", (0.75, 0.5), (-1, 0, 0)),
    ("mitsuba", (0.1, 0.0), (0, 1, 0)),
    ("openexr", (0.5, 0.5), (0, 0, 1)),  # centre +Z
    ("openexr", (0.25, 0.5), (1, 0, 0)),  # longitude grows to the left
    ("openexr", (0.2, 0.0), (0, 1, 0)),
]


@pytest.mark.parametrize("convention, uv, expected", LANDMARKS)
def test_landmarks_from_formulas_md(convention, uv, expected):
    d = hl.uv_to_direction(jnp.array(uv), convention)
    np.testing.assert_allclose(d, expected, atol=ATOL)
    back = hl.direction_to_uv(jnp.array(expected, jnp.float32), convention)
    if 0 < uv[1] < 1:  # at the poles u is arbitrary
        np.testing.assert_allclose(back, uv, atol=ATOL)
    else:
        assert abs(float(back[1]) - uv[1]) < ATOL


def test_hdrjax_convention_is_the_panorama_modules_and_sources_md():
    h, w = 8, 16
    ours = hl.uv_to_direction(
        jnp.stack(jnp.meshgrid((jnp.arange(w) + 0.5) / w, (jnp.arange(h) + 0.5) / h), axis=-1)
    )
    np.testing.assert_allclose(ours, pano.equirect_directions(h, w), atol=ATOL)
    # SOURCES.md: az = 360 (x + 0.5) / W - 180, el = 90 - 180 (y + 0.5) / H
    az, el = hl.azimuth_elevation(ours)
    np.testing.assert_allclose(az[3], 360 * (np.arange(w) + 0.5) / w - 180, atol=1e-4)
    np.testing.assert_allclose(el[:, 5], 90 - 180 * (np.arange(h) + 0.5) / h, atol=1e-4)
    np.testing.assert_allclose(
        hl.azel_to_direction(np.radians(az), np.radians(el)), ours, atol=ATOL
    )


uvs = st.tuples(st.floats(0.0, 0.999), st.floats(0.01, 0.99))


@settings(deadline=None, max_examples=60)
@given(uv=uvs, a=st.sampled_from(hl.CONVENTIONS), b=st.sampled_from(hl.CONVENTIONS))
def test_round_trips_between_conventions(uv, a, b):
    d = hl.uv_to_direction(jnp.array(uv), a)
    assert abs(float(jnp.linalg.norm(d)) - 1) < ATOL
    np.testing.assert_allclose(hl.direction_to_uv(d, a), uv, atol=2e-5)
    there = hl.convert_direction(d, a, b)
    np.testing.assert_allclose(hl.direction_to_uv(there, b), uv, atol=2e-5)
    np.testing.assert_allclose(hl.convert_direction(there, b, a), d, atol=5e-5)


def test_up_axis_swaps_are_inverse_rotations():
    basis = jnp.eye(3)
    z = hl.to_z_up(basis)
    assert math.isclose(float(jnp.linalg.det(z)), 1.0, abs_tol=1e-6)  # no mirror
    np.testing.assert_allclose(hl.to_z_up([0.0, 1.0, 0.0]), [0, 0, 1], atol=ATOL)  # up
    np.testing.assert_allclose(hl.to_z_up([0.0, 0.0, -1.0]), [0, 1, 0], atol=ATOL)  # ahead
    np.testing.assert_allclose(hl.to_y_up(z), basis, atol=ATOL)


def test_angle_between_is_accurate_for_tiny_angles():
    a = jnp.array([0.0, 0.0, -1.0])
    b = hl.azel_to_direction(jnp.radians(1e-3), 0.0)
    assert math.isclose(float(hl.angle_between(a, b)), 1e-3, rel_tol=1e-3)


def test_unknown_convention_is_a_value_error():
    with pytest.raises(ValueError, match="convention"):
        hl.uv_to_direction([0.5, 0.5], "unity")


# ----------------------------------------------------------------------------- sequences


def test_van_der_corput_known_values():
    np.testing.assert_allclose(
        hl.van_der_corput(np.arange(8)), [0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875]
    )
    np.testing.assert_allclose(
        hl.van_der_corput(np.arange(1, 6), base=3), [1 / 3, 2 / 3, 1 / 9, 4 / 9, 7 / 9]
    )


@settings(deadline=None, max_examples=50)
@given(i=st.integers(0, 2**32 - 1))
def test_bit_reversal_matches_the_radical_inverse_definition(i):
    # Φ₂(i) = Σ d_k 2^(-k-1), written out digit by digit (formulas.md §6.1)
    expected, f, n = 0.0, 0.5, i
    while n:
        expected += f * (n & 1)
        n >>= 1
        f /= 2
    assert float(np.asarray(hl.van_der_corput(np.array([i], np.uint64)))[0]) == pytest.approx(
        expected, abs=1e-7
    )


def test_hammersley_and_halton():
    h = np.asarray(hl.hammersley(8))
    np.testing.assert_allclose(h[:, 0], np.arange(8) / 8)
    np.testing.assert_allclose(h[:, 1], [0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875])
    ha = np.asarray(hl.halton(4, 2))
    np.testing.assert_allclose(ha, [[0.5, 1 / 3], [0.25, 2 / 3], [0.75, 1 / 9], [0.125, 4 / 9]])
    with pytest.raises(ValueError):
        hl.hammersley(-1)


@pytest.mark.parametrize("width, n_samples", [(512, None), (1024, None), (256, None), (512, 300)])
def test_sample_windows_leave_no_light_unseen(width, n_samples):
    """Every pixel within 55° of the horizon lies in some sample's window; nearer the poles
    the columns read are at most 2 equator pixels (in angle) apart, so any light 2 pixels
    wide is seen."""
    plan = _loghin2019._plan(
        True,
        512,
        1024,
        width=width,
        n_samples=n_samples,
        blur=0.0,
        max_radius=10.0,
        max_lights=32,
        max_candidates=None,
        weights=None,
    )
    idx, _, _ = _loghin2019._window_indices(plan)
    q = _loghin2019._pool_factor(plan)
    h, w = plan.h // q, plan.w // q
    seen = np.zeros(h * w, bool)
    seen[idx.ravel()] = True
    seen = seen.reshape(h, w)
    for y in range(h):
        el = 90 - 180 * (y + 0.5) / h
        row = np.concatenate([seen[y], seen[y]])
        gaps = np.diff(np.flatnonzero(row)) - 1
        gap_px = q * (gaps.max() if gaps.size else w)
        if abs(el) < 55:
            assert gap_px == 0, (y, el)
        else:
            assert gap_px <= 2 / math.cos(math.radians(el)), (y, el, gap_px)
