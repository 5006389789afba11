"""Spectral image to CIE XYZ: hdrjax.spectral.spectral_to_xyz against colour-science.

A 2048 × 1024 float32 reflectance image with 31 bands (400-700 nm at 10 nm; quick mode
1024 × 512) integrated under D65 with the CIE 1931 observer. Peers, timed alternately with
hdrjax in one process (one warm-up call each, then the repeats):

  * colour-science's ``msds_to_XYZ(image, cmfs, D65, method="Integration",
    shape=SpectralShape(400, 700, 10))``: its path for spectral images (arrays), which
    subsamples the CMFs and illuminant to the image's bands (its ``MultiSpectralDistributions``
    path aligns the image to the CMFs instead, which for millions of pixels would need
    ~8 GB; hdrjax reproduces that path exactly, ``max_rel_err_vs_colour_msds``, checked on
    256 pixels);
  * NumPy ``image @ W`` with hdrjax's own weights: the same product without JAX, near the
    memory-bandwidth bound.

hdrjax is timed with the image already a JAX array (as the other benchmarks: the product
alone, in a jit-compiled caller) and called eagerly on the NumPy array (the host-to-JAX
copy included, what a caller holding ``hdrjax.io.read(...).image`` pays). The weights'
one-off NumPy/colour-science derivation (``weights_s``) and the compile time
(``lower().compile()``) are reported separately.

Run: ``.venv/bin/python benchmarks/bench_spectral.py [--quick] [--repeat R]``.
"""

import argparse
import time
import warnings

import _harness as H
import jax
import numpy as np

from hdrjax.spectral import spectral_to_xyz, spectral_weights

BENCH = "spectral"
WAVELENGTHS = np.arange(400.0, 701.0, 10.0)


def _clock(fn) -> float:
    t = time.perf_counter()
    jax.block_until_ready(fn())
    return time.perf_counter() - t


def _colour_object_path(spectra: np.ndarray) -> np.ndarray:
    """colour-science's ``MultiSpectralDistributions`` path (alignment to the CMFs), /100."""
    import colour

    msds = colour.MultiSpectralDistributions(spectra.astype(np.float64).T, WAVELENGTHS)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        xyz = colour.msds_to_XYZ(
            msds,
            colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"],
            colour.SDS_ILLUMINANTS["D65"],
            method="Integration",
        )
    return np.asarray(xyz) / 100.0


def run(
    quick: bool = False, *, size: tuple[int, int] | None = None, repeat: int | None = None
) -> list[dict]:
    """Records of benchmark ``"spectral"`` (see the module docstring)."""
    import colour

    w_px, h_px = size or ((1024, 512) if quick else (2048, 1024))
    reps = repeat or (5 if quick else 7)
    n = WAVELENGTHS.size
    rng = np.random.default_rng(0)
    image = rng.uniform(0.0, 1.0, (h_px, w_px, n)).astype(np.float32)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    shape = colour.SpectralShape(400, 700, 10)

    t0 = time.perf_counter()
    weights = spectral_weights(WAVELENGTHS, kind="reflective")
    weights_s = time.perf_counter() - t0
    w32 = weights.astype(np.float32)
    on_device = jax.device_put(image)
    jitted = jax.jit(lambda s: spectral_to_xyz(s, WAVELENGTHS, kind="reflective"))
    t0 = time.perf_counter()
    compiled = jitted.lower(on_device).compile()
    compile_s = time.perf_counter() - t0

    def ours():
        return compiled(on_device)

    def ours_numpy():
        return spectral_to_xyz(image, WAVELENGTHS, kind="reflective")

    def theirs():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return colour.msds_to_XYZ(image, cmfs, d65, method="Integration", shape=shape)

    def numpy_product():
        return image @ w32

    impls = {
        "hdrjax": ours,
        "hdrjax (from NumPy, incl. transfer)": ours_numpy,
        "colour.msds_to_XYZ (array, shape=)": theirs,
        "NumPy image @ W (same weights)": numpy_product,
    }
    first = {name: _clock(fn) for name, fn in impls.items()}
    times: dict[str, list[float]] = {name: [] for name in impls}
    for _ in range(reps):  # alternately, so every implementation sees the same machine load
        for name, fn in impls.items():
            times[name].append(_clock(fn))

    got = np.asarray(ours()).reshape(-1, 3)
    pick = rng.choice(got.shape[0], 256, replace=False)
    exact = _colour_object_path(image.reshape(-1, n)[pick])
    err_exact = float(np.max(np.abs(got[pick] - exact) / np.abs(exact)))
    peer = np.asarray(theirs()).reshape(-1, 3) / 100.0
    err_peer = float(np.max(np.abs(got - peer) / np.abs(peer)))

    case = f"D65 reflective {w_px}x{h_px}x{n} float32"
    common = {"pixels": w_px * h_px, "bands": n, "megabytes": round(image.nbytes / 1e6, 1)}
    out = []
    for name in impls:
        timing = H.summarize(times[name], first[name])
        extra = dict(common)
        if name.startswith("hdrjax"):
            extra.update(
                weights_s=round(weights_s, 4),
                max_rel_err_vs_colour_msds=err_exact,
                max_rel_diff_vs_colour_array_path=err_peer,
            )
        compile_ours = compile_s if name == "hdrjax" else None
        out.append(H.record(BENCH, case, name, timing=timing, compile_s=compile_ours, **extra))
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1024×512, 5 repeats")
    ap.add_argument("--repeat", type=int, default=None)
    a = ap.parse_args()
    records = run(a.quick, repeat=a.repeat)
    base = {r["impl"]: r["median_s"] for r in records}
    for impl, t in base.items():
        if not impl.startswith("hdrjax"):
            print(
                f"ratio hdrjax / {impl}: {base['hdrjax'] / t:.3f}; from NumPy: "
                f"{base['hdrjax (from NumPy, incl. transfer)'] / t:.3f}"
            )
