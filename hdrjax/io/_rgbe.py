"""Radiance ``.hdr`` / ``.pic`` (RGBE) reading and writing in vectorised NumPy.

Format (Ward, "Real pixels", Graphics Gems II; Radiance ``color.c``/``header.c``):

- A text header of ``NAME=value`` lines and comments, ending with an empty line. The
  magic line ``#?RADIANCE`` (or ``#?RGBE``, or another ``#?`` program name) may be
  preceded by other lines (some writers put ``VIEW=`` first). ``EXPOSURE=`` and
  ``COLORCORR=`` lines multiply: the original radiance is pixel / (EXPOSURE · COLORCORR),
  and the reader applies that. ``PRIMARIES=`` is used only when it holds 8 numbers that
  define a valid set of primaries (Photoshop writes ``PRIMARIES=0 0 0 0 0 0 0 0``).
  ``FORMAT=32-bit_rle_xyze`` means the three channels hold CIE X, Y, Z.
- A resolution line, normally ``-Y H +X W`` (rows top to bottom, columns left to right);
  all eight orientations are read.
- Pixels: 4 bytes (R, G, B mantissas, shared exponent E), value = m · 2^(E−136), 0 when
  E = 0. This is Ward's ``rgbe.c`` convention, also used by OpenCV and stb_image (Radiance's
  own ``colr_color`` adds 0.5 to m); it makes decode → encode bit-exact. Scanlines are
  either flat, or "new" RLE
  (``2 2 W_hi W_lo`` then the four components one after another, each as runs
  ``128+n, byte`` and literals ``n, n bytes``), or "old" RLE (pixel ``1 1 1 n`` repeats the
  previous pixel ``n << 8k`` times for the k-th repeat in a row).

RLE decoding walks the run headers of every candidate scanline in lock-step (one Python
iteration, of three NumPy calls, per run header of the longest scanline), then expands the
runs with one ``np.repeat`` per block of scanlines and converts each block to float while
it is in cache; there is no Python loop per pixel or per run.
"""

import math
import os
import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ..layers._errors import ReadError

MAX_DIM = 1 << 20
"""Largest width or height accepted from a header."""

_HEADER_LIMIT = 1 << 16
_BLOCK_BYTES = 1 << 17  # decoded bytes per block (np.repeat and float conversion in cache)
_WALK_STEPS = 128  # most run headers walked between looks for finished walks (_rle_walk)
_HEAD = np.arange(256)  # RLE header byte values
_MAG = np.where(_HEAD <= 128, _HEAD, _HEAD - 128)  # pixels a header stands for (0: invalid)
_ADV = np.where(_HEAD > 128, 2, 1 + _HEAD).astype(np.intp)  # bytes from a header to the next
_REP = np.where(_HEAD > 128, _HEAD - 128, 1).astype(np.int8)  # copies of the byte after it
_RES_RE = re.compile(rb"^([-+])([XY]) +(\d+) +([-+])([XY]) +(\d+)\s*$")

_F32_MAX = float(np.finfo(np.float32).max)
_RGBE_MAX = 255.0 * 2.0**119  # the largest value an RGBE pixel holds (below _F32_MAX)

# value of mantissa m with exponent e: m * 2**(e - 136); e = 0 means zero.
_EXP_TABLE = np.array([0.0] + [math.ldexp(1.0, e - 136) for e in range(1, 256)], dtype=np.float32)


def _parse_floats(name: str, key: str, text: str, n: int) -> tuple[float, ...] | None:
    parts = text.split()
    if len(parts) != n:
        return None
    try:
        vals = tuple(float(p) for p in parts)
    except ValueError:
        return None
    if not all(math.isfinite(v) for v in vals):
        return None
    return vals


def _check_correction(name: str, v: float) -> None:
    """Refuse an EXPOSURE × COLORCORR product that float32 pixels cannot be divided by:
    0 or infinite in float32, or whose inverse is (every pixel would decode to 0 or inf)."""
    ok = 0.0 < v < math.inf
    if ok:
        with np.errstate(over="ignore", under="ignore"):
            a, b = np.float32(v), np.float32(1.0 / v)
        ok = bool(np.isfinite(a) and np.isfinite(b) and a > 0 and b > 0)
    if not ok:
        raise ReadError(
            f"{name}: unusable Radiance EXPOSURE x COLORCORR product {v:.6g}; dividing "
            "float32 pixels by it gives 0 or infinity (expected 3e-39 to 3e38)"
        )


def parse_header(data: bytes | memoryview, name: str) -> tuple[dict, int]:
    """Parse a Radiance header; returns ``(info, offset_of_pixel_data)``.

    ``info`` holds ``width``, ``height``, ``orientation`` (the resolution line),
    ``format``, ``exposure`` (product of all EXPOSURE lines), ``colorcorr`` (3 floats),
    ``primaries`` (8 floats or ``None``), ``lines`` (all header lines as text) and
    ``variables`` (``NAME -> value`` of the last ``NAME=value`` line for each name).

    Raises:
        ReadError: not a Radiance file, a malformed or absurd resolution line, a
            truncated header, or an EXPOSURE × COLORCORR product (per channel) that is
            not finite and non-zero, with a finite inverse, in float32.
    """
    head = bytes(data[:_HEADER_LIMIT])
    end = head.find(b"\n\n")
    if end < 0:
        if b"#?" not in head[:4096]:
            raise ReadError(
                f"{name}: not a Radiance file (missing '#?RADIANCE' or '#?RGBE' header)"
            )
        raise ReadError(f"{name}: truncated Radiance header (no empty line ending it)")
    lines = head[:end].split(b"\n")
    if not any(ln.startswith(b"#?") for ln in lines):
        raise ReadError(f"{name}: not a Radiance file (missing '#?RADIANCE' or '#?RGBE' header)")
    nl = head.find(b"\n", end + 2)
    if nl < 0:
        raise ReadError(f"{name}: truncated Radiance file (no resolution line)")
    res = _RES_RE.match(head[end + 2 : nl])
    if res is None:
        text = head[end + 2 : nl][:40].decode("latin-1")
        raise ReadError(
            f"{name}: bad Radiance resolution line {text!r}; expected e.g. '-Y 512 +X 1024'"
        )
    s1, a1, n1, s2, a2, n2 = res.groups()
    if a1 == a2:
        raise ReadError(f"{name}: bad Radiance resolution line (both axes are {a1.decode()})")
    n1, n2 = int(n1), int(n2)
    if min(n1, n2) < 1:
        raise ReadError(f"{name}: empty Radiance image {n1} x {n2}; expected at least 1 x 1")
    if not (0 < n1 <= MAX_DIM and 0 < n2 <= MAX_DIM):
        raise ReadError(f"{name}: absurd Radiance image size {n1} x {n2} (limit {MAX_DIM})")
    width, height = (n2, n1) if a1 == b"Y" else (n1, n2)
    info: dict = {
        "width": width,
        "height": height,
        "orientation": (s1 + a1 + b" " + s2 + a2).decode(),
        "format": "32-bit_rle_rgbe",
        "exposure": 1.0,
        "colorcorr": (1.0, 1.0, 1.0),
        "primaries": None,
        "lines": [],
        "variables": {},
    }
    for raw in lines:
        line = raw.decode("latin-1").rstrip("\r")
        info["lines"].append(line)
        if line.startswith("#") or "=" not in line:
            continue
        key, _, value = line.partition("=")
        key = key.strip()
        value = value.strip()
        info["variables"][key] = value
        ukey = key.upper()
        if ukey == "FORMAT":
            info["format"] = value
        elif ukey == "EXPOSURE":
            v = _parse_floats(name, key, value, 1)
            if v is None or v[0] <= 0:
                raise ReadError(f"{name}: bad Radiance EXPOSURE value {value!r}")
            info["exposure"] *= v[0]
        elif ukey == "COLORCORR":
            v = _parse_floats(name, key, value, 3)
            if v is None or min(v) <= 0:
                raise ReadError(f"{name}: bad Radiance COLORCORR value {value!r}")
            c = info["colorcorr"]
            info["colorcorr"] = (c[0] * v[0], c[1] * v[1], c[2] * v[2])
        elif ukey == "PRIMARIES":
            info["primaries"] = _parse_floats(name, key, value, 8)
    for c in info["colorcorr"]:
        _check_correction(name, c * info["exposure"])
    if info["format"] not in ("32-bit_rle_rgbe", "32-bit_rle_xyze"):
        raise ReadError(
            f"{name}: unsupported Radiance FORMAT {info['format']!r}; expected "
            "32-bit_rle_rgbe or 32-bit_rle_xyze"
        )
    return info, nl + 1


def _rle_candidates(buf: np.ndarray, length: int) -> np.ndarray:
    """Byte offsets of every ``2 2 W_hi W_lo`` pattern (``buf`` holds at least 4 bytes)."""
    c = np.flatnonzero(buf[:-3] == 2)
    return c[(buf[c + 1] == 2) & (buf[c + 2] == length >> 8) & (buf[c + 3] == length & 0xFF)]


def _rle_walk(
    buf: np.ndarray, cand: np.ndarray, length: int, budget: int, name: str
) -> tuple[np.ndarray, np.ndarray, list[tuple[np.ndarray, ...]]]:
    """Walk the run headers after every candidate scanline header, all in lock-step.

    A walk ends once it covers ``4 · length`` pixels, and is exact when it lands there with
    its last byte inside ``buf``. A step is three NumPy calls on arrays of one entry per
    walk (read the header bytes, look up how far each jumps, add), so the Python loop runs
    as often as the longest scanline has run headers. Pixel counts are summed, and finished
    walks leave the arrays, once per block of ``length / 8`` steps (16 to ``_WALK_STEPS``):
    the maps in data/ have about ``length / 4`` run headers per scanline, and on them this
    block decoded fastest (the block-wise calls cost more than the steps a walk takes past
    its end before the block ends, which are dropped). Reads past the data see its last
    byte.

    Raises:
        ReadError: the walks together take more than ``budget`` steps.

    Returns:
        ``(ends, whole, records)``: the offset after each candidate's scanline (-1 where
        its walk is not exact); whether its pixel counts land on the component boundaries
        (``length``, ``2 · length``, ``3 · length``: no run or literal crosses one); and
        per block of steps ``(ids, offsets, headers, used, decoded)``: the candidates
        walked, their run-header offsets ``(steps + 1, walks)`` (the last row is where the
        next block starts) and bytes ``(steps, walks)``, how many of the block's steps
        belong to each walk, and the pixels each had decoded before the block.
    """
    n, target, k = buf.size, 4 * length, cand.size
    block = min(max(16, length // 8), _WALK_STEPS)
    mag = _MAG.copy()
    mag[0] = target + 1  # header byte 0 is invalid: its walk ends at once, not exact
    edge = np.zeros(target + 1, bool)
    edge[[length, 2 * length, 3 * length]] = True
    ends = np.full(k, -1, np.int64)
    hits = np.zeros(k, np.int64)
    ids = np.arange(k)
    p = cand + 4
    f = np.zeros(k, np.int64)
    records = []
    while ids.size:
        a = ids.size
        steps = min(block, budget // a + 1)  # no more work than the budget allows
        pos = np.empty((steps + 1, a), np.intp)
        head = np.empty((steps, a), np.uint8)
        pos[0] = p
        rows, heads = list(pos), list(head)
        for i in range(steps):
            h = heads[i]
            buf.take(rows[i], mode="clip", out=h)
            np.add(rows[i], _ADV.take(h), out=rows[i + 1])
        # Pixels decoded after each step, walk by walk (a cumsum along the steps axis is
        # slow in NumPy): take() transposes to (walks, steps), one flat cumsum, and each
        # row is shifted to start from its walk's count so far.
        after = mag.take(head.T)
        np.cumsum(after.ravel(), out=after.ravel())
        shift = f.copy()
        shift[1:] -= after[:-1, -1]
        after += shift[:, None]
        over = after >= target
        fin = over[:, -1]
        col = np.flatnonzero(fin)
        used = np.full(a, steps)
        stop = np.argmax(over[col], axis=1) + 1
        used[col] = stop
        budget -= int(used.sum())
        if budget < 0:
            raise ReadError(f"{name}: corrupt Radiance run-length data (runaway decoding)")
        # component boundaries reached exactly (counts past a walk's end are all >= target)
        on_edge = np.flatnonzero(edge.take(after, mode="clip")) // steps
        hits[ids] += np.bincount(on_edge, minlength=a)
        records.append((ids, pos, head, used, f))
        if col.size:
            end = pos[stop, col]
            exact = (after[col, stop - 1] == target) & (end <= n)
            ends[ids[col[exact]]] = end[exact]
            keep = ~fin
            ids, p, f = ids[keep], pos[-1, keep], after[keep, -1]
        else:
            p, f = pos[-1], after[:, -1]
    return ends, hits == 3, records


def _rle_chain(cand: np.ndarray, ends: np.ndarray, nscan: int, name: str) -> np.ndarray:
    """Indices into ``cand`` of the real scanlines: the chain of exact walks from byte 0."""
    k = cand.size
    if k >= nscan and ends[nscan - 1] >= 0 and np.array_equal(ends[: nscan - 1], cand[1:nscan]):
        return np.arange(nscan)  # the usual file: the first nscan candidates
    nxt = np.minimum(np.searchsorted(cand, ends), k - 1)
    nxt = np.where((ends >= 0) & (cand[nxt] == ends), nxt, -1).tolist()
    ok = (ends >= 0).tolist()
    chain = [0]
    for row in range(nscan):
        i = chain[row]
        if i < 0 or not ok[i]:
            raise ReadError(
                f"{name}: corrupt or truncated Radiance run-length data at scanline {row}"
            )
        chain.append(nxt[i])
    return np.array(chain[:nscan])


def _straddle_row(records: list, on_chain: np.ndarray, starts: np.ndarray, length: int) -> int:
    """The scanline of the first run or literal, in walk order (step by step, then scanline
    by scanline), that crosses a component boundary; called when there is one."""
    for ids, pos, head, used, f in records:
        cnt = _MAG.take(head)
        before = np.cumsum(cnt, axis=0) - cnt + f
        bad = before % length + cnt > length
        bad &= (np.arange(len(head))[:, None] < used) & on_chain[ids]
        if bad.any():
            step, col = np.argwhere(bad)[0]
            return max(int(np.searchsorted(starts, pos[step, col])) - 1, 0)
    raise AssertionError("no run or literal crosses a component boundary")


def _rle_plan(buf: np.ndarray, nscan: int, length: int, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Parse ``nscan`` new-style RLE scanlines of ``length`` pixels.

    Every position that looks like a scanline header (``2 2 W_hi W_lo``) is decoded in
    parallel (:func:`_rle_walk`); the real scanlines are then the chain that starts at the
    first byte.

    Returns:
        ``(starts, rep)``: the byte offset of each scanline (and the end), and how often
        each byte appears in the decoded planes (``np.repeat`` counts).
    """
    if buf.size < 4:
        raise ReadError(f"{name}: truncated Radiance pixel data")
    cand = _rle_candidates(buf, length)
    if cand.size == 0 or cand[0] != 0:
        raise ReadError(f"{name}: corrupt Radiance run-length data at scanline 0")
    budget = 16 * nscan * length + (1 << 20)  # work bound: linear in the image size
    ends, whole, records = _rle_walk(buf, cand, length, budget, name)
    chain = _rle_chain(cand, ends, nscan, name)
    starts = np.append(cand[chain], ends[chain[-1]])
    on_chain = np.zeros(cand.size, bool)
    on_chain[chain] = True
    if not whole[chain].all():
        row = _straddle_row(records, on_chain, starts, length)
        raise ReadError(f"{name}: corrupt Radiance run-length data at scanline {row}")
    # How often each byte appears in the output: literal data bytes once (the default),
    # run headers and scanline headers never, run value bytes `count` times. Steps of
    # walks that are not scanlines, or past a scanline's end, are left out.
    rep = np.ones(int(starts[-1]), np.int8)
    after_head = rep[1:]
    for ids, pos, head, used, _ in records:
        at = pos[:-1]
        lim = np.where(on_chain[ids], used, 0)
        if lim.min() < len(head):
            mine = np.arange(len(head))[:, None] < lim
            at, head = at[mine], head[mine]
        rep[at] = 0
        after_head[at] = _REP.take(head)
    for d in range(4):
        rep[starts[:-1] + d] = 0
    return starts, rep


def _rle_blocks(
    buf: np.ndarray, nscan: int, length: int, name: str
) -> Iterator[tuple[int, int, np.ndarray]]:
    """Decoded RLE scanlines in blocks: ``(row0, row1, planes (rows, 4, length))``.

    Blocks of about ``_BLOCK_BYTES`` decoded bytes keep the temporaries in cache (np.repeat
    makes intp counts) and let the caller convert each block while it is hot.
    """
    starts, rep = _rle_plan(buf, nscan, length, name)
    rows = max(1, _BLOCK_BYTES // (4 * length))
    for r0 in range(0, nscan, rows):
        r1 = min(nscan, r0 + rows)
        s, e = int(starts[r0]), int(starts[r1])
        seg = np.repeat(buf[s:e], rep[s:e])
        if seg.size != (r1 - r0) * 4 * length:
            raise ReadError(f"{name}: corrupt Radiance run-length data (wrong pixel count)")
        yield r0, r1, seg.reshape(r1 - r0, 4, length)


def _decode_new_rle(buf: np.ndarray, nscan: int, length: int, name: str) -> np.ndarray:
    """Decode ``nscan`` new-style RLE scanlines of ``length`` pixels; ``(nscan, 4, length)``."""
    out = np.empty((nscan, 4, length), np.uint8)
    for r0, r1, planes in _rle_blocks(buf, nscan, length, name):
        out[r0:r1] = planes
    return out


def _decode_flat(buf: np.ndarray, nscan: int, length: int, name: str) -> np.ndarray:
    """Flat pixels, with old-style RLE repeats (``1 1 1 n``); ``(nscan, length, 4)``."""
    need = nscan * length
    ngroups = buf.size // 4
    px = buf[: ngroups * 4].reshape(ngroups, 4)
    marker = (px[:, 0] == 1) & (px[:, 1] == 1) & (px[:, 2] == 1)
    if not marker.any():
        if ngroups < need:
            raise ReadError(
                f"{name}: truncated Radiance pixel data ({ngroups} of {need} pixels present)"
            )
        return px[:need].reshape(nscan, length, 4)
    # Old RLE: the k-th marker of a run of markers repeats the last pixel (n << 8k) times.
    idx = np.arange(ngroups)
    run_start = np.maximum.accumulate(np.where(~marker, idx, -1))
    if marker[0]:
        raise ReadError(f"{name}: corrupt old-style Radiance run-length data (repeat at start)")
    shift = np.where(marker, idx - run_start - 1, 0)
    if np.any(shift[marker] > 3):
        raise ReadError(f"{name}: corrupt old-style Radiance run-length data (repeat overflow)")
    reps = np.where(marker, px[:, 3].astype(np.int64) << (8 * shift), 1)
    counts = np.zeros(ngroups, np.int64)
    np.add.at(counts, run_start, reps)
    total = np.cumsum(counts)
    if total[-1] < need:
        raise ReadError(
            f"{name}: truncated Radiance pixel data ({int(total[-1])} of {need} pixels)"
        )
    last = int(np.searchsorted(total, need))
    counts = counts[: last + 1].copy()
    counts[last] -= int(total[last]) - need
    out = np.repeat(px[: last + 1], counts, axis=0)
    return out.reshape(nscan, length, 4)


def _pixel_buffer(data: bytes | memoryview, name: str) -> tuple[dict, np.ndarray, int, int, bool]:
    """Header info, the pixel bytes, ``(nscan, length)`` and whether the data is new RLE."""
    info, off = parse_header(data, name)
    w, h = info["width"], info["height"]
    orient = info["orientation"]
    slow_is_y = orient[1] == "Y"
    nscan, length = (h, w) if slow_is_y else (w, h)
    if len(data) > off:
        buf = np.frombuffer(data, dtype=np.uint8, offset=off)
    else:
        buf = np.zeros(0, np.uint8)
    if buf.size < _min_pixel_bytes(nscan, length):
        raise ReadError(
            f"{name}: truncated Radiance file ({buf.size} bytes of pixel data for a "
            f"{w} x {h} image)"
        )
    rle = 8 <= length <= 0x7FFF and buf.size >= 4 and buf[0] == 2 and buf[1] == 2
    if rle and (int(buf[2]) << 8 | int(buf[3])) != length:
        raise ReadError(f"{name}: corrupt Radiance run-length data at scanline 0")
    return info, buf, nscan, length, rle


def _decode_components(data: bytes | memoryview, name: str) -> tuple[list[np.ndarray], dict]:
    """The four RGBE components as ``(H, W)`` uint8 views, top-to-bottom, left-to-right."""
    info, buf, nscan, length, rle = _pixel_buffer(data, name)
    orient = info["orientation"]
    slow_is_y = orient[1] == "Y"
    if rle:
        planes = _decode_new_rle(buf, nscan, length, name)  # (nscan, 4, length)
        comps = [planes[:, i, :] for i in range(4)]
    else:
        px = _decode_flat(buf, nscan, length, name)  # (nscan, length, 4)
        comps = [px[:, :, i] for i in range(4)]
    y_sign, x_sign = (orient[0], orient[3]) if slow_is_y else (orient[3], orient[0])
    if not slow_is_y:
        comps = [c.T for c in comps]
    if y_sign == "+":
        comps = [c[::-1] for c in comps]  # +Y: stored bottom to top
    if x_sign == "-":
        comps = [c[:, ::-1] for c in comps]  # -X: stored right to left
    return comps, info


def decode_rgbe(
    data: bytes | memoryview, name: str = "image.hdr"
) -> tuple[np.ndarray, np.ndarray, dict]:
    """Decode a Radiance file held in memory.

    Returns:
        ``(mantissas, exponents, info)``: ``(H, W, 3)`` and ``(H, W)`` uint8 arrays in
        top-to-bottom, left-to-right order, and the header ``info`` of :func:`parse_header`.

    Raises:
        ReadError: malformed header, truncated or corrupt pixel data.
    """
    comps, info = _decode_components(data, name)
    return np.stack(comps[:3], axis=2), np.ascontiguousarray(comps[3]), info


def _to_float(comps: list[np.ndarray], out: np.ndarray) -> None:
    scale = _EXP_TABLE[comps[3]]
    for i in range(3):
        np.multiply(comps[i], scale, out=out[:, :, i])


def decode_rgbe_float(data: bytes | memoryview, name: str = "image.hdr") -> tuple[np.ndarray, dict]:
    """Decode a Radiance file held in memory to ``(H, W, 3)`` float32 (no EXPOSURE applied)."""
    info, buf, nscan, length, rle = _pixel_buffer(data, name)
    if rle and info["orientation"] == "-Y +X":
        # the common layout: convert each decoded block of scanlines while it is in cache
        out = np.empty((nscan, length, 3), np.float32)
        for r0, r1, planes in _rle_blocks(buf, nscan, length, name):
            _to_float([planes[:, i, :] for i in range(4)], out[r0:r1])
        return out, info
    comps, info = _decode_components(data, name)
    out = np.empty((*comps[3].shape, 3), np.float32)
    for r0 in range(0, out.shape[0], 64):
        _to_float([c[r0 : r0 + 64] for c in comps], out[r0 : r0 + 64])
    return out, info


def rgbe_to_float(mant: np.ndarray, exp: np.ndarray) -> np.ndarray:
    """Float32 values ``m · 2^(E−136)`` (0 where E = 0) of RGBE pixels."""
    scale = _EXP_TABLE[exp]
    return np.multiply(mant, scale[..., None], dtype=np.float32)


def float_to_rgbe(rgb: np.ndarray) -> np.ndarray:
    """Encode ``(..., 3)`` float values as ``(..., 4)`` uint8 RGBE (Radiance ``setcolr``).

    Negative values and NaN become 0 (RGBE holds only non-negative values); values above
    the largest representable (about 1.7e38) saturate.
    """
    v = np.nan_to_num(
        np.asarray(rgb, dtype=np.float32), nan=0.0, posinf=float(np.finfo(np.float32).max)
    )
    v = np.maximum(v, 0.0)
    vmax = v.max(axis=-1)
    mant, e = np.frexp(vmax)
    small = vmax < 1e-32
    # scale so that the largest component maps to mantissa in [128, 256)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(small, 0.0, mant * 256.0 / np.where(small, 1.0, vmax))
    out = np.empty(v.shape[:-1] + (4,), np.uint8)
    out[..., :3] = np.clip(v * f[..., None], 0, 255).astype(np.uint8)
    out[..., 3] = np.where(small, 0, np.clip(e + 128, 0, 255)).astype(np.uint8)
    return out


def _encode_rle_block(planes: np.ndarray) -> bytes:
    """New-style RLE for a block ``(rows, 4, L)`` of uint8 component planes."""
    rows, _, length = planes.shape
    a = planes.reshape(-1)
    total = a.size
    # runs of equal bytes within each (row, component) stream
    j = np.arange(total) % length
    brk = np.ones(total, bool)
    brk[1:] = (a[1:] != a[:-1]) | (j[1:] == 0)
    rs = np.flatnonzero(brk)
    rl = np.diff(np.append(rs, total))
    long = rl >= 4
    # literal segments: maximal groups of consecutive short runs within a stream
    stream = rs // length
    seg_start = long.copy()
    seg_start[1:] |= long[:-1] | (stream[1:] != stream[:-1])
    seg_start[0] = True
    sidx = np.flatnonzero(seg_start)
    seg_len = np.add.reduceat(rl, sidx)
    seg_pos = rs[sidx]
    seg_long = long[sidx]
    # split segments into chunks of at most 127 (runs) or 128 (literals)
    maxlen = np.where(seg_long, 127, 128)
    nchunk = -(-seg_len // maxlen)
    cseg = np.repeat(np.arange(sidx.size), nchunk)
    first = np.cumsum(nchunk) - nchunk
    k = np.arange(cseg.size) - first[cseg]
    c_pos = seg_pos[cseg] + k * maxlen[cseg]
    c_len = np.minimum(maxlen[cseg], seg_len[cseg] - k * maxlen[cseg])
    c_run = seg_long[cseg]
    c_size = np.where(c_run, 2, 1 + c_len)
    c_stream = c_pos // length
    # output offset of each chunk: 4 header bytes before each row's first stream
    row_of = c_stream // 4
    c_out = np.cumsum(c_size) - c_size + 4 * (row_of + 1)
    out = np.empty(int(c_size.sum()) + 4 * rows, np.uint8)
    # row header position: 4*row + bytes of all chunks before the row's first chunk
    first_chunk = np.searchsorted(row_of, np.arange(rows))
    before = np.concatenate([[0], np.cumsum(c_size)])[first_chunk]
    row_head = before + 4 * np.arange(rows)
    out[row_head] = 2
    out[row_head + 1] = 2
    out[row_head + 2] = length >> 8
    out[row_head + 3] = length & 0xFF
    out[c_out] = np.where(c_run, 128 + c_len, c_len).astype(np.uint8)
    out[c_out[c_run] + 1] = a[c_pos[c_run]]
    lit = ~c_run
    l_pos, l_len, l_out = c_pos[lit], c_len[lit], c_out[lit] + 1
    ne = int(l_len.sum())
    if ne:
        lchunk = np.repeat(np.arange(l_pos.size), l_len)
        off = np.arange(ne) - (np.cumsum(l_len) - l_len)[lchunk]
        out[l_out[lchunk] + off] = a[l_pos[lchunk] + off]
    return out.tobytes()


def encode_rgbe(
    rgb: np.ndarray,
    *,
    rle: bool = True,
    header_lines: list[str] | None = None,
    exposure: float | None = None,
) -> bytes:
    """Encode ``(H, W, 3)`` linear values as a Radiance file (``-Y H +X W``).

    Args:
        rgb: non-negative linear values (negative values are written as 0).
        rle: new-style run-length encoding (ignored for widths outside 8..32767, which
            Radiance cannot run-length encode).
        header_lines: extra ``NAME=value`` lines for the header.
        exposure: when given, write an ``EXPOSURE=`` line (pixels are stored multiplied
            by it; readers divide it out).
    """
    rgb = np.asarray(rgb, dtype=np.float32)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"expected an (H, W, 3) image for Radiance RGBE, got {rgb.shape}")
    h, w = rgb.shape[:2]
    lines = ["#?RADIANCE", "SOFTWARE=hdrjax", "FORMAT=32-bit_rle_rgbe"]
    if exposure is not None:
        lines.append(f"EXPOSURE={float(exposure):.9g}")
        rgb = rgb * np.float32(exposure)
    for ln in header_lines or []:
        if "\n" in ln:
            raise ValueError(f"Radiance header lines must not contain newlines: {ln!r}")
        lines.append(ln)
    head = ("\n".join(lines) + f"\n\n-Y {h} +X {w}\n").encode("latin-1")
    px = float_to_rgbe(rgb)
    if not rle or not (8 <= w <= 0x7FFF):
        return head + px.tobytes()
    chunks = [head]
    block = max(1, (1 << 22) // (4 * w))
    for r0 in range(0, h, block):
        planes = px[r0 : r0 + block].transpose(0, 2, 1)
        chunks.append(_encode_rle_block(np.ascontiguousarray(planes)))
    return b"".join(chunks)


def _min_pixel_bytes(nscan: int, length: int) -> int:
    """The fewest bytes ``nscan`` scanlines of ``length`` pixels can take: every RLE
    scanline has 4 header bytes + 2 bytes per 127 pixels per component (or flat pixels,
    when fewer); absurd headers are refused with this before anything is allocated."""
    return min(nscan * (4 + 8 * -(-length // 127)), nscan * length * 4)


def _max_pixel_bytes(nscan: int, length: int) -> int:
    """The most bytes ``nscan`` scanlines of ``length`` pixels can take: flat pixels, or
    new RLE scanlines made of literals only (a count byte per 128 bytes)."""
    return nscan * max(4 * length, 4 + 4 * (length + -(-length // 128)))


def correct_exposure(rgb: np.ndarray, info: dict) -> None:
    """Divide ``rgb`` (float32, in place) by the header's EXPOSURE × COLORCORR.

    The product is checked by :func:`parse_header`; a pixel whose corrected value exceeds
    float32's range (a large mantissa and exponent with a small exposure) saturates at the
    largest finite float32, as :func:`float_to_rgbe` saturates when encoding.
    """
    corr = np.array(info["colorcorr"], np.float64) * info["exposure"]
    if np.all(corr == 1.0):
        return
    inv = (1.0 / corr).astype(np.float32)
    with np.errstate(over="ignore"):
        rgb *= inv
    if float(inv.max()) * _RGBE_MAX >= 0.99 * _F32_MAX:
        np.minimum(rgb, np.float32(_F32_MAX), out=rgb)


def decode_radiance(data: bytes | memoryview, name: str = "image.hdr") -> tuple[np.ndarray, dict]:
    """Decode a Radiance file held in memory to ``(values (H, W, 3) float32, info)`` with
    EXPOSURE and COLORCORR divided out (see :func:`correct_exposure`)."""
    rgb, info = decode_rgbe_float(data, name)
    correct_exposure(rgb, info)
    return rgb, info


def read_rgbe_file(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Read a Radiance file; returns ``(values (H, W, 3) float32, info)``.

    EXPOSURE and COLORCORR are divided out, so the values are the original radiance
    (in the file's units). The header is read first; then at most the bytes the declared
    image can take (flat, or run-length encoded with no runs): data after the image is
    ignored, as Radiance's own readers stop after the last scanline.
    """
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = f.read(_HEADER_LIMIT)
            info, off = parse_header(data, path.name)
            nscan = info["height"] if info["orientation"][1] == "Y" else info["width"]
            length = info["width"] + info["height"] - nscan
            limit = off + _max_pixel_bytes(nscan, length)
            size = os.fstat(f.fileno()).st_size
            if 0 < size < off + _min_pixel_bytes(nscan, length):
                raise ReadError(
                    f"{path.name}: truncated Radiance file ({size - off} bytes of pixel data "
                    f"for a {info['width']} x {info['height']} image)"
                )
            data = _read_rest(f, data, min(limit, size) if size > 0 else limit)
    except OSError as e:
        raise OSError(f"{path.name}: cannot read ({e.strerror or e})") from None
    return decode_radiance(data[:limit], path.name)


def _read_rest(f, head: bytes, end: int) -> memoryview:
    """``head`` (the first bytes of ``f``) followed by the rest of ``f`` up to byte ``end``,
    in one buffer (no second copy of the pixel data)."""
    if len(head) >= end:
        return memoryview(head)
    buf = bytearray(end)
    buf[: len(head)] = head
    view = memoryview(buf)
    n = len(head)
    while n < end:
        k = f.readinto(view[n:])
        if not k:
            break
        n += k
    return view[:n]


__all__ = [
    "correct_exposure",
    "decode_radiance",
    "decode_rgbe",
    "decode_rgbe_float",
    "encode_rgbe",
    "float_to_rgbe",
    "parse_header",
    "read_rgbe_file",
    "rgbe_to_float",
]
