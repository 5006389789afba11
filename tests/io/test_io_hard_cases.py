"""Hard cases for the readers: concurrent EXR reads and the process's output, files whose
header promises less (or more) than the file holds, pipes instead of files, and Radiance
exposure values at the edges of float32.
"""

import os
import subprocess
import sys
import textwrap

import numpy as np

import hdrjax.io as hio

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
