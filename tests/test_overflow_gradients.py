"""Finite in, finite out near the largest float, for outputs and image gradients (issue 16,
point 3): the vision colour effects, Budak 2005, the gamma operator and the light
detectors. Gradients are those of the sum of the finite outputs. 8×8 images; frames of one
function share one compile (vmap)."""

import jax
import jax.numpy as jnp
import numpy as np

import hdrjax.lights as hl
import hdrjax.operators as ho
import hdrjax.vision as hv
from hdrjax import luminance

from .operators.cases import natural

MAX32 = float(np.finfo(np.float32).max)
DIM = np.float32(2.0**-80)  # exact: a bright pixel times DIM is still far above 4 cd/m²


def _finite_sum(f):
    return lambda x: jnp.sum(jnp.where(jnp.isfinite(y := f(x)), y, 0.0))


def _lamp_frames():
    """(natural image with a 3e38 cd/m² lamp, the same with the lamp 2^80 times dimmer,
    uniform 1e38, uniform 1e38 · 2^-80)."""
    img = natural((8, 8))
    img[5, 7] = (3e38, 2e38, 1e38)
    dim = img.copy()
    dim[5, 7] *= DIM
    flat = np.full((8, 8, 3), 1e38, np.float32)
    return np.stack([img, dim, flat, flat * DIM])


def test_blue_shift_gradients_near_the_float_maximum():
    """Above 4 cd/m² the blue shift is homogeneous of degree 1, so its gradient does not
    change when a pixel is 2^80 times dimmer (NaN at the lamp and the uniform 1e38 image
    before: the backward pass carried the headroom's 2^64 through XYZ near 2^64)."""
    g = np.asarray(jax.vmap(jax.grad(_finite_sum(hv.blue_shift)))(_lamp_frames()))
    assert np.all(np.isfinite(g))
    np.testing.assert_allclose(g[0], g[1], rtol=1e-5)
    np.testing.assert_allclose(g[2], g[3], rtol=1e-5)


def test_colour_loss_and_scotopic_luminance_near_the_float_maximum():
    """Photopic pixels keep their colour (out = RGB): gradient 1 per channel at a 3e38 lamp
    and in an image at the float maximum (NaN before: c·x − c·V/2.26 overflowed). The
    lamp's scotopic luminance (beyond the float range) saturates at the float maximum (+Inf
    before); V is homogeneous of degree 1 elsewhere."""
    img = natural((8, 8)).astype(np.float64)
    top = (img / img.max() * MAX32).astype(np.float32)
    frames = np.stack([_lamp_frames()[0], np.minimum(top, MAX32)])
    g = np.asarray(jax.vmap(jax.grad(_finite_sum(hv.colour_loss)))(frames))
    bright = np.asarray(hv.mesopic_weight(luminance(frames))) == 1
    assert bright[0, 5, 7] and bright[1].sum() > 10
    np.testing.assert_array_equal(g[bright], 1.0)
    assert np.all(np.isfinite(g))
    both = np.stack([frames[0], frames[1], frames[1] * DIM])  # one compile each
    V = np.asarray(hv.scotopic_luminance(both))
    assert V[0, 5, 7] == MAX32
    want = V[2].astype(np.float64) / float(DIM)  # V/Y reaches 2.3: some saturate
    assert (want > MAX32).any() and (want < MAX32).sum() > 30
    np.testing.assert_allclose(V[1], np.minimum(want, MAX32), rtol=1e-5)
    gV = np.asarray(jax.vmap(jax.grad(lambda x: jnp.sum(hv.scotopic_luminance(x))))(both))
    assert np.all(np.isfinite(gV))
    ok = np.broadcast_to((want < MAX32)[..., None], gV[1].shape)  # saturated: gradient 0
    np.testing.assert_allclose(gV[1][ok], gV[2][ok], rtol=1e-5)
    np.testing.assert_array_equal(gV[1][~ok], 0.0)


def test_perceptual_reproduction_gradients_of_very_bright_images():
    """NaN gradients at every pixel before, from the image's mean chromaticity (its
    derivative formed mY², beyond float32 from 1e19 cd/m²) and from L/L_a overflowing in
    the brightness. These images clip to the display's white or primaries: the gradient
    is 0 wherever the output is clipped in all three channels."""
    img = natural((8, 8)).astype(np.float64)
    frames = np.stack([img / img.max() * (MAX32 / 400), np.full((8, 8, 3), 1e36)])
    frames = frames.astype(np.float32)
    g = np.asarray(jax.vmap(jax.grad(_finite_sum(hv.perceptual_reproduction)))(frames))
    out = np.asarray(jax.vmap(hv.perceptual_reproduction)(frames))
    clipped = np.all((out == 0) | (out == 1), axis=-1)
    assert clipped.sum() > 64
    np.testing.assert_array_equal(g[clipped], 0.0)
    assert np.all(np.isfinite(g))


def test_budak2005_readapt_of_a_lamp_near_the_float_maximum():
    """A 3e38 lamp over a dim background: its cone ratios overflowed (NaN coordinates, NaN
    display RGB and gradients); the re-adapted values now saturate below the float
    maximum."""
    frames = _lamp_frames()[:2]
    step = hv.Budak2005(adaptation=jnp.asarray(1e-3, jnp.float32))
    out = np.asarray(jax.vmap(step.readapt)(frames))
    assert np.all(np.isfinite(out))
    g = np.asarray(jax.vmap(jax.grad(_finite_sum(step)))(frames))
    assert np.all(np.isfinite(g))


def test_gamma_operator_near_the_float_maximum():
    """2^EV · RGB overflowed (+Inf, NaN gradients) although (2^EV RGB)^(1/2.2) is 5e17:
    values and derivatives match float64; with gamma 1 the result saturates at the float
    maximum, the other pixels are 2^EV · RGB."""
    img = natural((8, 8)).astype(np.float64)
    x = (img / img.max() * (MAX32 * 0.999)).astype(np.float32)
    x64 = x.astype(np.float64)
    op = ho.Gamma(gamma=2.2, EV=4.0)
    out = np.asarray(op(x))
    ref = (16 * x64) ** (1 / 2.2)
    assert (16 * x64 > MAX32).sum() > 5
    np.testing.assert_allclose(out, ref, rtol=1e-5)
    g = np.asarray(jax.grad(lambda y: jnp.sum(op(y)))(x))
    np.testing.assert_allclose(g, ref / (2.2 * x64), rtol=1e-4)
    lin = np.asarray(ho.Gamma(gamma=1.0, EV=4.0)(x))
    over = 16 * x64 > MAX32
    np.testing.assert_array_equal(lin[over], MAX32)
    np.testing.assert_allclose(lin[~over], x[~over] * 16, rtol=1e-5)  # exp(ln(2^EV x))


def test_median_cut_of_a_uniform_map_near_the_float_maximum():
    """The map's total energy 4π·1e38 exceeds float32: the last region's energy was +Inf
    and its share NaN. Shares are exact; energies are the same as for the map 2^80 times
    dimmer, times 2^80, where representable, and the float maximum where not."""
    flat = np.full((8, 16, 3), 1e38, np.float32)
    res = hl.median_cut(np.stack([flat, flat * DIM]), n_lights=4, width=16)
    share, energy = np.asarray(res.energy_share), np.asarray(res.energy)
    np.testing.assert_array_equal(share[0], share[1])
    np.testing.assert_allclose(share[0].sum(), 1.0, rtol=1e-6)
    want = energy[1].astype(np.float64) / float(DIM)
    np.testing.assert_array_equal(energy[0], np.where(want > MAX32, MAX32, want))
    big = (np.full((8, 16, 3), 3e38, np.float32),)
    e = np.asarray(hl.median_cut(big[0], n_lights=1, width=16).energy)
    assert e[0] == MAX32  # 4π·3e38: saturated


def test_detected_light_positions_near_the_float_maximum():
    """The light sums overflowed for pixels near the float maximum (a NaN light position);
    they now run on values times an exact power of two: the lights of the image scaled to
    the maximum are those of the image 2^100 times dimmer (positions, shares)."""
    img = natural((8, 16)).astype(np.float64)
    top = (img / img.max() * MAX32).astype(np.float32)
    frames = np.stack([top, top * np.float32(2.0**-100)])
    res = hl.detect_image(frames, width=16)  # its light sums are detect's (one compile)
    assert int(res.count[0]) > 0
    pix = np.asarray(res.pixel)
    assert np.all(np.isfinite(pix))
    np.testing.assert_array_equal(pix[0], pix[1])
    np.testing.assert_array_equal(np.asarray(res.energy_share)[0], np.asarray(res.energy_share)[1])
