"""TMQI (Yeganeh & Wang 2013) in float64 NumPy/SciPy, step by step as the authors' MATLAB
code (HDR Toolbox's ``TMQI.m``, ``TMQI_StructuralFidelity.m``,
``TMQI_LocalStructuralFidelity.m``, ``TMQI_StatisticalNaturalness.m``) computes it: the
11×11 window as one 2-D correlation with zero padding (``filter2``), the 2×2 averaging with
symmetric edges (``imfilter``), blocks with their own pixels (``blkproc``), SciPy's normal
and beta distributions. The tests' reference and the benchmark's peer; written from the
paper and the reading of that code, none of it copied."""

import numpy as np
from scipy import ndimage, stats

WEIGHTS = (0.0448, 0.2856, 0.3001, 0.2363, 0.1333)


def _window() -> np.ndarray:
    x = np.arange(11) - 5.0
    g = np.exp(-(x[:, None] ** 2 + x[None, :] ** 2) / (2 * 1.5**2))
    return g / g.sum()


def _lum(rgb: np.ndarray) -> np.ndarray:
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


def local_fidelity(x: np.ndarray, y: np.ndarray, f: float) -> float:
    w = _window()

    def filt(v):
        return ndimage.correlate(v, w, mode="constant", cval=0.0)

    mu1, mu2 = filt(x), filt(y)
    s1 = np.sqrt(np.maximum(0.0, filt(x * x) - mu1 * mu1))
    s2 = np.sqrt(np.maximum(0.0, filt(y * y) - mu2 * mu2))
    s12 = filt(x * y) - mu1 * mu2
    csf = 100.0 * 2.6 * (0.0192 + 0.114 * f) * np.exp(-((0.114 * f) ** 1.1))
    u = 128 / (1.4 * csf)
    p1 = stats.norm.cdf(s1, u, u / 3)
    p2 = stats.norm.cdf(s2, u, u / 3)
    s_map = ((2 * p1 * p2 + 0.01) / (p1 * p1 + p2 * p2 + 0.01)) * ((s12 + 10) / (s1 * s2 + 10))
    return float(s_map.mean())


def _downsample(v: np.ndarray) -> np.ndarray:
    # imfilter(v, ones(2)/4, 'symmetric', 'same'): the 2×2 block starting at each pixel
    p = np.pad(v, ((0, 1), (0, 1)), mode="symmetric")
    m = (p[:-1, :-1] + p[1:, :-1] + p[:-1, 1:] + p[1:, 1:]) / 4
    return m[::2, ::2]


def naturalness(y: np.ndarray) -> float:
    h, w = y.shape
    stds = [
        np.std(y[i : i + 11, j : j + 11], ddof=1) if y[i : i + 11, j : j + 11].size > 1 else 0.0
        for i in range(0, h, 11)
        for j in range(0, w, 11)
    ]
    sig = float(np.mean(stds))
    a, b = 4.4, 10.1
    mode = (a - 1) / (a + b - 2)
    pc = stats.beta.pdf(sig / 64.29, a, b) / stats.beta.pdf(mode, a, b)
    pb = stats.norm.pdf(y.mean(), 115.94, 27.99) / stats.norm.pdf(115.94, 115.94, 27.99)
    return float(pb * pc)


def tmqi(hdr: np.ndarray, ldr255: np.ndarray) -> tuple[float, float, float]:
    """``(Q, S, N)`` of one HDR image (linear RGB, any scale) and its LDR rendition
    (encoded RGB, 0–255)."""
    L = _lum(np.asarray(hdr, np.float64))
    lo, hi = L.min(), L.max()
    x = np.round((2**32 - 1) / (hi - lo)) * (L - lo)
    y = _lum(np.asarray(ldr255, np.float64))
    n = naturalness(y)
    s_l = []
    f = 32.0
    for _ in WEIGHTS:
        f /= 2
        s_l.append(local_fidelity(x, y, f))
        x, y = _downsample(x), _downsample(y)
    s = float(np.prod(np.asarray(s_l) ** np.asarray(WEIGHTS)))
    q = 0.8012 * s**0.3046 + (1 - 0.8012) * n**0.7088
    return q, s, n
