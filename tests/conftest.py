"""Test configuration: strict rank promotion, named tolerances, data locations."""

import contextlib
import os
from pathlib import Path

CORES = tuple(sorted(os.sched_getaffinity(0))) if hasattr(os, "sched_getaffinity") else ()
"""The cores this test run may use (before a worker is pinned to one of them)."""


def _pin_test_worker() -> None:
    """One core per pytest-xdist worker when there are as many workers as cores: XLA:CPU
    processes whose thread pools share cores slow each other down many times over (two
    workers running mantiuk2008's solver took 6 min each, against 13 s each when pinned;
    a busy non-XLA process next to it costs only its share). Subprocesses inherit it."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    count = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "0") or 0)
    if not (worker.startswith("gw") and hasattr(os, "sched_setaffinity")):
        return
    cores = CORES
    if 1 < count <= len(cores):
        os.sched_setaffinity(0, {cores[int(worker[2:]) % len(cores)]})


_pin_test_worker()


def _share_compiled_programs() -> None:
    """One persistent XLA cache for the whole run (its workers and the command-line
    subprocesses of its tests), in a temporary folder the first process makes: a program
    compiled by one test file is read back by the next that needs it instead of compiled
    again (a quarter of the programs a full run asks for), and nothing outlives the run."""
    if "JAX_COMPILATION_CACHE_DIR" in os.environ:  # set by the user, or by the controller
        return
    import tempfile

    os.environ["JAX_COMPILATION_CACHE_DIR"] = tempfile.mkdtemp(prefix="hdrjax-test-xla-")
    os.environ["HDRJAX_TEST_OWN_CACHE"] = os.environ["JAX_COMPILATION_CACHE_DIR"]
    # every program: the suite's are small and compiled once each
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES", "0")


_share_compiled_programs()

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


def pytest_unconfigure(config):
    """The run's XLA cache goes with the process that made it (the controller)."""
    own = os.environ.get("HDRJAX_TEST_OWN_CACHE")
    if own and not os.environ.get("PYTEST_XDIST_WORKER"):
        import shutil

        shutil.rmtree(own, ignore_errors=True)
