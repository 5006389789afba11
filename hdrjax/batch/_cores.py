"""Each worker process of a local Dask cluster on its own cores.

XLA:CPU sizes its thread pool to the cores a process may run on. Worker processes that each
may run on every core make several such pools share them, and then each computation waits
for threads descheduled by the others: on 2 cores, two processes running mantiuk2008's
solver (many small steps, each handing work to the pool) took over 6 min each, against 13 s
each with one core apiece, while a busy process that is not XLA's costs only its share.
So the cores this process may use are split into one disjoint group per worker (whole
groups of ``cores // workers``; with more workers than cores, workers share single cores in
turn), and each worker is pinned to its group right after the cluster starts, before its
first task.
"""

import os

from distributed import WorkerPlugin


def core_groups(cores: list[int], workers: int) -> list[list[int]]:
    """``workers`` groups of ``cores``: disjoint and equal while there are enough cores."""
    if workers <= len(cores):
        per = len(cores) // workers
        return [cores[i * per : (i + 1) * per] for i in range(workers)]
    return [[cores[i % len(cores)]] for i in range(workers)]


class OwnCores(WorkerPlugin):
    """Pins worker ``k`` (LocalCluster names them 0, 1, …) to ``groups[k]``."""

    name = "hdrjax-own-cores"

    def __init__(self, groups: list[list[int]]):
        self.groups = groups

    def setup(self, worker) -> None:
        try:
            k = int(worker.name)
        except (TypeError, ValueError):  # a worker this cluster did not name
            return
        os.sched_setaffinity(0, self.groups[k % len(self.groups)])


class TunedMemory(WorkerPlugin):
    """Runs :func:`hdrjax.tune_memory` in each worker before its first task, as the
    command line does in its own process."""

    name = "hdrjax-tuned-memory"

    def setup(self, worker) -> None:
        from .._memory import tune_memory

        tune_memory()


def tune_workers(client) -> None:
    """Register :class:`TunedMemory` when this process is tuned (its JAX dispatch is
    synchronous: :func:`hdrjax.tune_memory` ran here)."""
    import jax

    if not jax.config.read("jax_cpu_enable_async_dispatch"):
        client.register_plugin(TunedMemory())


def pin_workers(client, workers: int) -> None:
    """Register :class:`OwnCores` for a new local cluster of ``workers`` processes (where the
    platform lets a process choose its cores, and there are several workers)."""
    if workers < 2 or not hasattr(os, "sched_setaffinity"):
        return
    cores = sorted(os.sched_getaffinity(0))
    client.register_plugin(OwnCores(core_groups(cores, workers)))


__all__ = ["OwnCores", "TunedMemory", "core_groups", "pin_workers", "tune_workers"]
