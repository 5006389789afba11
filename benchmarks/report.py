"""Markdown report, PNG plots and the documentation's performance page from the suite's JSON.

    python benchmarks/report.py [--results benchmarks/results] [--readme docs/performance.md]
                                [--no-plots]

Reads every ``results-<backend>.json`` written by ``run.py`` (``cpu`` first; a ``gpu`` file,
from running the same suite on a GPU machine, adds a column to every table) and writes into
the same folder:

- ``REPORT.md``: the run's date, machine, versions and modules; per benchmark a table
  ``case | impl | median ms | ± | compile s | hdrjax/peer`` (the last column, on hdrjax
  rows, gives the ratio of that hdrjax time to each peer of the case: below 1 means hdrjax
  is faster), then the extra fields; each accuracy/time curve as a table with the default
  setting marked; failed modules with their error.
- ``accuracy-<curve>.png`` (error vs time, log–log, default highlighted), ``scaling-<op>.png``
  (time vs pixels, log–log, records of benchmark ``scaling`` with ``extra={"op", "pixels"}``)
  and ``ratios.png`` (hdrjax/peer of every case, log scale).

``--readme PATH`` also replaces the text between ``<!-- perf:begin -->`` and
``<!-- perf:end -->`` in that Markdown file (``docs/performance.md``, the documentation
site's performance page, is the one ``make bench`` updates) with a generated performance
section (date, machine, tables of ratios, each curve's default point); everything outside
the markers is kept byte for byte. A file without exactly one pair of markers is an error
and is left unchanged. Links to files outside the page's folder (the full report) point at
the repository on GitHub, as the documentation site holds only its own folder.

Record format: see ``_harness.py``. Within one ``(benchmark, case)``, impls starting with
``"hdrjax"`` are compared with every other impl (the peers).
"""

import argparse
import json
import math
import os
import re
import sys
import textwrap
from collections.abc import Iterable
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
REPO_URL = "https://github.com/hdrjax/hdrjax/blob/main/"
BEGIN = "<!-- perf:begin -->"
END = "<!-- perf:end -->"
PLOT_GLOBS = ("accuracy-*.png", "scaling-*.png", "ratios.png")


# ----------------------------------------------------------------------------- data


def load_results(folder: str | os.PathLike) -> dict[str, dict]:
    """``{backend: {"meta", "records"}}`` of every ``results-<backend>.json``, cpu first."""
    folder = Path(folder)
    found = {p.stem.removeprefix("results-"): p for p in folder.glob("results-*.json")}
    if not found:
        raise FileNotFoundError(
            f"{folder}: no results-*.json (run `python benchmarks/run.py --quick` first)"
        )
    order = sorted(found, key=lambda b: (b != "cpu", b))
    out = {}
    for b in order:
        try:
            data = json.loads(found[b].read_text())
        except ValueError as e:
            raise ValueError(f"{found[b]}: not valid JSON ({e})") from e
        if not isinstance(data, dict) or "records" not in data or "meta" not in data:
            raise ValueError(f"{found[b]}: expected an object with 'meta' and 'records'")
        out[b] = data
    return out


def is_hdrjax(impl: str) -> bool:
    return impl.startswith("hdrjax")


def primary_impl(impls: Iterable[str]) -> str | None:
    """The case's main hdrjax impl: ``"hdrjax"`` itself, else the first ``hdrjax...``."""
    impls = list(impls)
    if "hdrjax" in impls:
        return "hdrjax"
    return next((i for i in impls if is_hdrjax(i)), None)


def timings(records: list[dict]) -> list[dict]:
    """Timing records (everything that has a case and an impl)."""
    return [r for r in records if "case" in r and "impl" in r and "median_s" in r]


def group(records: list[dict], *keys: str) -> dict[tuple, list[dict]]:
    """Records grouped by the values of ``keys``, in order of first appearance."""
    out: dict[tuple, list[dict]] = {}
    for r in records:
        out.setdefault(tuple(r.get(k) for k in keys), []).append(r)
    return out


def ratios(records: list[dict]) -> list[dict]:
    """Every hdrjax impl against every peer of the same ``(benchmark, case)``.

    Returns dicts ``benchmark, case, hdrjax, peer, ratio`` with ``ratio = hdrjax median /
    peer median`` (below 1: hdrjax is faster), and ``primary`` marking the case's main
    hdrjax impl (:func:`primary_impl`).
    """
    out = []
    for (bench, case), recs in group(timings(records), "benchmark", "case").items():
        prim = primary_impl(r["impl"] for r in recs)
        for h in (r for r in recs if is_hdrjax(r["impl"])):
            for p in (r for r in recs if not is_hdrjax(r["impl"])):
                if p["median_s"] > 0:
                    out.append(
                        {
                            "benchmark": bench,
                            "case": case,
                            "hdrjax": h["impl"],
                            "peer": p["impl"],
                            "ratio": h["median_s"] / p["median_s"],
                            "primary": h["impl"] == prim,
                        }
                    )
    return out


def curves(records: list[dict]) -> dict[str, list[dict]]:
    """Accuracy points grouped by curve, in order of appearance."""
    return {k[0]: v for k, v in group([r for r in records if "curve" in r], "curve").items()}


def scaling_series(records: list[dict]) -> dict[str, dict[str, list[tuple[int, float]]]]:
    """``{op: {impl: [(pixels, median_s), ...]}}`` of the ``scaling`` benchmark's records."""
    out: dict[str, dict[str, list[tuple[int, float]]]] = {}
    for r in timings(records):
        if r["benchmark"] != "scaling":
            continue
        extra = r.get("extra", {})
        op = extra.get("op") or re.sub(r"\s*\d+\s*[x×]\s*\d+\s*$", "", r["case"]) or r["case"]
        px = extra.get("pixels")
        if px is None:
            m = re.search(r"(\d+)\s*[x×]\s*(\d+)", r["case"])
            if not m:
                continue
            px = int(m.group(1)) * int(m.group(2))
        out.setdefault(str(op), {}).setdefault(r["impl"], []).append((int(px), r["median_s"]))
    for impls in out.values():
        for pts in impls.values():
            pts.sort()
    return out


# ----------------------------------------------------------------------------- formatting


def _finite(v: Any) -> bool:
    """A finite number (the JSON writes NaN and infinities as null)."""
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def fmt_ms(seconds: float | None) -> str:
    if not _finite(seconds):
        return ""
    ms = seconds * 1e3
    if ms >= 100:
        return f"{ms:.0f}"
    if ms >= 10:
        return f"{ms:.1f}"
    if ms >= 1:
        return f"{ms:.2f}"
    return f"{ms:.3g}"


def fmt_num(v: Any) -> str:
    if v is None:
        return "n/a"
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            return str(v)
        return f"{v:.3g}"
    return str(v)


def fmt_ratio(r: float) -> str:
    if r >= 99.5:
        return f"{r:.0f}"
    if r >= 9.95:
        return f"{r:.1f}"
    return f"{r:.2f}" if r >= 0.095 else f"{r:.2g}"


def cell(text: Any) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def extras(rec: dict, skip: Iterable[str] = ()) -> str:
    """The record's scalar extra fields as ``k=v, ...`` (nested values stay in the JSON)."""
    items = [
        f"{k}={fmt_num(v)}"
        for k, v in rec.get("extra", {}).items()
        if k not in skip and (v is None or isinstance(v, int | float | str | bool))
    ]
    return ", ".join(items)


def backend_title(backend: str, meta: dict) -> str:
    label = meta.get("device_label") or meta.get("jax", {}).get("device_kind") or ""
    return backend.upper() + (f" ({label})" if label and label.lower() != backend else "")


def machine_line(meta: dict) -> str:
    m, v, j = meta.get("machine", {}), meta.get("versions", {}), meta.get("jax", {})
    ram = f", {m['ram_gb']:g} GB RAM" if m.get("ram_gb") else ""
    dev = j.get("device_kind", "")
    tun = f"; GLIBC_TUNABLES={m['glibc_tunables']}" if m.get("glibc_tunables") else ""
    return (
        f"{m.get('cpu_model', '?')} ({m.get('cpu_count', '?')} cores{ram}), "
        f"{m.get('platform', '?')}; JAX {v.get('jax', '?')} on {j.get('backend', '?')}"
        + (f" ({dev})" if dev and dev.lower() != j.get("backend") else "")
        + tun
    )


def _date(meta: dict) -> str:
    d = meta.get("date", "?")
    return d.replace("T", " ").replace("Z", " UTC")


def slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "curve"


def _table(header: list[str], rows: list[list[str]], align: list[str] | None = None) -> str:
    align = align or ["---"] * len(header)
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(align) + "|"]
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


# ----------------------------------------------------------------------------- markdown


def _ratio_cell(rec: dict, ratio_rows: list[dict]) -> str:
    mine = [
        r
        for r in ratio_rows
        if r["benchmark"] == rec["benchmark"]
        and r["case"] == rec["case"]
        and r["hdrjax"] == rec["impl"]
    ]
    return "; ".join(f"{fmt_ratio(r['ratio'])} vs {r['peer']}" for r in mine)


def benchmark_tables(results: dict[str, dict]) -> list[str]:
    """One Markdown section per benchmark: timings, ratios per backend, extras."""
    backends = list(results)
    by_backend = {b: timings(results[b]["records"]) for b in backends}
    ratio_rows = {b: ratios(results[b]["records"]) for b in backends}
    index = {
        b: {(r["benchmark"], r["case"], r["impl"]): r for r in by_backend[b]} for b in backends
    }
    keys: list[tuple] = []  # union of (benchmark, case, impl), first backend's order first
    for b in backends:
        for r in by_backend[b]:
            k = (r["benchmark"], r["case"], r["impl"])
            if k not in keys:
                keys.append(k)
    out = []
    for bench in dict.fromkeys(k[0] for k in keys):
        header = ["case", "impl"]
        align = ["---", "---"]
        for b in backends:
            t = backend_title(b, results[b]["meta"])
            header += [f"{t} median ms", "±", "compile s", f"hdrjax/peer ({b.upper()})"]
            align += ["---:", "---:", "---:", "---"]
        header.append("extra")
        align.append("---")
        rows = []
        for k in (k for k in keys if k[0] == bench):
            row = [k[1], f"**{k[2]}**" if is_hdrjax(k[2]) else k[2]]
            extra = ""
            for b in backends:
                r = index[b].get(k)
                if r is None:
                    row += ["", "", "", ""]
                    continue
                comp = r.get("compile_s")
                row += [
                    fmt_ms(r["median_s"]),
                    fmt_ms(r.get("spread_s")),
                    "" if comp is None else f"{comp:.2f}",
                    _ratio_cell(r, ratio_rows[b]),
                ]
                extra = extra or extras(r)
            rows.append(row + [extra])
        out.append(f"### {bench}\n\n" + _table(header, rows, align))
    return out


def accuracy_tables(results: dict[str, dict], plots: dict[str, str]) -> list[str]:
    """One table per accuracy/time curve, the default row marked, with its plot."""
    backends = list(results)
    per = {b: curves(results[b]["records"]) for b in backends}
    names = list(dict.fromkeys(c for b in backends for c in per[b]))
    out = []
    for name in names:
        settings = list(dict.fromkeys(p["setting"] for b in backends for p in per[b].get(name, [])))
        header, align = ["setting"], ["---"]
        for b in backends:
            t = backend_title(b, results[b]["meta"])
            header += [f"{t} error", f"{t} time ms"]
            align += ["---:", "---:"]
        header.append("extra")
        align.append("---")
        rows = []
        kind = ""
        for s in settings:
            pts = {
                b: next((p for p in per[b].get(name, []) if p["setting"] == s), None)
                for b in backends
            }
            first = next(p for p in pts.values() if p is not None)
            kind = kind or first.get("error_kind", "")
            default = any(p is not None and p.get("default") for p in pts.values())
            row = [f"**{s}** (default)" if default else s]
            for b in backends:
                p = pts[b]
                row += ["", ""] if p is None else [fmt_num(p["error"]), fmt_ms(p["time_s"])]
            rows.append(row + [extras(first)])
        text = f"### {name}\n\nerror: {kind}\n\n" + _table(header, rows, align)
        if name in plots:
            text += f"\n\n![{name}]({plots[name]})"
        out.append(text)
    return out


def modules_table(results: dict[str, dict]) -> str:
    rows = []
    for b, data in results.items():
        for name, st in data["meta"].get("modules", {}).items():
            err = st.get("error", "")
            rows.append(
                [
                    b.upper(),
                    name,
                    st.get("status", "?"),
                    f"{st.get('wall_s', float('nan')):.1f}",
                    str(st.get("records", "")),
                    "quick" if st.get("quick") else "full",
                    _date({"date": st["date"]}) if st.get("date") else "",
                    err[:200],
                ]
            )
    return _table(
        ["backend", "module", "status", "wall s", "records", "mode", "finished", "error"],
        rows,
        ["---", "---", "---", "---:", "---:", "---", "---", "---"],
    )


def failures(results: dict[str, dict]) -> list[str]:
    out = []
    for b, data in results.items():
        for name, st in data["meta"].get("modules", {}).items():
            if st.get("status") == "ok":
                continue
            out.append(f"- **{name}** ({b.upper()}): `{st.get('error', '?')}`")
            tb = st.get("traceback", "").strip()
            if tb:
                out.append(
                    f"\n<details><summary>traceback</summary>\n\n```\n{tb}\n```\n\n</details>\n"
                )
    return out


def render(results: dict[str, dict], plots: dict[str, Any] | None = None) -> str:
    """The whole REPORT.md text."""
    plots = plots or {}
    lines = ["# hdrjax benchmark report", ""]
    lines.append(
        "Generated by `python benchmarks/report.py` from "
        + ", ".join(f"`results-{b}.json`" for b in results)
        + ". Times are medians over repeats after a warm-up (± half the range); compile time"
        " (first call minus the median, or a measured `lower().compile()`) is separate."
        " `hdrjax/peer` is hdrjax's median over the peer's, measured in the same process:"
        " below 1 means hdrjax is faster."
    )
    lines.append("")
    for b, data in results.items():
        meta = data["meta"]
        v = meta.get("versions", {})
        vers = ", ".join(f"{k} {x}" for k, x in v.items() if x)
        lines += [
            f"## {backend_title(b, meta)}: {_date(meta)}"
            + (" (quick mode)" if meta.get("quick") else ""),
            "",
            f"- machine: {machine_line(meta)}; load average at the start "
            f"{fmt_num(meta.get('machine', {}).get('load_average_at_start'))}",
            f"- versions: {vers}",
            f"- command: `{meta.get('command', '?')}`, {meta.get('wall_s', float('nan')):.0f} s",
            "",
        ]
    lines += ["## Modules", "", modules_table(results), ""]
    fails = failures(results)
    if fails:
        lines += ["## Failures", ""] + fails + [""]
    lines += ["## Timings", ""]
    for t in benchmark_tables(results):
        lines += [t, ""]
    if "ratios" in plots:
        lines += [f"![hdrjax/peer ratios]({plots['ratios']})", ""]
    acc = accuracy_tables(results, plots.get("accuracy", {}))
    if acc:
        lines += ["## Accuracy/time curves", ""]
        for t in acc:
            lines += [t, ""]
    if plots.get("scaling"):
        lines += ["## Scaling", ""]
        lines += [f"![{op}]({p})" for op, p in plots["scaling"].items()] + [""]
    return "\n".join(lines).rstrip() + "\n"


OPERATORS_BENCH = "operators"
"""The benchmark whose records make the operator table (bench_operators.py)."""
LATER = "operators"
"""Subfolder of the results folder for benchmarks run later than the whole suite, on
another day or machine (``run.py --only operators metrics --out <results>/operators``):
the README shows them under their own date and machine."""


def operator_table(records: list[dict], others: dict[str, dict] | None = None) -> str | None:
    """Every operator of the ``operators`` benchmark: hdrjax's warm time and compile time,
    pfstmo's and OpenCV's times for the same paper where they have one, the ratio to
    pfstmo and whether the issue's goal is met, and hdrjax's time on each backend of
    ``others`` (``{backend: {"meta", "records"}}``, e.g. a GPU); ``None`` without records."""
    others = others or {}
    cases = group([r for r in records if r.get("benchmark") == OPERATORS_BENCH], "case")
    rows = []
    for (case,), recs in cases.items():
        ours = next((r for r in recs if r["impl"] == "hdrjax" and "median_s" in r), None)
        if ours is None:
            continue

        def peer(prefix: str, recs: list[dict] = recs) -> str:
            r = next((r for r in recs if r["impl"].startswith(prefix)), None)
            if r is None:
                return ""
            return "absent" if "median_s" not in r else fmt_ms(r["median_s"])

        ex = ours.get("extra", {})
        ratio = ex.get("ratio_vs_pfstmo")
        goal = "" if "met" not in ex else f" ({'met' if ex['met'] else 'not met'}: {ex['goal']})"
        rows.append(
            [
                f"`{case.split()[0]}`",
                fmt_ms(ours["median_s"]),
                fmt_num(ours.get("compile_s")),
                peer("pfstmo"),
                peer("OpenCV"),
                "" if ratio is None else f"**{fmt_ratio(ratio)}**{goal}",
            ]
            + [
                next(
                    (
                        fmt_ms(r["median_s"])
                        for r in timings(o["records"])
                        if (r["benchmark"], r["case"], r["impl"])
                        == (OPERATORS_BENCH, case, "hdrjax")
                    ),
                    "",
                )
                for o in others.values()
            ]
        )
    if not rows:
        return None
    size = next(iter(cases))[0].split()[1]
    return (
        f"Every registered operator at {size} RGB float32 (warm; compile time apart), and"
        " pfstmo's program of the same paper (its pipeline minus the same pipeline without"
        " it) and OpenCV's where they have one:\n\n"
        + _table(
            ["operator", "hdrjax ms", "compile s", "pfstmo ms", "OpenCV ms", "hdrjax/pfstmo"]
            + [f"{backend_title(b, o['meta'])} hdrjax ms" for b, o in others.items()],
            rows,
            ["---", "---:", "---:", "---:", "---:", "---"] + ["---:"] * len(others),
        )
    )


def _median(records: list[dict], bench: str, case: str, impl: str) -> float:
    return next(
        r["median_s"]
        for r in timings(records)
        if (r["benchmark"], r["case"], r["impl"]) == (bench, case, impl)
    )


def page_link(target: Path, page_dir: Path) -> str:
    """A link from a page in ``page_dir`` to ``target``: relative within the page's folder,
    the repository's URL for a file of the repository outside it."""
    rel = os.path.relpath(target, page_dir).replace(os.sep, "/")
    if rel.startswith("../"):
        try:
            return REPO_URL + target.resolve().relative_to(REPO).as_posix()
        except ValueError:
            pass
    return rel


def _command_name(page: Path | None) -> str:
    if page is None:
        return "docs/performance.md"
    try:
        return page.resolve().relative_to(REPO).as_posix()
    except ValueError:
        return page.name


def readme_section(
    results: dict[str, dict], readme_dir: Path, results_dir: Path, page: Path | None = None
) -> str:
    """The performance section: date, machine, headline ratios, curve defaults."""
    link = page_link(results_dir / "REPORT.md", readme_dir)
    shown = link.removeprefix(REPO_URL)  # the repository path, not the whole URL
    backends = list(results)
    main = backends[0]
    meta = results[main]["meta"]
    lines = [
        f"<!-- generated by `python benchmarks/report.py --readme {_command_name(page)}` from "
        "benchmarks/results/results-*.json: edit the generator, not this text -->",
        "",
        f"Measured {_date(meta)} on {machine_line(meta)}"
        + (" (quick mode: small sizes)" if meta.get("quick") else "")
        + ".",
    ]
    for b in backends[1:]:
        m = results[b]["meta"]
        lines.append(f"{backend_title(b, m)}: measured {_date(m)} on {machine_line(m)}.")
    lines += [
        "",
        "Every figure is the median of several runs after a warm-up, timed in one process with"
        " its peers; compile time is reported separately. `hdrjax/peer` below 1 means hdrjax"
        f" is faster. Spreads, compile times, all variants and plots: [{shown}]({link}).",
        "",
    ]
    rat = {
        b: [
            r
            for r in ratios(results[b]["records"])
            if r["primary"] and r["benchmark"] not in ("scaling", OPERATORS_BENCH)
        ]
        for b in backends
    }
    med = {
        b: {
            (r["benchmark"], r["case"], r["impl"]): r["median_s"]
            for r in timings(results[b]["records"])
        }
        for b in backends
    }
    header = ["benchmark", "case", "peer", "hdrjax ms", "peer ms", "hdrjax/peer"]
    align = ["---", "---", "---", "---:", "---:", "---:"]
    for b in backends[1:]:
        header += [f"{b.upper()} hdrjax ms", f"{b.upper()} hdrjax/peer"]
        align += ["---:", "---:"]
    rows = []
    for r in rat[main]:
        row = [
            r["benchmark"],
            r["case"],
            r["peer"],
            fmt_ms(med[main][(r["benchmark"], r["case"], r["hdrjax"])]),
            fmt_ms(med[main][(r["benchmark"], r["case"], r["peer"])]),
            f"**{fmt_ratio(r['ratio'])}**",
        ]
        for b in backends[1:]:
            o = next(
                (
                    x
                    for x in rat[b]
                    if (x["benchmark"], x["case"], x["peer"])
                    == (r["benchmark"], r["case"], r["peer"])
                ),
                None,
            )
            row += (
                ["", ""]
                if o is None
                else [
                    fmt_ms(med[b][(o["benchmark"], o["case"], o["hdrjax"])]),
                    fmt_ratio(o["ratio"]),
                ]
            )
        rows.append(row)
    if rows:
        lines += [_table(header, rows, align), ""]
    later_file = results_dir / LATER / f"results-{main}.json"
    later_all = load_results(later_file.parent) if later_file.exists() else {}
    later = later_all.get(main)
    others = {b: d for b, d in later_all.items() if b != main}
    if later is not None:
        lines += [
            f"Measured {_date(later['meta'])} on {machine_line(later['meta'])}"
            f" (`benchmarks/run.py --only {' '.join(later['meta'].get('modules', {}))}"
            f" --out benchmarks/results/{LATER}`)"
            + "".join(
                f"; {backend_title(b, d['meta'])}: {_date(d['meta'])} on {machine_line(d['meta'])}"
                for b, d in others.items()
            )
            + ":",
            "",
        ]
        rows = [
            [
                r["benchmark"],
                r["case"],
                r["peer"],
                fmt_ms(_median(later["records"], r["benchmark"], r["case"], r["hdrjax"])),
                fmt_ms(_median(later["records"], r["benchmark"], r["case"], r["peer"])),
                f"**{fmt_ratio(r['ratio'])}**",
            ]
            for r in ratios(later["records"])
            if r["primary"] and r["benchmark"] != OPERATORS_BENCH
        ]
        if rows:
            lines += [_table(header[:6], rows, align[:6]), ""]
    ops = operator_table((later or results[main])["records"], others)
    if ops:
        lines += [ops, ""]
    defaults = [
        (name, p)
        for name, pts in curves(results[main]["records"]).items()
        for p in pts
        if p.get("default")
    ]
    if defaults:
        lines += [
            "Accuracy/time curves (error against a float64 or exact reference): the default"
            " setting of each.",
            "",
            _table(
                ["curve", "default", "error", "time ms", "error measured as"],
                [
                    [
                        n,
                        p["setting"],
                        fmt_num(p["error"]),
                        fmt_ms(p["time_s"]),
                        p.get("error_kind", ""),
                    ]
                    for n, p in defaults
                ],
                ["---", "---", "---:", "---:", "---"],
            ),
            "",
        ]
    failed = [n for n, st in meta.get("modules", {}).items() if st.get("status") != "ok"]
    if failed:
        lines += [f"Failed in this run (see the report): {', '.join(failed)}.", ""]
    return "\n".join(lines).strip() + "\n"


def update_readme(readme: str | os.PathLike, section: str) -> None:
    """Replace the text between the perf markers of ``readme`` with ``section``.

    Raises:
        ValueError: the file does not have exactly one ``<!-- perf:begin -->`` followed by
            one ``<!-- perf:end -->`` (the file is left unchanged).
    """
    from hdrjax.io._atomic import atomic_path

    readme = Path(readme)
    text = readme.read_text(encoding="utf-8")
    nb, ne = text.count(BEGIN), text.count(END)
    if nb != 1 or ne != 1:
        raise ValueError(
            f"{readme}: expected exactly one '{BEGIN}' and one '{END}' marker around the "
            f"generated performance section, found {nb} and {ne}"
        )
    i, j = text.index(BEGIN) + len(BEGIN), text.index(END)
    if j < i:
        raise ValueError(f"{readme}: '{END}' comes before '{BEGIN}'")
    new = text[:i] + "\n" + section.strip("\n") + "\n" + text[j:]
    with atomic_path(readme) as tmp:
        tmp.write_bytes(new.encode("utf-8"))


# ----------------------------------------------------------------------------- plots


def _plt():
    import matplotlib

    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _log_tick_labels(axis) -> None:
    """Plain numbers on a log axis (``0.5``, ``2``, ``1e-05``), the decades labelled and, on an
    axis spanning less than two decades, also 2× and 5× each decade (no crowded ``3×10^0``)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    lo, hi = sorted(axis.get_view_interval())
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    if hi > 0 and lo > 0 and math.log10(hi / lo) < 2:
        axis.set_minor_locator(LogLocator(base=10, subs=(2.0, 5.0)))
        axis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    else:
        axis.set_minor_formatter(NullFormatter())


def _place_labels(ax, points: list[tuple[float, float, str, float]], fontsize: float = 8) -> None:
    """Annotate each data point with its text where it overlaps no other label, no marker,
    the legend nor the axes' border: the first free place right or left of the point,
    stepping up and down (with a thin leader line when it moved away); a label with no free
    place goes where it overlaps least. ``points``: ``(x, y, text, marker radius in
    points)``."""
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    to_px = fig.dpi / 72.0
    frame = ax.get_window_extent(renderer)
    taken, centres = [], []
    for x, y, _, radius in points:
        px, py = ax.transData.transform((x, y))
        r = radius * to_px
        taken.append((px - r, py - r, px + r, py + r))
        centres.append((px, py))
    legend = ax.get_legend()
    if legend is not None:
        b = legend.get_window_extent(renderer)
        taken.append((b.x0, b.y0, b.x1, b.y1))
    steps = [0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6, -6]
    offsets = [(side * 5, 3 + k * (fontsize + 2)) for k in steps for side in (1, -1)]

    def overlap(a, b) -> float:
        w = min(a[2], b[2]) - max(a[0], b[0])
        h = min(a[3], b[3]) - max(a[1], b[1])
        return w * h if w > 0 and h > 0 else 0.0

    for x, y, text, _ in points:
        # the text's size once; each candidate place is then arithmetic
        probe = ax.annotate(text, (x, y), fontsize=fontsize, ha="left", va="bottom")
        size = probe.get_window_extent(renderer)
        probe.remove()
        w, h = size.width, size.height
        px, py = ax.transData.transform((x, y))
        best = None
        for dx, dy in offsets:
            x0 = px + dx * to_px - (w if dx < 0 else 0)
            y0 = py + dy * to_px - (h if dy < 0 else 0)
            box = (x0, y0, x0 + w, y0 + h)
            outside = (
                max(frame.x0 - box[0], 0)
                + max(box[2] - frame.x1, 0)
                + max(frame.y0 - box[1], 0)
                + max(box[3] - frame.y1, 0)
            ) * (w + h)
            cost = outside + sum(overlap(box, t) for t in taken)
            # a label nearer another point than its own would be read as that point's
            ax_, ay_ = (box[0] if dx > 0 else box[2]), (box[1] + box[3]) / 2
            own = (ax_ - px) ** 2 + (ay_ - py) ** 2
            if any((ax_ - cx) ** 2 + (ay_ - cy) ** 2 < own for cx, cy in centres):
                cost += 0.25 * w * h
            if best is None or cost < best[0]:
                best = (cost, dx, dy, box)
            if cost == 0:
                break
        _, dx, dy, box = best
        far = dy != offsets[0][1]  # moved up or down: a leader line to its point
        ax.annotate(
            text,
            (x, y),
            xytext=(dx, dy),
            textcoords="offset points",
            fontsize=fontsize,
            ha="left" if dx > 0 else "right",
            va="bottom" if dy >= 0 else "top",
            arrowprops={
                "arrowstyle": "-",
                "lw": 0.5,
                "color": "0.4",
                "shrinkA": 0,
                "shrinkB": 2,
                "relpos": (0.0 if dx > 0 else 1.0, 0.5),
            }
            if far
            else None,
        )
        taken.append(box)


def accuracy_figure(curve: str, series: dict[str, list[dict]]):
    """Error vs time (log–log) of one curve; ``series``: ``{label: accuracy points}``.

    Points with error 0 (the reference itself) are drawn at a floor a decade below the
    smallest positive error and labelled ``0``; the default setting is a large star. Each
    point is labelled with its setting where the label overlaps nothing else.
    """
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    pos = [
        p["error"] for pts in series.values() for p in pts if _finite(p["error"]) and p["error"] > 0
    ]
    floor = min(pos) / 10 if pos else 1e-9
    markers = "osD^v"
    labels = []
    for k, (label, pts) in enumerate(series.items()):
        pts = [p for p in pts if _finite(p["error"]) and _finite(p["time_s"]) and p["time_s"] > 0]
        pts.sort(key=lambda p: p["time_s"])
        x = [p["time_s"] * 1e3 for p in pts]
        y = [p["error"] if p["error"] > 0 else floor for p in pts]
        (line,) = ax.plot(x, y, markers[k % len(markers)], alpha=0.85, label=label)
        front, best = [], math.inf  # settings no other is both faster and more accurate
        for xi, yi in zip(x, y, strict=True):
            if yi < best:
                front.append((xi, yi))
                best = yi
        if len(front) > 1:
            ax.plot(*zip(*front, strict=True), "--", color=line.get_color(), alpha=0.5, lw=1)
        for p, xi, yi in zip(pts, x, y, strict=True):
            text = p["setting"] + (" (0)" if p["error"] <= 0 else "")
            labels.append((xi, yi, text, 9.0 if p.get("default") else 4.0))
            if p.get("default"):
                ax.plot(
                    [xi],
                    [yi],
                    "*",
                    ms=18,
                    mfc="none",
                    mec="crimson",
                    mew=2,
                    label="default" if k == 0 else None,
                )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.margins(x=0.25, y=0.15)  # room for the labels of the outermost points
    ax.set_xlabel("time after compilation (ms)", fontsize=9)
    kind = next((p.get("error_kind") for pts in series.values() for p in pts), "error")
    ax.set_ylabel(textwrap.fill(kind, 48, break_on_hyphens=False), fontsize=9)
    ax.set_title(curve + "\n(dashed: settings no other beats on both axes)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.tick_params(labelsize=8, which="both")
    ax.legend(fontsize=8)
    _log_tick_labels(ax.xaxis)
    _log_tick_labels(ax.yaxis)
    fig.tight_layout()  # the axes' size is now fixed; the legend's place too, once frozen
    legend = ax.get_legend()
    if legend is not None:
        box = legend.get_window_extent(fig.canvas.get_renderer())
        legend.set_loc(tuple(box.transformed(ax.transAxes.inverted()).p0))
    _place_labels(ax, labels)
    return fig


def scaling_figure(op: str, series: dict[str, list[tuple[int, float]]]):
    """Time vs pixels (log–log) of one operation; ``series``: ``{label: [(pixels, s)]}``."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for label, pts in series.items():
        ax.plot([p for p, _ in pts], [t * 1e3 for _, t in pts], "o-", label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("pixels")
    ax.set_ylabel("median time (ms)")
    ax.set_title(op, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def ratio_figure(rows: dict[str, list[dict]]):
    """Horizontal bars of the primary hdrjax/peer ratio of every case, per backend."""
    plt = _plt()
    labels = list(
        dict.fromkeys(
            f"{r['benchmark']}: {r['case']} vs {r['peer']}" for rs in rows.values() for r in rs
        )
    )
    n, nb = len(labels), max(1, len(rows))
    fig, ax = plt.subplots(figsize=(11, 1.5 + 0.36 * n * nb))
    h = 0.8 / nb
    for k, (b, rs) in enumerate(rows.items()):
        val = {f"{r['benchmark']}: {r['case']} vs {r['peer']}": r["ratio"] for r in rs}
        ys = [i + k * h for i, lab in enumerate(labels) if lab in val]
        ax.barh(ys, [val[lab] for lab in labels if lab in val], height=h, label=b)
    ax.axvline(1.0, color="k", lw=1)
    ax.set_xscale("log")
    ax.set_yticks([i + 0.4 - h / 2 for i in range(n)])
    ax.set_yticklabels([textwrap.fill(lab, 60) for lab in labels], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("hdrjax time / peer time (below 1: hdrjax faster)")
    ax.grid(True, axis="x", which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def write_plots(results: dict[str, dict], folder: Path) -> dict[str, Any]:
    """Write every PNG into ``folder``; returns their names for the Markdown links."""
    plt = _plt()
    for pattern in PLOT_GLOBS:  # no stale plot of a curve that is gone
        for p in folder.glob(pattern):
            p.unlink()
    made: dict[str, Any] = {"accuracy": {}, "scaling": {}}

    def save(fig, name: str) -> str:
        fig.savefig(folder / name, dpi=110, bbox_inches="tight")
        plt.close(fig)
        return name

    titles = {b: backend_title(b, results[b]["meta"]) for b in results}
    per = {b: curves(results[b]["records"]) for b in results}
    for name in dict.fromkeys(c for b in results for c in per[b]):
        series = {titles[b]: per[b][name] for b in results if name in per[b]}
        made["accuracy"][name] = save(accuracy_figure(name, series), f"accuracy-{slug(name)}.png")
    sc = {b: scaling_series(results[b]["records"]) for b in results}
    for op in dict.fromkeys(o for b in results for o in sc[b]):
        series = {
            f"{impl} ({b.upper()})" if len(results) > 1 else impl: pts
            for b in results
            for impl, pts in sc[b].get(op, {}).items()
        }
        made["scaling"][op] = save(scaling_figure(op, series), f"scaling-{slug(op)}.png")
    bars = {
        titles[b]: [
            r for r in ratios(results[b]["records"]) if r["primary"] and r["benchmark"] != "scaling"
        ]
        for b in results
    }
    if any(bars.values()):
        made["ratios"] = save(ratio_figure(bars), "ratios.png")
    return made


# ----------------------------------------------------------------------------- entry


def generate(folder: str | os.PathLike = HERE / "results", *, plots: bool = True) -> Path:
    """Write ``REPORT.md`` (and the plots) from the JSON files in ``folder``; its path."""
    from hdrjax.io._atomic import atomic_path

    folder = Path(folder)
    results = load_results(folder)
    made = write_plots(results, folder) if plots else {}
    path = folder / "REPORT.md"
    with atomic_path(path) as tmp:
        tmp.write_text(render(results, made), encoding="utf-8")
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", type=Path, default=HERE / "results", help="results folder")
    ap.add_argument("--readme", type=Path, help="also regenerate this file's perf section")
    ap.add_argument("--no-plots", action="store_true", help="Markdown only")
    args = ap.parse_args(argv)
    try:
        print(f"wrote {generate(args.results, plots=not args.no_plots)}")
        if args.readme:
            results = load_results(args.results)
            section = readme_section(
                results, args.readme.resolve().parent, args.results.resolve(), args.readme
            )
            update_readme(args.readme, section)
            print(f"updated the performance section of {args.readme}")
    except (FileNotFoundError, ValueError) as e:
        print(f"report.py: error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
