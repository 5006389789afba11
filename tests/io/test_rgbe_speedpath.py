"""The vectorised Radiance decoder against a slow scanline-by-scanline reference.

The reference below follows the format description (Ward, "Real pixels", Graphics Gems II,
1991; Radiance ``color.c``: ``freadcolrs`` and ``oldreadcolrs``) one scanline and one run
header at a time in plain Python, and shares no code with hdrjax's reader. Files come from
hdrjax's writer at widths on both sides of the run-length limits (8 and 32767 pixels),
from hand-made bytes (old-style repeats, data full of bytes that look like scanline
headers, corrupt runs) and from data/; every decoded value must be the reference's, bit
for bit.
"""

import numpy as np
import pytest
from hypothesis import given, strategies as st

import hdrjax.io as hio
from hdrjax.io import ReadError, _rgbe

from ..conftest import DATA

WIDTHS = [1, 7, 8, 9, 100, 1024, 32767, 32768]


def _reference_rgbe(data: bytes) -> np.ndarray:
    """``(H, W, 4)`` RGBE bytes of a valid ``-Y H +X W`` Radiance file."""
    pos = data.index(b"\n\n") + 2
    eol = data.index(b"\n", pos)
    y_axis, h, x_axis, w = data[pos:eol].split()
    assert (y_axis, x_axis) == (b"-Y", b"+X")
    h, w = int(h), int(w)
    pos = eol + 1
    rows = []
    for _ in range(h):
        new_rle = 8 <= w <= 0x7FFF and data[pos : pos + 2] == b"\x02\x02" and data[pos + 2] < 128
        if new_rle:  # 2 2 W_hi W_lo, then each component as runs (128 + n, byte) and literals
            assert data[pos + 2] << 8 | data[pos + 3] == w
            pos += 4
            planes = []
            for _ in range(4):
                plane = b""
                while len(plane) < w:
                    count = data[pos]
                    assert count != 0
                    if count > 128:
                        plane += data[pos + 1 : pos + 2] * (count - 128)
                        pos += 2
                    else:
                        plane += data[pos + 1 : pos + 1 + count]
                        pos += 1 + count
                assert len(plane) == w
                planes.append(plane)
            rows.append(np.frombuffer(b"".join(planes), np.uint8).reshape(4, w).T)
        else:  # flat pixels; 1 1 1 n repeats the previous pixel n << 8k times (k-th in a row)
            pixels: list[bytes] = []
            shift = 0
            while len(pixels) < w:
                px = data[pos : pos + 4]
                pos += 4
                if px[:3] == b"\x01\x01\x01":
                    pixels += [pixels[-1]] * (px[3] << shift)
                    shift += 8
                else:
                    pixels.append(px)
                    shift = 0
            assert len(pixels) == w
            rows.append(np.frombuffer(b"".join(pixels), np.uint8).reshape(w, 4))
    return np.stack(rows)


def _reference_float(rgbe: np.ndarray) -> np.ndarray:
    """m · 2^(E − 136), 0 where E = 0; every such value is exact in float32 (denormals
    included), so the float64 result casts without rounding."""
    m = rgbe[..., :3].astype(np.float64)
    e = rgbe[..., 3:].astype(np.int64)
    return np.where(e > 0, np.ldexp(m, e - 136), 0.0).astype(np.float32)


def _assert_decodes_as_reference(data: bytes, tmp_path, name: str = "f.hdr") -> None:
    want = _reference_rgbe(data)
    p = tmp_path / name
    p.write_bytes(data)
    got = hio.read(p, sidecars=False).image
    assert got.dtype == np.float32
    np.testing.assert_array_equal(got.view(np.uint32), _reference_float(want).view(np.uint32))
    mant, exp, _ = _rgbe.decode_rgbe(data, name)
    np.testing.assert_array_equal(mant, want[..., :3])
    np.testing.assert_array_equal(exp, want[..., 3])


def _image(h: int, w: int, kind: str, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    if kind == "noise":  # few runs: mostly literals
        rgb = np.exp(rng.normal(0, 3, (h, w, 3)))
        rgb[rng.random((h, w)) < 0.05] = 0.0  # exponent 0
        return rgb.astype(np.float32)
    # runs of 1 to 300 equal pixels (longer than the 127 one run header holds), a black row
    lengths = rng.integers(1, 300, size=(h, w))
    starts = np.cumsum(lengths, axis=1) % w
    change = np.zeros((h, w), bool)
    change[np.arange(h)[:, None], starts] = True
    idx = np.cumsum(change, axis=1)
    values = np.exp(rng.normal(0, 2, (h, w + 1, 3)))
    rgb = np.take_along_axis(values, idx[:, :, None].repeat(3, axis=2), axis=1)
    rgb[0] = 0.0
    return rgb.astype(np.float32)


@pytest.mark.parametrize("kind", ["noise", "runs"])
@pytest.mark.parametrize("width", WIDTHS)
def test_written_files_decode_as_reference(tmp_path, width, kind):
    h = 3 if width < 30000 else 2
    rgb = _image(h, width, kind, seed=width)
    for rle in (True, False):
        data = _rgbe.encode_rgbe(rgb, rle=rle)
        body = data[data.index(f"+X {width}\n".encode()) + len(f"+X {width}\n") :]
        runs = rle and 8 <= width <= 0x7FFF
        assert (body[:4] == bytes([2, 2, width >> 8, width & 0xFF])) == runs
        _assert_decodes_as_reference(data, tmp_path)


@pytest.mark.parametrize("path", sorted(DATA.glob("*.hdr")), ids=lambda p: p.name)
def test_shipped_files_decode_as_reference(tmp_path, path):
    _assert_decodes_as_reference(path.read_bytes(), tmp_path, path.name)


def test_old_style_repeats_decode_as_reference(tmp_path):
    rng = np.random.default_rng(7)
    w = 300
    flat = rng.integers(2, 256, size=(3, w, 4), dtype=np.uint8)
    a, b = bytes([9, 8, 7, 130]), bytes([40, 50, 60, 120])
    # a then 43 copies, then (a second repeat in a row) 1 << 8 more: 300 pixels
    row0 = a + bytes([1, 1, 1, 43, 1, 1, 1, 1])
    row1 = a + bytes([1, 1, 1, 3]) + b + bytes([1, 1, 1, 2]) + flat[1, : w - 7].tobytes()
    body = row0 + row1 + flat[2].tobytes()
    data = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 3 +X 300\n" + body
    _assert_decodes_as_reference(data, tmp_path)


def _rle_file(planes: np.ndarray) -> bytes:
    """A Radiance file of ``(rows, 4, width)`` RGBE byte planes, run-length encoded."""
    h, _, w = planes.shape
    head = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n".encode()
    return head + _rgbe._encode_rle_block(np.ascontiguousarray(planes))


def _literal_file(planes: np.ndarray) -> bytes:
    """The same as literals only (at most 128 bytes each), never runs: valid, though no
    writer would store equal bytes so."""
    h, _, w = planes.shape
    out = [f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n".encode()]
    for row in planes:
        out.append(bytes([2, 2, w >> 8, w & 0xFF]))
        for comp in row:
            for i in range(0, w, 128):
                out.append(bytes([min(128, w - i)]) + comp[i : i + 128].tobytes())
    return b"".join(out)


@pytest.mark.parametrize("encode", [_rle_file, _literal_file])
def test_data_that_looks_like_scanline_headers(tmp_path, encode):
    """Width 514 has the scanline header 2 2 2 2: pixel bytes of 2 put that pattern all
    over the data, and only the real scanlines may be used."""
    rng = np.random.default_rng(5)
    planes = rng.integers(0, 256, size=(5, 4, 514), dtype=np.uint8)
    planes[rng.random(planes.shape) < 0.5] = 2
    planes[2] = 2
    data = encode(planes)
    body = np.frombuffer(data, np.uint8)
    looks = (body[:-3] == 2) & (body[1:-2] == 2) & (body[2:-1] == 2) & (body[3:] == 2)
    assert looks.sum() > (5 if encode is _rle_file else 1000)
    _assert_decodes_as_reference(data, tmp_path)


@given(
    st.integers(8, 40),
    st.integers(1, 4),
    st.sampled_from([2, 3, 256]),
    st.integers(0, 2**32 - 1),
)
def test_random_planes_decode_as_reference(width, height, alphabet, seed):
    """Run-length files of random bytes from a small alphabet (long runs) or all 256."""
    planes = np.random.default_rng(seed).integers(0, alphabet, size=(height, 4, width))
    data = _rle_file(planes.astype(np.uint8))
    got, _ = _rgbe.decode_rgbe_float(data, "r.hdr")
    want = _reference_float(_reference_rgbe(data))
    np.testing.assert_array_equal(got.view(np.uint32), want.view(np.uint32))


def _scanline(w: int, *components: bytes) -> bytes:
    return bytes([2, 2, w >> 8, w & 0xFF]) + b"".join(components)


def _read_error(data: bytes) -> str:
    with pytest.raises(ReadError) as e:
        _rgbe.decode_rgbe_float(data, "f.hdr")
    return str(e.value)


def test_corrupt_runs_are_refused_with_the_scanline():
    head = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 3 +X 8\n"
    run8 = bytes([128 + 8, 1])
    good = _scanline(8, run8, run8, run8, run8)
    # scanline 1: a run of 10 crosses from the first component into the second
    cross = _scanline(8, bytes([128 + 10, 5, 128 + 6, 6]), run8, run8)
    msg = _read_error(head + good + cross + good)
    assert msg == "f.hdr: corrupt Radiance run-length data at scanline 1"
    # scanline 1: a literal crosses the boundary the same way
    lit = _scanline(8, bytes([9]) + bytes(range(1, 10)), bytes([128 + 7, 3]), run8, run8)
    msg = _read_error(head + good + lit + good)
    assert msg == "f.hdr: corrupt Radiance run-length data at scanline 1"
    # scanline 1 one pixel short: scanline 2 does not start where it ends
    short = _scanline(8, run8, run8, run8, bytes([128 + 7, 1]))
    msg = _read_error(head + good + short + good)
    assert msg == "f.hdr: corrupt or truncated Radiance run-length data at scanline 1"
    # a run header of 0 in scanline 2
    zero = _scanline(8, run8, run8, bytes([0]) + run8, run8)
    msg = _read_error(head + good + good + zero)
    assert msg == "f.hdr: corrupt or truncated Radiance run-length data at scanline 2"
    # the data ends inside scanline 2
    lit8 = bytes([8]) + bytes(range(10, 18))
    msg = _read_error(head + good + good + _scanline(8, lit8, lit8, lit8, lit8)[:-1])
    assert msg == "f.hdr: corrupt or truncated Radiance run-length data at scanline 2"


def test_runaway_decoding_is_refused():
    """Width 514 and data of nothing but 2s: every byte starts a plausible scanline, and
    walking them all would take work quadratic in the file size."""
    data = b"#?RADIANCE\n\n-Y 40 +X 514\n" + bytes([2]) * 200_000
    assert _read_error(data) == "f.hdr: corrupt Radiance run-length data (runaway decoding)"
