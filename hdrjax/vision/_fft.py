"""Zero-padded (linear, not circular) FFT convolution of channels-last images.

The kernel's spectrum is computed once in NumPy float64 from a centred kernel and passed to
the traced code as an array, so a compiled function holds no large constant. The padded size
is the smallest 5-smooth size (factors 2, 3, 5 only) of at least ``H + ry`` by ``W + rx`` for
a kernel of radius ``(ry, rx)``, which is exactly what keeps the kernel's tail from wrapping
round onto the image; ``circular=True`` skips the padding (FFT size = image size) and is
only for measuring what padding buys (benchmarks/bench_vision.py).
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array


@functools.lru_cache(maxsize=1024)
def next_smooth(n: int) -> int:
    """Smallest integer ``>= n`` whose prime factors are 2, 3 and 5 only."""
    n = max(1, int(n))
    best = 1 << (n - 1).bit_length()
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            m = p35
            while m < n:
                m *= 2
            best = min(best, m)
            p35 *= 3
        p5 *= 5
    return best


def fft_size(h: int, w: int, ry: int, rx: int, *, circular: bool = False) -> tuple[int, int]:
    """FFT grid for an ``h × w`` image and a kernel of radius ``(ry, rx)`` pixels."""
    if circular:
        return h, w
    return next_smooth(h + ry), next_smooth(w + rx)


def kernel_spectrum(kernel: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """``rfft2`` (complex128, shape ``(C, Hp, Wp//2 + 1)``) of centred kernels ``(C, kh, kw)``.

    The kernel centre goes to index (0, 0); entries beyond the FFT grid fold back (modulo),
    which only happens for ``circular`` grids.
    """
    k = np.asarray(kernel, dtype=np.float64)
    if k.ndim == 2:
        k = k[None]
    C, kh, kw = k.shape
    Hp, Wp = size
    iy = (np.arange(kh) - kh // 2) % Hp
    ix = (np.arange(kw) - kw // 2) % Wp
    import scipy.fft  # NumPy-side, once per kernel: not worth its import time at start-up

    grid = np.zeros((C, Hp, Wp))
    if kh <= Hp and kw <= Wp:  # no folding: place the kernel, then centre it at (0, 0)
        grid[:, :kh, :kw] = k
        grid = np.roll(grid, (-(kh // 2), -(kw // 2)), axis=(1, 2))
    else:
        for c in range(C):
            np.add.at(grid[c], (iy[:, None], ix[None, :]), k[c])
    return scipy.fft.rfft2(grid, axes=(-2, -1), workers=-1)


def normalise(x: Array) -> tuple[Array, Array]:
    """``(x / r, r)`` with ``r = clip(max|x|, 1, 2^100)``, so that sums over many pixels
    (FFT, box filters) stay finite up to the dtype's maximum; undo with :func:`denormalise`.

    ``r`` is capped at 2^100 because XLA may divide through the reciprocal, and ``1/r`` of a
    value near float32's maximum is subnormal (flushed to zero); at 2^100 the normalised
    values stay below 2^28. ``r`` carries no gradient (the result does not depend on it).
    """
    m = jax.lax.stop_gradient(jnp.max(jnp.abs(x)))
    r = jnp.clip(m, 1.0, 2.0**100)
    return x / r, r


def denormalise(y: Array, r: Array) -> Array:
    """Inverse of :func:`normalise`."""
    return y * r


def convolve(x: Array, spectrum: Array, size: tuple[int, int]) -> Array:
    """Convolve ``x`` ``(H, W, C)`` with kernels given by their ``spectrum``.

    ``spectrum`` has shape ``(C or 1, Hp, Wp//2 + 1)`` for the grid ``size = (Hp, Wp)``.
    The image is divided by its largest magnitude before the transform (and multiplied back
    after, :func:`normalise`), so values up to the dtype's maximum do not overflow. ``x`` must
    be finite (callers replace NaN/Inf first).
    """
    H, W, _ = x.shape
    Hp, Wp = size
    xn, r = normalise(x)
    xc = jnp.moveaxis(xn, -1, 0)
    xc = jnp.pad(xc, ((0, 0), (0, Hp - H), (0, Wp - W)))
    y = jnp.fft.irfft2(jnp.fft.rfft2(xc) * spectrum, s=(Hp, Wp))
    return denormalise(jnp.moveaxis(y[:, :H, :W], 0, -1).astype(x.dtype), r)


__all__ = ["convolve", "fft_size", "kernel_spectrum", "next_smooth"]
