"""``hdrjax batch --fps``: the operator's time course over the frames in order, its state
carried across the compiled batches, equal to the operator's own ``sequence`` (one scan)."""

import numpy as np
import pytest

from hdrjax import batch, io as hio
from hdrjax.cli import main
from hdrjax.operators import make_operator, time_dependent_names

from ._frames import frame

FPS = 16.0
N = 5
SCALE = 100.0  # cd/m²: the frames' relative values placed at indoor levels


@pytest.fixture(scope="module")
def video(tmp_path_factory):
    """Five frames whose level changes from frame to frame (1, ¼, 4, 4, 1 × the crop)."""
    folder = tmp_path_factory.mktemp("video")
    levels = (1.0, 0.25, 4.0, 4.0, 1.0)
    frames = [frame(i % 2) * np.float32(k) for i, k in enumerate(levels)]
    paths = []
    for i, f in enumerate(frames):
        paths.append(folder / f"v_{i:03d}.exr")
        hio.write(paths[-1], f)
    return folder, np.stack(frames)


def _read(folder, n=N):
    return np.stack([hio.read(folder / f"v_{i:03d}.exr", sidecars=False).rgb() for i in range(n)])


@pytest.mark.parametrize("method", ["pattanaik2000", "vanhateren2006"])
def test_cli_fps_equals_the_sequence_function(video, tmp_path, method):
    """``--batch-size 2`` over five frames: three compiled batches (the last padded), the
    state carried across them; the outputs equal one scan of the operator's sequence."""
    folder, frames = video
    out = tmp_path / "out"
    argv = ["batch", str(folder / "v_*.exr"), "-o", str(out), "--method", method]
    argv += ["--fps", str(FPS), "--scale", str(SCALE), "--format", "exr", "--batch-size", "2"]
    assert main([*argv, "-q"]) == 0
    ref, _ = make_operator(method).sequence(frames * np.float32(SCALE), FPS)
    np.testing.assert_allclose(_read(out), np.asarray(ref), rtol=2e-5, atol=1e-6)
    # and the time course matters: the third frame (after a dim one) differs from the
    # still-image mapping of it
    still = np.asarray(make_operator(method)(frames[2] * np.float32(SCALE)))
    assert np.abs(_read(out)[2] - still).max() > 1e-3


def test_api_fps_resume_keeps_the_time_course(video, tmp_path):
    """A resumed run computes every frame (the state needs them) and writes the missing
    ones: the same bytes as the first run."""
    folder, frames = video
    out = tmp_path / "out"
    pipe = batch.Pipeline("vanhateren2006", format="exr", scale=SCALE)
    paths = sorted(folder.glob("v_*.exr"))
    s = batch.run(paths, pipe, out, fps=FPS, batch_size=3, progress=False)
    assert s.ok and len(s.done) == N
    first = _read(out)
    (out / "v_003.exr").unlink()
    s = batch.run(paths, pipe, out, fps=FPS, batch_size=3, progress=False)
    assert len(s.done) == 1 and len(s.skipped) == N - 1
    np.testing.assert_array_equal(_read(out), first)


def test_fps_with_an_operator_without_a_time_course(video, tmp_path, capsys):
    folder, _ = video
    argv = ["batch", str(folder / "v_*.exr"), "-o", str(tmp_path / "o"), "--fps", "16"]
    assert main(argv) == 2  # reinhard2002, the default
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--fps: reinhard2002 has no time course" in err[0]
    assert all(n in err[0] for n in time_dependent_names())
    assert set(time_dependent_names()) >= {"pattanaik2000", "vanhateren2006"}
    assert not (tmp_path / "o").exists()
    with pytest.raises(ValueError, match="^fps: reinhard2002 has no time course"):
        batch.run(str(folder / "v_*.exr"), "reinhard2002", tmp_path / "o", fps=16.0)
    with pytest.raises(ValueError, match="^fps: the time course"):
        batch.run(folder / "v_000.exr", "pattanaik2000", tmp_path / "o", fps=16, parameters="same")
    with pytest.raises(ValueError, match="^fps: expected"):
        batch.run(folder / "v_000.exr", "pattanaik2000", tmp_path / "o", fps=0.0)
