"""Sequence parameters for any operator: ``"same"`` is the operator's ``bind`` of the frames'
merged statistics, ``"smooth"`` the per-frame values averaged over time as each parameter's
declared ``pooling`` says (hdrjax.batch._sequence module docstring)."""

import functools
import math

import equinox as eqx
import numpy as np
import pytest

import hdrjax
from hdrjax import batch, io as hio
from hdrjax.batch._frames import measure_frames
from hdrjax.batch._sequence import smoothed_values
from hdrjax.operators import parameter_info

SCALES = (1.0, 4.0, 16.0)  # exposures far apart: pooled values differ from per-frame ones
W709 = np.array([0.2126, 0.7152, 0.0722])


def _frames() -> list[np.ndarray]:
    rng = np.random.default_rng(3)
    return [
        np.exp(rng.normal(0.0, 1.0, (8, 8, 3))).astype(np.float32) * np.float32(s) for s in SCALES
    ]


def _ema(series: np.ndarray, tau: float, log: bool) -> np.ndarray:
    """The centred exponential moving average, written out (module docstring)."""
    x = np.log(series) if log else series
    r = math.ceil(4 * tau)
    out = np.empty_like(x)
    for t in range(len(x)):
        ks = [k for k in range(-r, r + 1) if 0 <= t + k < len(x)]
        w = np.array([math.exp(-abs(k) / tau) for k in ks]).reshape((-1,) + (1,) * (x.ndim - 1))
        out[t] = (w * x[[t + k for k in ks]]).sum(0) / w.sum()
    return np.exp(out) if log else out


def _read(p) -> np.ndarray:
    return np.asarray(hio.read(p, sidecars=False).rgb(), np.float64)


def test_same_and_smooth_for_a_non_reinhard2002_operator(tmp_path):
    frames = _frames()
    paths = []
    for i, f in enumerate(frames):
        paths.append(tmp_path / f"t_{i}.exr")
        hio.write(paths[-1], f)
    op = hdrjax.make_operator("tumblin_reinhard")
    pipe = batch.Pipeline(op, format="exr")
    run = functools.partial(batch.run, paths, pipe, batch_size=4, progress=False)
    run(tmp_path / "same", parameters="same")
    run(tmp_path / "smooth", parameters="smooth", smooth_frames=1.5)

    # "same": bind of the merged statistics of all frames, as if they were one image
    @eqx.filter_jit  # (eager, the merge and bind run op by op: seconds)
    def bind_merged(op, frames):
        return op.bind(functools.reduce(lambda a, b: a.merge(b), map(op.statistics, frames)))

    shared = bind_merged(op, frames)
    L_all = np.concatenate([f.astype(np.float64) @ W709 for f in frames], axis=None)
    assert float(shared.L_max) == pytest.approx(L_all.max(), rel=1e-6)  # the max of all pixels
    for i, f in enumerate(frames):
        ref = np.asarray(shared(f), np.float64)
        np.testing.assert_allclose(_read(tmp_path / "same" / f"t_{i}.exr"), ref, rtol=1e-4)

    # "smooth": each frame's own values, averaged over time in ln (log_mean and max here)
    per = [op.measure(f) for f in frames]
    names = ("L_wa", "L_max", "L_white")
    smooth = {n: _ema(np.array([float(getattr(m, n)) for m in per]), 1.5, True) for n in names}
    for i, f in enumerate(frames):
        bound = hdrjax.make_operator("tumblin_reinhard", **{n: smooth[n][i] for n in names})
        ref = np.asarray(bound(f), np.float64)
        np.testing.assert_allclose(_read(tmp_path / "smooth" / f"t_{i}.exr"), ref, rtol=1e-4)


def test_smooth_averages_each_parameter_as_its_pooling_declares():
    # reinhard2004: channel_average pools as a mean (arithmetic), log_average / L_min / L_max
    # in ln; far-apart exposures make the two averages differ by a factor ~2
    frames = _frames()
    op = hdrjax.make_operator("reinhard2004")
    pipe = batch.Pipeline(op)
    key = ((8, 8, 3), None, True)  # shape, primaries (Rec.709), all pixels finite
    recs = measure_frames(pipe, frames, key, 4, pooled=False)
    got = smoothed_values(op, recs, 2.0)
    pooling = {p.name: p.pooling for p in parameter_info(op)}
    assert pooling["channel_average"] == "mean"
    per = [op.measure(f) for f in frames]
    for n in ("channel_average", "log_average", "L_min", "L_max"):
        series = np.stack([np.asarray(getattr(m, n), np.float64) for m in per])
        ref = _ema(series, 2.0, log=pooling[n] != "mean")
        np.testing.assert_allclose(np.stack([g[n] for g in got]), ref, rtol=1e-4)
    arith = np.stack([g["channel_average"] for g in got])
    geo = _ema(np.stack([np.asarray(m.channel_average, np.float64) for m in per]), 2.0, True)
    assert np.all(arith > 1.2 * geo)  # the mean, not the geometric mean


def test_same_refuses_statistics_that_do_not_merge(tmp_path):
    op = hdrjax.make_operator("reinhard2002", percentile_method="exact")
    with pytest.raises(ValueError, match=r"^parameters: 'same' merges .*'histogram'$"):
        batch.run([tmp_path / "x.exr"], op, tmp_path, parameters="same", progress=False)
