"""Scaling: run time vs image size for the operators, filters and statistics (issue 9).

Run: ``.venv/bin/python benchmarks/bench_scaling.py [--quick]``

Sizes n×n: 256², 512², 1024², 2048², 4096², 8192² in full mode, and 15000² for the filters
(2.7 GB of float32 RGB); quick mode 256², 1024², 2048² (``reinhard2002_local`` up to
1024²). Images are ``data/venice_sunset_1k.hdr`` tiled to the size (real content, 26
stops). Each size is compiled separately (its first call is reported as ``compile_s``) and
timed with :func:`_harness.measure`. A size whose estimated working memory exceeds 70 % of
the available memory is skipped (printed, and listed in the slope record).

Records: ``benchmark="scaling"``, ``case="<op> <n>x<n>"``, ``extra={"op", "pixels"}``; one
``benchmark="scaling-slope"`` record per operation with the least-squares slope of
log(time) against log(pixels) (``slope``: sizes from 512² up, where the fixed per-call
overhead no longer dominates, or every size when fewer than two are that large;
``slope_all``: every size). A slope of 1 means cost linear
in the number of pixels; the report plots time vs pixels on log–log axes.
"""

import argparse
import json
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import _harness as H
import jax
import numpy as np

import hdrjax
import hdrjax.io

REPO = Path(__file__).resolve().parents[1]
IMAGE = REPO / "data" / "venice_sunset_1k.hdr"
FULL_SIZES = (256, 512, 1024, 2048, 4096, 8192)
FILTER_EXTRA = (15000,)
QUICK_SIZES = (256, 1024, 2048)
QUICK_CAP = {"reinhard2002_local": 1024}
SLOPE_MIN_PIXELS = 512 * 512
MEMORY_SHARE = 0.7
"""A size runs when its estimated working set is below this share of MemAvailable."""
BYTES_PER_PIXEL = {
    # rough peak working set per pixel (input included), to skip sizes that cannot fit
    "reinhard2002": 40,
    "tumblin_reinhard": 40,
    "linear": 30,
    "reinhard2002_local": 160,
    "median_filter 5x5": 30,
    "mean_filter 5x5": 30,
    "stats.measure": 20,
}


def _tonemap(name: str) -> Callable[[jax.Array], jax.Array]:
    return lambda rgb: hdrjax.tonemap(rgb, name)


OPS: dict[str, tuple[str, Callable[[jax.Array], Any]]] = {
    # name: (input kind, function); "reinhard2002" is the automatic (JGT key/white) default
    "reinhard2002": ("rgb", _tonemap("reinhard2002")),
    "tumblin_reinhard": ("rgb", _tonemap("tumblin_reinhard")),
    "linear": ("rgb", _tonemap("linear")),
    "reinhard2002_local": ("rgb", _tonemap("reinhard2002_local")),
    "median_filter 5x5": ("rgb", lambda rgb: hdrjax.median_filter(rgb, 5)),
    "mean_filter 5x5": ("rgb", lambda rgb: hdrjax.mean_filter(rgb, 5)),
    "stats.measure": ("lum", jax.jit(hdrjax.stats.measure)),
}
FILTERS = ("median_filter 5x5", "mean_filter 5x5")


def loglog_slope(pixels, times) -> float:
    """Least-squares slope of ``log(time)`` against ``log(pixels)`` (1 = linear cost)."""
    x = np.log(np.asarray(pixels, np.float64))
    y = np.log(np.asarray(times, np.float64))
    if x.size < 2 or np.ptp(x) == 0:
        return float("nan")
    return float(np.polyfit(x, y, 1)[0])


def available_bytes() -> int:
    """``MemAvailable`` from /proc/meminfo (a large number where it cannot be read)."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 1 << 50


def tiled(base: np.ndarray, n: int) -> np.ndarray:
    """``base`` repeated to fill n×n (cropped), float32, filled in place (no temporaries
    larger than the result: at 15000² the result alone is 2.7 GB)."""
    h, w = base.shape[:2]
    out = np.empty((n, n) + base.shape[2:], np.float32)
    for i in range(0, n, h):
        for j in range(0, n, w):
            out[i : i + h, j : j + w] = base[: n - i, : n - j]
    return out


def sizes_for(op: str, quick: bool) -> tuple[int, ...]:
    if quick:
        cap = QUICK_CAP.get(op, max(QUICK_SIZES))
        return tuple(n for n in QUICK_SIZES if n <= cap)
    return FULL_SIZES + (FILTER_EXTRA if op in FILTERS else ())


def repeats_for(n: int) -> int:
    return 5 if n <= 1024 else 3 if n <= 4096 else 2


def run(quick: bool = False, ops: tuple[str, ...] | None = None) -> list[dict]:
    """Time every operation at every size; slope records at the end."""
    t0 = time.perf_counter()
    base = np.asarray(hdrjax.io.read(IMAGE).rgb(), np.float32)
    ops = tuple(OPS) if ops is None else ops
    plan = {op: sizes_for(op, quick) for op in ops}
    recs: list[dict] = []
    points: dict[str, list[tuple[int, float]]] = {op: [] for op in ops}
    skipped: dict[str, list[int]] = {op: [] for op in ops}
    for n in sorted({n for s in plan.values() for n in s}):
        todo = [op for op in ops if n in plan[op]]
        host = tiled(base, n)
        rgb = jax.device_put(host)
        del host
        lum = x = None
        for op in todo:
            kind, fn = OPS[op]
            if BYTES_PER_PIXEL[op] * n * n > MEMORY_SHARE * available_bytes():
                print(f"[scaling] {op} {n}x{n}: skipped (not enough free memory)", flush=True)
                skipped[op].append(n)
                continue
            if kind == "lum" and lum is None:
                lum = jax.block_until_ready(jax.jit(hdrjax.luminance)(rgb))
            x = rgb if kind == "rgb" else lum
            rec = H.record(
                "scaling",
                f"{op} {n}x{n}",
                "hdrjax",
                lambda fn=fn, x=x: fn(x),
                repeats=repeats_for(n),
                compiled=True,
                op=op,
                pixels=n * n,
            )
            recs.append(rec)
            points[op].append((n * n, rec["median_s"]))
        del rgb, lum, x  # free this size's arrays before the next (8192²: 1 GB)
    for op in ops:
        if not points[op]:
            continue
        px, ts = zip(*points[op], strict=True)
        big = [(p, t) for p, t in points[op] if p >= SLOPE_MIN_PIXELS]
        all_slope = loglog_slope(px, ts)
        slope = loglog_slope(*zip(*big, strict=True)) if len(big) >= 2 else all_slope
        last = next(r for r in reversed(recs) if r["extra"]["op"] == op)
        last["extra"]["slope"] = slope
        recs.append(
            H.record(
                "scaling-slope",
                op,
                "hdrjax",
                timing={"median_s": ts[-1], "spread_s": 0.0, "repeats": 1, "first_s": math.nan},
                op=op,
                slope=slope,
                slope_all=all_slope,
                pixels=list(px),
                times_s=list(ts),
                skipped_sizes=skipped[op],
            )
        )
    print(f"[scaling] {len(recs)} records in {time.perf_counter() - t0:.1f} s", flush=True)
    return recs


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="256², 1024², 2048² only")
    ap.add_argument("--ops", help="comma-separated subset of: " + ", ".join(OPS))
    ap.add_argument("--json", help="write the records to this file")
    args = ap.parse_args()
    ops = tuple(s.strip() for s in args.ops.split(",")) if args.ops else None
    if ops is not None:
        unknown = sorted(set(ops) - set(OPS))
        if unknown:
            ap.error(f"--ops: unknown {', '.join(unknown)}; valid: {', '.join(OPS)}")
    recs = run(args.quick, ops)
    if args.json:
        Path(args.json).write_text(json.dumps(recs, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
