"""Shared timing and record format for every benchmark in ``benchmarks/``.

Every ``benchmarks/bench_*.py`` module exposes ``run(quick: bool = False) -> list[dict]``
returning records made by :func:`record` (timings) or :func:`accuracy_point` (one point of an
accuracy/time curve). The suite runner collects them into one JSON file, a Markdown report
and plots. Records with the same ``benchmark`` and ``case`` are compared: ``impl == "hdrjax"``
(or an impl starting with ``"hdrjax"``) is the numerator of each ratio, every other impl of
the same case is a peer, so a ratio below 1 means hdrjax is faster.

Times: one warm-up call first (its extra time over the median run is the compile time when
the function is jit-compiled), then ``repeats`` calls; the median and the half-range are
recorded (and the fastest call, ``min_s``: other processes on a shared machine only ever add
time). Outputs are blocked on (``jax.block_until_ready``) so asynchronous dispatch is not
mistaken for speed. A benchmark that times its calls itself (interleaving two readers, say)
turns its list of times into the same summary with :func:`summarize`; one that measures
compilation directly (``jit(f).lower(x).compile()``) passes ``compile_s=`` to :func:`record`.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any

import jax


def _call(fn: Callable[[], Any]) -> float:
    t0 = time.perf_counter()
    jax.block_until_ready(fn())
    return time.perf_counter() - t0


def summarize(times: list[float], first_s: float = float("nan")) -> dict[str, float]:
    """``{"median_s", "spread_s", "repeats", "first_s", "min_s"}`` of measured call times (s).

    The spread is the half-range ``(max - min) / 2``; ``first_s`` is the warm-up call (NaN
    when there was none).
    """
    if not times:
        raise ValueError("summarize: times is empty (expected at least one measured call)")
    return {
        "median_s": statistics.median(times),
        "spread_s": (max(times) - min(times)) / 2,
        "repeats": len(times),
        "first_s": first_s,
        "min_s": min(times),
    }


def measure(fn: Callable[[], Any], repeats: int = 5, warmup: bool = True) -> dict[str, float]:
    """Time ``fn()``: ``{"median_s", "spread_s", "repeats", "first_s", "min_s"}``.

    ``first_s`` is the first (warm-up) call, which includes tracing and compilation for a
    jit-compiled function; ``compile_s`` in :func:`record` is ``first_s - median_s``.
    """
    first = _call(fn) if warmup else float("nan")
    return summarize([_call(fn) for _ in range(max(1, repeats))], first)


def record(
    benchmark: str,
    case: str,
    impl: str,
    fn: Callable[[], Any] | None = None,
    *,
    repeats: int = 5,
    compiled: bool = False,
    timing: dict[str, float] | None = None,
    compile_s: float | None = None,
    verbose: bool = True,
    **extra: Any,
) -> dict[str, Any]:
    """Time ``fn`` (or take a ready ``timing`` from :func:`measure`) and make a record.

    ``compiled=True`` reports ``compile_s`` (first call minus median), for jit-compiled
    hdrjax functions; peers get ``compile_s = None``. A ``compile_s`` given explicitly (a
    measured ``lower(...).compile()``) is reported as it is. ``extra`` keeps anything else
    the report should show (error against a reference, steps, peak memory, frames/s ...).
    """
    t = timing if timing is not None else measure(fn, repeats)
    rec: dict[str, Any] = {
        "benchmark": benchmark,
        "case": case,
        "impl": impl,
        "median_s": float(t["median_s"]),
        "spread_s": float(t["spread_s"]),
        "repeats": int(t["repeats"]),
        "compile_s": (
            max(0.0, float(t["first_s"]) - float(t["median_s"]))
            if compiled and t.get("first_s") == t.get("first_s")
            else None
        ),
        "extra": dict(extra),
    }
    if compile_s is not None:
        rec["compile_s"] = float(compile_s)
    if "min_s" in t:
        rec["min_s"] = float(t["min_s"])
    if verbose:
        comp = "" if rec["compile_s"] is None else f"  compile {rec['compile_s']:.2f} s"
        more = "".join(f"  {k}={_fmt(v)}" for k, v in extra.items())
        print(
            f"[{benchmark}] {case:<40} {impl:<28} {rec['median_s'] * 1e3:10.2f} ms"
            f" ±{rec['spread_s'] * 1e3:.2f}{comp}{more}",
            flush=True,
        )
    return rec


def accuracy_point(
    curve: str,
    setting: str,
    error: float,
    time_s: float,
    *,
    default: bool = False,
    error_kind: str = "max relative error",
    verbose: bool = True,
    **extra: Any,
) -> dict[str, Any]:
    """One measured point of an accuracy/time curve (error against a float64 exact reference
    vs run time after compilation); ``default`` marks the library's default setting."""
    rec = {
        "benchmark": "accuracy",
        "curve": curve,
        "setting": setting,
        "error": float(error),
        "error_kind": error_kind,
        "time_s": float(time_s),
        "default": bool(default),
        "extra": dict(extra),
    }
    if verbose:
        mark = " (default)" if default else ""
        print(
            f"[accuracy] {curve:<28} {setting:<24}{mark:<10} error {error:.3g}"
            f"  time {time_s * 1e3:.2f} ms",
            flush=True,
        )
    return rec


def _fmt(v: Any) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)
