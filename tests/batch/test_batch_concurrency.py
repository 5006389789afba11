"""Runs writing into one folder at the same time: a run's cleanup removes only temporaries
whose writer is gone, never those of another live run."""

import os
import subprocess
import sys

import numpy as np

from hdrjax import batch, io as hio
from hdrjax.io._atomic import owner_token

from ..conftest import REPO
from ._frames import frame, write_sequence
from .test_batch_api import W709, log_average, read_png, reinhard_np, srgb_codes


def _waiting_process() -> subprocess.Popen:
    """A live process of this machine that ends when its stdin is closed."""
    code = "import sys; sys.stdin.read()"
    return subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE)


def _temp(folder, name: str, token: str, tail: str = "abcd_123") -> str:
    """A temporary file as ``atomic_path`` names it (``.<name>.<owner>.<random>.tmp``)."""
    p = folder / f".{name}.{token}.{tail}.tmp"
    p.write_bytes(b"partial")
    return p.name


def _old_temp(folder, name: str) -> str:
    """A temporary as earlier versions named it (``.<name>.<random>.tmp``, no owner)."""
    p = folder / f".{name}.k3j4l5m6.tmp"
    p.write_bytes(b"partial")
    return p.name


def test_cleanup_keeps_live_writers_temporaries_and_removes_dead_ones(tmp_path):
    src = tmp_path / "a.exr"
    hio.write(src, np.full((8, 8, 3), 0.5, np.float32))
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.png").write_bytes(b"done before")  # resume: nothing to render, only cleanup
    live, dead = _waiting_process(), _waiting_process()
    try:
        live_token, dead_token = owner_token(live.pid), owner_token(dead.pid)
        dead.communicate()  # finished and reaped: its id names no process any more
        pid, start, host = live_token.split("-")
        elsewhere = "0" * 8 if host != "0" * 8 else "1" * 8  # another machine's hash
        keep = {
            _temp(out, "a.png", live_token),  # another run, writing now
            _temp(out, "a.png", f"{dead.pid}-1-{elsewhere}"),  # its process: unknown here
            _temp(out, "b.png", dead_token),  # not an output of this run
            _old_temp(out, "a.png"),  # no owner in the name: cannot be judged
        }
        gone = {
            _temp(out, "a.png", dead_token),  # a killed writer's
            _temp(out, "a.png", f"{pid}-{int(start) + 1}-{host}"),  # the id reused since
        }
        s = batch.run([src], "reinhard2002", out, progress=False)
        assert s.skipped == (str(src),) and not s.done
        left = {p.name for p in out.iterdir()}
        assert left == keep | {"a.png"}, sorted(left ^ (keep | {"a.png"}))
        assert not gone & left
    finally:
        live.communicate()


def test_two_concurrent_runs_into_one_folder(tmp_path):
    # two real processes, same frames, same folder, every output rewritten by both
    frames = write_sequence(tmp_path / "frames", 4)
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "hdrjax", "batch", *map(str, frames), "-o", str(out)]
    cmd += ["--key", "0.18", "--white", "3.0", "--batch-size", "1", "--no-resume", "-q"]
    env = dict(os.environ, HDRJAX_CACHE="0")
    procs = [
        subprocess.Popen(cmd, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        for _ in range(2)
    ]
    results = [p.communicate(timeout=300) for p in procs]
    for p, (o, e) in zip(procs, results, strict=True):
        assert p.returncode == 0, e.decode()
        assert b"4 done, 0 skipped, 0 failed" in o, o.decode()
    assert sorted(p.name for p in out.iterdir()) == [f"frame_{i:03d}.png" for i in range(4)]
    for i in range(4):
        rgb = frame(i).astype(np.float64)
        ref = srgb_codes(reinhard_np(rgb, 0.18, 3.0, log_average(rgb @ W709)))
        got = read_png(out / f"frame_{i:03d}.png")
        assert np.abs(got - ref).max() <= 1
        assert np.mean(got != ref) < 0.01
