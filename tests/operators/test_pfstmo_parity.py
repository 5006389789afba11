"""drago2003 and reinhard2005 against pfstmo 2.2.0 (``pfstmo_drago03``, ``pfstmo_reinhard05``,
every option at its default) on four real images, and drago2003 against OpenCV's
``TonemapDrago``.

Fixtures: fixtures/pfstmo/pfstmo.npz, written by fixtures/pfstmo/make_fixtures.py (its
docstring: the commands, the pfstmo version, how the inputs were cropped and downscaled).

Issue 20's parity criterion: after clipping both to [0, 1] and sRGB encoding, the 99th
percentile of the absolute difference is at most 0.01 on every image (:data:`CRITERION`).
Measured with pfstmo's luminance weights, float32 and float64 alike (p99 / largest
difference, the worst image): drago2003 6e-7 / 1.6e-6; reinhard2005 5.4e-5 / 6.1e-5, all
but 2e-6 of it pfstmo's sums skipping the first pixel (a NumPy model of pfstmo with and
without that skip). With hdrjax's default Rec.709 weights (rounded to four places):
2.5e-5 / 4.9e-5 and 5.5e-5 / 6.2e-5. The tests also bound the largest difference by
:data:`TIGHT`, so that a regression well inside the criterion shows.

Each dtype maps every image through every operator of :func:`_operators` in one compiled
program (:func:`_outputs`).
"""

import functools
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax

from ..conftest import RTOL32, RTOL64
from .cases import natural

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "pfstmo" / "pfstmo.npz"
PFSTMO_WEIGHTS = (0.212656, 0.715158, 0.072186)
"""Luminance weights of pfstools' RGB-to-XYZ matrix (its Y row): pfstmo's luminance."""
OPENCV_WEIGHTS = (0.299, 0.587, 0.114)
"""OpenCV's ``COLOR_RGB2GRAY`` (Rec.601 luma), the luminance of its ``TonemapDrago``."""
CRITERION = 0.01
TIGHT = 2e-4
"""Largest absolute difference (encoded) allowed: 3 times the largest measured."""
BIAS = 0.7
"""A bias off the default, where the paper's adjustment of ``L_wa`` differs from pfstmo."""


@functools.cache
def fixtures() -> dict[str, np.ndarray]:
    with np.load(FIXTURES) as f:
        return {k: f[k] for k in f.files}


def _operators(dtype: str) -> dict[str, hdrjax.operators.AbstractOperator]:
    """The operators each test reads (float64: those compared in both dtypes)."""
    make = hdrjax.make_operator
    ops = {
        "drago03": make("drago2003", compat="pfstmo", weights=PFSTMO_WEIGHTS),
        "reinhard05": make("reinhard2005", compat="pfstmo", weights=PFSTMO_WEIGHTS),
        "drago_paper_bias": make("drago2003", bias=BIAS, weights=PFSTMO_WEIGHTS),
    }
    if dtype == "float32":
        ops["drago03_rec709"] = make("drago2003", compat="pfstmo")
        ops["reinhard05_rec709"] = make("reinhard2005", compat="pfstmo")
        ops["reinhard_paper"] = make("reinhard2005", weights=PFSTMO_WEIGHTS)
    return ops


@functools.cache
def _outputs(dtype: str) -> dict[str, np.ndarray]:
    """Every operator of :func:`_operators` on the four fixture images, in one program."""
    run = eqx.filter_jit(lambda ops, x: {k: op(x) for k, op in ops.items()})
    x = jnp.asarray(fixtures()["input"].astype(dtype))
    out = {k: np.asarray(v) for k, v in run(_operators(dtype), x).items()}
    assert all(v.dtype == np.dtype(dtype) for v in out.values())
    return out


def encoded(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB encoding after clipping to [0, 1] (float64 NumPy)."""
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def _differences(ours: np.ndarray, peer: np.ndarray) -> list[tuple[float, float]]:
    """Per image: (99th percentile, largest) of |encoded difference|."""
    d = np.abs(encoded(ours) - encoded(peer))
    return [(float(np.percentile(di, 99)), float(di.max())) for di in d]


@pytest.mark.parametrize("dtype", ["float32", "float64"])
@pytest.mark.parametrize("operator", ["drago03", "reinhard05"])
def test_matches_pfstmo(operator, dtype, request):
    if dtype == "float64":
        request.getfixturevalue("x64")
    out = _outputs(dtype)
    names = fixtures()["names"]
    for (p99, worst), name in zip(
        _differences(out[operator], fixtures()[operator]), names, strict=True
    ):
        assert p99 <= CRITERION, f"{operator}/{name}: p99 {p99:.2e}"
        assert worst <= TIGHT, f"{operator}/{name}: largest difference {worst:.2e}"
    assert np.ptp(encoded(fixtures()[operator])) > 0.9  # a real range of outputs compared


@pytest.mark.parametrize("operator", ["drago03", "reinhard05"])
def test_default_weights_meet_the_criterion(operator):
    """With hdrjax's Rec.709 weights instead of pfstools' the results move by the
    weights' rounding (module docstring's figures)."""
    out = _outputs("float32")[f"{operator}_rec709"]
    for p99, worst in _differences(out, fixtures()[operator]):
        assert p99 <= CRITERION and worst <= TIGHT, (p99, worst)


def test_reinhard2005_paper_mode_is_pfstmo_before_its_srgb_decoding():
    """pfstmo hands the normalised response V on as sRGB-encoded values: the paper mode's
    display-linear V is pfstmo's output encoded again, and clearly brighter than
    compat="pfstmo" (the option is not a no-op)."""
    out = _outputs("float32")
    V = out["reinhard_paper"]
    np.testing.assert_allclose(V, encoded(fixtures()["reinhard05"]), rtol=0, atol=TIGHT)
    assert np.all(V >= 0) and np.all(V <= 1 + 1e-6)
    assert np.mean(V - out["reinhard05"]) > 0.1


def _drago_paper(rgb: np.ndarray, bias: float) -> np.ndarray:
    """The paper's Eq. 4 with its adjustment of ``L_wa`` to the bias, in float64 NumPy
    (log-average with pfstmo's offset 1e-4)."""
    rgb = rgb.astype(np.float64)
    L = rgb @ np.asarray(PFSTMO_WEIGHTS)
    L_wa = np.exp(np.mean(np.log(L + 1e-4))) / (1 + bias - 0.85) ** 5
    x, x_max = L / L_wa, L.max() / L_wa
    p = np.log(bias) / np.log(0.5)
    Ld = np.log(1 + x) / np.log(2 + 8 * (L / L.max()) ** p) / np.log10(1 + x_max)
    return rgb * (Ld / L)[..., None]


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_drago2003_paper_mode(dtype, request):
    """The paper's formula off the default bias (pfstmo leaves the adjustment out); at
    the default bias, where the adjustment is 1, pfstmo's mode gives the paper's formula."""
    if dtype == "float64":
        request.getfixturevalue("x64")
    out = _outputs(dtype)
    rtol = RTOL32 if dtype == "float32" else RTOL64
    for i, rgb in enumerate(fixtures()["input"]):
        want = _drago_paper(rgb, BIAS)
        np.testing.assert_allclose(out["drago_paper_bias"][i], want, rtol=rtol, atol=1e-7)
        np.testing.assert_allclose(out["drago03"][i], _drago_paper(rgb, 0.85), rtol=rtol)
    assert not np.allclose(out["drago_paper_bias"], out["drago03"], rtol=0.01)


def test_drago2003_matches_opencv():
    """OpenCV's ``TonemapDrago`` (gamma 1, saturation 1: its power laws off, which hdrjax
    leaves to display encoding) maps the same curve between two min–max stretches (of the
    input and of the output, over all channel values), with Rec.601 luma and a log-average
    of luma floored at 1e-4 (no offset); with those steps around drago2003 (its
    ``compat="pfstmo"``: no bias adjustment, as OpenCV) the results agree to float32
    rounding. What is not comparable: OpenCV's output is relative to its own extremes
    (no ``1 / log10(1 + x_max)`` scale, no ``L_dmax``)."""
    cv2 = pytest.importorskip("cv2")
    op = hdrjax.make_operator("drago2003", compat="pfstmo", weights=OPENCV_WEIGHTS)
    run = eqx.filter_jit(lambda o, x: o(x))  # one program: the statistics are traced
    for rgb in fixtures()["input"]:
        want = cv2.createTonemapDrago(gamma=1.0, saturation=1.0, bias=0.85).process(rgb)
        x = (rgb - rgb.min()) / (rgb.max() - rgb.min())
        luma = x.astype(np.float64) @ np.asarray(OPENCV_WEIGHTS)
        L_wa = np.exp(np.mean(np.log(np.maximum(luma, 1e-4))))
        given = eqx.tree_at(
            lambda o: (o.log_average, o.L_max),
            op,
            (jnp.float32(L_wa), jnp.float32(luma.max())),
            is_leaf=lambda v: v is None,
        )
        got = np.asarray(run(given, x))
        got = (got - got.min()) / (got.max() - got.min())
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-5)


def test_reinhard2005_normalisation_reads_the_whole_image():
    """Unset, the response's range is the mapped image's (no tiles: infinite halo);
    measured, the operator is pointwise and maps a part of the image as the whole."""
    img = natural((12, 16), seed=5)
    op = hdrjax.make_operator("reinhard2005")
    assert op.halo(img.shape) == (np.inf, np.inf)

    @eqx.filter_jit  # one program
    def run(op, img):
        measured = op.measure(img)
        return measured, op(img), measured(img), measured(img[:5]), op(img[:5])

    measured, whole, again, top, own_range = run(op, img)
    assert measured.halo(img.shape) == (0, 0) and not measured.unset()
    whole = np.asarray(whole)
    np.testing.assert_allclose([whole.min(), whole.max()], [0.0, 1.0], atol=1e-6)
    np.testing.assert_allclose(np.asarray(again), whole, rtol=RTOL32, atol=1e-7)
    np.testing.assert_allclose(np.asarray(top), whole[:5], rtol=RTOL32, atol=1e-7)
    assert not np.allclose(np.asarray(own_range), whole[:5])  # the part's own range
