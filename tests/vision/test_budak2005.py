"""Seed 002's perceptual colour-contrast reproduction (with its documented stand-ins)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.vision as hv
from hdrjax._photometry import rgb_to_xyz, rgb_to_xyz_matrix
from hdrjax.operators._budak2005 import HPE

from ..conftest import RTOL32, RTOL64
from ._reference import np_tvi


def colourful(h=8, w=12, level=1.0, seed=0):
    rng = np.random.default_rng(seed)
    return level * rng.uniform(0.05, 1.0, (h, w, 3))


@pytest.mark.usefixtures("x64")
def test_space_round_trip_at_the_same_adaptation():
    space = hv.ConeOpponentSpace()
    rgb = jnp.asarray(colourful())
    xyz = rgb_to_xyz(rgb)
    bg = tuple(jnp.asarray(v) for v in (0.9, 1.0, 1.1))
    back = jax.jit(lambda xyz: space.inverse(space.forward(xyz, bg), bg))(xyz)
    for a, b in zip(back, xyz, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-9)


@pytest.mark.usefixtures("x64")
def test_coordinates_are_the_documented_formulas():
    rgb = colourful(3, 4, 2.0)
    X, Y, Z = np.moveaxis(rgb @ rgb_to_xyz_matrix().T, -1, 0)
    bg = np.array([1.9, 2.0, 2.2])
    M = np.array(HPE)
    Lc, Sc = (M @ np.stack([X, Y, Z]).reshape(3, -1))[[0, 2]].reshape(2, *X.shape)
    Lb, Sb = (M @ bg)[[0, 2]]

    def f(t):
        d = 6 / 29
        return np.where(t > d**3, np.cbrt(t), t / (3 * d * d) + 4 / 29)

    B = 2.0 / np_tvi(2.0) * np.log(Y / np_tvi(2.0))
    c = (2.0 - 5.62e-3) / (5.62 - 5.62e-3)  # pcond's mesopic weight of the background
    a = 500 * c * (f(Lc / Lb) / f(Y / 2.0) - 1)
    b = 200 * c * (1 - f(Sc / Sb) / f(Y / 2.0))
    got = np.asarray(
        hv.ConeOpponentSpace().forward(
            tuple(jnp.asarray(v) for v in (X, Y, Z)), tuple(jnp.asarray(v) for v in bg)
        )
    )
    np.testing.assert_allclose(got, np.stack([B, a, b], -1), rtol=RTOL64)


@pytest.mark.usefixtures("x64")
def test_grey_follows_the_fechner_power_law_and_stays_grey():
    # a grey image (background chromaticity) dimmer than the display: brightness above
    # threshold kept, luminance maps as ΔL_d (L/ΔL_w)^(k_d/k_w)
    L = np.array([0.01, 0.05, 0.2, 1.0])[None, :, None] * np.ones((1, 1, 3))
    La, Ldmax = 0.05, 100.0
    step = hv.Budak2005(display_max=Ldmax, adaptation=jnp.asarray(La))
    out = np.asarray(step.readapt(L))
    Lda = Ldmax / 2
    k_w, k_d = np_tvi(La) / La, np_tvi(Lda) / Lda
    expect = np_tvi(Lda) * (L[..., 1] / np_tvi(La)) ** (k_d / k_w)
    np.testing.assert_allclose(out @ np.array([0.2126, 0.7152, 0.0722]), expect, rtol=1e-9)
    np.testing.assert_allclose(out, out[..., :1].repeat(3, -1), rtol=1e-9)
    assert k_d / k_w < 0.2  # a night scene is strongly compressed (few JNDs)
    assert expect.max() < 0.06 * Ldmax  # and dim: its adaptation level below ΔL_d


def test_night_is_compressed_day_is_not_and_output_is_display_range():
    night = colourful(16, 16, 0.05, seed=1).astype(np.float32)
    day = colourful(16, 16, 500.0, seed=1).astype(np.float32)
    n = np.asarray(hv.perceptual_reproduction(night))
    d = np.asarray(hv.perceptual_reproduction(day))
    for out in (n, d):
        assert out.dtype == np.float32 and (out >= 0).all() and (out <= 1).all()

    def spread(x):
        return np.log(x.mean(-1).max() / x.mean(-1).min())

    assert spread(n) < spread(d)


def test_custom_space_is_pluggable_and_transforms_work():
    class Identity(hv.AbstractContrastSpace):
        def forward(self, xyz, background):
            return jnp.stack([c / background[1] for c in xyz], -1)

        def inverse(self, coords, background):
            return tuple(coords[..., i] * background[1] for i in range(3))

    rgb = jnp.asarray(colourful(6, 7, 2.0).astype(np.float32))
    lin = hv.Budak2005(space=Identity(), adaptation=jnp.asarray(2.0), gamma=1.0)
    # identity contrasts: the image is scaled from its adaptation to half the display max
    np.testing.assert_allclose(lin.readapt(rgb), rgb * 25.0, rtol=RTOL32)
    step = hv.Budak2005()
    bad = rgb.at[1, 1, 0].set(jnp.nan)
    batch = np.asarray(jax.vmap(step)(jnp.stack([bad, 2 * rgb])))
    out = batch[0]
    assert np.isfinite(batch).all() and out[1, 1, 0] == 0.0  # display encoding: NaN → 0
    g = jax.grad(lambda x: jnp.sum(step(x)))(bad)
    assert np.isfinite(np.asarray(g)).all()
    with pytest.raises(ValueError, match="gamma"):
        hv.Budak2005(gamma=0.0)
