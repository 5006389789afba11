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
        "nan_and_inf": bad,
    }
    with np.errstate(over="ignore"):  # float16: 1e5 and 1e30 become inf, on purpose
        return {k: v.astype(dtype) for k, v in cases.items()}


def bad_pixel_cases(dtype=np.float32):
    """One kind of bad pixel at a time in the natural 8×8 image, as {name: image}: NaN,
    +Inf or −Inf, each as whole pixels and as one channel of a pixel (``nan_and_inf`` of
    :func:`hard_cases` mixes them)."""
    base = natural((8, 8), dtype=np.float64)
    out = {}
    for name, v in (("nan_only", np.nan), ("posinf_only", np.inf), ("neginf_only", -np.inf)):
        img = base.copy()
        img[2, 3] = v
        img[5, 1, 2] = v
        img[7, 7] = v  # a corner: neighbourhoods are cut there
        out[name] = img.astype(dtype)
    return out


SCALES_PER_DTYPE = 10


def scales(dtype) -> np.ndarray:
    """Brightness scales spanning the dtype: ``SCALES_PER_DTYPE`` log-spaced values from
    the smallest normal (``finfo.tiny``) to the largest finite value (``finfo.max``), both
    exactly, plus the scale at which the natural image's dimmest pixel is ``tiny``."""
    fi = np.finfo(dtype)
    tiny, big = float(fi.tiny), float(fi.max)
    with np.errstate(over="ignore"):  # 10**log10(max) may round above max: replaced
        s = np.logspace(np.log10(tiny), np.log10(big), SCALES_PER_DTYPE)
    s[0], s[-1] = tiny, big
    base = natural((8, 8), dtype=np.float64)
    dimmest = tiny * base.max() / base.min()  # every channel of every pixel normal
    return np.sort(np.append(s, dimmest))


def scale_cases(dtype=np.float32, lo=None, hi=None):
    """The natural 8×8 image at every brightness scale of ``dtype``, as {name: image}.

    ``scale_<s>``: the image divided by its largest value and multiplied by ``s`` for every
    ``s`` of :func:`scales` within ``[lo, hi]`` (the smallest frames are partly subnormal,
    which XLA:CPU flushes to zero; the largest has a channel at exactly ``finfo.max``).
    Without bounds, three more: ``flat_max`` (every value ``finfo.max``: its luminance can
    round above the largest float), ``one_max`` (one pixel at ``finfo.max`` in the unscaled
    image) and ``one_huge`` (one pixel at 0.88 ``finfo.max``, 3e38 in float32).
    """
    fi = np.finfo(dtype)
    base = natural((8, 8), dtype=np.float64)
    base = base / base.max()
    out = {}
    for s in scales(dtype):
        if (lo is None or s >= lo) and (hi is None or s <= hi):
            # float64 rounding of s·base may exceed the dtype's max by an ulp: clip
            out[f"scale_{s:.1e}"] = np.minimum(base * s, float(fi.max)).astype(dtype)
    if lo is None and hi is None:
        out["flat_max"] = np.full((8, 8, 3), fi.max, dtype)
        for name, v in (("one_max", float(fi.max)), ("one_huge", 0.88 * float(fi.max))):
            img = natural((8, 8), dtype=np.float64)
            img[3, 4] = v
            out[name] = img.astype(dtype)
    return out


GRAD_SCALES = (1e-18, 1e30)
"""Scales (float32) at which gradients must be finite, and where the operators are meant to
be differentiable. Below: JAX differentiates ``x / y`` with respect to ``y`` as
``−x · y⁻²``, and ``y⁻²`` leaves float32 once ``y < 1.1e-19`` (hdrjax's luminance floor),
so a statistic dimmer than that (``L_max``, a log-average) has no finite gradient even where
the exact one (about ``1/s``) is representable. Above: 1e30 is the top of the hard family
``range_1e-30_1e30``; beyond it, squares and products of two luminances in the backward
pass leave float32. Outside this range only the outputs must be finite (every scale of
:func:`scales`)."""


def families(dtype=np.float32):
    """Every image family of the conformance suites, as {name: image}: the hard values,
    one kind of bad pixel at a time, and every brightness scale of ``dtype``."""
    return {**hard_cases(dtype), **bad_pixel_cases(dtype), **scale_cases(dtype)}


def gradient_families():
    """The float32 families whose gradients must be finite: all but the scales outside
    :data:`GRAD_SCALES` (and the frames at the largest finite value), plus the natural
    image at both ends of that range."""
    base = natural((8, 8), dtype=np.float64)
    ends = {f"scale_{s:.1e}": (base * (s / base.max())).astype(np.float32) for s in GRAD_SCALES}
    return {
        **hard_cases(np.float32),
        **bad_pixel_cases(np.float32),
        **scale_cases(np.float32, *GRAD_SCALES),
        **ends,
    }


SINGLE_PIXEL = np.array([[[0.3, 0.2, 0.1]]])
