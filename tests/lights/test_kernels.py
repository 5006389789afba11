"""The fast kernels of hdrjax.lights.detect against plain NumPy formulations of the same
steps (the detection must not depend on how a step is computed)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import ndimage

from hdrjax.lights import _loghin2019 as L


def _plan(sphere: bool, width: int = 512, max_radius: float = 10.0) -> L._Plan:
    return L._plan(
        sphere,
        256,
        512,
        width=width,
        n_samples=None,
        blur=0.0,
        max_radius=max_radius,
        max_lights=32,
        max_candidates=None,
        weights=None,
    )


@pytest.mark.parametrize("sphere", [True, False])
def test_separable_window_search_is_the_whole_window_argmax(sphere):
    """Column-wise maximum + one value per column (step 5) = the first maximum of the whole
    window, read pixel by pixel (NumPy), ties included (few distinct values)."""
    plan = _plan(sphere)
    q = L._pool_factor(plan)
    h, w = plan.h // q, plan.w // q
    pooled = np.random.default_rng(1).integers(0, 6, (h, w)).astype(np.float32)
    widx, sx, sy = L._window_indices(plan)
    win = pooled.reshape(-1)[widx]
    ref = widx[np.arange(len(widx)), np.argmax(win, axis=1)]

    cols, _, _, rr = L._search_columns(plan)
    V, I = (
        np.asarray(a) for a in jax.jit(L._search_image, static_argnums=(1, 2))(pooled, rr, sphere)
    )
    row0 = (sy // q) * w
    vals = V.reshape(-1)[row0[:, None] + cols]
    bc = cols[np.arange(len(cols)), np.argmax(vals, axis=1)]
    by = sy // q + I.reshape(-1)[row0 + bc] - rr
    bx = bc.copy()
    if sphere:
        flip = (by < 0) | (by >= h)
        bx = np.where(flip, (bc + w // 2) % w, bc)
        by = np.where(by < 0, -by - 1, np.where(by >= h, 2 * h - 1 - by, by))
    else:
        by = np.clip(by, 0, h - 1)
    np.testing.assert_array_equal(by * w + bx, ref)
    np.testing.assert_array_equal(vals.max(axis=1), win.max(axis=1))


@pytest.mark.parametrize("history", [False, True])
@pytest.mark.parametrize("ny", [9, 31, 45])
def test_bit_packed_growth_matches_breadth_first_search(ny, history):
    """Grown masks and step counts = a breadth-first search over 8-connected pixels
    (scipy.ndimage binary propagation, one ring per step), with one and two packed words;
    step counter and stored step masks (``history``, a single map's form)."""
    rng = np.random.default_rng(ny)
    above = rng.random((3, ny, 23)) < 0.6
    seeds = np.zeros_like(above)
    seeds[0, ny // 2, 11] = seeds[1, 0, 0] = seeds[2, ny - 1, 22] = True
    seeds &= above
    grow = jax.jit(L._grow, static_argnums=(2, 3))
    fill, dist = (np.asarray(a) for a in grow(seeds, above, 10_000, history))
    for k in range(3):
        ref_fill, cur = seeds[k].copy(), seeds[k].copy()
        ref_dist = np.where(cur, 0, -1)
        step = 0
        while True:
            step += 1
            nxt = ndimage.binary_dilation(cur, np.ones((3, 3), bool)) & above[k]
            new = nxt & ~cur
            if not new.any():
                break
            ref_dist[new] = step
            cur = nxt
        ref_fill = cur
        np.testing.assert_array_equal(fill[k], ref_fill)
        np.testing.assert_array_equal(dist[k][ref_fill], ref_dist[ref_fill])


def _serpentine(ny: int = 9, nx: int = 23) -> tuple[np.ndarray, np.ndarray]:
    """``(above, seeds)``: every even row, joined by one connector per odd row at alternate
    ends (geodesic distances up to ~120 steps), grown from the top-left pixel."""
    above = np.zeros((ny, nx), bool)
    above[0::2] = True
    for i, y in enumerate(range(1, ny, 2)):
        above[y, nx - 1 if i % 2 == 0 else 0] = True
    seeds = np.zeros_like(above)
    seeds[0, 0] = True
    return above, seeds


def _bfs(seeds: np.ndarray, above: np.ndarray, limit: int) -> tuple[np.ndarray, np.ndarray]:
    """Breadth-first search (scipy binary dilation, one 8-connected ring per step) for at
    most ``limit`` rings: ``(reached, distance)``, distance -1 where not reached."""
    cur, ref = seeds.copy(), np.where(seeds, 0, -1)
    for step in range(1, limit + 1):
        new = ndimage.binary_dilation(cur, np.ones((3, 3), bool)) & above & ~cur
        if not new.any():
            break
        ref[new] = step
        cur |= new
    return cur, ref


@pytest.mark.parametrize("history", [False, True])
def test_bit_packed_growth_long_path_past_the_first_counter(history):
    """The serpentine's geodesic distances run past the 31 steps of the first, 5-plane
    counter (or of the stored masks, ``history``); against a breadth-first search."""
    above, seeds = _serpentine()
    fill, dist = (
        np.asarray(a)[0]
        for a in jax.jit(L._grow, static_argnums=(2, 3))(seeds[None], above[None], 10_000, history)
    )
    cur, ref = _bfs(seeds, above, 10_000)
    np.testing.assert_array_equal(cur, above)
    np.testing.assert_array_equal(fill, above)
    np.testing.assert_array_equal(dist[above], ref[above])
    assert ref.max() > 100


@pytest.mark.parametrize("history", [False, True])
@pytest.mark.parametrize("limit", [7, 20])
def test_bit_packed_growth_stops_at_the_step_limit(limit, history):
    """At most ``limit`` rings (fewer than the 31 stored masks / counter steps): the
    serpentine's fill and distances = a breadth-first search cut after ``limit`` rings."""
    above, seeds = _serpentine()
    grow = jax.jit(L._grow, static_argnums=(2, 3))
    fill, dist = (np.asarray(a)[0] for a in grow(seeds[None], above[None], limit, history))
    cur, ref = _bfs(seeds, above, limit)
    np.testing.assert_array_equal(fill, cur)
    np.testing.assert_array_equal(dist[cur], ref[cur])
    assert ref.max() == limit


def test_window_rows_wrap_across_the_seam():
    """Slices of window rows (inner rows and rows across the seam) = modular indexing."""
    rng = np.random.default_rng(3)
    img = rng.random((20, 64, 3)).astype(np.float32)
    r, n = 5, 11
    strip = np.concatenate([img[:, 64 - n :], img[:, :n]], axis=1)
    y = rng.integers(0, 20, (4, 7)).astype(np.int32)
    x0 = np.array([0, 1, 4, 5, 30, 58, 59, 63] * 4)[:28].reshape(4, 7).astype(np.int32)
    got = np.asarray(jax.jit(L._windows, static_argnums=4)(img, strip, y, x0, r))
    cols = (x0[..., None] + np.arange(-r, r + 1)) % 64
    np.testing.assert_array_equal(got, img[y[..., None], cols])


@pytest.mark.parametrize("n", [1, 2, 7, 786, 787])
def test_median_from_integer_sort(n):
    x = np.random.default_rng(n).integers(0, 50, n).astype(np.float32)  # ties
    assert float(L._median(jnp.asarray(x))) == np.median(x)


def test_median_signed_zero_inf_float64(x64):
    x = np.array([0.0, -0.0, 3.0, np.inf, 1.0, -0.0], np.float32)
    assert float(L._median(jnp.asarray(x))) == np.median(x) == 0.5
    y = np.random.default_rng(3).random(101) * 1e3
    assert L._median(jnp.asarray(y)).dtype == jnp.float64
    assert float(L._median(jnp.asarray(y))) == np.median(y)
