"""16-bit TIFF export speed: hdrjax.io.write_display against tifffile.imwrite and cv2.imwrite.

hdrjax writes TIFF through tifffile (deflate strips at zlib level 1, its ICC display profile,
an atomic rename); the peers write the same pixels with the same compression (Adobe deflate):
tifffile called directly, and OpenCV's libtiff writer. Two inputs of N × N/2 (full 4096 × 2048,
quick 1024 × 512), a smooth gradient with noise as a tone-mapped photograph has: 16-bit code
values, and float32 display RGB in [0, 1] (hdrjax quantises it; the peers get NumPy's
``round(x * 65535)``, the same code values). Each writer's file is read back and checked
against the code values before timing; one warm-up call each, then the repeats, in one
process.

Run: ``.venv/bin/python benchmarks/bench_tiff_write.py [--quick]``.
"""

import argparse
import tempfile
from pathlib import Path

import _harness as H
import numpy as np
import tifffile

import hdrjax.io as hio

BENCH = "tiff_write"


def _image(h: int, w: int) -> np.ndarray:
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    f = np.stack([x / w, y / h, 0.5 + 0.25 * np.sin(x / 37.0) * np.cos(y / 53.0)], axis=2)
    f += np.random.default_rng(0).normal(0, 0.01, f.shape).astype(np.float32)
    return np.clip(f, 0, 1).astype(np.float32)


def _code(f: np.ndarray) -> np.ndarray:
    return (f * np.float32(65535) + np.float32(0.5)).astype(np.uint16)


def _writers(out: Path, img: np.ndarray) -> dict:
    import cv2

    level = hio.DEFAULT_COMPRESSION
    as_code = _code if img.dtype == np.float32 else (lambda a: a)

    def ours():
        return hio.write_display(out / "hdrjax.tif", img, bits=16)

    def with_tifffile():
        tifffile.imwrite(
            out / "tifffile.tif",
            as_code(img),
            photometric="rgb",
            compression="zlib",
            compressionargs={"level": level},
            metadata=None,
        )

    def with_cv2():
        params = [cv2.IMWRITE_TIFF_COMPRESSION, 8]  # Adobe deflate, as the others
        cv2.imwrite(str(out / "cv2.tif"), as_code(img)[:, :, ::-1], params)

    return {"hdrjax": ours, "tifffile.imwrite": with_tifffile, "cv2.imwrite": with_cv2}


def run(quick: bool = False) -> list[dict]:
    """Records of benchmark ``"tiff_write"``: each writer on each input."""
    h, w = (512, 1024) if quick else (2048, 4096)
    reps = 3 if quick else 5
    f = _image(h, w)
    records = []
    with tempfile.TemporaryDirectory() as d:
        out = Path(d)
        for label, img in (("16-bit RGB", _code(f)), ("float32 RGB to 16 bit", f)):
            case = f"{label} {w}x{h}"
            for impl, fn in _writers(out, img).items():
                fn()
                back = tifffile.imread(out / f"{impl.split('.')[0]}.tif")
                if not np.array_equal(back, _code(f)):
                    raise AssertionError(f"{impl}: {case} does not read back as written")
                size = (out / f"{impl.split('.')[0]}.tif").stat().st_size
                records.append(
                    H.record(BENCH, case, impl, fn, repeats=reps, file_mb=round(size / 2**20, 1))
                )
    return records


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1024×512, fewer repeats")
    recs = run(ap.parse_args().quick)
    by_case: dict[str, dict[str, float]] = {}
    for r in recs:
        by_case.setdefault(r["case"], {})[r["impl"]] = r["median_s"]
    for case, t in by_case.items():
        peers = ", ".join(f"/ {k} = {t['hdrjax'] / v:.2f}" for k, v in t.items() if k != "hdrjax")
        print(f"[{BENCH}] {case:<32} hdrjax {peers}  (hdrjax {t['hdrjax'] * 1e3:.0f} ms)")
