"""hdrjax.metrics.contrast_distortion: the visible contrast distortion of Mantiuk, Daly &
Kerofsky 2008 as a metric of any rendition.

The references are the operator's own: for a grey scene, the metric of mantiuk2008's
rendition must equal the objective at the curve its solver found (the paper's Eq. 9–10
evaluated on that curve), and no other operator's rendition on the same display can be
below it (mantiuk2008 minimises it over global curves)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
import hdrjax.metrics as hm
from hdrjax.display import encode
from hdrjax.io import read
from hdrjax.operators import Mantiuk2008
from hdrjax.operators._mantiuk2008 import conditional_density, contrast_distortion

from ..conftest import DATA

WEIGHTS = np.array([0.2126, 0.7152, 0.0722], np.float32)
RTOL_CURVE = 1e-3
"""Metric of mantiuk2008's rendition vs its objective: the rendition's curve is estimated
from the pixels (a line per node's pixels), measured 3e-5 relative on this scene."""


@pytest.fixture(scope="module")
def scene():
    """venice_sunset_1k.hdr at 1/8 size in cd/m² (Radiance units × 179), as grey."""
    rgb = np.asarray(read(DATA / "venice_sunset_1k.hdr").rgb())[::8, ::8] * 179.0
    L = rgb @ WEIGHTS
    return np.repeat(L[..., None], 3, -1).astype(np.float32)


@pytest.fixture(scope="module")
def solved(scene):
    return Mantiuk2008().measure(scene)


@pytest.fixture(scope="module")
def renditions(scene, solved):
    out = {n: np.asarray(encode(hdrjax.tonemap(scene, n))) for n in ("reinhard2002", "linear")}
    return {"mantiuk2008": np.asarray(encode(solved(scene))), **out}


def test_mantiuk2008s_rendition_scores_its_own_objective(scene, renditions, solved):
    op = solved
    bottom, _ = op.display_model().luminance_range()
    curve = jnp.maximum(op.curve, jnp.log10(bottom))  # what the display can show
    objective = float(contrast_distortion(curve, conditional_density(scene @ WEIGHTS)))
    got = float(hm.contrast_distortion(scene, renditions["mantiuk2008"]))
    assert got == pytest.approx(objective, rel=RTOL_CURVE)


def test_no_rendition_beats_the_minimiser(scene, renditions):
    scores = {n: float(hm.contrast_distortion(scene, v)) for n, v in renditions.items()}
    best = scores.pop("mantiuk2008")
    assert all(s > best for s in scores.values()), (best, scores)
    # a display of higher contrast reproduces more: the same rendition distorts less there
    bright = float(hm.contrast_distortion(scene, renditions["reinhard2002"], display="lcd_bright"))
    assert bright < scores["reinhard2002"]


def test_gradient_matches_central_differences(scene, renditions):
    """The rendition's derivative along one direction (float64); batches, NaN pixels and
    finite gradients are the conformance suite's (tests/conformance/_table.py)."""
    with jax.enable_x64(True):
        s64 = scene[::2, ::2].astype(np.float64)
        v64 = renditions["reinhard2002"][::2, ::2].astype(np.float64)
        d = np.random.default_rng(1).normal(size=v64.shape) * 1e-3
        f64 = jax.jit(jax.value_and_grad(lambda x: hm.contrast_distortion(s64, x)))
        _, g64 = f64(v64)
        h = 1e-3
        fd = (float(f64(v64 + h * d)[0]) - float(f64(v64 - h * d)[0])) / (2 * h)
        assert np.abs(g64).max() > 0
        assert float(jnp.sum(g64 * d)) == pytest.approx(fd, rel=1e-3)


def test_bad_arguments_name_themselves(scene):
    with pytest.raises(ValueError, match="ldr") as e:
        hm.contrast_distortion(scene, scene[:-1])
    assert "\n" not in str(e.value)
    with pytest.raises(ValueError, match="display"):
        hm.contrast_distortion(scene, scene, display="oled")
