"""hdrjax.study (parameter sweeps, plot_sweep) and hdrjax.plot.tone_curve.

References are independent of the code under test: the grid is re-evaluated one point at a
time with :func:`hdrjax.tonemap` (or the operator's formula in NumPy), the image reduction
and the statistics are recomputed in float64 NumPy (``numpy.percentile`` for percentiles,
the logistic step of ``ClippedFraction`` written out), and plotted data are compared with
curves computed from the papers' formulas.
"""

import matplotlib

matplotlib.use("Agg")

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.collections import PathCollection, QuadMesh  # noqa: E402
from matplotlib.patches import StepPatch  # noqa: E402

import hdrjax  # noqa: E402
import hdrjax.targets as ht  # noqa: E402
from hdrjax import plot, study  # noqa: E402

from ..conftest import DATA, RTOL32  # noqa: E402

W = np.asarray(hdrjax.REC709_WEIGHTS)
TINY32 = float(np.finfo(np.float32).tiny)
TARGET = ht.MeanLuminance(0.4) + ht.Percentiles(99, 0.95)
KEYS = np.geomspace(0.09, 0.72, 4)
WHITES = np.array([0.8, 2.0, 50.0])


@pytest.fixture(scope="module")
def cornell():
    """data/cornell_box.exr (512 × 512, float32)."""
    return np.asarray(hdrjax.io.read(DATA / "cornell_box.exr").rgb(), np.float32)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _box(x, f):
    h, w = x.shape[0] // f, x.shape[1] // f
    return x[: h * f, : w * f].reshape(h, f, w, f, 3).mean(axis=(1, 3), dtype=np.float64)


def _np_stats(display):
    """mean, P1, P50, P99 of clipped display luminance; soft clipped fraction (float64)."""
    d = np.asarray(display, np.float64)
    Ld = np.clip(d, 0.0, 1.0) @ W
    p = np.percentile(Ld[Ld >= TINY32], [1, 50, 99])
    clipped = np.mean(1.0 / (1.0 + np.exp(-(d.max(axis=-1) - 1.0) / 0.01)))
    return np.array([Ld.mean(), *p, clipped])


def _np_log_average(rgb, delta=1e-6):
    """Reinhard et al. 2002 Eq. 1 in float64."""
    L = np.asarray(rgb, np.float64) @ W
    return float(np.exp(np.mean(np.log(delta + np.maximum(L, 0.0)))))


@pytest.fixture(scope="module")
def reinhard_sweep(cornell):
    return study.sweep(
        "reinhard2002", cornell, {"key": KEYS, "L_white": WHITES}, TARGET, max_size=32
    )


@pytest.fixture(scope="module")
def reinhard_reference(cornell):
    """Loop of single tonemap calls on the 32 × 32 box-filtered image, NumPy statistics."""
    small = _box(cornell, 16).astype(np.float32)
    lbar = _np_log_average(cornell)  # measured once, full resolution
    stats = np.empty((len(KEYS), len(WHITES), 5))
    for i, k in enumerate(KEYS):
        for j, w in enumerate(WHITES):
            out = hdrjax.tonemap(small, "reinhard2002", key=k, L_white=w, log_average=lbar)
            stats[i, j] = _np_stats(out)
    loss = (stats[..., 0] - 0.4) ** 2 + (stats[..., 3] - 0.95) ** 2
    return stats, loss


def test_sweep_equals_loop_of_tonemap_calls(reinhard_sweep, reinhard_reference):
    res = reinhard_sweep
    stats, loss = reinhard_reference
    assert res.params == ("key", "L_white") and res.shape == (4, 3)
    assert res.stat_names == ("mean", "p1", "p50", "p99", "clipped")
    np.testing.assert_allclose(res.axes[0], KEYS, rtol=1e-7)
    np.testing.assert_allclose(res.grid["L_white"], WHITES, rtol=1e-7)
    assert res.statistics.shape == (4, 3, 5) and res.loss.shape == (4, 3)
    np.testing.assert_allclose(res.statistics, stats, rtol=RTOL32, atol=1e-6)
    np.testing.assert_allclose(res.loss, loss, rtol=1e-3, atol=1e-7)
    np.testing.assert_allclose(res.stat("p99"), stats[..., 3], rtol=RTOL32, atol=1e-6)
    i, j = np.unravel_index(np.argmin(loss), loss.shape)
    assert res.argmin() == pytest.approx({"key": KEYS[i], "L_white": WHITES[j]}, rel=1e-6)
    # the grid spans the clipping edge: most pixels clip at key 0.72, L_white 0.8; at key
    # 0.09, L_white 50 only the lamp (~1 % of the pixels) does
    assert stats[-1, 0, 4] > 0.5 and stats[0, -1, 4] < 0.02


def test_unset_parameters_are_measured_per_grid_point(cornell):
    # reinhard2002's automatic L_white (JGT Eq. 5 with hdritools' guard) depends on the key:
    # each grid point must equal the operator with that key, measured on the full image
    full = _box(cornell, 4).astype(np.float32)  # 128 × 128
    keys = np.array([0.05, 0.18, 0.5])
    res = study.sweep("reinhard2002", full, {"key": keys}, max_size=32)
    small = _box(full, 4).astype(np.float32)
    one = eqx.filter_jit(lambda o, img, x: o.measure(img)(x))  # one compile for the loop
    for i, k in enumerate(keys):
        out = one(hdrjax.make_operator("reinhard2002", key=k), full, small)
        np.testing.assert_allclose(res.statistics[i], _np_stats(out), rtol=RTOL32, atol=1e-6)


def test_linear_one_parameter_numpy_reference_and_chunks(cornell):
    # Linear: display = rgb / L_max (formula in NumPy, no hdrjax call); 65 × 65 → factor 2
    img = cornell[:130:2, :130:2]
    L_max = np.geomspace(0.05, 5.0, 5)
    tgt = ht.MeanLuminance(0.3)
    res = study.sweep("linear", img, {"L_max": L_max}, tgt, max_size=40)
    chunked = study.sweep("linear", img, {"L_max": L_max}, tgt, max_size=40, batch_size=2)
    small = _box(img, 2)
    assert small.shape == (32, 32, 3)
    ref = np.stack([_np_stats(small / m) for m in L_max])
    np.testing.assert_allclose(res.statistics, ref, rtol=RTOL32, atol=1e-6)
    np.testing.assert_allclose(res.loss, (ref[:, 0] - 0.3) ** 2, rtol=1e-3, atol=1e-8)
    np.testing.assert_allclose(chunked.statistics, res.statistics, rtol=1e-6, atol=1e-7)
    rev = study.sweep("linear", img, {"L_max": L_max[::-1]}, tgt, max_size=40)  # any order
    np.testing.assert_allclose(rev.statistics, ref[::-1], rtol=RTOL32, atol=1e-6)
    ax = study.plot_sweep(rev, "mean")  # drawn in increasing L_max
    np.testing.assert_allclose(ax.lines[0].get_xdata(), L_max, rtol=1e-6)
    np.testing.assert_allclose(ax.lines[0].get_ydata(), ref[:, 0], rtol=RTOL32)
    sub = study.sweep("linear", img, {"L_max": L_max[:1]}, max_size=None)
    np.testing.assert_allclose(sub.statistics[0], _np_stats(img / L_max[0]), rtol=RTOL32)


def test_three_parameters_outer_product_and_select(cornell):
    img = cornell[::16, ::16]  # 32 × 32
    grid = {"q": [1.0, 2.0], "k": [1.0, 3.0, 5.0], "L_max": [0.5, 2.0]}
    res = study.sweep("logarithmic", img, grid, max_size=None)
    assert res.shape == (2, 3, 2) and res.statistics.shape == (2, 3, 2, 5)
    # colour-hdri's logarithmic operator: log10(1 + q L) / log10(1 + k L_max), colour kept
    L = np.asarray(img, np.float64) @ W
    for i, q in enumerate(grid["q"]):
        for j, k in enumerate(grid["k"]):
            for m, lm in enumerate(grid["L_max"]):
                Ld = np.log10(1 + q * L) / np.log10(1 + k * lm)
                ratio = np.where(L > 0, Ld / np.where(L > 0, L, 1.0), 0.0)  # black stays black
                ref = _np_stats(img * ratio[..., None])
                np.testing.assert_allclose(res.statistics[i, j, m], ref, rtol=RTOL32, atol=1e-6)
    part = res.select(k=1)
    assert part.params == ("q", "L_max") and part.shape == (2, 2)
    np.testing.assert_array_equal(part.statistics, res.statistics[:, 1])
    with pytest.raises(ValueError, match="1 or 2 parameters"):
        study.plot_sweep(res)
    with pytest.raises(ValueError, match="outside the grid"):
        res.select(k=3)


@pytest.mark.parametrize(
    "grid, match",
    [
        ({"kee": [0.1, 0.2]}, r"\['kee'\] are not parameters of reinhard2002; valid: L_white"),
        ({"key": []}, r"grid\['key'\]: no values"),
        ({"key": [[0.1, 0.2]]}, r"grid\['key'\]: expected 1-D values, got shape \(1, 2\)"),
        ({"key": 0.18}, r"expected 1-D values, got shape \(\)"),
        ({"key": [0.1, np.nan]}, r"grid\['key'\]: values must be finite"),
        ({"key": ["a"]}, r"grid\['key'\]: expected 1-D numeric values"),
        ({}, "non-empty dict"),
        ([0.1, 0.2], "non-empty dict"),
        ({"delta": [1e-6]}, r"\['delta'\] are not parameters"),  # a static setting
    ],
)
def test_validation(cornell, grid, match):
    with pytest.raises(ValueError, match=match):
        study.sweep("reinhard2002", cornell[:8, :8], grid)


def test_validation_operator_target_and_non_scalar(cornell):
    img = cornell[:8, :8]
    with pytest.raises(ValueError, match="unknown operator 'nope'"):
        study.sweep("nope", img, {"key": [1.0]})
    with pytest.raises(ValueError, match="operator: expected an operator"):
        study.sweep(3, img, {"key": [1.0]})
    with pytest.raises(ValueError, match="target: expected"):
        study.sweep("linear", img, {"L_max": [1.0]}, target="mean")
    with pytest.raises(ValueError, match=r"channel_average has shape \(3,\); only scalars"):
        study.sweep("reinhard2004", img, {"channel_average": [1.0]})
    with pytest.raises(ValueError, match=r"image: expected one image"):
        study.sweep("linear", np.stack([img, img]), {"L_max": [1.0]})
    res = study.sweep("linear", img, {"L_max": [1.0]})
    with pytest.raises(ValueError, match="'loss' needs a sweep with a target"):
        res.argmin()
    with pytest.raises(ValueError, match="unknown statistic 'p95'; valid: mean, p1"):
        res.stat("p95")
    ax = study.plot_sweep(res)  # no target: the five statistics, no loss axis
    assert len(ax.lines) == 5 and len(ax.figure.axes) == 1
    with pytest.raises(ValueError, match="'loss' needs a sweep with a target"):
        study.plot_sweep(res, "loss")


def test_plot_sweep_heat_map(reinhard_sweep, reinhard_reference, tmp_path):
    stats, loss = reinhard_reference
    ax = study.plot_sweep(reinhard_sweep)
    meshes = [c for c in ax.collections if isinstance(c, QuadMesh)]
    assert len(meshes) == 1
    np.testing.assert_allclose(meshes[0].get_array().reshape(3, 4), loss.T, rtol=1e-3, atol=1e-7)
    assert ax.get_xscale() == "log" and ax.get_yscale() == "linear"  # KEYS geomspace only
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("key", "L_white")
    assert len(ax.figure.axes) == 2 and ax.figure.axes[1].get_ylabel() == "loss"  # colour bar
    # cell edges: geometric midpoints of the log-spaced keys
    xe = meshes[0].get_coordinates()[0, :, 0]
    np.testing.assert_allclose(xe[1:-1], np.sqrt(KEYS[1:] * KEYS[:-1]), rtol=1e-6)
    (star,) = [ln for ln in ax.lines if ln.get_marker() == "*"]
    i, j = np.unravel_index(np.argmin(loss), loss.shape)
    assert star.get_xdata()[0] == pytest.approx(KEYS[i], rel=1e-6)
    assert star.get_ydata()[0] == pytest.approx(WHITES[j], rel=1e-6)
    out = tmp_path / "sweep2d.png"
    ax.figure.savefig(out, dpi=50)
    assert out.stat().st_size > 1000

    fig, ax2 = plt.subplots()
    assert study.plot_sweep(reinhard_sweep, "p50", ax=ax2, log=False) is ax2
    (mesh,) = [c for c in ax2.collections if isinstance(c, QuadMesh)]
    np.testing.assert_allclose(mesh.get_array().reshape(3, 4), stats[..., 2].T, rtol=RTOL32)
    assert ax2.get_xscale() == "linear" and ax2.get_title() == "reinhard2002: p50"


def test_plot_sweep_curves(reinhard_sweep, reinhard_reference, tmp_path):
    stats, loss = reinhard_reference
    one = reinhard_sweep.select(L_white=1)  # L_white = 2.0
    ax = study.plot_sweep(one)
    assert len(ax.lines) == 5  # one curve per statistic
    assert [ln.get_label() for ln in ax.lines] == list(study.STAT_NAMES)
    for k, ln in enumerate(ax.lines):
        np.testing.assert_allclose(ln.get_xdata(), KEYS, rtol=1e-6)
        np.testing.assert_allclose(ln.get_ydata(), stats[:, 1, k], rtol=RTOL32, atol=1e-6)
    twin = [a for a in ax.figure.axes if a is not ax]
    assert len(twin) == 1 and len(twin[0].lines) == 2  # loss and its minimum
    np.testing.assert_allclose(twin[0].lines[0].get_ydata(), loss[:, 1], rtol=1e-3, atol=1e-7)
    assert twin[0].lines[1].get_xdata()[0] == pytest.approx(KEYS[np.argmin(loss[:, 1])])
    out = tmp_path / "sweep1d.png"
    ax.figure.savefig(out, dpi=50)
    assert out.stat().st_size > 1000
    ax = study.plot_sweep(one, ["p1", "p99"])
    assert [ln.get_label() for ln in ax.lines] == ["p1", "p99"]


def test_tone_curve_of_a_curve_operator(cornell, tmp_path):
    img = _box(cornell, 8).astype(np.float32)  # 64 × 64
    op = hdrjax.make_operator("reinhard2002", key=0.25, L_white=3.0)  # log_average measured
    ax = plot.tone_curve(op, img, bins=32, points=100)
    (line,) = [ln for ln in ax.lines if ln.get_gid() == "tone_curve"]
    L = np.asarray(img, np.float64) @ W
    x = line.get_xdata()
    np.testing.assert_allclose(x[[0, -1]], [L[L > 0].min(), L.max()], rtol=1e-5)
    np.testing.assert_allclose(np.diff(np.log(x)), np.log(x[1] / x[0]), rtol=1e-4)
    # Reinhard et al. 2002 Eqs. 2-4, log-average (Eq. 1) of this image
    s = 0.25 / _np_log_average(img) * x
    np.testing.assert_allclose(line.get_ydata(), s * (1 + s / 9.0) / (1 + s), rtol=RTOL32)
    assert ax.get_xscale() == "log"
    (hax,) = [a for a in ax.figure.axes if a is not ax]
    (hist,) = [p for p in hax.patches if isinstance(p, StepPatch)]
    counts, _ = np.histogram(np.log10(L[L > 0]), 32)
    np.testing.assert_allclose(hist.get_data().values, counts / (L > 0).sum(), rtol=1e-12)
    out = tmp_path / "curve.png"
    ax.figure.savefig(out, dpi=50)
    assert out.stat().st_size > 1000


def test_tone_curve_of_a_per_channel_operator(cornell):
    # "simple" maps each channel c → c / (1 + c): no luminance curve, so the plot shows the
    # display luminance of each pixel and its mean per log-luminance bin
    img = _box(cornell, 16).astype(np.float32)  # 32 × 32
    ax = plot.tone_curve("simple", img, bins=8, max_scatter=500)
    rgb = np.asarray(img, np.float64)
    L = rgb @ W
    ok = L > 0
    c = np.maximum(rgb, 0.0)  # negative channels clamp to 0 (hdrjax.operators._classic)
    Ld = (c / (1 + c))[ok] @ W
    (pts,) = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert pts.get_gid() == "pixels" and 250 <= len(pts.get_offsets()) <= 500
    edges = np.linspace(np.log10(L[ok].min()), np.log10(L[ok].max()), 9)
    which = np.clip(np.searchsorted(edges, np.log10(L[ok]), side="right") - 1, 0, 7)
    ref = [Ld[which == b].mean() for b in range(8) if np.any(which == b)]
    (line,) = [ln for ln in ax.lines if ln.get_gid() == "tone_curve"]
    np.testing.assert_allclose(line.get_ydata(), ref, rtol=1e-5)


def test_tone_curve_validation():
    with pytest.raises(ValueError, match="no pixel with finite positive luminance"):
        plot.tone_curve("linear", jnp.zeros((4, 4, 3)))
    with pytest.raises(ValueError, match="bins: expected an integer >= 2"):
        plot.tone_curve("linear", jnp.ones((4, 4, 3)), bins=1)


def test_float64_sweep(cornell, x64):
    img = np.asarray(cornell[::16, ::16], np.float64)  # 32 × 32
    L_max = np.array([0.1, 0.7, 3.0])
    res = study.sweep("linear", img, {"L_max": L_max}, ht.MeanLuminance(0.3), max_size=None)
    assert res.statistics.dtype == np.float64 and res.axes[0].dtype == np.float64
    ref = np.stack([_np_stats(img / m) for m in L_max])
    np.testing.assert_allclose(res.statistics, ref, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(res.loss, (ref[:, 0] - 0.3) ** 2, rtol=1e-9)
