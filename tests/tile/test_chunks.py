"""Shape-independent execution (``hdrjax.tile.tonemap_chunked``): the pixels of any image in
chunks of one fixed shape, so that one compiled program serves every image size. The
results equal the whole-image operator whatever the chunk size, and a new image size
compiles nothing (in the library, the command line and batches)."""

import contextlib
import math

import jax
import jax.monitoring
import numpy as np
import pytest

import hdrjax
from hdrjax import batch, spaces
from hdrjax.io import read, write
from hdrjax.operators import apply_in_space, measure_in_space
from hdrjax.tile import chunkable, measure_chunked, statistics_chunked, tonemap_chunked

from .._png import decode_png
from ..conftest import DATA
from ..operators.cases import make, natural

NAMES = hdrjax.operator_names()
_HALOS = {n: max(make(n).halo((64, 64, 3))) for n in NAMES}
LOCAL = {n for n, h in _HALOS.items() if 0 < h < math.inf}  # neighbourhoods (a finite halo)
# operators that need the whole image until measured (an infinite halo): pfstmo's stretch
# of the output by its own minimum and maximum (reinhard2005)
WHOLE = {n for n, h in _HALOS.items() if h == math.inf}
CHUNKED = [n for n in NAMES if n not in LOCAL | WHOLE]

_compiles: list[str] = []
_counting = [False]


def _listener(name: str, duration: float, **kw) -> None:
    if _counting[0] and name == "/jax/core/compile/backend_compile_duration":
        _compiles.append(name)


jax.monitoring.register_event_duration_secs_listener(_listener)


@contextlib.contextmanager
def count_compiles():
    """The number of XLA compilations inside the block (``len`` of the yielded list)."""
    _compiles.clear()
    _counting[0] = True
    try:
        yield _compiles
    finally:
        _counting[0] = False


def _image(shape=(23, 37), seed=3):
    x = natural(shape, seed=seed)
    x[2, 5] = (np.nan, 1.0, 1.0)
    x[7, 1] = (np.inf, 2.0, 2.0)
    x[9, 3] = (-np.inf, 0.0, 0.0)
    return x


def _compare(name, got, want):
    want = np.asarray(want)
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want), err_msg=name)
    ok = ~np.isnan(want)
    # statistics merged from chunks: the log sum in float64 against the whole image's
    # float32 reduction, and estimates the operators take from the merged histogram
    np.testing.assert_allclose(got[ok], want[ok], rtol=2e-5, atol=2e-6, err_msg=name)


def test_the_pointwise_operators_run_chunked_the_local_ones_not():
    x = _image()
    assert {n for n in NAMES if not chunkable(make(n), x.shape)} == LOCAL | WHOLE
    assert chunkable(make("reinhard2005").measure(x), x.shape)  # its stretch measured
    exact = make("reinhard2002", percentile_method="exact")
    assert not chunkable(exact, x.shape)  # a sort of the whole image does not merge
    assert chunkable(make("reinhard2002", key=0.18, L_white=4.0, log_average=1.0), x.shape)


@pytest.mark.parametrize("name", CHUNKED)
def test_chunked_equals_the_whole_image(name):
    """Every pointwise operator, chunks that split rows and leave a padded last chunk, an
    image with NaN, +Inf and −Inf pixels: the whole-image operator's result."""
    x = _image()
    op = make(name)
    measured, got = tonemap_chunked(op, x, chunk=(4, 8))
    assert got.shape == x.shape and got.dtype == np.float32
    _compare(name, got, op(x))
    if op.unset():  # the estimates of the chunks' merged statistics
        assert not measured.unset() or name == "linear", measured.unset()


@pytest.mark.parametrize("name", ["reinhard2002", "tumblin_reinhard", "budak2005"])
def test_results_do_not_depend_on_the_chunk_size(name):
    x = _image((31, 29), seed=5)
    op = make(name)
    outs = [tonemap_chunked(op, x, chunk=c)[1] for c in [(1, 7), (4, 8), (16, 64), (64, 64)]]
    for out in outs[1:]:
        _compare(name, out, outs[0])
    # one chunk that holds the whole image is the whole-image program's pixels exactly
    stats_one = statistics_chunked(op, x, chunk=(64, 64))
    stats_many = statistics_chunked(op, x, chunk=(1, 7))
    for leaf in ("n_pixels", "n_finite", "n_positive", "min", "max", "min_positive", "counts"):
        np.testing.assert_array_equal(getattr(stats_one, leaf), getattr(stats_many, leaf), leaf)
    assert int(stats_one.n_pixels) == 31 * 29 and int(stats_one.n_finite) == 31 * 29 - 3


def test_a_small_image_in_one_large_chunk():
    """64 pixels padded to a chunk of 2^19: the padding leaves the sums alone (the pooled
    log-average of a sequence is these sums)."""
    x = natural((8, 8), seed=2)
    for name in ("reinhard2002", "reinhard2004"):
        op = make(name)
        got = statistics_chunked(op, x)
        want = op.statistics(x)
        assert int(got.n_pixels) == 64 and int(got.n_finite) == 64
        np.testing.assert_allclose(got.log_sum, want.log_sum, rtol=2e-7, err_msg=name)
        if want.channel_sum is not None:
            np.testing.assert_allclose(got.channel_sum, want.channel_sum, rtol=2e-7)
        np.testing.assert_array_equal(got.counts, want.counts)


def test_converted_pixels_equal_the_compiled_conversion():
    """XYZ pixels into sRGB: the chunked statistics (weights w·M on the file's pixels) and
    mapping equal measure_in_space/apply_in_space, for a luminance curve and an operator
    with channel statistics."""
    x = np.abs(_image((19, 21), seed=7))
    m = spaces.conversion_matrix("CIE XYZ", "sRGB")
    for name in ("reinhard2002", "reinhard2004"):
        op = make(name)
        want = apply_in_space(measure_in_space(op, x, m), x, m)
        _compare(name, tonemap_chunked(op, x, m, chunk=(5, 8))[1], want)


def test_a_new_image_size_compiles_nothing():
    op = make("reinhard2002")
    chunk = (8, 16)
    tonemap_chunked(op, natural((9, 10)), chunk=chunk)
    for shape in [(31, 7), (2, 3), (40, 41)]:
        with count_compiles() as n:
            out = tonemap_chunked(op, natural(shape, seed=shape[0]), chunk=chunk)[1]
        assert out.shape == shape + (3,)
        assert len(n) == 0, f"{shape}: {len(n)} compilation(s)"
    with count_compiles() as n:
        op(natural((31, 7)))  # the whole-image program: one per shape
    assert len(n) > 0


def test_a_set_parameter_skips_the_statistics():
    op = make("reinhard2002", key=0.18, L_white=4.0, log_average=1.0)
    assert measure_chunked(op, natural()) is op


def test_the_command_line_compiles_once_for_many_sizes(tmp_path):
    """``hdrjax tonemap`` in one process on files of three sizes: the second and third
    compile nothing; the PNG equals the whole-image operator's, encoded."""
    from hdrjax.cli import main

    x = np.asarray(read(DATA / "rooitou_park_1k.hdr").native_rgb(), np.float32)
    sizes = [(64, 96), (50, 33), (77, 120)]
    for i, (h, w) in enumerate(sizes):
        src = tmp_path / f"f{i}.hdr"
        write(src, np.ascontiguousarray(x[:h, :w]))
        with count_compiles() as n:
            assert main(["tonemap", str(src), "-o", str(tmp_path / f"f{i}.png")]) == 0
        if i:
            assert len(n) == 0, f"{(h, w)}: {len(n)} compilation(s)"
    got = decode_png((tmp_path / "f2.png").read_bytes())[0].astype(np.float64)
    img = read(tmp_path / "f2.hdr").native_rgb()
    want = np.asarray(hdrjax.display.encode(hdrjax.tonemap(img, "reinhard2002"), "srgb")) * 255
    assert got.shape == want.shape
    assert np.max(np.abs(got - want)) <= 0.5 + 1e-3  # rounding to code values


def test_a_batch_of_mixed_sizes_compiles_once(tmp_path):
    """Frames of six sizes: the second run over three new sizes compiles nothing, and every
    output equals its frame tone-mapped by itself."""
    x = natural((90, 120), seed=11)
    frames = []
    for i, (h, w) in enumerate([(20, 30), (41, 17), (64, 64), (33, 90), (7, 120), (90, 5)]):
        p = tmp_path / "in" / f"f{i}.exr"
        p.parent.mkdir(exist_ok=True)
        write(p, np.ascontiguousarray(x[:h, :w]))
        frames.append(p)
    pipe = batch.Pipeline("reinhard2002", format="exr")
    assert batch.run(frames[:3], pipe, tmp_path / "a", progress=False).ok
    with count_compiles() as n:
        assert batch.run(frames[3:], pipe, tmp_path / "b", progress=False).ok
    assert len(n) == 0
    for i, p in enumerate(frames):
        out = read(tmp_path / ("a" if i < 3 else "b") / f"f{i}.exr").native_rgb()
        img = read(p).native_rgb()
        _compare(p.name, np.asarray(out), hdrjax.tonemap(img, "reinhard2002"))
