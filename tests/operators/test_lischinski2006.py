"""lischinski2006 (Lischinski et al. 2006, automatic mode) against HDR Toolbox's
``LischinskiTMO`` (GNU Octave, its sparse system solved directly; the fixtures of
fixtures/hdrtoolbox/make_lischinski2006.py) and a float64 NumPy/SciPy model of the paper's
equations (zones, Reinhard targets, the weighted least-squares system solved by a sparse
factorisation).

Issue 21's parity criterion, per image: SSIM of the encoded luminance ≥ 0.97 and mean
absolute difference ≤ 0.02 (both outputs clipped to [0, 1], sRGB encoded; the SSIM of
tests/operators/test_durand2002.py). HDR Toolbox's outputs are display-linear, as ours.
Measured, float32 with the default ``tol = 1e-4`` (SSIM / mean / largest encoded
difference): rooitou_park 1.0000 / 3.8e-6 / 2.5e-5, venice_sunset 1.0000 / 2.5e-5 /
3.6e-5, CandleGlass 1.0000 / 2.4e-5 / 9.8e-5.
"""

import functools
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

import hdrjax
import hdrjax.tile as T
from hdrjax.operators._lischinski2006 import propagate

from ..conftest import RTOL32, enable_x64
from .test_durand2002 import assert_parity, encoded_luminance

FIXTURES = Path(__file__).parent / "fixtures" / "hdrtoolbox" / "lischinski2006.npz"
SSIM_TIGHT, MAD_TIGHT, MAX_TIGHT = 0.9999, 1e-4, 5e-4
"""Measured: SSIM 1.0000, mean ≤ 2.5e-5, largest encoded difference 9.8e-5."""
CONVERGED_MAX = 2e-4
"""Default ``tol`` (1e-4) against the converged solve (float64, ``tol = 1e-12``): largest
encoded difference (measured 3.4e-5 here, 7.3e-5 at 256 × 512; benchmarks/bench_accuracy.py)."""
MODEL_MAX = 2e-3
"""float64 against the NumPy model with sorted zone quantiles: the histogram's quantiles
(≤ 0.1 % of a zone's representative) move a zone's target by at most 0.0015 stops."""
SOLVE_RTOL = 1e-9
"""The conjugate-gradient solve (``tol = 1e-13``) against SciPy's sparse factorisation."""
REC709 = np.array(hdrjax.REC709_WEIGHTS)
NAMES = ["rooitou_park", "venice_sunset", "CandleGlass"]


@functools.cache
def toolbox() -> dict[str, np.ndarray]:
    with np.load(FIXTURES) as d:
        return {k: d[k] for k in d.files}


apply = eqx.filter_jit(lambda o, x: o(x))


@functools.cache
def outputs() -> np.ndarray:
    return np.asarray(apply(hdrjax.make_operator("lischinski2006"), toolbox()["input"]))


@functools.cache
def converged() -> np.ndarray:
    """float64, ``tol = 1e-12``: the converged solution."""
    with enable_x64():
        op = hdrjax.make_operator("lischinski2006", tol=1e-12, max_iterations=20000)
        x = toolbox()["input"].astype(np.float64)
        return np.asarray(apply(op, x))


def wls_matrix(ell, smoothness, alpha=1.0, epsilon=1e-4):
    """``I + smoothness · L_h`` (module docstring, step 3) as a SciPy sparse matrix."""
    h, w = ell.shape
    idx = np.arange(h * w).reshape(h, w)
    rows, cols, vals = [], [], []
    for a, b, d in (
        (idx[:, :-1], idx[:, 1:], ell[:, 1:] - ell[:, :-1]),
        (idx[:-1], idx[1:], ell[1:] - ell[:-1]),
    ):
        wt = smoothness / (np.abs(d) ** alpha + epsilon)
        rows += [a.ravel(), b.ravel()]
        cols += [b.ravel(), a.ravel()]
        vals += [-wt.ravel(), -wt.ravel()]
    off = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(h * w,) * 2
    )
    diag = 1.0 - np.asarray(off.sum(axis=1)).ravel()
    return off + sp.diags(diag)


def lischinski_reference(rgb, key, offset=1e-4, q=0.75, lam=0.4, weight=0.07):
    """The steps of the module docstring in float64, zone quantiles by sorting (HDR
    Toolbox's ranks), the system by a sparse factorisation; ``key`` given."""
    L = rgb @ REC709
    lbar = np.exp(np.mean(np.log(L + 1e-6)))
    lo = np.log2(L.min() + offset)
    g = np.zeros_like(L)
    with np.errstate(divide="ignore"):
        z = np.floor(np.log2(L) - lo) + 1
    for k in range(1, int(np.nanmax(z)) + 1):
        sel = z == k
        if sel.any():
            v = np.sort(L[sel])
            R = v[max(int(np.floor(q * v.size + 0.5)), 1) - 1]
            Rs = key * R / lbar
            g[sel] = np.log2(Rs / (1 + Rs) / R)
    ell = np.log2(L + offset)
    f = spsolve(wls_matrix(ell, lam / weight).tocsc(), g.ravel()).reshape(L.shape)
    return rgb * np.exp2(f)[..., None]


@pytest.mark.parametrize("i", range(3), ids=NAMES)
def test_matches_hdrtoolbox(i):
    assert_parity(outputs()[i], toolbox()["output"][i], SSIM_TIGHT, MAD_TIGHT, MAX_TIGHT)


def test_default_tolerance_is_within_the_criterion_of_the_converged_solve():
    """The accuracy of the default stopping rule (``tol = 1e-4``): float32 against the
    float64 solve converged to 1e-12, after clipping and sRGB encoding."""
    for got, ref in zip(outputs(), converged(), strict=True):
        a, b = encoded_luminance(got.astype(np.float64)), encoded_luminance(ref)
        assert np.abs(a - b).max() <= CONVERGED_MAX


def test_follows_the_paper_in_float64():
    """The converged float64 result against the NumPy model (sorted zone quantiles, a sparse
    direct solve) with the key HDR Toolbox's ``ReinhardAlpha`` gave (stored by the fixture
    script; the operator measures its own from histogram percentiles, 2e-4 apart)."""
    for x, key, got in zip(toolbox()["input"], toolbox()["key"], converged(), strict=True):
        ref = lischinski_reference(x.astype(np.float64), key)
        a, b = encoded_luminance(got), encoded_luminance(ref)
        assert np.abs(a - b).max() <= MODEL_MAX


def test_solve_equals_a_sparse_factorisation():
    """:func:`propagate` (conjugate gradients, matrix-free) against SciPy's ``spsolve`` of
    the same system, with non-default ``α``, ``λ / w`` and ``ε``."""
    rng = np.random.default_rng(1)
    ell = np.log2(toolbox()["input"][1] @ REC709)[:20, :30]
    g = rng.uniform(-6, 1, ell.shape)
    with enable_x64():
        f = propagate(
            jnp.asarray(g),
            jnp.asarray(ell),
            alpha=jnp.asarray(1.4),
            smoothness=jnp.asarray(3.0),
            epsilon=jnp.asarray(1e-3),
            tolerance=1e-13,
            max_iterations=5000,
        )
    ref = spsolve(wls_matrix(ell, 3.0, 1.4, 1e-3).tocsc(), g.ravel()).reshape(g.shape)
    np.testing.assert_allclose(np.asarray(f), ref, rtol=SOLVE_RTOL, atol=1e-10)


def test_whole_image_only():
    """The solve couples every pixel: an infinite halo, which hdrjax.tile refuses."""
    op = hdrjax.make_operator("lischinski2006")
    assert op.halo((48, 64, 3)) == (float("inf"), float("inf"))
    with pytest.raises(ValueError, match="whole image"):
        T.apply(T.Tonemap(op), toolbox()["input"][0], tile=16)


def test_dim_image_keeps_its_values():
    """Below HDR Toolbox's offset (``Y < 10⁻⁴`` image units) no pixel is in a zone: every
    target is 0 stops, so the exposure is 1 (the operator is not scale invariant)."""
    x = toolbox()["input"] * np.float32(1e-8 / toolbox()["input"].max())
    got = np.asarray(apply(hdrjax.make_operator("lischinski2006"), x))  # outputs()' program
    np.testing.assert_allclose(got, x, rtol=RTOL32)
