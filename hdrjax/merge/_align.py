"""Translation alignment of hand-held brackets: median threshold bitmaps (Ward 2003).

Ward, G. (2003). Fast, robust image registration for compositing high dynamic range
photographs from hand-held exposures. *Journal of Graphics Tools*, 8(2), 17–30.
DOI 10.1080/10867651.2003.10487583.

Each exposure is reduced to grey, ``(54 R + 183 G + 19 B) / 256`` (the paper's weights), on
an 8-bit scale (16-bit codes divided by 256). Its *median threshold bitmap* is ``grey >
median`` and its *exclusion bitmap* ``|grey − median| > exclude`` (pixels too close to the
median flip with noise and are left out). Both bitmaps hardly change with exposure, so two
exposures line up where the bitmaps agree. The shift is found coarse to fine on an image
pyramid (2 × 2 box averages, the paper's ``ImageShrink2``): at the coarsest level the nine
offsets ``{−1, 0, 1}²`` are tried (but see the deviations); each finer level doubles the
shift found so far and tries the nine offsets around it. The error of an offset is the
number of pixels where the threshold bitmaps differ and both exclusion bitmaps are set:
``popcount((tb₁ ⊕ tb₂) ∧ eb₁ ∧ eb₂)``. With ``d`` levels below full resolution the search
reaches ``±(2^{d+1} − 1)`` px; ``d`` follows ``max_shift`` (the smallest ``d`` that reaches
it), and the full-resolution shift is confined to ``±max_shift``.

Deviations from the paper: (1) the pyramid stops where the short side of a level would
drop below 32 px, and that coarsest level is searched exhaustively over ``±r`` (``r`` the
smallest radius that still reaches ``max_shift``) instead of ±1: with ±1 all the way down, a
256 × 384 bracket's coarsest level is 8 × 12 px, and 32-px shifts came out wrong on 3 of 6
test scenes. On large images (short side ≥ 1024 px for ``max_shift=32``) this is the paper's
search. (2) The errors of the offsets of one level are counted over one common region (the
overlap of the image with itself moved by the largest offset tried) instead of over the whole
bitmaps with zero fill, so all counts cover the same pixels. The median is found by
bisection over the 256 grey levels rather than from a histogram (the same value).

The bitmaps are packed eight pixels to a byte and counted with a population count (the
paper's bit-parallel implementation); NumPy, not JAX: the work is bit operations and a
median, not pixel arithmetic.

Sign convention: ``align_mtb`` returns for each exposure the translation ``(dx, dy)`` by
which its content is *displaced* relative to the reference exposure — the member shows the
scene moved ``dx`` px right and ``dy`` px down, as ``shifts=`` of
:func:`hdrjax.merge.simulate_bracket` means. :func:`apply_shifts` moves each exposure back
by ``(−dx, −dy)``. OpenCV's ``AlignMTB.calculateShift`` returns the opposite sign (the
correction to apply).
"""

import math
from typing import Any

import numpy as np

from ._bracket import as_codes, reference_index

_GREY_WEIGHTS = (54, 183, 19)  # Ward (2003): grey = (54 R + 183 G + 19 B) / 256
# Coarsest pyramid level's short side, px: at 8 × 12 px the 32-px shift of a 256 × 384
# bracket was wrong on 3 of 6 test scenes (a ±1 step there is a quarter of the image)
_MIN_SIZE = 32
_ROWS = 64  # rows per block of the grey conversion (stays in cache: twice as fast)


def _grey(codes: np.ndarray) -> np.ndarray:
    """8-bit grey of each exposure, ``(N, H, W)`` uint8."""
    n, h, w, _ = codes.shape
    out = np.empty((n, h, w), np.uint8)
    wide = np.uint32 if codes.dtype == np.uint16 else np.uint16
    shift = 16 if codes.dtype == np.uint16 else 8
    for j in range(n):
        for r in range(0, h, _ROWS):
            c = codes[j, r : r + _ROWS]
            acc = np.multiply(c[..., 0], _GREY_WEIGHTS[0], dtype=wide)
            acc += np.multiply(c[..., 1], _GREY_WEIGHTS[1], dtype=wide)
            acc += np.multiply(c[..., 2], _GREY_WEIGHTS[2], dtype=wide)
            out[j, r : r + _ROWS] = acc >> shift
    return out


def _shrink2(g: np.ndarray) -> np.ndarray:
    """Half-size image: the mean of each 2 × 2 block (an odd last row/column is dropped)."""
    h, w = g.shape[0] // 2 * 2, g.shape[1] // 2 * 2
    s = g[0:h:2, 0:w:2].astype(np.uint16)
    s += g[1:h:2, 0:w:2]
    s += g[0:h:2, 1:w:2]
    s += g[1:h:2, 1:w:2]
    return ((s + 2) >> 2).astype(np.uint8)


def _bitmaps(g: np.ndarray, exclude: int) -> tuple[np.ndarray, np.ndarray]:
    """Median threshold bitmap and exclusion bitmap of an 8-bit grey image."""
    # the median by bisection on the 256 grey levels: 8 counting passes over uint8 are
    # faster than a histogram (np.bincount widens every pixel to int64)
    half, lo, hi = (g.size + 1) // 2, 0, 255
    while lo < hi:
        mid = (lo + hi) // 2
        if np.count_nonzero(g <= mid) >= half:
            hi = mid
        else:
            lo = mid + 1
    median = lo
    tb = g > median
    low, high = max(median - exclude, 0), min(median + exclude, 255)
    # g outside [low, high] ⇔ (g − low) mod 256 > high − low
    eb = (g - np.uint8(low)) > np.uint8(high - low)
    return tb, eb


def _level_shift(
    ref: tuple[np.ndarray, np.ndarray],
    mov: tuple[np.ndarray, np.ndarray],
    centre: tuple[int, int],
    bound: int,
    radius: int = 1,
) -> tuple[int, int]:
    """The best offset (dx, dy) within ``±radius`` of ``centre`` at one pyramid level.

    ``mov`` is modelled as ``ref`` displaced by (dx, dy): ``mov[y + dy, x + dx] ≈ ref[y, x]``.
    """
    tb_r, eb_r = ref
    tb_m, eb_m = mov
    h, w = tb_r.shape
    cx, cy = centre
    # one region of ref valid for every offset (|dx|, |dy| ≤ |centre| + radius)
    mx, my = abs(cx) + radius, abs(cy) + radius
    x0, x1, y0, y1 = mx, w - mx, my, h - my
    if x1 <= x0 or y1 <= y0:
        return (int(np.clip(cx, -bound, bound)), int(np.clip(cy, -bound, bound)))
    rt = np.packbits(tb_r[y0:y1, x0:x1], axis=1)
    re = np.packbits(eb_r[y0:y1, x0:x1], axis=1)
    best, best_err = (cx, cy), None
    steps = range(-radius, radius + 1)
    offsets = [(0, 0)] + [(i, j) for j in steps for i in steps if (i, j) != (0, 0)]
    packed: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    for i, j in offsets:
        dx, dy = cx + i, cy + j
        if abs(dx) > bound or abs(dy) > bound:
            continue
        if dx not in packed:
            # rows y0 − radius … y1 + radius moved by the centre's dy, columns moved by dx
            rows = slice(y0 + cy - radius, y1 + cy + radius)
            cols = slice(x0 + dx, x1 + dx)
            packed[dx] = (
                np.packbits(tb_m[rows, cols], axis=1),
                np.packbits(eb_m[rows, cols], axis=1),
            )
        mt, me = packed[dx]
        sel = slice(radius + j, radius + j + (y1 - y0))
        diff = np.bitwise_xor(rt, mt[sel])
        diff &= re
        diff &= me[sel]
        err = int(np.bitwise_count(diff).sum(dtype=np.int64))
        if best_err is None or err < best_err:
            best, best_err = (dx, dy), err
    return best


def _check_int(value: Any, name: str, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
        raise ValueError(f"{name}: expected an integer ≥ {low}, got {value!r}")
    return int(value)


def align_mtb(
    images: Any, *, max_shift: int = 32, exclude: int = 4, reference: int | None = None
) -> np.ndarray:
    """Integer translations of a hand-held bracket by median threshold bitmaps (Ward 2003).

    Args:
        images: a bracket: ``(N, H, W, 3)`` uint8/uint16 code values, a list of ``(H, W, 3)``
            arrays, or file paths (see :func:`hdrjax.merge.as_codes`).
        max_shift: the largest translation searched, in pixels (per axis); the pyramid has
            the fewest levels that reach it. Shifts up to ``max_shift`` are found exactly when
            the scene has structure at the coarsest level.
        exclude: half-width of the exclusion band around the median, in 8-bit grey levels
            (Ward's 4; 16-bit grey is on the same 0–255 scale).
        reference: index of the exposure the others are aligned to; default ``N // 2`` (the
            middle one of an odd bracket; OpenCV's AlignMTB pivot).

    Returns:
        ``(N, 2)`` int64 ``(dx, dy)`` per exposure: its content is displaced ``dx`` px right
        and ``dy`` px down relative to the reference (the reference's row is ``(0, 0)``).
        :func:`apply_shifts` with these shifts aligns the bracket.
    """
    codes = as_codes(images, need_times=False).codes
    max_shift = _check_int(max_shift, "max_shift", 0)
    exclude = _check_int(exclude, "exclude", 0)
    n, h, w, _ = codes.shape
    ref = reference_index(reference, n)
    # d levels below full size reach ±(2^(d+1) − 1) px with Ward's ±1 per level; the
    # coarsest level keeps at least _MIN_SIZE px on its short side, and searches
    # ±r exhaustively, with r the smallest radius for which r 2^d + 2^d − 1 ≥ max_shift
    depth = max(0, math.ceil(math.log2(max_shift + 1)) - 1) if max_shift > 0 else 0
    depth = max(0, min(depth, int(math.log2(max(min(h, w) // _MIN_SIZE, 1)))))
    radius = max(1, -(-(max_shift - (1 << depth) + 1) // (1 << depth)))
    greys = _grey(codes)

    def pyramid(g: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        levels = [g]
        for _ in range(depth):
            levels.append(_shrink2(levels[-1]))
        return [_bitmaps(lv, exclude) for lv in levels]

    ref_pyr = pyramid(greys[ref])
    out = np.zeros((n, 2), np.int64)
    for j in range(n):
        if j == ref or max_shift == 0:
            continue
        mov_pyr = pyramid(greys[j])
        shift = (0, 0)
        for level in range(depth, -1, -1):
            bound = -(-max_shift // (1 << level))
            centre = (2 * shift[0], 2 * shift[1]) if level < depth else (0, 0)
            r = radius if level == depth else 1
            shift = _level_shift(ref_pyr[level], mov_pyr[level], centre, bound, r)
        out[j] = shift
    return out


def apply_shifts(images: Any, shifts: Any) -> np.ndarray:
    """Undo the translations :func:`align_mtb` found: member ``j`` moved by ``−shifts[j]``.

    ``out[j][y, x] = images[j][y + dy_j, x + dx_j]``; pixels that come from outside the
    frame repeat the nearest border pixel (as :func:`hdrjax.merge.simulate_bracket` fills
    its shifted members), so a strip of ``|dx|`` columns and ``|dy|`` rows at the borders
    holds no new information: crop it, or mask it out of a merge. Leave it out of
    :func:`hdrjax.merge.recover_response` above all: its flat, repeated pixels are what the
    sample selection prefers, and they disagree between exposures (measured: 9 % median
    error of the recovered response on a 512 × 256 bracket shaken by 6 px, 0.8 % cropped;
    ``hdrjax merge --align`` recovers the response from the inside).

    Args:
        images: ``(N, H, W)`` or ``(N, H, W, C)`` array (any dtype), or a list of such
            members of one shape.
        shifts: ``(N, 2)`` integer ``(dx, dy)``, as :func:`align_mtb` returns.

    Returns:
        A NumPy array of the input's shape and dtype.
    """
    try:
        arr = np.asarray(images)
    except ValueError:
        raise ValueError("images: expected N members of one shape") from None
    if arr.ndim not in (3, 4) or arr.dtype == object:
        raise ValueError(
            f"images: expected an (N, H, W) or (N, H, W, C) array, got shape {arr.shape}"
        )
    sh = np.asarray(shifts)
    if sh.shape != (arr.shape[0], 2) or not np.issubdtype(sh.dtype, np.integer):
        if not (
            sh.shape == (arr.shape[0], 2)
            and np.issubdtype(sh.dtype, np.floating)
            and np.all(sh == np.round(sh))
        ):
            raise ValueError(
                f"shifts: expected ({arr.shape[0]}, 2) integer (dx, dy), got "
                f"shape {sh.shape} dtype {sh.dtype}"
            )
    sh = sh.astype(np.int64)
    n, h, w = arr.shape[:3]
    out = np.empty_like(arr)
    for j in range(n):
        dx, dy = int(sh[j, 0]), int(sh[j, 1])
        rows = np.clip(np.arange(h) + dy, 0, h - 1)
        cols = np.clip(np.arange(w) + dx, 0, w - 1)
        out[j] = arr[j][rows][:, cols]
    return out
