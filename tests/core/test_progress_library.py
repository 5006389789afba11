"""Long library calls show their progress where a person watches — tiles
(:func:`hdrjax.tile.apply`), fits (:func:`hdrjax.fit.fit` and :func:`~hdrjax.fit.fit_sequence`,
the solver's steps; :func:`~hdrjax.fit.fit_batch`, the frames) and sweeps
(:func:`hdrjax.study.sweep`, the grid points) — and never in a pipe or a log.

That :func:`hdrjax._progress.interactive` is true in a Jupyter kernel and that tqdm draws
there is tested in a real kernel by tests/core/test_progress.py; here the calls run in this
process with ``interactive`` made true (a kernel per call would cost seconds each), and
with no delay before a bar appears (quick calls normally draw none)."""

import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax.fit as hf
import hdrjax.targets as ht
from hdrjax import _progress, study, tile

IMAGE = jnp.exp(jnp.linspace(-3.0, 3.0, 48)).reshape(4, 4, 3)


@pytest.fixture
def watched(monkeypatch):
    monkeypatch.setattr(_progress, "interactive", lambda: True)
    monkeypatch.setattr(_progress, "DELAY_S", 0.0)


def _last_bar(err: str) -> str:
    return err.replace("\r", "\n").strip().splitlines()[-1]


def test_tiles_show_progress(watched, capsys):
    x = np.random.default_rng(0).uniform(0.1, 4.0, (64, 64, 3)).astype(np.float32)
    out = tile.apply(tile.Mean(size=3), x, tile=32)
    bar = _last_bar(capsys.readouterr().err)
    assert bar.startswith("Mean: 100%") and " 4/4 " in bar, bar
    np.testing.assert_array_equal(out, tile.apply(tile.Mean(size=3), x, tile=32, progress=False))
    assert capsys.readouterr().err == ""


def test_fit_counts_its_steps(watched, capsys):
    res = hf.fit("linear", IMAGE, ht.MeanLuminance(0.3), params="L_max", max_size=None)
    bar = _last_bar(capsys.readouterr().err)
    assert bar.startswith(f"fit linear: {int(res.steps)}step"), bar
    assert bool(res.success)


def test_fit_batch_counts_frames_and_fit_sequence_its_steps(watched, capsys):
    frames = jnp.stack([IMAGE, 2.0 * IMAGE, 0.5 * IMAGE])
    target = ht.MeanLuminance(0.3)
    res = hf.fit_batch("linear", frames, target, params="L_max", max_size=None)
    bar = _last_bar(capsys.readouterr().err)
    assert bar.startswith("fit_batch linear: 100%") and " 3/3 " in bar, bar
    assert bool(np.all(res.success))
    seq = hf.fit_sequence("linear", frames, target, params="L_max", max_size=None)
    bar = _last_bar(capsys.readouterr().err)
    assert bar.startswith(f"fit_sequence linear: {int(seq.steps[0])}step"), bar
    quiet = hf.fit_batch("linear", frames, target, params="L_max", max_size=None, progress=False)
    np.testing.assert_array_equal(np.asarray(quiet.params["L_max"]), res.params["L_max"])
    assert capsys.readouterr().err == ""


def test_sweep_counts_its_points(watched, capsys):
    grid = {"L_max": [1.0, 10.0, 100.0]}
    res = study.sweep("linear", IMAGE, grid, max_size=None, batch_size=2)
    assert "sweep linear: 100%" in _last_bar(capsys.readouterr().err)
    assert res.statistics.shape == (3, 5)


def test_nothing_is_drawn_in_a_pipe(capsys):
    x = np.ones((8, 8, 3), np.float32)
    tile.apply(tile.Mean(size=3), x, tile=4)
    study.sweep("linear", IMAGE, {"L_max": [1.0, 10.0]}, max_size=None)
    assert capsys.readouterr().err == ""  # stderr is captured here: not a terminal
