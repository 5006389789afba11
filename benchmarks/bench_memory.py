"""What page faults cost, and what :func:`hdrjax.tune_memory` saves (issue 19, point 3).

Run: ``.venv/bin/python benchmarks/bench_memory.py [--quick]``

Each configuration runs in a fresh process of its own, as a user's would (the dispatch
setting is read when JAX starts): ``default`` (nothing tuned: the environment users have,
no ``GLIBC_TUNABLES``) and ``tune_memory`` (``hdrjax.tune_memory()`` first, as the command
line does in its own process). In each process, warm calls of:

* Reinhard 2002 (``reinhard2002``, automatic key and white) on a 4096² RGB image;
* the 5×5 mean filter (``hdrjax.filters.mean_filter``) on the same image, and OpenCV's
  ``cv2.blur`` on it in the same process when OpenCV is installed (the peer row of the
  issue's goal, "≤ 1.0× OpenCV"; OpenCV's buffers come from the same allocator);
* TMQI (``hdrjax.metrics.tmqi``) of a 2048×1024 pair.

Quick mode: 2048² and 1024×512. ``extra`` holds the minor page faults per call.
"""

import argparse
import json
import subprocess
import sys
from pathlib import Path

import _harness as H

BENCH = "memory"
REPO = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, resource, statistics, sys, time
mode, n = sys.argv[1], int(sys.argv[2])
import hdrjax
if mode == "tune_memory":
    hdrjax.tune_memory()
import jax, numpy as np
import hdrjax.metrics as hm
from hdrjax import filters
rng = np.random.default_rng(0)
x_np = rng.lognormal(0.0, 2.0, (n, n, 3)).astype(np.float32)
x = jax.device_put(x_np)
hdr = jax.device_put(x_np[: n // 4, : n // 2])
ldr = jax.device_put((x_np[: n // 4, : n // 2] / (1 + x_np[: n // 4, : n // 2])) ** (1 / 2.2))
op = jax.jit(hdrjax.make_operator("reinhard2002"))
mean = jax.jit(lambda v: filters.mean_filter(v, 5))
tmqi = jax.jit(lambda a, b: hm.tmqi(a, b).q)
cases = {
    f"reinhard2002 {n}x{n}": lambda: op(x),
    f"mean 5x5 {n}x{n}": lambda: mean(x),
    f"tmqi {n // 2}x{n // 4}": lambda: tmqi(hdr, ldr),
}
try:
    import cv2
    cases[f"cv2.blur 5x5 {n}x{n}"] = lambda: cv2.blur(x_np, (5, 5), borderType=cv2.BORDER_REPLICATE)
except ImportError:
    pass
out = {}
for name, fn in cases.items():
    t0 = time.perf_counter(); jax.block_until_ready(fn()); first = time.perf_counter() - t0
    times, faults = [], []
    for _ in range(7):
        f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - t0)
        faults.append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0)
    out[name] = {"times": times, "first": first, "faults": statistics.median(faults)}
print(json.dumps(out))
"""


def _child(mode: str, n: int) -> dict:
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, mode, str(n)],
        capture_output=True,
        text=True,
        cwd=REPO,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"bench_memory child ({mode}) failed: {proc.stderr.strip()[-500:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def run(quick: bool = False) -> list[dict]:
    """Records of benchmark ``"memory"`` (see the module docstring)."""
    n = 2048 if quick else 4096
    results = {mode: _child(mode, n) for mode in ("default", "tune_memory")}
    records = []
    for case in results["default"]:
        base = H.summarize(results["default"][case]["times"])["median_s"]
        for mode, res in results.items():
            r = res[case]
            timing = H.summarize(r["times"], r["first"])
            impl = ("opencv" if case.startswith("cv2") else "hdrjax") + f" ({mode})"
            records.append(
                H.record(
                    BENCH,
                    case,
                    impl,
                    timing=timing,
                    compiled=not case.startswith("cv2"),
                    faults_per_call=r["faults"],
                    vs_default=timing["median_s"] / base,
                )
            )
    blur = next((c for c in results["default"] if c.startswith("cv2")), None)
    if blur is not None:
        mean = next(c for c in results["default"] if c.startswith("mean"))
        for mode, res in results.items():
            ratio = (
                H.summarize(res[mean]["times"])["median_s"]
                / H.summarize(res[blur]["times"])["median_s"]
            )
            print(f"[{BENCH}] mean 5x5 / cv2.blur ({mode}): {ratio:.2f}x", flush=True)
            records[-1]["extra"][f"mean_vs_cv2_{mode}"] = ratio
    else:
        print(f"[{BENCH}] OpenCV not installed: no cv2.blur row", flush=True)
    return records


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    run(ap.parse_args().quick)
