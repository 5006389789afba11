"""The benchmark suite's single entry: every ``benchmarks/bench_*.py``, one process, one JSON.

    python benchmarks/run.py [--quick] [--only NAME ...] [--out benchmarks/results]
                             [--device-label LABEL] [--no-report]

Each module ``bench_<name>.py`` exposes ``run(quick: bool) -> list[dict]`` made of
``_harness.record`` / ``_harness.accuracy_point`` records (see ``_harness.py``). The runner
imports the modules one after the other in this process and calls ``run(quick)``; a module
that raises is recorded (error and traceback) and the others still run. Between modules the
JAX settings a benchmark may touch are restored and the in-memory compilation caches are
cleared, so every module's compile times are cold; the persistent compilation cache of the
command line (``HDRJAX_CACHE``) is off unless the caller turned it on.

Output: ``<out>/results-<backend>.json`` (``backend = jax.default_backend()``: ``cpu``,
``gpu``, ...) with ``meta`` (UTC date, a hostname-free machine description, library
versions, JAX backend and devices, the quick flag, each module's status and wall time) and
``records`` (each tagged with its ``module``); NaN and infinities are written as ``null``.
With ``--only`` the other modules' records of an earlier run on the same machine are kept,
so one benchmark can be rerun alone. Then ``report.py`` writes ``<out>/REPORT.md`` and the
PNG plots from every ``results-*.json``.

Exit status: 0 when every module ran, 1 when one failed (the JSON and report are written
either way), 2 for a usage error.
"""

import argparse
import datetime
import gc
import importlib.metadata
import importlib.util
import json
import math
import os
import platform
import sys
import time
import traceback
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
PACKAGES = {  # name in the JSON: distributions that provide it (the first installed wins)
    "hdrjax": ["hdrjax"],
    "jax": ["jax"],
    "jaxlib": ["jaxlib"],
    "numpy": ["numpy"],
    "scipy": ["scipy"],
    "opencv": ["opencv-python-headless", "opencv-python", "opencv-contrib-python"],
    "colour-science": ["colour-science"],
    "colour-hdri": ["colour-hdri"],
    "matplotlib": ["matplotlib"],
    "equinox": ["equinox"],
    "optimistix": ["optimistix"],
}
# JAX settings a benchmark may change (float64, compilation cache ...): restored after each.
JAX_SETTINGS = (
    "jax_enable_x64",
    "jax_enable_compilation_cache",
    "jax_compilation_cache_dir",
    "jax_persistent_cache_min_compile_time_secs",
    "jax_persistent_cache_min_entry_size_bytes",
    "jax_numpy_rank_promotion",
    "jax_default_matmul_precision",
    "jax_platforms",
)


def discover(bench_dir: Path) -> dict[str, Path]:
    """``{name: path}`` of ``bench_<name>.py`` in ``bench_dir``, sorted by name."""
    found = {p.stem.removeprefix("bench_"): p for p in sorted(Path(bench_dir).glob("bench_*.py"))}
    if not found:
        raise FileNotFoundError(f"{bench_dir}: no bench_*.py benchmark modules")
    return found


def select(found: dict[str, Path], only: list[str] | None) -> dict[str, Path]:
    """The modules named in ``only`` (``reinhard`` or ``bench_reinhard``); all when None."""
    if not only:
        return found
    names = [n.removeprefix("bench_").removesuffix(".py") for n in only]
    unknown = [n for n in names if n not in found]
    if unknown:
        raise ValueError(
            f"--only: unknown benchmark(s) {', '.join(unknown)}; expected some of "
            f"{', '.join(found)}"
        )
    return {n: found[n] for n in found if n in names}


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                key, _, value = line.partition(":")
                if key.strip() in ("model name", "Hardware", "Processor", "cpu model"):
                    return value.strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _ram_gb() -> float | None:
    try:
        return round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30, 1)
    except (AttributeError, OSError, ValueError):
        return None


def machine() -> dict[str, Any]:
    """The machine without its host name: OS, CPU model, cores, RAM, load average."""
    try:
        usable = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        usable = os.cpu_count()
    try:
        load = round(os.getloadavg()[0], 2)
    except (AttributeError, OSError):
        load = None
    return {
        "platform": platform.platform(),
        "architecture": platform.machine(),
        "cpu_model": _cpu_model(),
        "cpu_count": os.cpu_count(),
        "cpu_usable": usable,
        "ram_gb": _ram_gb(),
        "load_average_at_start": load,
        # glibc.malloc.hugetlb=1 (make bench): XLA's buffers get huge pages like NumPy's
        "glibc_tunables": os.environ.get("GLIBC_TUNABLES", ""),
    }


def versions() -> dict[str, str | None]:
    """Python and the library versions (``None``: not installed)."""
    out: dict[str, str | None] = {"python": platform.python_version()}
    for name, dists in PACKAGES.items():
        out[name] = None
        for d in dists:
            try:
                out[name] = importlib.metadata.version(d)
                break
            except importlib.metadata.PackageNotFoundError:
                continue
    return out


def jax_description() -> dict[str, Any]:
    import jax

    devs = jax.devices()
    return {
        "backend": jax.default_backend(),
        "device_kind": devs[0].device_kind,
        "device_count": len(devs),
        "devices": sorted({f"{d.platform}: {d.device_kind}" for d in devs}),
        "x64": bool(jax.config.jax_enable_x64),
        "persistent_compilation_cache": jax.config.jax_compilation_cache_dir,
    }


def _snapshot() -> dict[str, Any]:
    import jax

    return {k: getattr(jax.config, k) for k in JAX_SETTINGS if hasattr(jax.config, k)}


def _restore(saved: dict[str, Any]) -> None:
    import jax

    for k, v in saved.items():
        if getattr(jax.config, k) != v:
            try:
                jax.config.update(k, v)
            except Exception as e:  # a setting that can no longer change is reported
                print(f"[suite] could not restore {k}={v!r}: {e}", file=sys.stderr)


def _check_records(name: str, records: Any) -> list[dict]:
    if not isinstance(records, list) or not all(
        isinstance(r, dict) and "benchmark" in r for r in records
    ):
        raise TypeError(
            f"bench_{name}.run returned {type(records).__name__}; expected a list of "
            "_harness.record / _harness.accuracy_point dicts"
        )
    return records


def run_module(name: str, path: Path, quick: bool) -> tuple[list[dict], dict[str, Any]]:
    """Import ``path`` and call its ``run(quick)``: (records, status); never raises."""
    import jax

    saved = _snapshot()
    status: dict[str, Any] = {"file": path.name, "quick": quick}
    t0 = time.perf_counter()
    records: list[dict] = []
    print(f"[suite] {name}: {path}", flush=True)
    try:
        spec = importlib.util.spec_from_file_location(f"bench_{name}", path)
        if spec is None or spec.loader is None:
            raise ImportError(f"{path}: not an importable Python file")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = mod
        spec.loader.exec_module(mod)
        fn = getattr(mod, "run", None)
        if not callable(fn):
            raise AttributeError(f"{path}: no run(quick) function")
        records = _check_records(name, fn(quick))
        status["status"] = "ok"
    except (Exception, SystemExit) as e:
        status["status"] = "error"
        status["error"] = f"{type(e).__name__}: {e}"
        status["traceback"] = traceback.format_exc()
        print(f"[suite] {name} FAILED: {status['error']}", file=sys.stderr, flush=True)
    finally:
        status["wall_s"] = round(time.perf_counter() - t0, 3)
        _restore(saved)
        sys.modules.pop(f"bench_{name}", None)
        jax.clear_caches()
        gc.collect()
    status["records"] = len(records)
    status["date"] = _now()
    for r in records:
        r["module"] = name
    print(f"[suite] {name}: {status['status']} in {status['wall_s']:.1f} s", flush=True)
    return records, status


def _now() -> str:
    return datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def _merge_previous(path: Path, meta: dict, records: list[dict], ran: set[str]) -> list[dict]:
    """Records and module statuses of an earlier run (same machine) for modules not rerun."""
    try:
        old = json.loads(path.read_text())
    except (OSError, ValueError):
        return records
    om = old.get("meta", {})
    if (
        om.get("machine", {}).get("cpu_model") != meta["machine"]["cpu_model"]
        or om.get("jax", {}).get("device_kind") != meta["jax"]["device_kind"]
    ):
        print(f"[suite] {path}: earlier results from another machine are not kept")
        return records
    for name, st in om.get("modules", {}).items():
        if name not in ran:
            meta["modules"][name] = st
    kept = [r for r in old.get("records", []) if r.get("module") not in ran]
    return kept + records


def _strict(o: Any) -> Any:
    """NaN and ±Inf as ``null`` (strict JSON: any JSON reader can load the file)."""
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    if isinstance(o, dict):
        return {str(k): _strict(v) for k, v in o.items()}
    if isinstance(o, list | tuple):
        return [_strict(v) for v in o]
    return o


def _write_json(path: Path, data: dict) -> None:
    from hdrjax.io._atomic import atomic_path

    text = json.dumps(data, indent=1, default=_json_default)  # numpy scalars → Python
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(_strict(json.loads(text)), indent=1, allow_nan=False))


def _json_default(o: Any) -> Any:
    try:
        import numpy as np

        if isinstance(o, np.generic):
            return o.item()
        if isinstance(o, np.ndarray):
            return o.tolist()
    except ImportError:
        pass
    if isinstance(o, Path):
        return str(o)
    return repr(o)


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="quick mode (small sizes, few runs)")
    ap.add_argument("--only", nargs="+", metavar="NAME", help="run only these benchmarks")
    ap.add_argument("--out", type=Path, default=HERE / "results", help="results folder")
    ap.add_argument("--device-label", default=None, help="column title for this machine")
    ap.add_argument("--no-report", action="store_true", help="write the JSON only")
    ap.add_argument("--bench-dir", type=Path, default=HERE, help="where bench_*.py live")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and exit")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    # compile times are cold: no persistent cache unless the caller asked for one
    os.environ.setdefault("HDRJAX_CACHE", "0")
    bench_dir = args.bench_dir.resolve()
    for d in (str(HERE), str(bench_dir)):  # `import _harness as H`, and report.py
        if d not in sys.path:
            sys.path.insert(0, d)
    try:
        chosen = select(discover(bench_dir), args.only)
    except (FileNotFoundError, ValueError) as e:
        print(f"run.py: error: {e}", file=sys.stderr)
        return 2
    if args.list:
        print("\n".join(f"{n}\t{p}" for n, p in chosen.items()))
        return 0
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    meta: dict[str, Any] = {
        "date": _now(),
        "machine": machine(),
        "versions": versions(),
        "jax": jax_description(),
        "device_label": args.device_label,
        "quick": bool(args.quick),
        "command": "python benchmarks/run.py "
        + " ".join(argv if argv is not None else sys.argv[1:]),
        "modules": {},
    }
    print(
        f"[suite] {len(chosen)} benchmark(s), {'quick' if args.quick else 'full'} mode, "
        f"jax {meta['versions']['jax']} on {meta['jax']['backend']} "
        f"({meta['jax']['device_kind']})",
        flush=True,
    )
    t_all = time.perf_counter()
    records: list[dict] = []
    for name, path in chosen.items():
        recs, status = run_module(name, path, args.quick)
        records += recs
        meta["modules"][name] = status
    meta["wall_s"] = round(time.perf_counter() - t_all, 3)
    path = out / f"results-{meta['jax']['backend']}.json"
    if args.only and path.exists():
        records = _merge_previous(path, meta, records, set(chosen))
        meta["modules"] = dict(sorted(meta["modules"].items()))
        records.sort(key=lambda r: r.get("module", ""))  # stable: each module's own order
    _write_json(path, {"meta": meta, "records": records})
    print(f"[suite] wrote {path} ({len(records)} records) in {meta['wall_s']:.0f} s")
    failed = [n for n in chosen if meta["modules"][n].get("status") != "ok"]
    if not args.no_report:
        import report

        print(f"[suite] wrote {report.generate(out)}")
    if failed:
        print(f"[suite] failed: {', '.join(failed)} (see {path})", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
