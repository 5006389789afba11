"""Every registered operator at 2048 × 1024, against pfstmo's program of the same paper and
OpenCV's where they have one, in one process.

Run: ``.venv/bin/python benchmarks/bench_operators.py [--quick] [--only NAME ...]``

Image: data/venice_sunset_1k.hdr (or the same file in ../shared/data/hdr) tiled 2 × 2 to
2048 × 1024 RGB float32, in cd/m² (Radiance units × 179, so that the operators with
parameters in cd/m² see a daylight scene; the others are scale-invariant or estimate their
scale, and their time does not depend on it); quick mode: its 512 × 256 top-left crop.

Per operator (one case each: the entries of :data:`OPERATORS`, then every other registered
operator at its defaults, ``tabulated`` with :data:`TABLE`):

* ``hdrjax``: the operator compiled (``jax.jit``, its parameters the peer's defaults),
  warm: the median of ``repeats`` calls after one warm-up, the output blocked on; compile
  time measured apart (``lower().compile()``).
* ``pfstmo <program>``: ``pfsinpfm f.pfm … | <program> | pfsoutpfm o%04d.pfm`` minus the
  same pipeline without the program, ``pfsinpfm f.pfm … | pfsoutpfm o%04d.pfm`` (reading,
  converting and writing the frames), the two run alternately ``PEER_REPEATS`` times: the
  median of the per-pair differences divided by the frames, each pipeline's median in
  ``extra``. The pipelines carry ``frames`` copies of the image, at least
  :data:`PEER_PIXELS` pixels in all (1 frame at full size, 16 in quick mode), so that the
  program's time stands out of the processes' start-up (tens of ms, varying by ±10 ms).
* ``OpenCV <name>``: the peer's ``process`` on the same float32 image (its defaults).

A missing peer (pfstools not installed, no OpenCV, an operator not registered yet) gets a
record without a time that says so (``absent``), instead of a time.

``extra`` of the hdrjax record: ``goal`` (``ours / pfstmo ≤ 0.1`` for a global operator,
``≤ 0.25`` for a local one), ``ratio_vs_pfstmo`` and ``met``. An operator with a peer joins
by adding an :class:`Entry` to :data:`OPERATORS`; one without is timed as it is registered.
"""

import argparse
import dataclasses
import shutil
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import _harness as H
import jax
import numpy as np

REPO = Path(__file__).resolve().parents[1]
IMAGE_NAME = "venice_sunset_1k.hdr"
BENCH = "operators"
GOAL_GLOBAL = 0.1
"""Issue 20's goal for a global operator: at most 0.1 × pfstmo's time."""
GOAL_LOCAL = 0.25
"""Issue 21's goal for a local or gradient-domain operator: at most 0.25 × pfstmo's time."""
EFFICACY = 179.0
"""cd/m² per Radiance unit (W/(sr·m²)): the image's scale."""
TABLE = {"luminance": [0.001, 0.18, 100.0], "display": [0.0, 0.18, 1.0]}
"""``tabulated``'s table (it has no default)."""
PEER_REPEATS = 5
PEER_PIXELS = 2**21
"""Pixels the pfstmo pipelines carry at least (in copies of the image)."""


@dataclasses.dataclass(frozen=True)
class Entry:
    """One operator and its peers.

    Attributes:
        name: hdrjax registry name.
        params: hdrjax parameters that match the peer's defaults.
        pfstmo: the pfstmo program of the same paper (``None``: none).
        opencv: makes OpenCV's tone mapper of the same paper (``cv2`` in, an object with
            ``process`` out); ``None``: OpenCV has none.
        global_op: a global (pointwise) operator, for which the goal applies.
    """

    name: str
    params: dict[str, Any] = dataclasses.field(default_factory=dict)
    pfstmo: str | None = None
    opencv: Callable[[Any], Any] | None = None
    global_op: bool = True


OPERATORS: tuple[Entry, ...] = (
    Entry(
        "drago2003",
        {"compat": "pfstmo"},
        pfstmo="pfstmo_drago03",
        opencv=lambda cv2: cv2.createTonemapDrago(gamma=1.0, saturation=1.0, bias=0.85),
    ),
    Entry("reinhard2005", {"compat": "pfstmo"}, pfstmo="pfstmo_reinhard05"),
    Entry("mai2011", {"compat": "pfstmo"}, pfstmo="pfstmo_mai11"),
    Entry("mantiuk2008", {}, pfstmo="pfstmo_mantiuk08"),
    Entry("pattanaik2000", {}, pfstmo="pfstmo_pattanaik00"),
    Entry("durand2002", {}, pfstmo="pfstmo_durand02", global_op=False),
    Entry("fattal2002", {}, pfstmo="pfstmo_fattal02", global_op=False),
    Entry(
        "mantiuk2006",
        {},
        pfstmo="pfstmo_mantiuk06",
        # pfstmo's contrast factor and saturation (OpenCV's defaults are 0.7 and 1)
        opencv=lambda cv2: cv2.createTonemapMantiuk(gamma=1.0, scale=0.1, saturation=0.8),
        global_op=False,
    ),
    Entry("ferradans2011", {}, pfstmo="pfstmo_ferradans11", global_op=False),
    Entry("ashikhmin2002", {}, global_op=False),
    Entry("chiu1993", {}, global_op=False),
)


def entries(registered: list[str]) -> list[Entry]:
    """:data:`OPERATORS`, then an entry for every other registered operator."""
    named = {e.name for e in OPERATORS}
    rest = [Entry(n, TABLE if n == "tabulated" else {}) for n in registered if n not in named]
    return [*OPERATORS, *rest]


def image(quick: bool) -> np.ndarray:
    """The benchmark image (module docstring), float32 RGB."""
    from hdrjax.io import read

    path = REPO / "data" / IMAGE_NAME
    if not path.exists():
        path = REPO.parent / "shared" / "data" / "hdr" / IMAGE_NAME
    a = np.asarray(read(path).rgb(), np.float32) * np.float32(EFFICACY)
    tiled = np.concatenate([np.concatenate([a, a], 1)] * 2, 0)[:1024, :2048]
    return np.ascontiguousarray(tiled[:256, :512] if quick else tiled)


def write_pfm(path: Path, rgb: np.ndarray) -> None:
    """Little-endian PFM (rows bottom to top)."""
    h, w = rgb.shape[:2]
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(np.ascontiguousarray(rgb[::-1], "<f4").tobytes())


def _shell(cmd: str) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, shell=True, check=True, capture_output=True)
    return time.perf_counter() - t0


def pfstmo_time(program: str, pfm: Path, frames: int, repeats: int) -> dict[str, float]:
    """The program's own time per frame: its pipeline over ``frames`` copies of ``pfm``
    minus the pipeline without it, run alternately (a load on the machine falls on both);
    :func:`_harness.summarize` of the differences per frame, plus each pipeline's median
    (all frames)."""
    src = " ".join([f"'{pfm}'"] * frames)
    out = f"'{pfm.parent / 'out%04d.pfm'}'"
    with_op = f"pfsinpfm {src} | {program} | pfsoutpfm {out}"
    io_only = f"pfsinpfm {src} | pfsoutpfm {out}"
    _shell(with_op)  # warm-up: the programs and the file in the page cache
    _shell(io_only)
    pairs = [(_shell(with_op), _shell(io_only)) for _ in range(repeats)]
    t = H.summarize([max(a - b, 0.0) / frames for a, b in pairs])
    t["pipeline_s"] = float(np.median([a for a, _ in pairs]))
    t["io_only_s"] = float(np.median([b for _, b in pairs]))
    return t


def absent(case: str, impl: str, why: str) -> dict:
    """A record of a peer that could not be timed (no time; ``absent`` says why)."""
    print(f"[{BENCH}] {case:<40} {impl:<28} absent: {why}", flush=True)
    return {"benchmark": BENCH, "case": case, "impl": impl, "absent": why}


def _ours(entry: Entry, x: jax.Array, reps: int, common: dict) -> tuple[dict, dict]:
    import hdrjax

    op = hdrjax.make_operator(entry.name, **entry.params)
    fn = jax.jit(lambda img: op(img))
    t0 = time.perf_counter()
    fn.lower(x).compile()
    compile_s = time.perf_counter() - t0
    return H.measure(lambda: fn(x), reps), {"compile_s": compile_s, **common}


def run(quick: bool = False, *, only: list[str] | None = None) -> list[dict]:
    """Records of benchmark ``"operators"`` (module docstring)."""
    import hdrjax

    rgb = image(quick)
    h, w = rgb.shape[:2]
    reps = 5 if quick else 7
    common = {"pixels": h * w, "megabytes": round(rgb.nbytes / 1e6, 1)}
    x = jax.device_put(rgb)
    out: list[dict] = []
    have_pfs = all(shutil.which(t) for t in ("pfsinpfm", "pfsoutpfm"))
    try:
        import cv2
    except ImportError:
        cv2 = None
    with tempfile.TemporaryDirectory() as tmp:
        pfm = Path(tmp) / "in.pfm"
        write_pfm(pfm, rgb)
        frames = -(-PEER_PIXELS // (h * w))
        for entry in entries(hdrjax.operator_names()):
            if only and entry.name not in only:
                continue
            case = f"{entry.name} {w}x{h} RGB"
            if entry.name not in hdrjax.operator_names():
                out.append(absent(case, "hdrjax", f"{entry.name} is not registered"))
                continue
            ours, extra = _ours(entry, x, reps, common)
            peer = None
            if entry.pfstmo is not None:
                impl = f"pfstmo {entry.pfstmo} (pipeline - I/O)"
                if not (have_pfs and shutil.which(entry.pfstmo)):
                    out.append(absent(case, impl, f"{entry.pfstmo} not on PATH (pfstmo)"))
                else:
                    peer = pfstmo_time(entry.pfstmo, pfm, frames, PEER_REPEATS)
                    more = {k: peer[k] for k in ("pipeline_s", "io_only_s")}
                    rec = H.record(BENCH, case, impl, timing=peer, frames=frames, **more, **common)
                    out.append(rec)
            if peer is not None and peer["median_s"] > 0:
                ratio = ours["median_s"] / peer["median_s"]
                extra["ratio_vs_pfstmo"] = ratio
                goal = GOAL_GLOBAL if entry.global_op else GOAL_LOCAL
                extra["goal"] = f"<= {goal} x pfstmo"
                extra["met"] = ratio <= goal
            compile_s = extra.pop("compile_s")
            out.append(H.record(BENCH, case, "hdrjax", timing=ours, compile_s=compile_s, **extra))
            if entry.opencv is not None:
                impl = "OpenCV " + entry.name
                if cv2 is None:
                    out.append(absent(case, impl, "OpenCV (cv2) not installed"))
                else:
                    tm = entry.opencv(cv2)
                    impl = f"OpenCV {type(tm).__name__}"
                    out.append(
                        H.record(BENCH, case, impl, lambda tm=tm: tm.process(rgb), repeats=reps)
                    )
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="512×256, 5 repeats")
    ap.add_argument("--only", nargs="*", help="operator names (default: all of OPERATORS)")
    a = ap.parse_args()
    run(a.quick, only=a.only)
