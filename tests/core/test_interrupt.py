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


# the filter command with its tiles replaced by a call that stays in C for minutes (as XLA
# does while it compiles for a new size, 1-5 s) inside a temporary output file
BLOCKED = """
import hashlib, signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)
import hdrjax.tile
from hdrjax.io import atomic_path

def blocked(step, image, **kw):
    with atomic_path("partial.pfm") as tmp:
        tmp.write_bytes(b"half")
        print("blocked", flush=True)
        hashlib.pbkdf2_hmac("sha256", b"key", b"salt", 10**9)  # releases the GIL
    raise AssertionError("not interrupted")

hdrjax.tile.apply = blocked
from hdrjax.cli import main
sys.exit(main())
"""


def test_ctrl_c_ends_a_command_blocked_outside_python(tmp_path):
    """Ctrl-C while the main thread is inside C (XLA compiling the first tile): the
    process still ends within a second, status 130, one line, its temporary file gone."""
    src = tmp_path / "small.pfm"
    hio.write(src, np.ones((8, 8, 3), np.float32))
    argv = ["filter", str(src), "-o", str(tmp_path / "out.pfm"), "--median", "3"]
    proc = subprocess.Popen(
        [sys.executable, "-c", BLOCKED, *argv],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=tmp_path,
    )
    try:
        assert proc.stdout.readline() == b"blocked\n"
        assert [p.name for p in tmp_path.glob(".partial.pfm.*.tmp")], "no temporary file"
        time.sleep(0.2)  # well inside the hash
        proc.send_signal(signal.SIGINT)
        sent = time.monotonic()
        code = proc.wait(timeout=30)
        took = time.monotonic() - sent
        err = proc.stderr.read().decode()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert code == 130, err
    assert took < BOUND_S, f"ended {took:.2f} s after SIGINT"
    assert err.strip().splitlines() == ["hdrjax filter: interrupted"], err
    assert sorted(os.listdir(tmp_path)) == ["small.pfm"]  # no output, no temporary file
