"""Ctrl-C stops a long ``hdrjax filter`` within a second, with exit status 130, one line on
standard error and no output or temporary file left; its progress bar shows on a terminal.

The command runs in a child process whose standard error is a pseudo-terminal (so the
progress bar is drawn, which tells the test that filtering has begun) and receives a real
SIGINT. The filter is sized so that the tiles after the first (which compiles) take
seconds: a command that waited for them would miss the one-second bound."""

import fcntl
import os
import pty
import select
import signal
import struct
import subprocess
import sys
import termios
import time

import numpy as np
import pytest

from hdrjax import io as hio

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals and terminals")

BOUND_S = 1.0
"""Longest time from SIGINT to the end of the process."""

# the command line's entry point, with Python's own SIGINT handler even where the test
# runner ignores SIGINT (children inherit an ignored signal)
ENTRY = (
    "import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
    "from hdrjax.cli import main; sys.exit(main())"
)


def _read(fd, until: bytes, timeout: float) -> bytes:
    got, end = b"", time.monotonic() + timeout
    while until not in got and time.monotonic() < end:
        ready, _, _ = select.select([fd], [], [], 0.1)
        if ready:
            try:
                got += os.read(fd, 4096)
            except OSError:  # the child closed the terminal: it has ended
                break
    return got


def test_filter_stops_within_a_second_of_ctrl_c(tmp_path):
    src, out = tmp_path / "big.pfm", tmp_path / "out.pfm"
    rng = np.random.default_rng(0)
    hio.write(src, rng.uniform(0.1, 4.0, (1536, 1536, 3)).astype(np.float32))
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))
    argv = ["filter", str(src), "-o", str(out), "--median", "5", "--passes", "40"]
    proc = subprocess.Popen(
        [sys.executable, "-c", ENTRY, *argv],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=slave,
        cwd=tmp_path,
    )
    os.close(slave)
    try:
        shown = _read(master, b"tile", timeout=60)
        assert b"tile" in shown, f"no progress bar on the terminal: {shown!r}"
        assert proc.poll() is None, "the filter ended before it could be interrupted"
        proc.send_signal(signal.SIGINT)
        sent = time.monotonic()
        code = proc.wait(timeout=30)
        took = time.monotonic() - sent
        err = _read(master, b"interrupted\r\n", timeout=1)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(master)
    assert code == 130
    assert took < BOUND_S, f"ended {took:.2f} s after SIGINT"
    assert err.strip().endswith(b"hdrjax filter: interrupted"), err
    assert sorted(os.listdir(tmp_path)) == ["big.pfm"]  # no output, no temporary file
