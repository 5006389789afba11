"""Progress bars where a person watches: a terminal, or a Jupyter notebook.

tqdm's ``auto`` bar draws a widget in a notebook and text on a terminal; it is shown when
standard error is a terminal or the code runs in a Jupyter kernel (where standard error is
a pipe to the front end, not a terminal), and never in pipes, logs and test runs.
"""

import contextlib
import sys
from collections.abc import Iterator
from typing import Any

import numpy as np

DELAY_S = 1.0
"""Seconds a library call (tiles, a fit, a sweep) runs before its bar appears, so that quick
calls draw none."""


def in_notebook() -> bool:
    """Whether this code runs in a Jupyter (IPython) kernel."""
    if "ipykernel" not in sys.modules:
        return False
    shell = getattr(sys.modules.get("IPython"), "get_ipython", lambda: None)()
    return shell is not None and "IPKernelApp" in getattr(shell, "config", {})


def interactive() -> bool:
    """A person is watching: standard error is a terminal, or a notebook shows the output."""
    try:
        tty = sys.stderr.isatty()
    except (AttributeError, ValueError):  # replaced or closed stderr
        tty = False
    return tty or in_notebook()


def progress_bar(iterable: Any = None, *, enabled: bool = True, **kw: Any):
    """``tqdm.auto.tqdm(iterable, **kw)``, shown only when ``enabled`` and
    :func:`interactive`."""
    from tqdm.auto import tqdm

    kw.setdefault("dynamic_ncols", True)
    return tqdm(iterable, disable=not (enabled and interactive()), **kw)


def wait_ready(x: Any) -> Any:
    """``jax.block_until_ready(x)`` that lets Ctrl-C through: the arrays' readiness is
    polled from Python (1 ms, doubling to 20 ms), so a ``KeyboardInterrupt`` is raised
    within 20 ms instead of when a long compiled computation ends (a thread blocked in XLA
    sees no signal). Returns ``x``."""
    import time

    import jax

    for leaf in jax.tree_util.tree_leaves(x):
        pause = 0.001
        while hasattr(leaf, "is_ready") and not leaf.is_ready():
            time.sleep(pause)
            pause = min(2 * pause, 0.02)
    return x


_ACTIVE: list = []
"""The bars that :func:`tick` advances from compiled code, innermost last."""


@contextlib.contextmanager
def compiled_progress(enabled: bool = True, **kw: Any) -> Iterator[bool]:
    """A progress bar advanced from inside compiled code (a fit's steps, a sweep's points).

    Yields whether a person watches (``enabled`` and :func:`interactive`; a caller passes
    ``enabled=False`` when traced by an enclosing ``jit``): the code to compile then calls
    :func:`tick` where one unit of work ends; otherwise it compiles without callbacks,
    unchanged. The caller waits for its result inside the block (:func:`wait_ready`); the
    bar is closed once every callback has run. ``kw``: :func:`progress_bar`'s (``total``,
    ``unit``, ``desc``; ``delay`` defaults to :data:`DELAY_S`)."""
    import jax

    if not (enabled and interactive()):
        yield False
        return
    kw.setdefault("delay", DELAY_S)
    bar = progress_bar(**kw)
    _ACTIVE.append(bar)
    try:
        yield True
        jax.effects_barrier()
    finally:
        _ACTIVE.remove(bar)
        bar.close()


def _advance(x: Any) -> None:
    if _ACTIVE:
        _ACTIVE[-1].update(int(np.size(x)))


def tick(x: Any) -> None:
    """In traced code: advance the bar of :func:`compiled_progress` by ``x``'s size when
    this point of the computation runs (once per element under ``vmap``/``lax.map``)."""
    import jax

    jax.debug.callback(_advance, x)


__all__ = [
    "DELAY_S",
    "compiled_progress",
    "in_notebook",
    "interactive",
    "progress_bar",
    "tick",
    "wait_ready",
]
