"""Ctrl-C ends a command within a second, wherever its main thread is.

Python raises ``KeyboardInterrupt`` only when the main thread runs Python code again. A
thread inside XLA (compiling a program for a new image size, 1–5 s; a long computation)
sees the signal only when that returns, so the command would keep running for seconds
after Ctrl-C. :func:`prompt_interrupt` watches for SIGINT from a second thread (Python
writes each caught signal to a wakeup file descriptor, from C, at once). When the main
thread has not started handling the interrupt :data:`GRACE_S` seconds later, the watcher
does what the command's own handler would: it removes the temporary files being written
(those of :func:`hdrjax.io.atomic_path`; finished outputs are complete files,
renamed into place), prints the command's one line and ends the process with status 130.
When the main thread does handle it in time (it was running Python code), nothing changes:
the command's own cleanup runs (``hdrjax batch`` records what it finished).
"""

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator

GRACE_S = 0.3
"""How long the main thread has to start handling Ctrl-C before the watcher ends the
process."""

_REPORTED = threading.Lock()
"""Held by whichever reports the interrupt first (the command's handler or the watcher):
one line, never two."""


def claim_report() -> bool:
    """``True`` for the first caller only: it prints the interrupt's line."""
    return _REPORTED.acquire(blocking=False)


def interrupted_line(command: str) -> str:
    """The line a command prints on Ctrl-C (on a new line where a progress bar was
    drawn on a terminal)."""
    try:
        newline = "\n" if sys.stderr.isatty() else ""
    except (AttributeError, ValueError):
        newline = ""
    return f"{newline}hdrjax {command}: interrupted"


def _end(command: str) -> None:
    atomic = sys.modules.get("hdrjax.io._atomic")  # not imported: nothing is being written
    if atomic is not None:
        atomic.remove_live_temporaries()
    if claim_report():
        with contextlib.suppress(OSError, ValueError):
            print(interrupted_line(command), file=sys.stderr, flush=True)
    with contextlib.suppress(OSError, ValueError):
        sys.stdout.flush()
    os._exit(130)


def _watch(read_fd: int, seen: threading.Event, command: str) -> None:
    while True:
        try:
            data = os.read(read_fd, 64)
        except OSError:
            return
        if not data:  # the command ended: the write end is closed
            return
        if signal.SIGINT in data and not seen.wait(GRACE_S):
            _end(command)
        seen.clear()


@contextlib.contextmanager
def prompt_interrupt(command: str) -> Iterator[None]:
    """Within this block (in the main thread), Ctrl-C ends the process within
    :data:`GRACE_S` seconds even while the main thread is blocked outside Python (module
    docstring). Does nothing where SIGINT is ignored or left to the system's default, or
    outside the main thread."""
    handler = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or not callable(handler):
        yield
        return
    read_fd, write_fd = os.pipe()
    os.set_blocking(write_fd, False)
    seen = threading.Event()

    def on_sigint(signum, frame):
        seen.set()  # the main thread runs Python: the command handles it
        handler(signum, frame)

    old_fd = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
    signal.signal(signal.SIGINT, on_sigint)
    watcher = threading.Thread(
        target=_watch, args=(read_fd, seen, command), name="hdrjax-interrupt", daemon=True
    )
    watcher.start()
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, handler)
        signal.set_wakeup_fd(old_fd)
        os.close(write_fd)
        watcher.join(GRACE_S + 1.0)
        os.close(read_fd)
