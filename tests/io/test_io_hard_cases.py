"""Hard cases for the readers: concurrent EXR reads and the process's output, files whose
header promises less (or more) than the file holds, pipes instead of files, and Radiance
exposure values at the edges of float32.
"""

import os
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import hdrjax.io as hio
from hdrjax.cli import main
from hdrjax.io import ReadError

from ..conftest import REPO

ENV = dict(os.environ, HDRJAX_CACHE="0")


def _run_python(code: str, *args: str, cwd=REPO) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-c", textwrap.dedent(code), *args]
    return subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, env=ENV, timeout=120)


# -- EXR reads in threads keep the process's output ------------------------------------


def test_concurrent_exr_reads_keep_stdout_and_stderr(tmp_path):
    """Two threads reading EXRs (good and truncated ones) while the main thread prints, as
    the batch command does: every line printed during and after the reads arrives, on
    stdout and on stderr, and the truncated files are reported without library noise."""
    rng = np.random.default_rng(0)
    good = hio.write(tmp_path / "good.exr", rng.random((8, 8, 3)).astype(np.float32))
    data = good.read_bytes()
    (tmp_path / "trunc.exr").write_bytes(data[: len(data) - 40])
    code = """
        import sys, threading, time
        import hdrjax.io as hio
        from hdrjax.io import ReadError
        good, trunc = sys.argv[1], sys.argv[2]
        errors = []
        def work():
            for i in range(40):
                try:
                    hio.read(trunc if i % 2 else good, sidecars=False)
                except ReadError as e:
                    errors.append(str(e))
        threads = [threading.Thread(target=work) for _ in range(2)]
        for t in threads:
            t.start()
        i = 0
        while any(t.is_alive() for t in threads):
            print(f"progress {i}", flush=True)
            print(f"status {i}", file=sys.stderr, flush=True)
            i += 1
            time.sleep(0.002)
        for t in threads:
            t.join()
        print(f"summary out {len(errors)} {i}", flush=True)
        print("summary err", file=sys.stderr, flush=True)
        print(errors[0], file=sys.stderr, flush=True)
    """
    r = _run_python(code, str(good), str(tmp_path / "trunc.exr"), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    out, err = r.stdout.splitlines(), r.stderr.splitlines()
    summary = [ln for ln in out if ln.startswith("summary out")]
    assert len(summary) == 1, r.stdout[-2000:]
    n_errors, n_lines = (int(v) for v in summary[0].split()[2:])
    assert n_errors == 40  # every truncated read failed, none succeeded as garbage
    assert [ln for ln in out if ln.startswith("progress")] == [
        f"progress {i}" for i in range(n_lines)
    ]
    assert [ln for ln in err if ln.startswith("status")] == [f"status {i}" for i in range(n_lines)]
    assert "summary err" in err
    assert err[-1].startswith("trunc.exr: corrupt or truncated OpenEXR file (EXR_ERR_")
    # the library's own messages never reached the terminal
    assert "Warning" not in r.stdout and "EXR_ERR" not in r.stderr.replace(err[-1], "")


# -- a small header on a huge file: read the header first ------------------------------

_PIXELS = np.array([[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], [[0.5, 0.25, 8.0], [16.0, 32.0, 64.0]]])


def _radiance(rgb: np.ndarray, *, rle: bool) -> bytes:
    from hdrjax.io import _rgbe

    return _rgbe.encode_rgbe(rgb, rle=rle)


@pytest.mark.parametrize("kind", ["pfm", "hdr flat", "hdr rle"])
def test_huge_trailing_data_is_not_read(tmp_path, kind):
    """A 2-row image followed by 6 GiB (sparse) of padding reads its pixels without
    reading the padding (pfstools' pfsinpfm and Radiance's readers stop after the image
    too): peak memory stays small. A bound on memory is what the defect was about (the
    whole file was read first: 2.8 GB for 2.5 GiB, MemoryError at 6 GiB)."""
    import tracemalloc

    if kind == "pfm":
        rgb = _PIXELS.astype(np.float32)
        p = hio.write(tmp_path / "pad.pfm", rgb)
    else:
        rle = kind == "hdr rle"
        rgb = np.tile(_PIXELS, (1, 5, 1)).astype(np.float32)  # 10 wide: RLE needs >= 8
        p = tmp_path / "pad.hdr"
        p.write_bytes(_radiance(rgb, rle=rle))
        assert (p.read_bytes().find(b"\n\x02\x02\x00\x0a") > 0) == rle
    want = hio.read(p).image
    with open(p, "r+b") as f:
        f.truncate(6 * 2**30)
    try:
        tracemalloc.start()
        got = hio.read(p, sidecars=False).image
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
        p.unlink()
    np.testing.assert_array_equal(got, want)
    np.testing.assert_allclose(got[:, :2], _PIXELS, rtol=0.01)  # RGBE keeps 8-bit mantissas
    assert peak < 50 * 2**20, peak


@pytest.mark.parametrize("suffix", [".pfm", ".hdr"])
def test_header_larger_than_file_is_refused_before_reading(tmp_path, suffix):
    """A header declaring more pixel data than a (6 GiB, sparse) file holds: ReadError
    naming the file, without allocating the declared size."""
    import tracemalloc

    p = tmp_path / f"big{suffix}"
    if suffix == ".pfm":
        p.write_bytes(b"PF\n60000 60000\n-1.0\n")  # 43 GB of floats declared
    else:
        # even run-length encoded, 10^6 scanlines of 10^6 pixels take over 60 GB
        p.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1000000 +X 1000000\n")
    with open(p, "r+b") as f:
        f.truncate(6 * 2**30)
    try:
        tracemalloc.start()
        with pytest.raises(ReadError, match=f"^big{suffix}: truncated"):
            hio.read(p, sidecars=False)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
        p.unlink()
    assert peak < 50 * 2**20, peak


# -- Radiance EXPOSURE at the edges of float32 -----------------------------------------


def _with_header_line(rgb: np.ndarray, line: str) -> bytes:
    data = _radiance(rgb, rle=False)
    return data.replace(b"FORMAT=", line.encode() + b"\nFORMAT=", 1)


@pytest.mark.parametrize(
    "line", ["EXPOSURE=1e-45", "EXPOSURE=1e300", "EXPOSURE=1e-30\nEXPOSURE=1e-30"]
)
def test_exposure_outside_float32_is_refused(tmp_path, line):
    p = tmp_path / "exp.hdr"
    p.write_bytes(_with_header_line(_PIXELS.astype(np.float32), line))
    value = {"EXPOSURE=1e-45": "1e-45", "EXPOSURE=1e300": "1e+300"}.get(line, "1e-60")
    pattern = rf"^exp\.hdr: unusable Radiance EXPOSURE .* {re.escape(value)};"
    with pytest.raises(ReadError, match=pattern):
        hio.read(p)


def test_small_exposure_saturates_instead_of_overflowing(tmp_path):
    """The largest RGBE value (mantissa 255, exponent 255: 1.7e38) divided by EXPOSURE=0.25
    exceeds float32: it saturates at the largest float32; other pixels are divided."""
    from hdrjax.io import _rgbe

    head = b"#?RADIANCE\nEXPOSURE=0.25\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n"
    px = bytes([255, 255, 128, 255, 128, 64, 0, 129])  # second pixel: 1.0, 0.5, 0 (x 1/0.25)
    p = tmp_path / "max.hdr"
    p.write_bytes(head + px)
    got = hio.read(p).image
    f32max = np.finfo(np.float32).max
    assert np.all(np.isfinite(got))
    np.testing.assert_array_equal(got[0, 0, :2], [f32max, f32max])
    np.testing.assert_allclose(got[0, 0, 2], 128 * 2.0**119 / 0.25, rtol=1e-6)
    np.testing.assert_array_equal(got[0, 1], [4.0, 2.0, 0.0])
    raw, _ = _rgbe.decode_rgbe_float(head + px)  # without the exposure: finite, unclamped
    np.testing.assert_allclose(raw[0, 0, 0], 255 * 2.0**119, rtol=1e-6)


# -- pipes and standard input ----------------------------------------------------------


def test_read_from_a_pipe_and_dev_stdin(tmp_path):
    """``read('-')`` and ``read('/dev/stdin')`` with a pipe on standard input: the bytes
    are read once, sniffed and decoded (the sniffer used to consume them first)."""
    rgb = np.random.default_rng(3).random((4, 9, 3)).astype(np.float32)
    files = [hio.write(tmp_path / f"p.{ext}", rgb) for ext in ("hdr", "pfm", "exr")]
    code = """
        import sys, numpy as np, hdrjax.io as hio
        img = hio.read(sys.argv[1])
        np.save(sys.argv[2], img.image)
        print(img.name)
    """
    for f, arg in zip(files, ("-", "/dev/stdin", "-"), strict=True):
        out = tmp_path / "got.npy"
        cmd = [sys.executable, "-c", textwrap.dedent(code), arg, str(out)]
        r = subprocess.run(cmd, input=f.read_bytes(), capture_output=True, env=ENV)
        assert r.returncode == 0, r.stderr.decode()
        np.testing.assert_array_equal(np.load(out), hio.read(f).image)
        assert r.stdout.decode().strip() == ("<stdin>" if arg == "-" else "stdin")


def _hdrjax(*args: str, stdin: bytes | None = None) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "hdrjax", *args]
    return subprocess.run(cmd, input=stdin, capture_output=True, cwd=REPO, env=ENV, timeout=300)


def test_cli_layers_and_tonemap_through_pipes(tmp_path):
    """``hdrjax layers -`` reads standard input; ``hdrjax tonemap - -o - --format png``
    writes the same PNG as with files, and its status text goes to standard error."""
    from PIL import Image

    rgb = np.random.default_rng(4).random((6, 10, 3)).astype(np.float32) * 50
    src = hio.write(tmp_path / "in.hdr", rgb)
    # `layers` rather than `info`: the same reading path, without `info`'s many compiles
    r = _hdrjax("layers", "-", stdin=src.read_bytes())
    assert r.returncode == 0, r.stderr.decode()
    assert "image: 10 x 6, channels R, G, B" in r.stdout.decode()
    piped = _hdrjax("tonemap", "-", "-o", "-", "--format", "png", stdin=src.read_bytes())
    assert piped.returncode == 0, piped.stderr.decode()
    assert "wrote: -" in piped.stderr.decode() and "operator: reinhard2002" in piped.stderr.decode()
    ref = tmp_path / "ref.png"
    assert main(["tonemap", str(src), "-o", str(ref)]) == 0
    assert piped.stdout[:8] == b"\x89PNG\r\n\x1a\n"
    (tmp_path / "piped.png").write_bytes(piped.stdout)
    a = np.asarray(Image.open(tmp_path / "piped.png"))
    assert a.shape == (6, 10, 3)
    np.testing.assert_array_equal(a, np.asarray(Image.open(ref)))
    # no format for standard output: a usage error, and nothing written to it
    r = _hdrjax("tonemap", "-", "-o", "-", stdin=src.read_bytes())
    assert r.returncode == 2 and r.stdout == b""
    assert "-o -: give --format (png, hdr, pfm)" in r.stderr.decode()
