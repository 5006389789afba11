"""Benchmark: hdrjax.lights.detect against Loghin 2019's own listing, and its accuracy/time curve.

Run: ``.venv/bin/python benchmarks/bench_lights.py [--quick]``

Everything runs in one process on the same maps: ``data/rooitou_park_1k.hdr`` always, and in
full mode the lat-long maps of ``../shared/data/hdr`` when present. Times are wall-clock
medians over repeats after a warm-up; hdrjax's compile time (first call minus the median) is
reported separately and never mixed into the ratios. Quick mode: the bundled map only, 5
repeats, three points of the accuracy/time curve, median cut with 16 lights, no batch.

Records: ``detect defaults <map>`` (hdrjax with a JAX and a NumPy input against Loghin's
listing, with the quality figures below as extras), ``detect batch of N maps``, ``median_cut
<map> n=<lights>``, and the accuracy/time curve ``lights.detect (width, samples/px, blur)``:
error = mean angular error (degrees) of the found significant blobs over the maps, time =
median over the maps of each map's median time.

**The peer** is the Python listing of D.-A. Loghin, "Detection of light sources from
environment maps", 2019 (http://alinloghin.com/articles/env_lights.html), made runnable with
the fewest changes, in :class:`SeedListing`: OpenCV bilinear resize to width 1024 and a
σ = 1 px Gaussian blur (the article's "1–2 px"), the listing's loops as written. What the
listing leaves out or gets wrong, and what was done (each marked ``# fix:`` in the code):

- ``computeNeighborLuminance``, ``distance2d`` and ``euclideanThresholdPixel`` are not
  given: the neighbourhood is the max over a ``localSize × localSize`` window centred on
  the sample (``localSize = 13`` at width 1024, odd: a window width; clipped at the image
  border), ``distance2d`` is Euclidean in pixels, ``euclideanThresholdPixel = 32`` (16 px
  at width 1024, 1.5 sample spacings);
- ``lum[x, y]`` indexing: the listing's luminance is indexed ``[x][y]``, so it gets the
  transposed array; float positions are truncated to int and clipped to the image;
- ``bresenhamCheck`` is called with 7 arguments but defined with 6 (``imageSize``): the
  definition takes ``width, height``; ``localIndices`` holds floats, used as int indices.

**Quality** is measured against the maps' bright blobs, by hdrjax's own definition (pixels with
``Y > T``, ``T = max(50·median(Y), 0.02·max(Y))``, 8-connected, seam merged; :func:`quality` has
the details): a light is *spurious* when no blob pixel is within 1° (plus the light's own
angular radius); a blob with ≥ 1 % of the cos-weighted energy is *missed* when no light is that
close; the angular error is measured from the blob's energy centroid to the (energy-weighted)
mean direction of the lights covering it.
"""

import argparse
import math
import statistics
from pathlib import Path

import _harness as H
import cv2
import jax
import jax.numpy as jnp
import numpy as np
from scipy import ndimage

import hdrjax.io
import hdrjax.lights as hl

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared" / "data" / "hdr"
MAPS = [
    ("rooitou_park_1k.hdr", REPO / "data" / "rooitou_park_1k.hdr"),
    ("venice_sunset_1k.hdr", SHARED / "venice_sunset_1k.hdr"),
    ("empty_warehouse_01_1k.hdr", SHARED / "empty_warehouse_01_1k.hdr"),
    ("studio_small_03_1k.hdr", SHARED / "studio_small_03_1k.hdr"),
    ("StageEnvLatLong.exr", SHARED / "StageEnvLatLong.exr"),
]
SUN_MAPS = ("rooitou_park_1k.hdr", "venice_sunset_1k.hdr")
MATCH_DEG = 1.0
SIGNIFICANT_SHARE = 0.01
BENCH = "lights"
CURVE = "lights.detect (width, samples/px, blur)"


# ----------------------------------------------------------------------------- the peer


class SeedListing:
    """Loghin 2019's listing, runnable: see the module docstring for every change (``# fix:``)."""

    samplesMultiplier = 0.006
    luminanceThreshold = 0.8
    euclideanThresholdPixel = 32  # fix: not given in the listing

    def __init__(self, width: int = 1024, blur: float = 1.0):
        self.width = width
        self.blur = blur

    # --- the listing's helpers, verbatim apart from Python 3 details
    @staticmethod
    def vdcSequence(bits):
        bits = (bits << 16) | (bits >> 16)
        bits = ((bits & 0x55555555) << 1) | ((bits & 0xAAAAAAAA) >> 1)
        bits = ((bits & 0x33333333) << 2) | ((bits & 0xCCCCCCCC) >> 2)
        bits = ((bits & 0x0F0F0F0F) << 4) | ((bits & 0xF0F0F0F0) >> 4)
        bits = ((bits & 0x00FF00FF) << 8) | ((bits & 0xFF00FF00) >> 8)
        return float(bits) * 2.3283064365386963e-10  # / 0x100000000

    def hammersleySequence(self, i, N):
        return (float(i) / float(N), self.vdcSequence(i))

    @staticmethod
    def sphereSample(u, v):
        PI = 3.14159265358979
        phi = v * 2.0 * PI
        cosTheta = 2.0 * u - 1.0  # map to -1,1
        sinTheta = math.sqrt(1.0 - cosTheta * cosTheta)
        return (math.cos(phi) * sinTheta, math.sin(phi) * sinTheta, cosTheta)

    @staticmethod
    def sphereToEquirectangular(pos):
        invAngles = (0.1591, 0.3183)
        xy = (math.atan2(pos[1], pos[0]), math.asin(pos[2]))
        xy = (xy[0] * invAngles[0], xy[1] * invAngles[1])
        return (xy[0] + 0.5, xy[1] + 0.5)

    @staticmethod
    def computeNeighborLuminance(lum, width, height, pos, localSize):
        # fix: not given; max over the localSize × localSize window centred on the sample
        # (localSize = 13 at width 1024 is odd: a window width), lum indexed [x][y]
        x, y, r = pos[0], pos[1], localSize // 2
        return lum[
            max(0, x - r) : min(width, x + r + 1), max(0, y - r) : min(height, y + r + 1)
        ].max()

    @staticmethod
    def distance2d(a, b):  # fix: not given
        return math.hypot(a[0] - b[0], a[1] - b[1])

    @staticmethod
    def bresenhamCheck(lum, width, height, x0, y0, x1, y1):  # fix: (width, height)
        dX = int(x1 - x0)
        stepX = int((dX > 0) - (dX < 0))
        dX = abs(dX) << 1
        dY = int(y1 - y0)
        stepY = int((dY > 0) - (dY < 0))
        dY = abs(dY) << 1
        luminanceThreshold = 0.15
        prevLum = lum[x0][y0]
        sumLum = 0.0
        c = 0
        if dX >= dY:
            delta = int(dY - (dX >> 1))
            while x0 != x1:
                if (delta > 0) or (delta == 0 and (stepX > 0)):
                    delta -= dX
                    y0 += stepY
                delta += dY
                x0 += stepX
                sumLum = sumLum + min(lum[x0][y0], 1.25)
                c = c + 1
                if abs(sumLum / c - prevLum) > luminanceThreshold and (sumLum / c) < 1.0:
                    return 0
        else:
            delta = int(dX - (dY >> 1))
            while y0 != y1:
                if (delta > 0) or (delta == 0 and (stepY > 0)):
                    delta -= dY
                    x0 += stepX
                delta += dX
                y0 += stepY
                sumLum = sumLum + min(lum[x0][y0], 1.25)
                c = c + 1
                if abs(sumLum / c - prevLum) > luminanceThreshold and (sumLum / c) < 1.0:
                    return 0
        return 1

    # --- steps 1-2 (OpenCV) and the listing's main body
    def prepare(self, rgb: np.ndarray) -> np.ndarray:
        h, w = rgb.shape[:2]
        if w != self.width:
            rgb = cv2.resize(rgb, (self.width, round(h * self.width / w)), cv2.INTER_LINEAR)
        rgb = np.nan_to_num(rgb, nan=0.0, posinf=0.0, neginf=0.0)
        lum = rgb[:, :, 0] * 0.2126 + rgb[:, :, 1] * 0.7152 + rgb[:, :, 2] * 0.0722
        if self.blur > 0:
            lum = cv2.GaussianBlur(lum, (0, 0), self.blur)
        return np.ascontiguousarray(lum.T)  # fix: the listing indexes lum[x][y]

    def __call__(self, rgb: np.ndarray) -> list[dict]:
        lum = self.prepare(rgb)
        width, height = lum.shape
        samplesMultiplier = self.samplesMultiplier
        samples = int(samplesMultiplier * width * height)
        localSize = int(float(12) * (width / 1024.0)) + 1
        samplesList = []
        for i in range(0, samples):
            xi = self.hammersleySequence(i, samples)
            xyz = self.sphereSample(xi[0], xi[1])  # to cartesian
            imagePos = self.sphereToEquirectangular(xyz)
            # fix: int positions, clipped
            pos = (
                min(int(imagePos[0] * width), width - 1),
                min(int(imagePos[1] * height), height - 1),
            )
            luminance = lum[pos[0], pos[1]]
            luminanceThreshold = self.luminanceThreshold
            nLum = self.computeNeighborLuminance(lum, width, height, pos, localSize)
            if nLum > luminanceThreshold:
                samplesList.append({"luminance": luminance, "pos": pos, "worldPos": xyz})
        samplesList = sorted(samplesList, key=lambda obj: obj["luminance"], reverse=True)

        euclideanThreshold = int(float(self.euclideanThresholdPixel) * (width / 2048.0))
        filteredCount = len(samplesList)
        localIndices = np.empty(filteredCount)
        localIndices.fill(-1)
        for i in range(0, filteredCount):
            cpos = samplesList[i]["pos"]
            if localIndices[i] == -1:
                localIndices[i] = i
                for j in range(0, filteredCount):
                    if (
                        i != j
                        and localIndices[j] == -1
                        and self.distance2d(cpos, samplesList[j]["pos"]) < euclideanThreshold
                    ):
                        localIndices[j] = i

        lights = []
        finalIndices = np.empty(filteredCount)
        finalIndices.fill(-1)
        for i in localIndices:
            i = int(i)  # fix: float indices
            sample = samplesList[i]
            startPos = sample["pos"]
            if finalIndices[i] == -1:
                finalIndices[i] = i
                light = {
                    "originalPos": np.array(sample["pos"]),
                    "pos": np.array(sample["pos"], dtype=float),
                    "luminance": sample["luminance"],
                    "members": [sample["pos"]],
                }
                for j in localIndices:
                    j = int(j)
                    if i != j and finalIndices[j] == -1:
                        endPos = samplesList[j]["pos"]
                        if self.bresenhamCheck(
                            lum, width, height, startPos[0], startPos[1], endPos[0], endPos[1]
                        ):
                            finalIndices[j] = i
                            sampleWeight = samplesList[j]["luminance"] / sample["luminance"]
                            light["pos"] = light["pos"] + np.array(endPos) * sampleWeight
                            light["pos"] = light["pos"] / (1.0 + sampleWeight)
                            light["members"].append(endPos)
                lights.append(light)
        return lights

    def directions(self, lights: list[dict], shape: tuple[int, int]) -> np.ndarray:
        """hdrjax az/el (degrees) of the listing's light positions (pixel centres)."""
        h, w = shape
        sx = w / self.width
        out = []
        for light in lights:
            x, y = light["pos"] * sx
            out.append((360.0 * (x + 0.5) / w - 180.0, 90.0 - 180.0 * (y + 0.5) / h))
        return np.array(out).reshape(-1, 2)


# ----------------------------------------------------------------------------- ground truth


def unit_vectors(az_deg: np.ndarray, el_deg: np.ndarray) -> np.ndarray:
    """hdrjax directions (Y-up, ahead −Z) of azimuths/elevations in degrees (0° at the image
    centre, azimuth positive to the right)."""
    az, el = np.radians(az_deg), np.radians(el_deg)
    return np.stack([np.cos(el) * np.sin(az), np.sin(el) + 0 * az, -np.cos(el) * np.cos(az)], -1)


def blobs(rgb: np.ndarray) -> list[dict]:
    """The bright blobs: Y > max(50 median, 0.02 max), 8-connected, seam merged."""
    h, w = rgb.shape[:2]
    Y = rgb @ np.array([0.2126, 0.7152, 0.0722], np.float64)
    Y = np.where(np.isfinite(Y), Y, 0.0)
    T = max(50 * np.median(Y), 0.02 * Y.max())
    lab, n = ndimage.label(Y > T, structure=np.ones((3, 3), int))
    parent = list(range(n + 1))

    def root(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for y in range(h):
        for dy in (-1, 0, 1):
            if 0 <= y + dy < h and lab[y, w - 1] and lab[y + dy, 0]:
                parent[root(lab[y, w - 1])] = root(lab[y + dy, 0])
    lab = np.vectorize(root)(lab) if n else lab
    el = 90.0 - 180.0 * (np.arange(h) + 0.5) / h
    az = 360.0 * (np.arange(w) + 0.5) / w - 180.0
    cosw = np.cos(np.radians(el))[:, None] * np.ones((1, w))
    total = float((Y * cosw).sum())
    out = []
    for b in np.unique(lab[lab > 0]):
        ys, xs = np.nonzero(lab == b)
        e = Y[ys, xs] * cosw[ys, xs]
        d = unit_vectors(az[xs], el[ys])
        c = (d * e[:, None]).sum(0)
        out.append(
            {
                "dirs": d,
                "centroid": c / np.linalg.norm(c),
                "share": float(e.sum() / total),
                "peak": float(Y[ys, xs].max()),
                "area": int(ys.size),
            }
        )
    return sorted(out, key=lambda b: -b["share"])


def quality(
    dirs: np.ndarray,
    truth: list[dict],
    radius: np.ndarray | None = None,
    weight: np.ndarray | None = None,
) -> dict:
    """Correct/spurious lights, found/missed significant blobs and angular errors (deg).

    A light *covers* a blob when the blob's nearest pixel is within ``1° + radius`` of it
    (``radius``: the light's angular radius, 0 for point lights). Lights covering no blob
    are spurious; a significant blob (≥ 1 % of the energy) no light covers is missed. The
    error of a found blob is the angle between its energy centroid and the ``weight``ed
    mean direction of the lights covering it (a blob wider than ``max_radius`` is split
    into several lights; their mean is what a renderer integrating them sees).
    """
    dirs = np.asarray(dirs, np.float64).reshape(-1, 3)
    radius = np.zeros(len(dirs)) if radius is None else np.asarray(radius, np.float64)
    weight = np.ones(len(dirs)) if weight is None else np.asarray(weight, np.float64)
    near = np.zeros((len(dirs), len(truth)), bool)
    for j, b in enumerate(truth):
        if len(dirs):
            cos = np.clip(dirs @ b["dirs"].T, -1, 1).max(axis=1)
            near[:, j] = np.degrees(np.arccos(cos)) <= MATCH_DEG + radius
    sig = [j for j, b in enumerate(truth) if b["share"] >= SIGNIFICANT_SHARE]
    errs = []
    for j in sig:
        if near[:, j].any():
            m = (dirs[near[:, j]] * weight[near[:, j], None]).sum(0)
            m = m / max(np.linalg.norm(m), 1e-30)
            errs.append(float(np.degrees(np.arccos(np.clip(m @ truth[j]["centroid"], -1, 1)))))
    return {
        "lights": len(dirs),
        "correct": int(near.any(axis=1).sum()),
        "spurious": int((~near.any(axis=1)).sum()),
        "significant": len(sig),
        "found": len(errs),
        "missed": len(sig) - len(errs),
        "err_mean": float(np.mean(errs)) if errs else float("nan"),
        "err_max": float(np.max(errs)) if errs else float("nan"),
    }


# ----------------------------------------------------------------------------- benchmark


def ours_quality(res: hl.Lights, truth: list[dict]) -> dict:
    n = int(res.count)
    return quality(
        np.asarray(res.direction)[:n],
        truth,
        np.asarray(res.angular_diameter)[:n] / 2,
        np.asarray(res.energy)[:n],
    )


def _flat(q: dict) -> dict:
    """Quality figures as flat extras of a record."""
    return {k: q[k] for k in ("lights", "spurious", "missed", "significant", "err_mean")}


def _last(fn):
    """``fn`` that also keeps its latest result in ``fn.out`` (what was timed is checked)."""

    def call():
        call.out = fn()
        return call.out

    return call


def run(quick: bool = False) -> list[dict]:
    """Records of benchmark ``"lights"`` and the ``lights.detect`` accuracy/time curve."""
    rep = 5 if quick else 15
    maps = []
    for name, path in MAPS[:1] if quick else MAPS:
        if not path.exists():
            print(f"(skipping {name}: {path} not found)")
            continue
        rgb = np.ascontiguousarray(hdrjax.io.read(path).rgb(), np.float32)
        maps.append((name, rgb, jnp.asarray(rgb), blobs(rgb)))
    print(f"[lights] jax {jax.__version__}, {jax.devices()[0].platform}, maps: {len(maps)}")
    out: list[dict] = []

    # ---- 1. hdrjax defaults vs Loghin's listing, same process, same maps
    peer = SeedListing()
    for name, rgb, jrgb, truth in maps:
        case = f"detect defaults {name}"
        listing = _last(lambda rgb=rgb: peer(rgb))
        t_peer = H.measure(listing, max(3, rep // 3))
        qp = quality(unit_vectors(*peer.directions(listing.out, rgb.shape[:2]).T), truth)
        ours = _last(lambda jrgb=jrgb: hl.detect(jrgb))
        t_ours = H.measure(ours, rep)
        qo = ours_quality(ours.out, truth)
        t_np = H.measure(lambda rgb=rgb: hl.detect(rgb), rep)
        out += [
            H.record(BENCH, case, "hdrjax", timing=t_ours, compiled=True, **_flat(qo)),
            H.record(BENCH, case, "hdrjax (NumPy input)", timing=t_np),
            H.record(BENCH, case, "Loghin 2019 listing", timing=t_peer, **_flat(qp)),
        ]

    # ---- 2. batch: one vmapped call over the same-size maps
    same = [m for m in maps if m[1].shape == maps[0][1].shape]
    if len(same) > 1:
        batch = jnp.stack([m[2] for m in same])
        t_b = H.measure(lambda: hl.detect(batch), rep)
        out.append(
            H.record(
                BENCH,
                f"detect batch of {len(same)} maps",
                "hdrjax",
                timing=t_b,
                compiled=True,
                maps=len(same),
                per_map_ms=t_b["median_s"] * 1e3 / len(same),
            )
        )

    # ---- 3. the accuracy/time curve
    if quick:
        settings = [(256, 0.006, 0.0), (512, 0.002, 0.0), (512, 0.006, 0.0)]
    else:
        settings = [
            (w, mult, b)
            for w in (256, 512, 1024)
            for mult in (0.002, 0.006, 0.02)
            for b in (0.0, 1.0)
        ]
    for w, mult, b in settings:
        ms, mins, comp, qs = [], [], [], []
        for name, _, jrgb, truth in maps:
            n = max(64, round(mult * w * w / 2))
            det = _last(
                lambda jrgb=jrgb, n=n, w=w, b=b: hl.detect(jrgb, width=w, n_samples=n, blur=b)
            )
            t = H.measure(det, rep)
            ms.append(t["median_s"])
            mins.append(t["min_s"])
            comp.append(max(t["first_s"] - t["median_s"], 0.0))
            qs.append((name, ours_quality(det.out, truth)))
        errs = [q["err_mean"] for _, q in qs if q["found"]]
        out.append(
            H.accuracy_point(
                CURVE,
                f"w={w} s={mult:g} blur={b:g}",
                float(np.mean(errs)) if errs else float("nan"),
                statistics.median(ms),
                default=(
                    w == hl.DEFAULT_WIDTH
                    and mult == hl.DEFAULT_SAMPLES_PER_PIXEL
                    and b == hl.DEFAULT_BLUR
                ),
                error_kind="mean angular error (deg)",
                width=w,
                samples_per_px=mult,
                blur=b,
                min_ms=statistics.median(mins) * 1e3,
                compile_s=max(comp),  # the first map of each shape compiles
                lights=sum(q["lights"] for _, q in qs),
                sun_spurious=sum(q["spurious"] for nm, q in qs if nm in SUN_MAPS),
                missed=sum(q["missed"] for _, q in qs),
                significant=sum(q["significant"] for _, q in qs),
                err_max=max((q["err_max"] for _, q in qs if q["found"]), default=float("nan")),
                maps=len(qs),
                per_map=dict(qs),
            )
        )

    # ---- 4. median cut (the comparison method)
    for name, _, jrgb, _ in maps:
        for n in (16,) if quick else (16, 64):
            mc = _last(lambda jrgb=jrgb, n=n: hl.median_cut(jrgb, n_lights=n))
            t = H.measure(mc, rep)
            err = abs(float(np.asarray(mc.out.energy_share).sum()) - 1.0)
            out.append(
                H.record(
                    BENCH,
                    f"median_cut {name} n={n}",
                    "hdrjax",
                    timing=t,
                    compiled=True,
                    energy_err=err,
                )
            )
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="bundled map only, fewer repeats")
    run(ap.parse_args().quick)
