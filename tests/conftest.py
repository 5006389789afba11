"""Test configuration: strict rank promotion, named tolerances, data locations."""

import contextlib
import os
from pathlib import Path


def _pin_test_worker() -> None:
    """One core per pytest-xdist worker when there are as many workers as cores: XLA:CPU
    processes whose thread pools share cores slow each other down many times over (two
    workers running mantiuk2008's solver took 6 min each, against 13 s each when pinned;
    a busy non-XLA process next to it costs only its share). Subprocesses inherit it."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    count = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "0") or 0)
    if not (worker.startswith("gw") and hasattr(os, "sched_setaffinity")):
        return
    cores = sorted(os.sched_getaffinity(0))
    if 1 < count <= len(cores):
        os.sched_setaffinity(0, {cores[int(worker[2:]) % len(cores)]})


_pin_test_worker()

import jax  # noqa: E402
import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402

jax.config.update("jax_numpy_rank_promotion", "raise")

# CI runs the same examples every time (a failure is reproducible from the log);
# HYPOTHESIS_PROFILE=explore searches afresh.
settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("explore", max_examples=500)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

REPO = Path(__file__).resolve().parents[1]
DATA = REPO / "data"
SHARED_HDR = REPO.parent / "shared" / "data" / "hdr"

RTOL32 = 1e-4
RTOL64 = 1e-6


def shared_file(name: str) -> Path:
    """A file from ../shared/data/hdr; the test is skipped (reported) when it is absent."""
    p = SHARED_HDR / name
    if not p.exists():
        pytest.skip(f"{p} not available (only in the development checkout)")
    return p


@contextlib.contextmanager
def enable_x64(on: bool = True):
    """Context manager: float64 on (or off) inside the block."""
    old = jax.config.jax_enable_x64
    jax.config.update("jax_enable_x64", on)
    try:
        yield
    finally:
        jax.config.update("jax_enable_x64", old)


@pytest.fixture
def x64():
    """Enable float64 for the duration of a test."""
    with enable_x64():
        yield


os.environ.setdefault("HDRJAX_CACHE", "0")


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """Drop the compiled programs after each test file: a test worker runs whole files in
    sequence, and one that kept every executable of hundreds of files (several GB, each
    with its own code mappings) crashed inside an XLA:CPU compile late in two full runs
    (keeping them until a worker held 2 GiB showed no gain in one full run)."""
    yield
    jax.clear_caches()
