"""Finite in, finite out near the largest float (issue 16, point 3): values whose sums,
FFTs or powers overflow float32 although the results are representable, and dim images whose
gradients overflowed. 8×8 and 16×16 images; each function compiled once or twice."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
import hdrjax.filters as hf

from .conftest import RTOL32
from .operators.cases import natural

BIG = 3e38  # float32's maximum is 3.4e38
MAX32 = float(np.finfo(np.float32).max)


def _one_bright(shape=(16, 16), at=(5, 7)):
    img = natural(shape)
    img[at] = BIG
    return img


def test_mean_filter_of_values_near_the_float_maximum():
    """A k×k sum of values near the maximum overflows; the mean does not (it was +Inf)."""
    img = np.stack([np.full((8, 8, 3), 1e38), np.full((8, 8, 3), MAX32)]).astype(np.float32)
    for k, rows in ((3, None), (7, 2)):  # the fused pass and the strip schedule
        out = np.asarray(hf.mean_filter(img, k, strip_rows=rows))
        np.testing.assert_allclose(out, img, rtol=RTOL32, err_msg=f"size {k}")


def test_reinhard2002_local_with_one_pixel_near_the_float_maximum():
    """The lamp's FFT sums overflowed and turned its neighbourhood NaN. Its display
    luminance does not depend on how bright it is (it dominates its surround): the same
    as for a lamp 2^28 times dimmer, where nothing overflows."""
    img = _one_bright()
    dim = img.copy()
    dim[5, 7] = BIG * 2.0**-28
    out = np.asarray(hdrjax.tonemap(np.stack([img, dim]), "reinhard2002_local"))
    assert np.all(np.isfinite(out))
    lamp = np.asarray(hdrjax.luminance(out[:, 5, 7]))
    np.testing.assert_allclose(lamp[0], lamp[1], rtol=RTOL32)
    auto = np.asarray(hdrjax.tonemap(img, "reinhard2002_auto"))  # > 11 zones: local
    np.testing.assert_allclose(auto, out[0], rtol=RTOL32, atol=1e-7)


def test_desaturate_highlights_near_the_float_maximum():
    """The channel sum overflowed (NaN pixel); the brightest pixel becomes grey (its mean)."""
    img = _one_bright()
    img[5, 7] = (BIG, BIG / 2, BIG / 4)
    out = np.asarray(hdrjax.desaturate_highlights(img))
    assert np.all(np.isfinite(out))
    mean = (BIG / 3) * (1 + 0.5 + 0.25)
    np.testing.assert_allclose(out[5, 7], [mean] * 3, rtol=RTOL32)


def test_desaturate_highlights_gradients_are_scale_invariant():
    """``d(x) = d(kx) / k``: the gradient of a weighted sum is the same for an image and
    the same image × 2^-120 (its 1 / span² overflowed: NaN gradients)."""
    img = natural((8, 8))
    w = jnp.linspace(1.0, 2.0, img.size).reshape(img.shape)

    def loss(x, k):
        return jnp.sum(w * hdrjax.desaturate_highlights(x * k)) / k

    grad = jax.jit(jax.grad(loss))
    g1 = np.asarray(grad(img, 1.0))
    gk = np.asarray(grad(img, 2.0**-120))
    np.testing.assert_allclose(gk, g1, rtol=RTOL32, atol=1e-6)


def test_tumblin_power_saturates_below_the_float_maximum():
    """With ``L_wa > L_da`` the exponent γ_w/γ_d exceeds 1 and ``T(L)`` left the float range
    for a 3e38 lamp (+Inf in tumblin1999, NaN in tumblin_reinhard); it saturates: finite,
    still the brightest pixel, and every other pixel exactly as before."""
    img = natural((8, 8)) * np.float32(1e3)
    lamp = img.copy()
    lamp[5, 7] = BIG
    batch = np.stack([img, lamp])
    out = np.asarray(hdrjax.tonemap(batch, "tumblin1999", L_wa=1e3))
    assert np.all(np.isfinite(out))
    np.testing.assert_array_equal(
        np.delete(out[1].reshape(64, 3), 5 * 8 + 7, 0),
        np.delete(out[0].reshape(64, 3), 5 * 8 + 7, 0),
    )
    L = np.asarray(hdrjax.luminance(out[1]))
    assert L[5, 7] == L.max() and L[5, 7] > 1e30
    assert np.all(np.isfinite(np.asarray(hdrjax.tonemap(lamp, "tumblin_reinhard"))))


@pytest.mark.parametrize("name", ["tumblin1999", "tumblin_reinhard"])
def test_tumblin_with_a_dim_display_adaptation(name):
    """A display adaptation below 1 cd/m² makes ``m L_da`` small, and ``m`` itself huge near
    the denominator's pole (``1.855 + 0.4 ln L_da = 0`` at 0.0097 cd/m²): a 3e38 lamp gave
    +Inf at ``L_da = 1`` and every pixel NaN at ``L_da = 0.01``. Now the power law is one
    exponential in logarithms, saturated below the float maximum: finite outputs, finite
    gradients with respect to ``L_da`` (for a lamp within ``cases.GRAD_SCALES``), and a
    value at or below the pole is refused naming ``L_da``."""
    lamp = natural((8, 8))
    lamp[5, 7] = BIG
    for L_da in (1.0, 0.1, 0.02):
        out = np.asarray(hdrjax.tonemap(lamp, name, L_da=L_da, L_wa=1e-3))
        assert np.all(np.isfinite(out)), (name, L_da)
    lamp[5, 7] = 1e10
    g = jax.grad(lambda v: jnp.sum(hdrjax.make_operator(name, L_da=v, L_wa=1e-3)(lamp)))
    for L_da in (1.0, 0.02):
        assert np.isfinite(float(g(jnp.float32(L_da)))), (name, L_da)
    with pytest.raises(ValueError, match=r"^L_da: expected a display adaptation above 0.00968"):
        hdrjax.make_operator(name, L_da=0.005)
    with pytest.raises(ValueError, match=r"^L_da: .* above 2.3e-05"):
        hdrjax.make_operator(name, L_da=1e-5, gamma_log="log10")


def test_log_average_of_an_image_at_the_float_maximum():
    """``exp(mean ln L)`` rounded past the maximum for an image of maximal pixels: +Inf."""
    from hdrjax import stats

    st = stats.measure(jnp.full((8, 8), MAX32, jnp.float32))
    for v in (st.log_average, st.log_average_trimmed):
        assert np.isfinite(v) and v > 0.999 * MAX32


def test_operators_of_a_maximal_image_and_local_gradients_beside_a_lamp():
    """An image of float32's largest value: the log-average rounded to +Inf, and Tumblin's
    ``L_w / L_wa`` became ``L_w · (1/L_wa)`` with a subnormal reciprocal (0), so
    ``tumblin_reinhard``'s white was the smallest normal and its output +Inf. A uniform
    image maps to one grey: every pixel equals the first. And a 3e38 lamp made every image
    and parameter gradient of ``reinhard2002_local`` NaN (``x / d²`` in JAX's derivative
    of its ratio and ``out / scale`` in that of its scale)."""
    img = jnp.full((4, 4, 3), MAX32, jnp.float32)
    for name in ("tumblin_reinhard", "tumblin1999"):
        out = np.asarray(hdrjax.tonemap(img, name))
        assert np.all(np.isfinite(out)) and np.all(out == out[0, 0]), name
    op = hdrjax.make_operator("reinhard2002_local", key=0.2, log_average=4.8)
    lamp = _one_bright((8, 8), (3, 3))

    def loss(o, x):
        return jnp.sum(o(x))

    g_op, g_x = jax.jit(jax.grad(loss, argnums=(0, 1)))(op, lamp)
    for leaf in jax.tree_util.tree_leaves((g_op, g_x)):
        assert np.all(np.isfinite(np.asarray(leaf)))
