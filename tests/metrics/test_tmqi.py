"""tmqi (Yeganeh & Wang 2013) against HDR Toolbox's ``TMQI.m`` under GNU Octave, and the
float64 NumPy/SciPy model of the authors' code in ``tmqi_numpy.py``.

Fixtures: fixtures/tmqi.npz, written by fixtures/make_tmqi.py (its docstring: the commands,
the Toolbox commit, the Octave and package versions): three real images (66 × 110) each
tone-mapped by reinhard2002, drago2003 and linear, sRGB-encoded and quantised to 8 bits.

Issue 22's parity criterion: |ΔQ|, |ΔS|, |ΔN| ≤ 1e-3 (:data:`CRITERION`). Measured: float64
(x64) 4.7e-13 at most (S), float32 5e-7 at most (N).
"""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.metrics as hm

from ..conftest import enable_x64
from .tmqi_numpy import tmqi as tmqi_numpy

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "tmqi.npz"
CRITERION = 1e-3
TIGHT64 = 1e-9
"""float64 against Octave: the same arithmetic, to rounding (measured 4.7e-13)."""
TIGHT32 = 5e-6
"""float32 against Octave (measured 5.0e-7: 10 times that)."""


def _fixture():
    f = np.load(FIXTURES)
    hdr = np.broadcast_to(f["hdr"][:, None], f["ldr"].shape)
    return hdr, f["ldr"] / 255.0, {k: f[k] for k in ("Q", "S", "N")}


@pytest.mark.parametrize("x64,tol", [(True, TIGHT64), (False, TIGHT32)])
def test_matches_hdr_toolbox(x64, tol):
    hdr, ldr, ref = _fixture()
    dt = np.float64 if x64 else np.float32
    with enable_x64(x64):
        got = hm.tmqi(hdr.astype(dt), ldr.astype(dt))  # (3 images, 3 operators): one call
        got = {"Q": got.q, "S": got.s, "N": got.n}
        for k in ref:
            err = np.abs(np.asarray(got[k], np.float64) - ref[k]).max()
            assert err <= CRITERION, f"{k}: {err}"
            assert err <= tol, f"{k}: {err}"


def test_numpy_model_matches_hdr_toolbox():
    """The NumPy model (the benchmark's peer) is the reference code: to rounding."""
    hdr, ldr, ref = _fixture()
    for i, k in np.ndindex(ref["Q"].shape):
        q, s, n = tmqi_numpy(hdr[i, k], ldr[i, k] * 255)
        np.testing.assert_allclose([q, s, n], [ref[c][i, k] for c in "QSN"], rtol=0, atol=1e-12)


def test_odd_sizes_and_partial_blocks_match_the_numpy_model():
    """Sizes that are not multiples of 11 (MATLAB's partial blocks) or of 2 (the 2×2
    averaging repeats the last row and column)."""
    rng = np.random.default_rng(3)
    hdr = rng.lognormal(0.0, 2.0, (37, 53, 3))
    ldr = np.clip(hdr / (1 + hdr), 0, 1) ** (1 / 2.2)
    with enable_x64():
        got = hm.tmqi(hdr, ldr)
    np.testing.assert_allclose(
        [float(got.q), float(got.s), float(got.n)], tmqi_numpy(hdr, ldr * 255), atol=1e-10
    )


def test_batch_equals_single_and_hdr_scale_does_not_matter():
    hdr, ldr, _ = _fixture()
    batch = hm.tmqi(hdr[0], ldr[0])
    one = hm.tmqi(hdr[0, 1], ldr[0, 1])
    scaled = hm.tmqi(hdr[0, 1] * 179.0, ldr[0, 1])
    for a, b, c in zip(batch, one, scaled, strict=True):
        assert a.shape == (3,)
        np.testing.assert_allclose(a[1], b, rtol=1e-6)
        np.testing.assert_allclose(b, c, rtol=1e-4)


def test_gradient_matches_finite_differences():
    """d Q / d(LDR) against central differences along a random direction (float64)."""
    hdr, ldr, _ = _fixture()
    h, l0 = hdr[1, 1, :33, :44], ldr[1, 1, :33, :44]
    rng = np.random.default_rng(0)
    d = rng.normal(size=l0.shape)
    with enable_x64():
        f = jax.jit(lambda v: hm.tmqi(jnp.asarray(h, jnp.float64), v).q)
        g = jax.grad(f)(jnp.asarray(l0, jnp.float64))
        eps = 1e-6
        fd = (f(l0 + eps * d) - f(l0 - eps * d)) / (2 * eps)
        np.testing.assert_allclose(float(jnp.sum(g * d)), float(fd), rtol=1e-5)


def test_degenerate_images_have_finite_values_and_gradients():
    """Identical, black and NaN-holding pairs: finite Q, S, N in [0, 1] and gradients."""
    rng = np.random.default_rng(1)
    img = rng.random((22, 33, 3)).astype(np.float32)
    nan = img.copy()
    nan[3, 4, 1] = np.nan
    pairs = {
        "identical": (img, img),
        "black": (np.zeros_like(img), np.zeros_like(img)),
        "nan": (nan, nan),
        "constant": (np.full_like(img, 5.0), np.full_like(img, 0.5)),
    }
    h, l = (np.stack(v) for v in zip(*pairs.values(), strict=True))
    out = hm.tmqi(h, l)
    for v in out:
        assert np.all(np.isfinite(v) & (v >= 0) & (v <= 1)), out
    gh, gl = jax.jit(jax.grad(lambda a, b: jnp.sum(hm.tmqi(a, b).q), argnums=(0, 1)))(h, l)
    for k, name in enumerate(pairs):
        assert np.all(np.isfinite(gh[k])) and np.all(np.isfinite(gl[k])), name


def test_naturalness_model():
    """N is 1 at the models' modes: mean 115.94 and block standard deviation at the beta
    mode × 64.29; an image of one grey level has no contrast, N = 0."""
    mode = (4.4 - 1) / (4.4 + 10.1 - 2) * 64.29
    # alternating columns ±a around the mean: every 11×11 block's sample std is a·sqrt(k)
    cols = np.where(np.arange(66) % 2 == 0, 1.0, -1.0)
    a = mode / np.std(np.tile(cols[:11], (11, 1)), ddof=1)
    y = np.tile(115.94 + a * cols, (66, 1))[:66, :66] / 255.0
    # an even width of 66 = 6 blocks of 11: odd blocks start on −a; the std is the same
    with enable_x64():
        n = hm.tmqi(np.ones((66, 66, 3)), np.repeat(y[..., None], 3, -1)).n
        assert abs(float(n) - 1.0) < 1e-3
        flat = hm.tmqi(np.ones((22, 22, 3)), np.full((22, 22, 3), 0.5)).n
        assert float(flat) == 0.0


def test_shape_errors_name_the_argument():
    with pytest.raises(ValueError, match="^ldr: expected the shape of hdr"):
        hm.tmqi(np.ones((11, 11, 3)), np.ones((11, 12, 3)))
    with pytest.raises(ValueError, match="^hdr: expected shape"):
        hm.tmqi(np.ones((11, 11)), np.ones((11, 11)))
