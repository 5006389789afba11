"""Mergeable statistics and binding (issue 17): for every registered operator, the
statistics of two parts of an image merged and bound map the whole image as the operator
measuring the whole image does; statistics merge exactly; bind is checked."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax._stats import Statistics, measure, summarise

from .cases import make, natural

NAMES = hdrjax.operator_names()


_bind = eqx.filter_jit(lambda op, stats: op.bind(stats))


def _image():
    img = natural((16, 20), seed=4)
    img[0, 0] = 1e-4  # a wide range: reinhard2002_auto takes its local branch
    img[9, 11] = 5e3
    return img


@pytest.mark.parametrize("name", NAMES)
def test_merged_halves_bind_as_the_whole_image(name):
    img = _image()
    op = make(name)
    whole = np.asarray(op(img))
    top, bottom = op.statistics(img[:7]), op.statistics(img[7:])
    if op.statistics_settings() is None:
        assert top is None and bottom is None
        stats = None
    else:
        stats = top.merge(bottom)
    # compiled as hdrjax.tile binds (eagerly, each of bind's many small operations
    # compiles apart: about 80 programs an operator)
    bound = _bind(op, stats)
    estimated = [i.name for i in hdrjax.operators.parameter_info(op) if i.estimated]
    left = [n for n in estimated if getattr(bound, n) is None]
    assert not left, f"{name}: estimated parameters still unset after bind: {left}"
    # the histogram is the same; the log sums differ by float32 rounding (1e-6), which
    # the trimmed means carry through to the key (histogram estimates, not the exact
    # band mean of one image: tumblin's trimmed adaptation differs within its bound)
    atol = max(1e-6, op.rounding)  # budak2005: its colour transforms' conditioning
    np.testing.assert_allclose(np.asarray(bound(img)), whole, rtol=2e-5, atol=atol)


def test_merge_is_exact_for_counts_extrema_and_histogram():
    img = _image()
    L = jnp.asarray(img @ np.array(hdrjax.REC709_WEIGHTS, np.float32))
    L = L.at[3, 4].set(jnp.nan).at[12, 2].set(jnp.inf)
    whole = summarise(L)[1]
    parts = [summarise(L[a:b])[1] for a, b in ((0, 5), (5, 11), (11, 16))]
    left = parts[0].merge(parts[1]).merge(parts[2])
    right = parts[0].merge(parts[1].merge(parts[2]))
    for merged in (left, right, parts[2].merge(parts[0]).merge(parts[1])):
        for f in ("n_pixels", "n_finite", "n_positive", "min", "max", "min_positive", "counts"):
            np.testing.assert_array_equal(getattr(merged, f), getattr(whole, f), err_msg=f)
        np.testing.assert_allclose(merged.log_sum, whole.log_sum, rtol=1e-6)
    st, ref = left.luminance_stats(), measure(L)
    assert int(st.n_nonfinite) == 2
    for f in ("p01", "p99", "log_average", "log_average_trimmed", "max", "min_positive"):
        np.testing.assert_allclose(getattr(st, f), getattr(ref, f), rtol=1e-6, err_msg=f)


def test_merge_refuses_statistics_of_other_settings():
    L = jnp.asarray(_image()[..., 1])
    a = summarise(L)[1]
    with pytest.raises(ValueError, match=r"^other: statistics measured with different"):
        a.merge(summarise(L, delta=1e-3)[1])
    with pytest.raises(ValueError, match=r"^other: percentile_method='exact'"):
        summarise(L, method="exact")[1].merge(summarise(L, method="exact")[1])
    with pytest.raises(ValueError, match=r"^stats: expected the Statistics of reinhard2002"):
        hdrjax.make_operator("reinhard2002").bind(None)
    with pytest.raises(ValueError, match=r"^stats: measured with other settings"):
        hdrjax.make_operator("reinhard2002", delta=1e-3).bind(a)


def test_statistics_of_frames_merge_under_vmap_and_bind_is_differentiable():
    """Per-frame statistics (``vmap``) merged across frames bind one shared operator, and
    the bound output is differentiable with respect to the statistics' inputs."""
    frames = np.stack([_image(), 2.0 * _image()])
    op = hdrjax.make_operator("reinhard2002")
    per = jax.vmap(op.statistics)(jnp.asarray(frames))
    first = jax.tree.map(lambda v: v[0], per)
    second = jax.tree.map(lambda v: v[1], per)
    assert isinstance(first, Statistics)
    shared = op.bind(first.merge(second))
    both = op.statistics(np.concatenate(list(frames)))
    np.testing.assert_allclose(float(shared.key), float(op.bind(both).key), rtol=1e-6)

    def loss(scale):
        s = op.statistics(frames[0] * scale)
        return jnp.mean(op.bind(s)(frames[0]))

    g = jax.grad(loss)(jnp.float32(1.0))
    eps = 1e-2
    fd = (loss(jnp.float32(1 + eps)) - loss(jnp.float32(1 - eps))) / (2 * eps)
    assert np.isfinite(float(g)) and float(g) < 0  # a brighter measurement maps darker
    np.testing.assert_allclose(float(g), float(fd), rtol=0.05)
