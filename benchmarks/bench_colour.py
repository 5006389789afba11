"""What reading a file in other primaries costs: tone mapping an XYZ image, in one process.

``hdrjax tonemap`` converts a file into the working space (sRGB) inside the compiled
program: one 3×3 matrix per pixel, folded into the luminance weights for the statistics
and applied on the way out of the mapping (:func:`hdrjax.operators.apply_in_space`).
Compared on the same pixels (full mode 4096×4096, quick 1024×1024; Reinhard 2002 with
automatic key and white, measure + map as the command line runs them):

  * hdrjax on XYZ pixels (``CIE XYZ`` → sRGB in the program): the numerator;
  * hdrjax on the same pixels already in sRGB (no conversion): the goal is ≤ 1.05× this;
  * colour-science's ``XYZ_to_RGB`` in NumPy first, then hdrjax on its sRGB result.

Compile time is reported separately (first call minus the median).

Usage: ``python benchmarks/bench_colour.py [--quick]``
"""

import argparse

import _harness as H
import jax
import numpy as np

from hdrjax import spaces
from hdrjax.cli._cmd_tonemap import apply_in_space, eqx_jit_measure
from hdrjax.operators import Reinhard2002

BENCH = "colour"


def run(quick: bool = False) -> list[dict]:
    """Records of benchmark ``"colour"`` (see the module docstring)."""
    n = 1024 if quick else 4096
    reps = 5 if quick else 7
    rng = np.random.default_rng(0)
    y = rng.lognormal(0.0, 2.5, (n, n)).astype(np.float32)
    xyz = (y[..., None] * rng.uniform(0.7, 1.3, (n, n, 3))).astype(np.float32)
    m = spaces.conversion_matrix(spaces.XYZ_CHROMATICITIES, "sRGB")
    srgb = np.ascontiguousarray(xyz @ m.T.astype(np.float32))
    weights = spaces.luminance_weights_in(spaces.XYZ_CHROMATICITIES)
    op = Reinhard2002(weights=weights)
    case = f"Reinhard 2002 {n}x{n}, file in CIE XYZ"
    common = {"pixels": n * n}

    def tonemap(x, matrix):
        measured = eqx_jit_measure(op, x, matrix)
        return apply_in_space(measured, x, matrix)

    x_xyz, x_srgb = jax.device_put(xyz), jax.device_put(srgb)
    out = [
        H.record(
            BENCH,
            case,
            "hdrjax",
            lambda: tonemap(x_xyz, m),
            repeats=reps,
            compiled=True,
            **common,
        ),
        H.record(
            BENCH,
            case,
            "same pixels already in sRGB",
            lambda: tonemap(x_srgb, None),
            repeats=reps,
            **common,
        ),
    ]
    import colour

    out.append(
        H.record(
            BENCH,
            case,
            "colour-science XYZ_to_RGB, then hdrjax",
            lambda: tonemap(np.asarray(colour.XYZ_to_RGB(xyz, "sRGB"), np.float32), None),
            repeats=3,
            **common,
        )
    )
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    run(ap.parse_args().quick)
