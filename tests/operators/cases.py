"""Operators with the arguments the registry-driven tests use, and hard-case images."""

import numpy as np

import hdrjax

EXTRA = {"tabulated": dict(luminance=[0.01, 1.0, 100.0], display=[0.02, 0.5, 1.0])}


def make(name, **kw):
    return hdrjax.make_operator(name, **{**EXTRA.get(name, {}), **kw})


def natural(shape=(12, 16), seed=0, dtype=np.float32):
    """A lognormal HDR image with a wide range (about 17 stops)."""
    rng = np.random.default_rng(seed)
    L = rng.lognormal(0.0, 2.0, shape)
    tint = rng.uniform(0.5, 1.5, shape + (3,))
    return (L[..., None] * tint).astype(dtype)


def hard_cases(dtype=np.float32):
    """The hard-value families of issues 1 and 10, as {name: image}; all 8×8 (float64 values
    cast to ``dtype``: the denormal family is 0 in float16, the 1e±30 family saturates)."""
    base = natural((8, 8), dtype=np.float64)
    mixed = np.zeros((8, 8, 3))
    mixed[::3, ::2] = 1e5
    neg = base.copy()
    neg[0, :4] = -0.3
    neg[1, 1] = (-1.0, 0.5, 0.2)
    wide = np.logspace(-30, 30, 8 * 8 * 3).reshape(8, 8, 3)
    denormal = base.copy()
    denormal[::2] = 1e-42  # subnormal in float32 (XLA:CPU flushes these to zero)
    f16max = base.copy()
    f16max[2:4, 2:4] = 65504.0  # float16's largest finite value
    lit = np.zeros((8, 8, 3))
    lit[3, 4] = (5e3, 4e3, 3e3)  # one lamp in the dark
    clipped = base.copy()
    clipped[1:5, 1:5] = base.max()  # a clipped lamp: a flat maximum over many pixels
    bad = base.copy()
    bad[2, 3] = np.nan
    bad[4, 5, 1] = np.nan
    bad[1, 2] = np.inf
    bad[5, 5, 0] = -np.inf
    bad[6, 6] = (np.inf, -np.inf, 1.0)
    cases = {
        "zeros": np.zeros((8, 8, 3)),
        "constant": np.full((8, 8, 3), 2.5),
        "zeros_and_1e5": mixed,
        "negative": neg,
        "range_1e-30_1e30": wide,
        "denormal": denormal,
        "float16_max": f16max,
        "single_lit_pixel": lit,
        "clipped_flat_max": clipped,
        "nan_and_inf": bad,  # keep last: tests index it as the last frame
    }
    with np.errstate(over="ignore"):  # float16: 1e5 and 1e30 become inf, on purpose
        return {k: v.astype(dtype) for k, v in cases.items()}


SINGLE_PIXEL = np.array([[[0.3, 0.2, 0.1]]])
