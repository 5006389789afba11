"""Compile time and first-call latency of every public operation, and the persistent cache.

Run: ``.venv/bin/python benchmarks/bench_compile.py [--quick]``

Each operation runs in **fresh subprocesses**, so nothing compiled in this process (or by a
previous operation) hides its cost:

1. no persistent cache (``jax_enable_compilation_cache`` off): the first call's time is
   tracing + lowering + XLA compilation + the run;
2. persistent cache on, in an empty temporary folder (``jax_compilation_cache_dir``,
   ``jax_persistent_cache_min_compile_time_secs = 0``, minimum entry size 0): fills it;
3. a new process with the same, now warm, folder: the first call's time is tracing +
   lowering + loading the executable + the run.

Quick mode (four operations) skips process 1: the cache-filling first call (a miss:
compile + write, within noise of process 1) stands for the cold one (``cold_mode``).

The steady-state time is the median of three further calls in process 1. Each record's
``median_s`` is that steady time and ``compile_s`` the no-cache first call minus it;
``extra`` holds ``first_call_s`` (no cache), ``first_call_warm_s`` (warm cache), their
ratio and the process wall time. Inputs: ``data/venice_sunset_1k.hdr`` (1024×512; its
luminance for the statistics and false colour), in cd/m² for the vision step.

The command line enables the persistent cache by default (``hdrjax/cli``: in
``$XDG_CACHE_HOME/hdrjax/jax``, ``HDRJAX_CACHE=0`` disables it). ``hdrjax tonemap
data/venice_sunset_1k.hdr -o out.png`` is timed end to end (process start to PNG written)
with ``XDG_CACHE_HOME`` set to a temporary folder: once cold (empty cache), then warm; the
goal is under 2 s warm (``extra``: ``goal_s``, ``met``).
"""

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import _harness as H

REPO = Path(__file__).resolve().parents[1]
IMAGE = REPO / "data" / "venice_sunset_1k.hdr"
CLI_GOAL_S = 2.0
QUICK_OPS = ("tonemap reinhard2002", "tonemap linear", "median_filter", "desaturate_highlights")
OTHER_OPS = (
    "median_filter",
    "mean_filter",
    "desaturate_highlights",
    "false_color",
    "stats.measure",
    "lights.detect",
    "vision.simulate",
    "fit reinhard2002 key",
)

# The child process: configure the cache, build one operation, time its first call and
# three steady calls, print one JSON line. ``argv[1]``: operation; ``argv[2]``: cache dir
# or "" (cache off).
CHILD = r"""
import json, statistics, sys, time
t_start = time.perf_counter()
import jax
op, cache = sys.argv[1], sys.argv[2]
if cache:
    jax.config.update("jax_compilation_cache_dir", cache)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
else:
    jax.config.update("jax_enable_compilation_cache", False)
import numpy as np
import jax.numpy as jnp
import hdrjax, hdrjax.io
rgb = jnp.asarray(np.asarray(hdrjax.io.read(sys.argv[3]).rgb(), np.float32))
L = hdrjax.luminance(rgb)
jax.block_until_ready((rgb, L))
EXTRA = {"tabulated": dict(luminance=[0.01, 1.0, 100.0], display=[0.02, 0.5, 1.0])}
if op.startswith("tonemap "):
    name = op.split(" ", 1)[1]
    fn = lambda: hdrjax.tonemap(rgb, name, **EXTRA.get(name, {}))
elif op == "median_filter":
    fn = lambda: hdrjax.median_filter(rgb, 5)
elif op == "mean_filter":
    fn = lambda: hdrjax.mean_filter(rgb, 5)
elif op == "desaturate_highlights":
    fn = lambda: hdrjax.desaturate_highlights(rgb)
elif op == "false_color":
    fn = lambda: hdrjax.false_color(L, log=True, legend=False).image
elif op == "stats.measure":
    measure = jax.jit(hdrjax.stats.measure)
    fn = lambda: measure(L)
elif op == "lights.detect":
    import hdrjax.lights as hl
    fn = lambda: hl.detect(rgb)
elif op == "vision.simulate":
    import hdrjax.vision as hv
    fn = lambda: hv.simulate(rgb, effects="all", scale=1.0)[0]
elif op == "fit reinhard2002 key":
    import hdrjax.fit as hf, hdrjax.targets as ht
    fn = lambda: hf.fit("reinhard2002", rgb, ht.MeanLuminance(0.3), params="key").params
else:
    raise SystemExit(f"unknown operation {op!r}")
t_ready = time.perf_counter()
t0 = time.perf_counter(); jax.block_until_ready(fn()); first = time.perf_counter() - t0
steady = []
for _ in range(3):
    t0 = time.perf_counter(); jax.block_until_ready(fn()); steady.append(time.perf_counter() - t0)
print("RESULT " + json.dumps({
    "first_s": first, "steady_s": statistics.median(steady),
    "spread_s": (max(steady) - min(steady)) / 2, "setup_s": t_ready - t_start,
}))
"""


def operations(quick: bool) -> tuple[str, ...]:
    if quick:
        return QUICK_OPS
    import hdrjax

    return tuple(f"tonemap {n}" for n in hdrjax.operator_names()) + OTHER_OPS


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    for k in ("JAX_COMPILATION_CACHE_DIR", "JAX_ENABLE_COMPILATION_CACHE"):
        env.pop(k, None)
    return env


def _child_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_child(op: str, cache: str) -> dict[str, float]:
    """One fresh process: the operation's first-call and steady times (+ process wall)."""
    c0 = _child_cpu()
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, op, cache, str(IMAGE)],
        capture_output=True,
        text=True,
        cwd=REPO,
        env=_child_env(),
        timeout=600,
    )
    wall = time.perf_counter() - t0
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    if proc.returncode != 0 or not lines:
        raise RuntimeError(f"{op}: child failed ({proc.returncode}): {proc.stderr[-2000:]}")
    out = json.loads(lines[-1][len("RESULT ") :])
    out["process_s"] = wall
    out["process_cpu_s"] = _child_cpu() - c0
    return out


def count_files(folder: str) -> int:
    """Compiled executables in a JAX cache folder (``*-cache``; each has an ``*-atime``)."""
    return sum(f.endswith("-cache") for _, _, files in os.walk(folder) for f in files)


def op_record(op: str, no_cache_run: bool = True) -> dict[str, Any]:
    """Fresh processes: no cache, cache fill, warm cache. Without ``no_cache_run`` (quick
    mode) the fill process's first call (a cache miss: compile + write) is the cold one."""
    cold = run_child(op, "") if no_cache_run else None
    with tempfile.TemporaryDirectory(prefix="hdrjax-bench-cache-") as d:
        fill = run_child(op, d)
        entries = count_files(d)
        warm = run_child(op, d)
    ref = cold if cold is not None else fill
    timing = {
        "median_s": ref["steady_s"],
        "spread_s": ref["spread_s"],
        "repeats": 3,
        "first_s": ref["first_s"],
    }
    return H.record(
        "compile",
        op,
        "hdrjax",
        timing=timing,
        compiled=True,
        first_call_s=ref["first_s"],
        cold_mode="cache off" if cold is not None else "cache miss (fill)",
        first_call_fill_s=fill["first_s"],
        first_call_warm_s=warm["first_s"],
        warm_speedup=ref["first_s"] / warm["first_s"],
        cache_entries=entries,
        setup_s=ref["setup_s"],
        process_s=ref["process_s"],
        process_warm_s=warm["process_s"],
        process_cpu_s=ref["process_cpu_s"],
        process_warm_cpu_s=warm["process_cpu_s"],
    )


def cli_command(out_png: Path) -> list[str]:
    exe = Path(sys.executable).with_name("hdrjax")
    head = [str(exe)] if exe.exists() else [sys.executable, "-m", "hdrjax"]
    return head + ["tonemap", str(IMAGE), "-o", str(out_png)]


CLI_CPU: list[float] = []
"""CPU seconds (user + system) of each CLI run, in order: less sensitive to a busy machine
than the wall time (but JAX's threads can make it exceed the wall time)."""


def time_cli(out_png: Path, env: dict[str, str]) -> float:
    """Wall time from process start to exit, checking that the PNG was written."""
    if out_png.exists():
        out_png.unlink()
    c0 = _child_cpu()
    t0 = time.perf_counter()
    proc = subprocess.run(
        cli_command(out_png), capture_output=True, text=True, cwd=REPO, env=env, timeout=600
    )
    wall = time.perf_counter() - t0
    CLI_CPU.append(_child_cpu() - c0)
    if proc.returncode != 0 or not out_png.exists():
        raise RuntimeError(f"hdrjax tonemap failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return wall


def cli_records(warm_runs: int, no_cache: bool) -> list[dict[str, Any]]:
    """``hdrjax tonemap`` end to end: empty cache, then warm (and cache off in full mode)."""
    recs = []
    with tempfile.TemporaryDirectory(prefix="hdrjax-bench-cli-") as d:
        env = _child_env()
        env["XDG_CACHE_HOME"] = d
        env["HDRJAX_CACHE"] = "1"
        png = Path(d) / "out.png"
        CLI_CPU.clear()
        cold = time_cli(png, env)
        warm = [time_cli(png, env) for _ in range(warm_runs)]
        cpu = list(CLI_CPU)
        entries = count_files(os.path.join(d, "hdrjax"))
        off = None
        if no_cache:
            env_off = dict(env, HDRJAX_CACHE="0")
            off = [time_cli(png, env_off) for _ in range(warm_runs)]
    case = "hdrjax tonemap venice_sunset_1k.hdr (1024x512) -> PNG, end to end"
    w = statistics.median(warm)
    recs.append(
        H.record(
            "compile",
            case + " (warm cache)",
            "hdrjax",
            timing={
                "median_s": w,
                "spread_s": (max(warm) - min(warm)) / 2,
                "repeats": len(warm),
                "first_s": cold,
            },
            cold_cache_s=cold,
            cpu_cold_s=cpu[0],
            cpu_warm_s=statistics.median(cpu[1:]),
            goal_s=CLI_GOAL_S,
            met=w < CLI_GOAL_S,
            cache_entries=entries,
        )
    )
    if off is not None:
        recs.append(
            H.record(
                "compile",
                case + " (HDRJAX_CACHE=0)",
                "hdrjax",
                timing={
                    "median_s": statistics.median(off),
                    "spread_s": (max(off) - min(off)) / 2,
                    "repeats": len(off),
                    "first_s": float("nan"),
                },
                goal_s=CLI_GOAL_S,
                met=statistics.median(off) < CLI_GOAL_S,
            )
        )
    return recs


def run(quick: bool = False) -> list[dict]:
    """Every public operation (quick: four, two processes each) in fresh processes, and
    the CLI end to end."""
    t0 = time.perf_counter()
    recs = [op_record(op, no_cache_run=not quick) for op in operations(quick)]
    recs += cli_records(warm_runs=1 if quick else 3, no_cache=not quick)
    print(f"[compile] {len(recs)} records in {time.perf_counter() - t0:.1f} s", flush=True)
    return recs


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="four operations, one warm CLI run")
    ap.add_argument("--json", help="write the records to this file")
    args = ap.parse_args()
    recs = run(args.quick)
    if args.json:
        Path(args.json).write_text(json.dumps(recs, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
