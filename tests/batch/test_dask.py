"""Dask execution: a LocalCluster of 2 worker processes on loopback gives the same bytes as
the in-process path, and a worker killed mid-run loses no frame (the scheduler re-runs its
tasks)."""

import json
import logging
import os
import signal
import subprocess
import sys
import threading
import time

import jax
import pytest

from hdrjax import batch

from ._frames import write_sequence

distributed = pytest.importorskip("distributed")

N = 12


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    return write_sequence(tmp_path_factory.mktemp("frames"), N)


@pytest.fixture(scope="module")
def reference(frames, compile_cache, tmp_path_factory):
    """In-process outputs (per-frame and same-parameters), the bytes Dask must reproduce."""
    out = tmp_path_factory.mktemp("ref")
    pipe = batch.Pipeline("reinhard2002")
    s1 = batch.run(frames, pipe, out / "per", batch_size=2, progress=False)
    s2 = batch.run(frames, pipe, out / "same", parameters="same", batch_size=4, progress=False)
    assert len(s1.done) == N and len(s2.done) == N
    return out


@pytest.fixture(scope="module")
def compile_cache(tmp_path_factory):
    """A persistent XLA cache shared by this process and the workers (compile once)."""
    path = str(tmp_path_factory.mktemp("xla"))
    old = (jax.config.jax_compilation_cache_dir, os.environ.get("JAX_COMPILATION_CACHE_DIR"))
    jax.config.update("jax_compilation_cache_dir", path)
    os.environ["JAX_COMPILATION_CACHE_DIR"] = path
    yield path
    jax.config.update("jax_compilation_cache_dir", old[0])
    if old[1] is None:
        os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)
    else:
        os.environ["JAX_COMPILATION_CACHE_DIR"] = old[1]


@pytest.fixture(scope="module")
def cluster(compile_cache):
    logging.getLogger("distributed").setLevel(logging.ERROR)
    cl = distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=":0",
        silence_logs=logging.CRITICAL,
    )
    client = distributed.Client(cl)
    yield cl, client
    client.close()
    cl.close()


def _bytes(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if not p.name.startswith(".")}


def test_dask_outputs_equal_in_process(frames, reference, cluster, tmp_path, capsys):
    _, client = cluster
    pipe = batch.Pipeline("reinhard2002")
    # chunks of 4 on two workers vs. the in-process batches: the same bytes
    s = batch.run(
        frames,
        pipe,
        tmp_path / "same",
        parameters="same",
        batch_size=4,
        scheduler=client,
        progress=True,
    )
    assert len(s.done) == N and not s.failed
    # the dashboard's address is shown (bokeh comes with the [dask] extra): it answers
    err = capsys.readouterr().err
    link = client.dashboard_link
    assert f"hdrjax batch: Dask dashboard: {link}" in err
    import urllib.request

    with urllib.request.urlopen(link, timeout=10) as page:
        assert page.status == 200
    ref = _bytes(reference / "same")
    assert len(ref) == N
    assert _bytes(tmp_path / "same") == ref


def test_killed_worker_loses_no_frame(frames, reference, cluster, tmp_path):
    _, client = cluster
    out = tmp_path / "per"
    pids = client.run(os.getpid)  # worker address -> pid
    lost: list = []

    def kill_a_busy_worker():
        # once the first output exists, kill a worker that is running a task at that moment
        t_end = time.monotonic() + 60
        while time.monotonic() < t_end and not lost:
            if out.is_dir() and any(p.suffix == ".png" for p in out.iterdir()):
                busy = [a for a, keys in client.processing().items() if keys and a in pids]
                if busy:
                    lost.append(client.processing()[busy[0]])
                    os.kill(pids[busy[0]], signal.SIGKILL)
                    return
            time.sleep(0.005)

    watcher = threading.Thread(target=kill_a_busy_worker, daemon=True)
    watcher.start()
    # two frames per task, six tasks: the victim still has work when it dies
    s = batch.run(
        frames,
        batch.Pipeline("reinhard2002"),
        out,
        batch_size=2,
        scheduler=client,
        progress=False,
    )
    watcher.join(timeout=5)
    assert lost and len(lost[0]) >= 1  # the killed worker was running a task
    assert len(s.done) == N and not s.failed
    assert _bytes(out) == _bytes(reference / "per")
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temp file left


def test_core_groups_are_disjoint_while_there_are_enough_cores():
    from hdrjax.batch._cores import core_groups

    assert core_groups([0, 1, 2, 3], 2) == [[0, 1], [2, 3]]
    assert core_groups([0, 1, 2, 3, 4], 2) == [[0, 1], [2, 3]]
    assert core_groups([4, 7], 2) == [[4], [7]]
    assert core_groups([0, 1], 3) == [[0], [1], [0]]


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="no CPU affinity here")
def test_local_workers_each_run_on_their_own_cores():
    """``batch.run(workers=N)``'s cluster pins each worker process to its own cores (XLA
    processes sharing cores slow each other many times over: hdrjax/batch/_cores.py)."""
    from hdrjax.batch._run import _client

    from ..conftest import CORES

    mine, cores = os.sched_getaffinity(0), list(CORES)
    if len(cores) < 2:
        pytest.skip("one core: nothing to split")
    os.sched_setaffinity(0, cores)  # as a user's process (the test worker has one core)
    try:
        client, cluster, _ = _client(2, None)
    finally:
        os.sched_setaffinity(0, mine)
    try:
        got = sorted(sorted(s) for s in client.run(lambda: os.sched_getaffinity(0)).values())
    finally:
        client.close()
        cluster.close()
    half = len(cores) // 2
    assert got == [cores[:half], cores[half : 2 * half]]


def test_workers_of_a_tuned_process_are_tuned():
    """A cluster started by a process that ran ``hdrjax.tune_memory`` (the command line
    does) tunes its workers too: synchronous JAX dispatch, freed buffers kept."""
    code = """
import json, hdrjax
hdrjax.tune_memory()
from hdrjax.batch._run import _client
client, cluster, _ = _client(1, None)
try:
    import jax
    got = client.run(lambda: jax.config.read("jax_cpu_enable_async_dispatch"))
finally:
    client.close()
    cluster.close()
print(json.dumps(sorted(got.values())))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [False]
