"""``hdrjax batch`` on the command line: resume, skip-on-error and the exit code."""

import os
import subprocess
import sys

import numpy as np
import pytest

from hdrjax import io as hio
from hdrjax.cli import main

from ..conftest import REPO
from ._frames import frame, write_sequence


@pytest.fixture
def frames(tmp_path):
    folder = tmp_path / "frames"
    paths = write_sequence(folder, 4)
    (folder / "frame_004.exr").write_bytes(b"\x76\x2f\x31\x01" + b"\x00" * 40)  # truncated
    bad = frame(5)
    bad[0, 0, 1] = np.nan
    hio.write(folder / "frame_005.exr", bad)
    return folder, paths


def _outputs(folder):
    return {p.name: p.stat().st_mtime_ns for p in folder.iterdir() if not p.name.startswith(".")}


def test_skip_on_error_resume_and_exit_codes(frames, tmp_path, capsys):
    folder, good = frames
    out = tmp_path / "out"
    argv = ["batch", str(folder / "frame_*.exr"), "-o", str(out), "--batch-size", "4", "-q"]
    # two bad frames: reported (each by name), the four others written, exit status 1
    assert main(argv) == 1
    cap = capsys.readouterr()
    assert "4 done, 0 skipped, 2 failed" in cap.out
    assert "frame_004.exr" in cap.err and "frame_005.exr" in cap.err and "NaN" in cap.err
    first = _outputs(out)
    assert sorted(first) == [f"frame_{i:03d}.png" for i in range(4)]

    # resume: only the missing output is made again, the others are not touched
    os.remove(out / "frame_002.png")
    assert main(argv) == 1
    assert "1 done, 3 skipped, 2 failed" in capsys.readouterr().out
    second = _outputs(out)
    assert sorted(second) == sorted(first)
    assert all(second[k] == first[k] for k in first if k != "frame_002.png")

    # bad frames gone: nothing left to do, exit status 0
    os.remove(folder / "frame_004.exr")
    os.remove(folder / "frame_005.exr")
    assert main(argv) == 0
    assert "0 done, 4 skipped, 0 failed" in capsys.readouterr().out

    # --no-resume rewrites; --allow-nan would render the NaN frame (checked in the API tests)
    assert main([*argv, "--no-resume"]) == 0
    assert "4 done, 0 skipped" in capsys.readouterr().out


def test_compression_level_changes_bytes_not_pixels(frames, tmp_path):
    from PIL import Image

    folder, good = frames
    sizes, pixels = {}, {}
    for level in ("0", "9"):
        out = tmp_path / f"out{level}"
        argv = ["batch", *map(str, good[:2]), "-o", str(out), "--zlib-level", level, "-q"]
        assert main(argv) == 0
        with Image.open(out / "frame_000.png") as im:
            pixels[level] = np.asarray(im)
        sizes[level] = (out / "frame_000.png").stat().st_size
    np.testing.assert_array_equal(pixels["0"], pixels["9"])
    # stored (level 0) holds the raw rows: 3 bytes per pixel plus a filter byte per row
    h, w, _ = pixels["0"].shape
    assert sizes["0"] > h * (3 * w + 1) > sizes["9"]


@pytest.mark.parametrize(
    "extra,needle",
    [
        (["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "--workers"),
        (["--method", "nosuch"], "unknown operator"),
        (["--format", "jpg", "--bits", "16"], "--bits 16"),
        (["--median", "4"], "odd"),
        (["--zlib-level", "12"], "--zlib-level"),
        (["--same-parameters", "--smooth"], "not allowed"),
    ],
)
def test_usage_errors_exit_2(frames, tmp_path, capsys, extra, needle):
    folder, _ = frames
    argv = ["batch", str(folder / "*.exr"), "-o", str(tmp_path / "o"), *extra]
    try:
        code = main(argv)
    except SystemExit as e:  # argparse's own usage errors
        code = e.code
    assert code == 2
    assert needle in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_process_exit_status_and_explicit_file_list(frames, tmp_path):
    # the real process: explicit files (no pattern), one of them unreadable -> status 1
    folder, good = frames
    out = tmp_path / "o"
    cmd = [sys.executable, "-m", "hdrjax", "batch", str(good[0]), str(folder / "frame_004.exr")]
    cmd += ["-o", str(out), "--batch-size", "4", "--format", "exr"]
    env = dict(os.environ, HDRJAX_CACHE="0")
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=REPO, env=env, timeout=120)
    assert r.returncode == 1, r.stderr
    assert "1 done, 0 skipped, 1 failed" in r.stdout and "frame_004.exr" in r.stderr
    assert [p.name for p in out.iterdir()] == ["frame_000.exr"]


def test_pattern_matching_nothing_is_a_data_error(tmp_path, capsys):
    assert main(["batch", str(tmp_path / "none_*.exr"), "-o", str(tmp_path / "o")]) == 1
    assert "none_*.exr: no file matches" in capsys.readouterr().err
