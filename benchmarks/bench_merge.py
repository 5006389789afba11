"""HDR from exposure brackets: merge, response recovery, alignment and fusion against OpenCV
and colour-hdri, in one process, with the accuracy each one reaches.

Run: ``.venv/bin/python benchmarks/bench_merge.py [--quick]``

The bracket: ``data/venice_sunset_1k.hdr`` (Radiance units), tiled to 4000 × 3000
(12 Mpixel; quick mode 1000 × 750), photographed by :func:`hdrjax.merge.simulate_bracket`
through the sRGB curve at 8 bits, 5 exposures 2 EV apart (the middle one's 99th percentile
at half the sensor's range), so that the true radiance and the true inverse response are
known. Times are medians after a warm-up; hdrjax's compile time (first call minus median)
is reported apart.

Cases (issue 23's goals in ``extra``):

- ``merge``: :func:`hdrjax.merge.merge` with the true response and the hat weights, against
  OpenCV's ``MergeDebevec`` given the same response (its linear table), and colour-hdri's
  ``image_stack_to_HDRI`` given the same linearisation (float images in [0, 1]; its
  ``average_luminance`` scaling from f-number, time and ISO). Goal: ≤ 0.5× OpenCV, ≤ 0.2×
  colour-hdri. ``median_rel_error`` of each against the truth (after the one scale factor
  that best matches it, since the responses' scale differs).
- ``response``: :func:`hdrjax.merge.recover_response` (Debevec & Malik 1997, its default
  samples) against OpenCV's ``CalibrateDebevec`` (70 random samples, its default); goal
  ≤ 1×. ``response_error``: the largest relative error in linear exposure over codes 13–242
  (5–95 %), after matching the normalisation.
- ``align``: :func:`hdrjax.merge.align_mtb` against OpenCV's ``AlignMTB.process`` on the
  bracket with known shifts (up to 32 px); ``exact`` says whether every shift was found.
- ``fuse``: :func:`hdrjax.merge.fuse` (Mertens et al. 2007) against OpenCV's
  ``MergeMertens.process``; ``max_abs_diff`` between the two.
- accuracy/time curve ``merge.recover_response samples``: samples per channel against the
  response error.

A missing peer (no OpenCV, no colour-hdri) gets a record that says so instead of a time.
"""

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _harness as H  # noqa: E402

import hdrjax.merge as hm  # noqa: E402
from hdrjax.io import read  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
BENCH = "merge"
SHAPE = (3000, 4000)
QUICK_SHAPE = (750, 1000)
WELL_EXPOSED = slice(13, 243)
"""Codes 5 %–95 % of the 8-bit range: where a response is judged."""
SHIFTS = np.array([[0, 0], [7, -3], [0, 0], [-12, 5], [31, -32]])
"""(dx, dy) of each member in the alignment case (the middle one is the reference)."""


def scene(shape: tuple[int, int]) -> np.ndarray:
    """venice_sunset_1k.hdr tiled to ``shape`` (H, W), float64."""
    img = np.asarray(read(REPO / "data" / "venice_sunset_1k.hdr").rgb(), np.float64)
    reps = (-(-shape[0] // img.shape[0]), -(-shape[1] // img.shape[1]), 1)
    return np.tile(img, reps)[: shape[0], : shape[1]]


def response_error(g: np.ndarray, truth: np.ndarray) -> float:
    """Largest relative error in linear exposure over :data:`WELL_EXPOSED`, after the one
    offset in log (scale in linear) per channel that matches them best in least squares."""
    a, b = np.asarray(g, np.float64)[WELL_EXPOSED], truth[WELL_EXPOSED]
    off = np.mean(b - a, axis=0)
    return float(np.max(np.abs(np.expm1(a + off - b))))


def median_rel_error(x: np.ndarray, truth: np.ndarray) -> float:
    """Median relative error of ``x`` against ``truth`` (luminance), after the single scale
    (the median ratio) that matches them."""
    w = np.array([0.2126, 0.7152, 0.0722])
    a, b = np.asarray(x, np.float64) @ w, truth @ w
    ok = (b > 0) & np.isfinite(a) & (a > 0)
    s = np.median(b[ok] / a[ok])
    return float(np.median(np.abs(a[ok] * s - b[ok]) / b[ok]))


def _cv2():
    try:
        import cv2
    except ImportError:
        return None
    return cv2


def _absent(case: str, impl: str, why: str) -> dict:
    rec = H.record(
        BENCH,
        case,
        impl,
        timing={"median_s": float("nan"), "spread_s": 0.0, "repeats": 0, "first_s": float("nan")},
        verbose=False,
        absent=why,
    )
    print(f"[{BENCH}] {case:<40} {impl:<28} absent: {why}", flush=True)
    return rec


def run(quick: bool = False) -> list[dict]:
    """Records of benchmark ``"merge"`` (see the module docstring)."""
    shape = QUICK_SHAPE if quick else SHAPE
    reps = 3
    cv2 = _cv2()
    truth_scene = scene(shape)
    b = hm.simulate_bracket(truth_scene)
    codes, times, truth = b.codes, b.exposure_times, b.radiance
    mp = shape[0] * shape[1] / 1e6
    label = f"5 x {shape[1]}x{shape[0]} 8-bit"
    out: list[dict] = []

    # ---------------------------------------------------------------- merge
    case = f"merge {label}"
    ours = []
    rec = H.record(
        BENCH,
        case,
        "hdrjax",
        lambda: ours.append(hm.merge(codes, times, b.response)) or ours[-1],
        repeats=reps,
        compiled=True,
        megapixels=mp,
    )
    rec["extra"]["median_rel_error"] = median_rel_error(np.asarray(ours[-1]), truth)
    out.append(rec)
    peers = {}
    if cv2 is not None:
        lin = np.exp(b.response).astype(np.float32)[:, None, ::-1].copy()  # (256, 1, 3) BGR
        bgr = [np.ascontiguousarray(c[..., ::-1]) for c in codes]
        merger = cv2.createMergeDebevec()
        got = []
        peers["OpenCV MergeDebevec"] = H.record(
            BENCH,
            case,
            "OpenCV MergeDebevec",
            lambda: got.append(merger.process(bgr, times.astype(np.float32), lin)),
            repeats=reps,
            megapixels=mp,
        )
        peers["OpenCV MergeDebevec"]["extra"]["median_rel_error"] = median_rel_error(
            got[-1][..., ::-1], truth
        )
    else:
        out.append(_absent(case, "OpenCV MergeDebevec", "opencv-python is not installed"))
    try:
        import colour_hdri
    except ImportError:
        colour_hdri = None
        out.append(_absent(case, "colour-hdri image_stack_to_HDRI", "colour-hdri is not installed"))
    if colour_hdri is not None:
        lin_table = np.exp(b.response)
        lin_table[0] = 0.0

        def stack():
            s = colour_hdri.ImageStack()
            for c, t in zip(codes, times, strict=True):
                meta = colour_hdri.Metadata(f_number=8.0, exposure_time=float(t), iso=100.0)
                s.append(colour_hdri.Image(data=c.astype(np.float64) / 255.0, metadata=meta))
            return s

        got = []
        peers["colour-hdri image_stack_to_HDRI"] = H.record(
            BENCH,
            case,
            "colour-hdri image_stack_to_HDRI",
            lambda: got.append(
                colour_hdri.image_stack_to_HDRI(stack(), camera_response_functions=lin_table)
            ),
            repeats=1,
            megapixels=mp,
        )
        peers["colour-hdri image_stack_to_HDRI"]["extra"]["median_rel_error"] = median_rel_error(
            got[-1], truth
        )
    out.extend(peers.values())
    for name, goal in (("OpenCV MergeDebevec", 0.5), ("colour-hdri image_stack_to_HDRI", 0.2)):
        if name in peers:
            ratio = rec["median_s"] / peers[name]["median_s"]
            rec["extra"][f"ratio_vs_{name.split()[0].lower()}"] = ratio
            rec["extra"][f"goal_vs_{name.split()[0].lower()}"] = f"<= {goal}"
            rec["extra"][f"met_vs_{name.split()[0].lower()}"] = ratio <= goal

    # ---------------------------------------------------------------- response
    case = f"response debevec {label}"
    g = []
    rec = H.record(
        BENCH,
        case,
        "hdrjax",
        lambda: g.append(hm.recover_response(codes, times)) or g[-1],
        repeats=reps,
        compiled=True,
    )
    rec["extra"]["response_error"] = response_error(np.asarray(g[-1]), b.response)
    out.append(rec)
    if cv2 is not None:
        bgr = [np.ascontiguousarray(c[..., ::-1]) for c in codes]
        cal = cv2.createCalibrateDebevec()
        got = []
        peer = H.record(
            BENCH,
            case,
            "OpenCV CalibrateDebevec",
            lambda: got.append(cal.process(bgr, times.astype(np.float32))),
            repeats=reps,
        )
        peer["extra"]["response_error"] = response_error(
            np.log(np.maximum(got[-1][:, 0, ::-1], 1e-30)), b.response
        )
        out.append(peer)
        rec["extra"]["ratio_vs_opencv"] = rec["median_s"] / peer["median_s"]
        rec["extra"]["goal"] = "<= 1 x OpenCV CalibrateDebevec"
        rec["extra"]["met"] = rec["extra"]["ratio_vs_opencv"] <= 1.0

    # accuracy/time curve: samples against the response error
    small = hm.simulate_bracket(scene((750, 1000)))
    default = max(50, 2 * -(-255 // (len(small.exposure_times) - 1)))  # recover_response's
    for n in sorted({20, 50, 100, default, 200, 500, 1000}):
        f = lambda n=n: hm.recover_response(small.codes, small.exposure_times, samples=n)  # noqa: E731
        t = H.measure(f, repeats=3)
        err = response_error(np.asarray(f()), small.response)
        out.append(
            H.accuracy_point(
                "merge.recover_response samples",
                f"{n} samples",
                err,
                t["median_s"],
                default=n == default,
                error_kind="max relative error of the response (5-95 %)",
            )
        )

    # ---------------------------------------------------------------- align
    case = f"align MTB {label}"
    shifted = hm.simulate_bracket(truth_scene, shifts=SHIFTS)
    found = []
    rec = H.record(
        BENCH,
        case,
        "hdrjax",
        lambda: found.append(hm.align_mtb(shifted.codes)) or found[-1],
        repeats=reps,
        compiled=True,
    )
    expect = SHIFTS - SHIFTS[2]
    rec["extra"]["exact"] = bool(
        np.array_equal(np.asarray(found[-1]), -expect)
        or np.array_equal(np.asarray(found[-1]), expect)
    )
    out.append(rec)
    if cv2 is not None:
        greys = [
            cv2.cvtColor(np.ascontiguousarray(c[..., ::-1]), cv2.COLOR_BGR2GRAY)
            for c in shifted.codes
        ]
        mtb = cv2.createAlignMTB(max_bits=6)
        peer = H.record(
            BENCH,
            case,
            "OpenCV AlignMTB calculateShift x4",
            lambda: [mtb.calculateShift(greys[2], greys[j]) for j in (0, 1, 3, 4)],
            repeats=reps,
        )
        out.append(peer)
        rec["extra"]["ratio_vs_opencv"] = rec["median_s"] / peer["median_s"]

    # ---------------------------------------------------------------- fuse
    case = f"fuse Mertens {label}"
    fused = []
    rec = H.record(
        BENCH,
        case,
        "hdrjax",
        lambda: fused.append(hm.fuse(codes)) or fused[-1],
        repeats=reps,
        compiled=True,
    )
    out.append(rec)
    if cv2 is not None:
        bgr = [np.ascontiguousarray(c[..., ::-1]) for c in codes]
        mm = cv2.createMergeMertens()
        got = []
        peer = H.record(
            BENCH, case, "OpenCV MergeMertens", lambda: got.append(mm.process(bgr)), repeats=reps
        )
        out.append(peer)
        rec["extra"]["ratio_vs_opencv"] = rec["median_s"] / peer["median_s"]
        rec["extra"]["max_abs_diff"] = float(
            np.max(np.abs(np.clip(got[-1][..., ::-1], 0, 1) - np.asarray(fused[-1])))
        )
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    run(ap.parse_args().quick)
