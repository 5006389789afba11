"""hdrjax.batch.run and Pipeline against NumPy/SciPy references of the same formulas."""

import math

import numpy as np
import pytest
import scipy.ndimage as ndi

from hdrjax import batch, io as hio

from .._png import decode_png
from ..conftest import DATA
from ._frames import frame, write_sequence

W709 = np.array([0.2126, 0.7152, 0.0722])
DELTA = 1e-6  # Reinhard log-average offset (hdrjax._stats.DEFAULT_DELTA, HDR Toolbox)


def srgb_codes(linear: np.ndarray, bits: int = 8) -> np.ndarray:
    """IEC 61966-2-1 sRGB, rounded to code values (float64 reference)."""
    x = np.clip(np.nan_to_num(linear, nan=0.0), 0.0, 1.0)
    enc = np.where(x > 0.0031308, 1.055 * np.power(x, 1 / 2.4) - 0.055, 12.92 * x)
    return np.rint(enc * ((1 << bits) - 1)).astype(int)


def reinhard_np(rgb, key, white, lbar):
    """Reinhard et al. 2002 Eqs. 2-4 in float64, colour scaled by L_d / L_w."""
    rgb = rgb.astype(np.float64)
    L = rgb @ W709
    Ls = key / lbar * L
    Ld = Ls * (1 + Ls / white**2) / (1 + Ls)
    return rgb * np.where(L > 0, Ld / np.where(L > 0, L, 1), 0.0)[..., None]


def log_average(L):
    return math.exp(np.mean(np.log(DELTA + np.maximum(L, 0))))


def jgt_parameters(L):
    """JGT 2002 key (Eq. 4) and white (Eq. 5, hdritools' guard in scaled units) from all
    pixels ``L``."""
    Lp = L[L > 0]
    # hdrjax's percentile is the order statistic x_(floor(q (n - 1))) (hdrjax._stats)
    p01, p99 = np.percentile(Lp, [1, 99], method="lower")
    trimmed = math.exp(np.mean(np.log(Lp[Lp <= p99])))
    l1, l99 = math.log2(p01), math.log2(p99)
    key = 0.18 * 4 ** ((2 * math.log2(trimmed) - l1 - l99) / (l99 - l1))
    lbar = log_average(L)
    zones = math.log2(Lp.max()) - math.log2(Lp.min())
    if 1.5 * 2 ** (zones - 5) <= trimmed * key / lbar:  # Eq. 5's white vs the average
        white = 1.5 * Lp.max() * key / lbar
    else:
        white = 1.5 * 2 ** (zones - 5)
    return key, white, lbar


def read_png(p):
    """Code values of an RGB PNG as hdrjax writes it, as ints."""
    px, chunks = decode_png(p.read_bytes())
    assert px.shape[2] == 3  # truecolour RGB
    return px.astype(int)


@pytest.fixture(scope="module")
def seq(tmp_path_factory):
    return write_sequence(tmp_path_factory.mktemp("seq"), 6)


def test_per_frame_matches_numpy_reinhard(seq, tmp_path):
    # key and white fixed, log-average measured on each frame by itself
    pipe = batch.Pipeline(batch.Pipeline("reinhard2002").operator.__class__(key=0.18, L_white=3.0))
    s = batch.run(seq, pipe, tmp_path, batch_size=4, progress=False)
    assert len(s.done) == 6 and not s.failed and not s.skipped
    for i, p in enumerate(seq):
        rgb = frame(i).astype(np.float64)
        ref = srgb_codes(reinhard_np(rgb, 0.18, 3.0, log_average(rgb @ W709)))
        got = read_png(tmp_path / (p.stem + ".png"))
        assert np.abs(got - ref).max() <= 1
        assert np.mean(got != ref) < 0.01


def test_same_parameters_pool_every_pixel_of_the_sequence(seq, tmp_path):
    s = batch.run(seq, "reinhard2002", tmp_path, parameters="same", batch_size=4, progress=False)
    assert len(s.done) == 6
    frames = [frame(i).astype(np.float64) for i in range(6)]
    L_all = np.concatenate([(f @ W709).ravel() for f in frames])
    key, white, lbar = jgt_parameters(L_all)
    for i, p in enumerate(seq):
        ref = srgb_codes(reinhard_np(frames[i], key, white, lbar))
        got = read_png(tmp_path / (p.stem + ".png"))
        # percentiles from the merged histogram: within 0.15 % -> at most one code value
        assert np.abs(got - ref).max() <= 1
        assert np.mean(got != ref) < 0.02


def test_pooled_statistics_match_numpy(seq):
    from hdrjax.batch._frames import measure_frames

    pipe = batch.Pipeline("reinhard2002")
    frames = [frame(i) for i in range(6)]
    key = ((32, 64, 3), None, True)  # shape, primaries (Rec.709), all pixels finite
    # two batches of 4 (the second padded), as run() does
    recs = measure_frames(pipe, frames[:4], key, 4, True)
    recs += measure_frames(pipe, frames[4:], key, 4, True)
    st = batch.pooled_stats([r["stats"] for r in recs])
    L = np.concatenate([(f.astype(np.float64) @ W709).ravel() for f in frames])
    Lp = L[L > 0]
    p01, p99 = np.percentile(Lp, [1, 99], method="lower")  # order statistics
    assert int(st.n_pixels) == L.size and int(st.n_positive) == Lp.size
    assert float(st.max) == pytest.approx(L.max(), rel=1e-6)
    assert float(st.min_positive) == pytest.approx(Lp.min(), rel=1e-6)
    assert float(st.log_average) == pytest.approx(log_average(L), rel=1e-4)
    bound = float(st.rel_error_bound)
    assert bound < 2e-3
    # within one bin of the order statistic (hdrjax._stats module docstring)
    assert float(st.p01) == pytest.approx(p01, rel=bound * 1.01)
    assert float(st.p99) == pytest.approx(p99, rel=bound * 1.01)
    trimmed = math.exp(np.mean(np.log(Lp[Lp <= p99])))
    assert float(st.log_average_trimmed) == pytest.approx(trimmed, rel=1e-3)


def test_same_parameters_follow_exposure_per_frame_does_not(tmp_path):
    # frames = one image times 1, 2, 4: per-frame parameters undo the exposure (Reinhard
    # is scale invariant when measured), shared ones keep it
    base = frame(0)
    paths = []
    for i, k in enumerate((1.0, 2.0, 4.0)):
        p = tmp_path / f"x_{i}.exr"
        hio.write(p, base * np.float32(k))
        paths.append(p)
    batch.run(paths, "reinhard2002", tmp_path / "per", batch_size=4, progress=False)
    batch.run(
        paths, "reinhard2002", tmp_path / "same", parameters="same", batch_size=4, progress=False
    )
    per = [read_png(tmp_path / "per" / f"x_{i}.png") for i in range(3)]
    same = [read_png(tmp_path / "same" / f"x_{i}.png") for i in range(3)]
    assert np.abs(per[0] - per[1]).max() <= 1 and np.abs(per[0] - per[2]).max() <= 1
    means = [m.mean() for m in same]
    assert means[0] < means[1] - 5 < means[2] - 10


def test_smooth_series_is_the_centred_exponential_average():
    rng = np.random.default_rng(0)
    v = np.exp(rng.normal(size=(23, 2)))
    tau = 3.0
    got = batch.smooth_series(v, tau)
    r = math.ceil(4 * tau)
    ref = np.empty_like(v)
    for t in range(23):
        ks = [k for k in range(-r, r + 1) if 0 <= t + k < 23]
        w = np.array([math.exp(-abs(k) / tau) for k in ks])
        ref[t] = np.exp((w[:, None] * np.log(v[[t + k for k in ks]])).sum(0) / w.sum())
    np.testing.assert_allclose(got, ref, rtol=1e-12)


def test_smoothing_divides_alternating_flicker_as_documented():
    tau = 5.0
    a = math.exp(-1 / tau)
    v = np.exp(0.1 * (-1.0) ** np.arange(200))  # +-10 % frame-to-frame flicker
    out = np.log(batch.smooth_series(v, tau))[50:150]
    r = math.ceil(4 * tau)
    ks = np.arange(-r, r + 1)
    expected = np.sum(a ** np.abs(ks) * np.cos(np.pi * ks)) / np.sum(a ** np.abs(ks))
    assert np.abs(out).max() / 0.1 == pytest.approx(expected, rel=1e-6)
    assert 1 / expected == pytest.approx(85, abs=0.5)  # the figure in the docstring


def test_smooth_parameters_lie_between_per_frame_and_shared(tmp_path):
    # a sudden 8x exposure step at frame 3: smoothed frames near the step are between
    base = frame(0)
    paths = []
    for i in range(6):
        p = tmp_path / f"s_{i}.exr"
        hio.write(p, base * np.float32(1.0 if i < 3 else 8.0))
        paths.append(p)
    batch.run(
        paths,
        "reinhard2002",
        tmp_path / "sm",
        parameters="smooth",
        smooth_frames=2.0,
        batch_size=4,
        progress=False,
    )
    batch.run(paths, "reinhard2002", tmp_path / "per", batch_size=4, progress=False)
    sm = [read_png(tmp_path / "sm" / f"s_{i}.png").mean() for i in range(6)]
    per = [read_png(tmp_path / "per" / f"s_{i}.png").mean() for i in range(6)]
    # per-frame: the step is undone (all alike). Smoothed: the frames before the step
    # already adapt to the bright future (darker, more so near the step), those after it
    # still to the dark past (brighter)
    assert max(per) - min(per) < 1.0
    assert sm[2] < per[2] - 1 and sm[3] > per[3] + 1
    assert sm[0] > sm[1] > sm[2] and sm[3] > sm[4] > sm[5]


def test_bad_frames_are_reported_and_the_others_complete(seq, tmp_path):
    bad = tmp_path / "in"
    bad.mkdir()
    corrupt = bad / "corrupt.exr"
    corrupt.write_bytes(b"\x76\x2f\x31\x01" + b"\x00" * 40)  # EXR magic, then nothing
    nan = bad / "nan.exr"
    img = frame(1)
    img[3, 5] = np.nan
    hio.write(nan, img)
    messages = []
    paths = [seq[0], corrupt, nan, seq[2]]
    s = batch.run(
        paths, "reinhard2002", tmp_path / "o", batch_size=4, progress=False, report=messages.append
    )
    assert s.done == (str(seq[0]), str(seq[2]))
    assert set(s.failed) == {str(corrupt), str(nan)}
    assert "corrupt.exr" in s.failed[str(corrupt)]
    assert "NaN" in s.failed[str(nan)] and "nan.exr" in s.failed[str(nan)]
    assert len(messages) == 2
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == [
        seq[0].stem + ".png",
        seq[2].stem + ".png",
    ]
    # allow_nan renders it; the NaN pixel is black
    s2 = batch.run(
        [nan], "reinhard2002", tmp_path / "o2", allow_nan=True, batch_size=4, progress=False
    )
    assert len(s2.done) == 1
    assert read_png(tmp_path / "o2" / "nan.png")[3, 5].tolist() == [0, 0, 0]


def test_mean_step_and_exr_output(tmp_path):
    src = tmp_path / "a.exr"
    rgb = frame(2)
    hio.write(src, rgb)
    op = batch.Pipeline("reinhard2002").operator.__class__(key=0.2, L_white=4.0, log_average=0.5)
    pipe = batch.Pipeline(op, steps=[("mean", {"size": 3})], format="exr", scale=2.0)
    s = batch.run([src], pipe, tmp_path / "o", batch_size=4, progress=False)
    assert len(s.done) == 1
    x = rgb.astype(np.float64) * 2.0
    box = np.stack([ndi.uniform_filter(x[..., c], 3, mode="nearest") for c in range(3)], -1)
    ref = reinhard_np(box, 0.2, 4.0, 0.5)
    got = hio.read(tmp_path / "o" / "a.exr").rgb()
    np.testing.assert_allclose(got, ref, rtol=1e-4, atol=1e-6)


def test_sixteen_bit_png(tmp_path):
    src = tmp_path / "b.exr"
    hio.write(src, frame(0))
    op = batch.Pipeline("reinhard2002").operator.__class__(key=0.18, L_white=2.0, log_average=0.3)
    batch.run([src], batch.Pipeline(op, bits=16), tmp_path / "o", batch_size=4, progress=False)
    got = read_png(tmp_path / "o" / "b.png")
    ref = srgb_codes(reinhard_np(frame(0), 0.18, 2.0, 0.3), bits=16)
    assert np.abs(got - ref).max() <= 1


def test_invalid_arguments_name_the_problem(seq, tmp_path):
    with pytest.raises(ValueError, match="sise"):
        batch.step("median", sise=3)
    with pytest.raises(ValueError, match="parameters"):
        batch.run(seq, "reinhard2002", tmp_path, parameters="shared")
    with pytest.raises(ValueError, match="format"):
        batch.Pipeline("reinhard2002", format="gif")
    with pytest.raises(FileNotFoundError, match="nothing_here"):
        batch.run(str(tmp_path / "nothing_here*.exr"), "reinhard2002", tmp_path)
    twin = tmp_path / "other"
    twin.mkdir()
    (twin / seq[0].name).write_bytes(seq[0].read_bytes())
    with pytest.raises(ValueError, match="both be written"):
        batch.run([seq[0], twin / seq[0].name], "reinhard2002", tmp_path / "o")


def test_median_step_on_a_batch_of_frames(tmp_path):
    # 64-row frames, three per batch: the median runs frame by frame inside the batch
    rgb = hio.read(DATA / "rooitou_park_1k.hdr", sidecars=False).rgb()
    paths = []
    for i in range(3):
        p = tmp_path / f"m_{i}.exr"
        hio.write(p, np.ascontiguousarray(rgb[128 + 64 * i : 192 + 64 * i, 256:384]))
        paths.append(p)
    op = batch.Pipeline("reinhard2002").operator.__class__(key=0.18, L_white=8.0, log_average=0.4)
    steps = [batch.step("median", size=3, criterion="channels")]
    pipe = batch.Pipeline(op, steps=steps, format="exr")
    s = batch.run(paths, pipe, tmp_path / "o", batch_size=3, progress=False)
    assert len(s.done) == 3
    for p in paths:
        x = hio.read(p).rgb().astype(np.float64)
        med = np.stack([ndi.median_filter(x[..., c], 3, mode="nearest") for c in range(3)], -1)
        got = hio.read(tmp_path / "o" / p.name).rgb()
        np.testing.assert_allclose(got, reinhard_np(med, 0.18, 8.0, 0.4), rtol=1e-4, atol=1e-6)


def test_desaturate_step_then_operator(tmp_path):
    # Birukov et al. 2022 highlight desaturation, manual threshold T, by hand in NumPy
    src = tmp_path / "d.exr"
    rgb = frame(3)
    hio.write(src, rgb)
    x = rgb.astype(np.float64)
    L = x @ W709
    T = float(np.percentile(L, 80))
    op = batch.Pipeline("reinhard2002").operator.__class__(key=0.18, L_white=6.0, log_average=0.6)
    pipe = batch.Pipeline(op, steps=[batch.step("desaturate", threshold=T)], format="exr")
    s = batch.run([src], pipe, tmp_path / "o", batch_size=4, progress=False)
    assert len(s.done) == 1
    s_ = np.clip((L - T) / (L.max() - T), 0, 1)[..., None]
    mu = x.mean(axis=-1, keepdims=True)
    ref = reinhard_np(x - s_ * (x - mu), 0.18, 6.0, 0.6)
    got = hio.read(tmp_path / "o" / "d.exr").rgb()
    np.testing.assert_allclose(got, ref, rtol=1e-4, atol=1e-6)


def test_vmap_and_map_batches_agree(seq, tmp_path):
    # the two ways a compiled batch goes over its frames give the same images
    outs = {}
    for mode in ("map", "vmap"):
        pipe = batch.Pipeline("reinhard2002", vectorize=mode)
        batch.run(seq[:4], pipe, tmp_path / mode, batch_size=4, progress=False)
        outs[mode] = np.stack([read_png(tmp_path / mode / (p.stem + ".png")) for p in seq[:4]])
    assert np.abs(outs["map"] - outs["vmap"]).max() <= 1
    assert np.mean(outs["map"] != outs["vmap"]) < 1e-3


@pytest.mark.parametrize("method", ["mantiuk2008", "reinhard2005"])
def test_operators_with_their_own_measurement_batch_as_they_map(method, seq, tmp_path):
    """Operators that measure more than summary statistics (mantiuk2008's curve,
    reinhard2005's adaptation) render in a batch as by themselves: every mantiuk2008 frame
    once failed with a message-less "processing failed: "."""
    import hdrjax

    s = batch.run(seq[:2], batch.Pipeline(method), tmp_path, batch_size=2, progress=False)
    assert len(s.done) == 2 and not s.failed
    for p in seq[:2]:
        got = decode_png((tmp_path / (p.stem + ".png")).read_bytes())[0].astype(np.float64)
        ref = np.asarray(
            hdrjax.display.quantize(
                hdrjax.display.encode(hdrjax.tonemap(hio.read(p).rgb(), method)), 8
            ),
            np.float64,
        )
        assert np.abs(got - ref).max() <= 1, p.name


def test_a_failed_frame_says_what_failed():
    from hdrjax.batch._frames import failure

    assert failure(AssertionError()) == "AssertionError"
    assert failure(ValueError("bad\n  value")) == "bad value"
