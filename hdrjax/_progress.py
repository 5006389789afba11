"""Progress bars where a person watches: a terminal, or a Jupyter notebook.

tqdm's ``auto`` bar draws a widget in a notebook and text on a terminal; it is shown when
standard error is a terminal or the code runs in a Jupyter kernel (where standard error is
a pipe to the front end, not a terminal), and never in pipes, logs and test runs.
"""

import sys
from typing import Any


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


__all__ = ["in_notebook", "interactive", "progress_bar"]
