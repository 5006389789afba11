"""The benchmark suite's runner (benchmarks/run.py) and report (benchmarks/report.py).

Synthetic results with hand-chosen times: every ratio expected here is computed by hand
from those times, never taken from the code under test.
"""

import importlib.util
import json
import sys

import pytest

from ..conftest import REPO

BENCH = REPO / "benchmarks"


def _load(name: str):
    spec = importlib.util.spec_from_file_location(f"suite_{name}", BENCH / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


report = _load("report")
runner = _load("run")


def _rec(case, impl, median_s, spread_s=0.001, compile_s=None, **extra):
    return {
        "benchmark": "toy",
        "case": case,
        "impl": impl,
        "median_s": median_s,
        "spread_s": spread_s,
        "repeats": 5,
        "compile_s": compile_s,
        "extra": extra,
        "module": "toy",
    }


def _point(setting, error, time_s, default=False):
    return {
        "benchmark": "accuracy",
        "curve": "toy curve",
        "setting": setting,
        "error": error,
        "error_kind": "max relative error",
        "time_s": time_s,
        "default": default,
        "extra": {},
        "module": "toy",
    }


def _meta(backend, kind, date="2026-01-02T03:04:05Z"):
    return {
        "date": date,
        "machine": {"platform": "Linux-x86_64", "cpu_model": "Toy CPU", "cpu_count": 2},
        "versions": {"python": "3.11", "jax": "0.0.1"},
        "jax": {"backend": backend, "device_kind": kind},
        "quick": True,
        "device_label": None,
        "modules": {"toy": {"status": "ok", "wall_s": 1.0, "records": 5, "quick": True}},
    }


def _write(folder, backend, kind, records):
    data = {"meta": _meta(backend, kind), "records": records}
    (folder / f"results-{backend}.json").write_text(json.dumps(data))


CPU_RECORDS = [
    _rec("blur 64x64", "hdrjax", 0.010, compile_s=0.5, err=1e-7),
    _rec("blur 64x64", "hdrjax (donated)", 0.020),
    _rec("blur 64x64", "NumPy", 0.040),
    _rec("blur 64x64", "OpenCV", 0.005),
    _rec("stats 64x64", "hdrjax", 0.003),
    _point("coarse", 0.1, 0.001),
    _point("default", 0.01, 0.002, default=True),
    _point("exact", 0.0, 0.008),
]


def test_ratios_match_hand_computed_values(tmp_path):
    rows = {(r["hdrjax"], r["peer"]): r for r in report.ratios(CPU_RECORDS)}
    # 0.010/0.040, 0.010/0.005, 0.020/0.040, 0.020/0.005; "stats" has no peer
    assert set(rows) == {
        ("hdrjax", "NumPy"),
        ("hdrjax", "OpenCV"),
        ("hdrjax (donated)", "NumPy"),
        ("hdrjax (donated)", "OpenCV"),
    }
    assert rows["hdrjax", "NumPy"]["ratio"] == pytest.approx(0.25)
    assert rows["hdrjax", "OpenCV"]["ratio"] == pytest.approx(2.0)
    assert rows["hdrjax (donated)", "NumPy"]["ratio"] == pytest.approx(0.5)
    assert rows["hdrjax (donated)", "OpenCV"]["ratio"] == pytest.approx(4.0)
    assert rows["hdrjax", "NumPy"]["primary"] and not rows["hdrjax (donated)", "NumPy"]["primary"]


def test_report_tables_plots_and_default(tmp_path):
    _write(tmp_path, "cpu", "cpu", CPU_RECORDS)
    path = report.generate(tmp_path)
    md = path.read_text()
    assert "0.25 vs NumPy; 2.00 vs OpenCV" in md  # hdrjax row of the blur case
    assert "0.50 vs NumPy; 4.00 vs OpenCV" in md  # the donated variant
    row = next(line for line in md.splitlines() if line.startswith("| blur 64x64 | **hdrjax** |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[2:5] == ["10.0", "1.00", "0.50"]  # median ms, ± ms, compile s
    assert "err=1e-07" in cells[-1]
    assert "**default** (default)" in md and "GPU" not in md
    for name in ("accuracy-toy-curve.png", "ratios.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"]({name})" in md


def test_gpu_column_appears_with_a_gpu_file(tmp_path):
    _write(tmp_path, "cpu", "cpu", CPU_RECORDS)
    gpu = [
        _rec("blur 64x64", "hdrjax", 0.001),
        _rec("blur 64x64", "NumPy", 0.040),
        _point("default", 0.02, 0.0005, default=True),
    ]
    _write(tmp_path, "gpu", "NVIDIA H100", gpu)
    md = report.generate(tmp_path, plots=False).read_text()
    header = next(line for line in md.splitlines() if line.startswith("| case | impl |"))
    assert "GPU (NVIDIA H100) median ms" in header and "hdrjax/peer (GPU)" in header
    row = next(line for line in md.splitlines() if line.startswith("| blur 64x64 | **hdrjax** |"))
    assert "0.025 vs NumPy" in row  # 0.001 / 0.040 on the GPU
    assert "0.25 vs NumPy; 2.00 vs OpenCV" in row  # CPU column unchanged
    assert "GPU (NVIDIA H100) error" in md


README = """# Title

Some text. <!-- not a marker -->

## Performance

<!-- perf:begin -->
old generated text | with a table
<!-- perf:end -->

## Tests

Trailing text, no newline at the end"""


def test_readme_section_replaced_and_outside_untouched(tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    _write(results, "cpu", "cpu", CPU_RECORDS)
    readme = tmp_path / "README.md"
    readme.write_text(README)
    argv = ["--results", str(results), "--readme", str(readme), "--no-plots"]
    assert report.main(argv) == 0
    text = readme.read_text()
    head, rest = README.split(report.BEGIN)
    tail = rest.split(report.END)[1]
    assert text.startswith(head + report.BEGIN) and text.endswith(report.END + tail)
    inner = text[len(head + report.BEGIN) : -len(report.END + tail)]
    assert "old generated text" not in inner
    assert "2026-01-02 03:04:05 UTC" in inner and "Toy CPU" in inner
    assert "| toy | blur 64x64 | NumPy | 10.0 | 40.0 | **0.25** |" in inner
    assert "| toy curve | default | 0.01 | 2.00 |" in inner
    assert "(results/REPORT.md)" in inner  # link relative to the README's folder
    assert report.main(argv) == 0 and readme.read_text() == text  # idempotent


@pytest.mark.parametrize(
    "text, found",
    [
        ("# no markers at all\n", "found 0 and 0"),
        (f"{report.BEGIN}\nonly the start\n", "found 1 and 0"),
        (f"{report.END}\nx\n{report.BEGIN}\n", "comes before"),
    ],
)
def test_readme_without_markers_is_an_error(tmp_path, capsys, text, found):
    _write(tmp_path, "cpu", "cpu", CPU_RECORDS)
    readme = tmp_path / "README.md"
    readme.write_text(text)
    with pytest.raises(ValueError, match=found):
        report.update_readme(readme, "new")
    rc = report.main(["--results", str(tmp_path), "--readme", str(readme), "--no-plots"])
    assert rc == 1 and "perf:" in capsys.readouterr().err
    assert readme.read_text() == text


GOOD = """import _harness as H


def run(quick: bool = False) -> list[dict]:
    t = H.summarize([0.004, 0.002, 0.003])
    return [
        H.record("good", "case", "hdrjax", timing=t, quick=quick, err=float("nan")),
        H.record("good", "case", "peer", timing=H.summarize([0.012])),
    ]
"""
BAD = """def run(quick: bool = False) -> list[dict]:
    raise RuntimeError("boom in bad")
"""


@pytest.fixture
def bench_dir(tmp_path, monkeypatch):
    monkeypatch.setattr(sys, "path", list(sys.path))
    d = tmp_path / "benches"
    d.mkdir()
    (d / "bench_good.py").write_text(GOOD)
    (d / "bench_bad.py").write_text(BAD)
    (d / "helper.py").write_text("raise AssertionError('not a benchmark: never imported')\n")
    return d


def test_runner_discovers_runs_and_records_a_failure(bench_dir, tmp_path):
    out = tmp_path / "out"
    rc = runner.main(["--quick", "--bench-dir", str(bench_dir), "--out", str(out)])
    assert rc == 1  # one module failed, the other still ran
    text = (out / "results-cpu.json").read_text()

    def reject(name):
        raise AssertionError(f"not strict JSON: {name}")

    data = json.loads(text, parse_constant=reject)  # NaN is written as null
    mods = data["meta"]["modules"]
    assert set(mods) == {"good", "bad"}
    assert mods["good"]["status"] == "ok" and mods["good"]["records"] == 2
    assert mods["bad"]["status"] == "error" and "boom in bad" in mods["bad"]["error"]
    assert "RuntimeError" in mods["bad"]["traceback"]
    recs = data["records"]
    assert [(r["module"], r["impl"]) for r in recs] == [("good", "hdrjax"), ("good", "peer")]
    assert recs[0]["median_s"] == pytest.approx(0.003) and recs[0]["extra"]["quick"] is True
    assert recs[0]["extra"]["err"] is None
    assert recs[0]["spread_s"] == pytest.approx(0.001)
    meta = data["meta"]
    assert meta["quick"] is True and meta["jax"]["backend"] == "cpu"
    assert meta["versions"]["jax"] and meta["versions"]["numpy"] and meta["date"].endswith("Z")
    assert meta["machine"]["cpu_count"] >= 1 and "cpu_model" in meta["machine"]
    md = (out / "REPORT.md").read_text()
    assert "boom in bad" in md and "0.25 vs peer" in md  # 0.003 / 0.012


def test_runner_only_keeps_the_other_modules_results(bench_dir, tmp_path):
    out = tmp_path / "out"
    assert runner.main(["--bench-dir", str(bench_dir), "--out", str(out), "--no-report"]) == 1
    (bench_dir / "bench_bad.py").write_text(GOOD.replace('"good"', '"fixed"'))
    argv = ["--only", "bad", "--bench-dir", str(bench_dir), "--out", str(out), "--no-report"]
    assert runner.main(argv) == 0
    data = json.loads((out / "results-cpu.json").read_text())
    assert {m: s["status"] for m, s in data["meta"]["modules"].items()} == {
        "good": "ok",
        "bad": "ok",
    }
    assert sorted((r["module"], r["benchmark"]) for r in data["records"]) == [
        ("bad", "fixed"),
        ("bad", "fixed"),
        ("good", "good"),
        ("good", "good"),
    ]
    assert runner.main(["--only", "nope", "--bench-dir", str(bench_dir), "--no-report"]) == 2
