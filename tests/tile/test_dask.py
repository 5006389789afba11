"""``dask.array.map_overlap`` (on a 2-process LocalCluster) gives the whole-image results.

References: the whole-image filters (bit for bit), the in-process first pass (itself
checked against :func:`hdrjax._stats.measure` in test_stats.py) and the whole-image
Reinhard 2002 operator (``RTOL32``).
"""

import logging

import dask
import dask.array as da
import numpy as np
import pytest

import hdrjax.tile as T
from hdrjax.filters import mean_filter, median_filter
from hdrjax.operators import Reinhard2002

from ..conftest import RTOL32
from ._images import crop


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")  # part of dask[distributed], a dev dep
    for name in ("distributed", "distributed.worker", "distributed.scheduler"):
        logging.getLogger(name).setLevel(logging.CRITICAL)
    with (
        distributed.LocalCluster(
            n_workers=2,
            processes=True,
            threads_per_worker=1,
            dashboard_address=None,
            silence_logs=logging.CRITICAL,
        ) as lc,
        distributed.Client(lc) as client,
    ):
        yield client


@pytest.fixture(scope="module")
def image():
    # 2×2 chunks of 128×96: every chunk touches two image edges, so all overlap windows
    # have one shape (one compilation per worker)
    x = crop(256, 192)
    return x, da.from_array(x, chunks=(128, 96, 3))


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and np.array_equal(a.view(np.uint32), b.view(np.uint32))


def test_median_and_mean_bit_identical(cluster, image):
    x, d = image
    med = T.to_dask(T.Median(3), d)
    mean = T.to_dask(T.Mean(3, mode="reflect"), d)
    got_med, got_mean = dask.compute(med, mean)
    assert _same(got_med, median_filter(x, 3))
    assert _same(got_mean, mean_filter(x, 3, mode="reflect"))


def test_statistics_and_reinhard_threaded_scheduler(image):
    # dask's threads: the first pass over the chunks equals the in-process one over tiles
    # of the chunks' size bit for bit (same blocks, same order), which test_stats.py checks
    # against measure; Reinhard's key and white come from it
    x, d = image
    with dask.config.set(scheduler="threads"):
        st = T.dask_statistics(d)
        op_st = T.dask_operator_statistics(Reinhard2002(), d)  # the chunks' Statistics, merged
        got = np.asarray(T.to_dask(T.Tonemap(Reinhard2002()), d, stats=op_st).compute())
    ref = T.statistics(x, tile=(128, 96))
    for name, v in vars(ref).items():
        assert np.asarray(getattr(st, name)) == np.asarray(v), name
    want = np.asarray(Reinhard2002()(x))
    ok = ~np.isnan(want)
    assert np.array_equal(np.isnan(got), ~ok)
    np.testing.assert_allclose(got[ok], want[ok], rtol=RTOL32, atol=1e-7)


def _compiled_block_statistics() -> int:
    from hdrjax.tile._stats import block_statistics

    return block_statistics._cache_size()


def test_uneven_chunks_on_the_cluster_compile_once_per_worker(cluster, image):
    # chunks of 100×80 leave edge chunks of 56 rows and 32 columns: padded with NaN to one
    # shape in the worker, as the in-process tiles are, so the merged statistics are the
    # same bit for bit, and each worker compiles the chunk statistics once (the function
    # travels by reference: sent by value, it arrived with an empty cache every chunk)
    x, _ = image
    d = da.from_array(x, chunks=(100, 80, 3))
    st = T.dask_statistics(d)
    ref = T.statistics(x, tile=(100, 80))
    for name, v in vars(ref).items():
        assert np.asarray(getattr(st, name)) == np.asarray(v), name
    compiled = cluster.run(_compiled_block_statistics)
    # (a worker that got no chunk compiled nothing)
    assert all(n <= 1 for n in compiled.values()) and sum(compiled.values()) >= 1, compiled
