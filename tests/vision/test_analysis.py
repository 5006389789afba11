"""The scene statistics of ``analyze`` against a float64 NumPy transcription of their
definitions (pcond's foveal image, pixel subsample, mean brightness, 5th percentile and
range), on real images and synthetic scenes, through both the unmasked fast program and the
masked one; and the two building blocks: block reductions and the exact percentile."""

import math

import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.vision as hv
from hdrjax.io import read
from hdrjax.vision._fovea import block_reduce
from hdrjax.vision._report import SPARSE_SAMPLES, subsample_percentile

from ..conftest import DATA, RTOL32

W709 = np.array([0.2126, 0.7152, 0.0722])
LMIN, LMAX = 1e-7, 1e5  # pcond's visible range (formulas.md §3)


def reference(rgb: np.ndarray, block: tuple[int, int]) -> dict:
    """The report's statistics by their definitions, float64 NumPy, loops over blocks."""
    Y = np.asarray(rgb, np.float64) @ W709
    H, W = Y.shape
    by, bx = block
    hb, wb = -(-H // by), -(-W // bx)
    fov = np.zeros((hb, wb))
    cnt = np.zeros((hb, wb))
    for i in range(hb):
        for j in range(wb):
            b = Y[i * by : (i + 1) * by, j * bx : (j + 1) * bx]
            f = b[np.isfinite(b)]
            cnt[i, j] = f.size
            fov[i, j] = f.mean() if f.size else 0.0
    sy, sx = max(1, by // 4), max(1, bx // 4)
    sub = Y[sy // 2 :: sy, sx // 2 :: sx]
    sub = sub[np.isfinite(sub) & (sub > LMIN) & (sub < LMAX)]
    fok = fov[(cnt > 0) & (fov > LMIN) & (fov < LMAX)]
    means = [np.log(g).mean() for g in (fok, sub) if g.size]
    inr = Y[np.isfinite(Y) & (Y > LMIN) & (Y < LMAX)]
    return {
        "fovea": fov,
        "adaptation": math.exp(np.mean(means)) if means else LMIN,
        "p05": float(np.percentile(sub, 5)) if sub.size else math.nan,
        "lo": min(inr.min(initial=np.inf), fok.min(initial=np.inf)),
        "hi": max(inr.max(initial=-np.inf), fok.max(initial=-np.inf)),
        "n_nonfinite": int((~np.isfinite(Y)).sum()),
    }


def check_report(rep: hv.SceneReport, rgb: np.ndarray) -> None:
    ref = reference(rgb, rep.view.fovea_block)
    # float32 luminance against float64: a few float32 roundings per value
    np.testing.assert_allclose(rep.adaptation_foveal, ref["fovea"], rtol=RTOL32, atol=1e-30)
    assert rep.adaptation_global == pytest.approx(ref["adaptation"], rel=RTOL32)
    assert rep.luminance_p05 == pytest.approx(ref["p05"], rel=RTOL32)
    assert rep.p05_rel_error == 0.0
    assert rep.luminance_min == pytest.approx(ref["lo"], rel=RTOL32)
    assert rep.luminance_max == pytest.approx(ref["hi"], rel=RTOL32)
    assert rep.n_nonfinite == ref["n_nonfinite"]
    # the verdicts are those of the reference numbers (pcond's thresholds, formulas.md §3)
    assert ("colour_loss" in rep.selected) == (ref["p05"] < 5.62)
    assert ("blue_shift" in rep.selected) == (ref["p05"] < 10**0.6)
    assert ("glare" in rep.selected) == (math.log(ref["hi"] / ref["lo"]) >= 4.5)
    assert ("contrast" in rep.selected) == (ref["adaptation"] < 10**1.9)


REAL = ["cornell_box.exr", "Carrots.exr", "MtTamNorth.exr", "venice_sunset_1k.hdr"]


@pytest.mark.parametrize("name", REAL)
@pytest.mark.parametrize("scale", [0.05, 300.0])
def test_real_images_match_the_float64_definitions(name, scale):
    rgb = np.asarray(read(DATA / name).rgb(), np.float32)[::2, ::2] * np.float32(scale)
    check_report(hv.analyze(rgb, 60.0, scale=1.0), rgb)


def test_real_panorama_big_enough_for_the_sparse_percentile():
    # 1024×512 equiangular: stride-1 subsample of 512k pixels (> 4 × SPARSE_SAMPLES), so
    # the percentile goes through the sparse grid and the band
    rgb = np.asarray(read(DATA / "rooitou_park_1k.hdr").rgb(), np.float32) * np.float32(40.0)
    assert rgb.shape[0] * rgb.shape[1] > 4 * SPARSE_SAMPLES
    view = hv.View(hfov=360.0, vfov=180.0, projection="equiangular")
    check_report(hv.analyze(rgb, view, scale=1.0), rgb)


@pytest.mark.parametrize(
    "case", ["fast", "zeros", "nan_inf", "negative", "over_range", "ragged", "big_blocks"]
)
def test_synthetic_scenes_fast_and_masked_programs(case):
    rng = np.random.default_rng(3)
    h, w, fov = 90, 140, 40.0
    if case == "ragged":
        h, w = 97, 131  # partial blocks at the bottom and the right
    rgb = (10 ** rng.uniform(-3, 3, (h, w, 1)) * [1.0, 0.9, 0.8]).astype(np.float32)
    if case == "zeros":
        rgb[::7] = 0.0
    elif case == "nan_inf":
        rgb[3, 4] = np.nan
        rgb[50, 60, 1] = np.inf
        rgb[20, 21] = -np.inf
    elif case == "negative":
        rgb[::5, ::3] *= -1.0
    elif case == "over_range":
        rgb[10:12, 10:12] = 1e6  # beyond pcond's 1e5 cd/m²
    elif case == "big_blocks":
        fov = 1.0  # 1° over 140 px: 140-pixel blocks (reshape reduction)
    rep = hv.analyze(rgb, fov, scale=1.0)
    if case == "big_blocks":
        assert max(rep.view.fovea_block) > 64
    check_report(rep, rgb)


# -- building blocks ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "shape,block", [((7, 10), (3, 4)), ((6, 8), (3, 4)), ((130, 70), (65, 66))]
)
def test_block_reduce_against_numpy_loops(shape, block):
    x = np.random.default_rng(0).normal(size=shape).astype(np.float32)
    by, bx = block
    hb, wb = -(-shape[0] // by), -(-shape[1] // bx)
    blocks = [
        [x[i * by : (i + 1) * by, j * bx : (j + 1) * bx] for j in range(wb)] for i in range(hb)
    ]
    for op, fill, red in (
        (jnp.add, 0.0, np.sum),
        (jnp.minimum, np.inf, np.min),
        (jnp.maximum, -np.inf, np.max),
    ):
        got = np.asarray(block_reduce(jnp.asarray(x), by, bx, op, fill))
        want = np.array([[red(b) for b in row] for row in blocks])
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5)


def _values(kind: str, n: int, rng) -> np.ndarray:
    if kind == "uniform":
        return rng.uniform(1.0, 2.0, n)
    if kind == "log":
        return 10 ** rng.uniform(-6, 4.9, n)
    if kind == "ties":
        return rng.integers(1, 4, n).astype(np.float64)
    x = 10 ** rng.uniform(-3, 3, n)  # "dirty": values outside the range and non-finite
    x[rng.random(n) < 0.1] = 0.0
    x[rng.random(n) < 0.05] = -1.0
    x[rng.random(n) < 0.01] = np.nan
    x[rng.random(n) < 0.01] = np.inf
    x[rng.random(n) < 0.01] = -np.inf
    x[rng.random(n) < 0.01] = 1e6
    return x


@pytest.mark.parametrize("kind", ["uniform", "log", "ties", "dirty"])
@pytest.mark.parametrize("n", [1, 37, 5000, 600_000])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_subsample_percentile_is_numpy_percentile(kind, n, dtype):
    rng = np.random.default_rng(n)
    x = _values(kind, n, rng).astype(dtype)
    sub = x.reshape(-1, 1000) if n % 1000 == 0 else x
    ok = np.isfinite(sub) & (sub > LMIN) & (sub < LMAX)
    n_low = int(np.count_nonzero(sub <= LMIN))
    for q in (5.0, 0.0, 50.0, 100.0):
        got = subsample_percentile(sub, q, int(ok.sum()), n_low)
        want = np.percentile(sub[ok].astype(np.float64), q) if ok.any() else math.nan
        assert got == pytest.approx(want, rel=1e-12, nan_ok=True)


def _partition_sizes(monkeypatch) -> list[int]:
    import hdrjax.vision._report as report

    sizes: list[int] = []
    partition = np.partition

    def spy(a, k, *args, **kwargs):
        sizes.append(a.size)
        return partition(a, k, *args, **kwargs)

    monkeypatch.setattr(report.np, "partition", spy)
    return sizes


def test_subsample_percentile_partitions_only_a_narrow_band(monkeypatch):
    sizes = _partition_sizes(monkeypatch)
    sub = np.random.default_rng(2).lognormal(0.0, 2.0, (1000, 1000)).astype(np.float32)
    got = subsample_percentile(sub, 5.0, sub.size, 0)
    assert got == pytest.approx(np.percentile(sub.astype(np.float64), 5.0), rel=1e-12)
    assert sizes and max(sizes) < 0.05 * sub.size


def test_subsample_percentile_when_the_grid_misleads(monkeypatch):
    sizes = _partition_sizes(monkeypatch)
    # the sparse grid (every step-th pixel) sees only bright pixels: its interval misses
    # the 5th percentile, the counts notice and every pixel is partitioned instead
    rng = np.random.default_rng(1)
    sub = rng.uniform(0.01, 0.02, (1000, 1000))
    step = int(math.sqrt(sub.size / SPARSE_SAMPLES))
    sub.reshape(-1)[rng.random(sub.size) < 0.9] = 500.0  # 10 % dark pixels
    sub[step // 2 :: step, step // 2 :: step] = 1000.0  # none of them on the grid
    got = subsample_percentile(sub, 5.0, sub.size, 0)
    assert got == pytest.approx(np.percentile(sub, 5.0), rel=1e-12)
    assert sizes == [sub.size]  # the fallback: every pixel


def test_subsample_percentile_of_a_flat_image_partitions_nothing(monkeypatch):
    sizes = _partition_sizes(monkeypatch)
    sub = np.full((700, 1000), 0.05, np.float32)
    sub[:10] = 0.01  # 1.4 % darker: the 5th percentile is still the flat value
    got = subsample_percentile(sub, 5.0, sub.size, 0)
    assert got == np.percentile(sub.astype(np.float64), 5.0) == np.float32(0.05)
    assert sizes == []
