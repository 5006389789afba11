"""Image filters for noisy simulation results: mean (box) and median, jit-compiled and
vmapped over channels and batches.

Numeric contract: float images, channels last ``(..., H, W, C)`` (or ``(..., H, W)``
planes with ``channel_axis=None``), any units; outputs keep the shape and units. Edge
handling follows SciPy's modes, replicate (``"nearest"``) by default. Large images run in
row strips, so temporaries stay a few strips in size; results do not depend on the strip
size.

Birukov, Barladian, Denisov, Voloboy, "Implementation of High Dynamic Range Image
Processing Module as a Part of Lighting Simulation Software System", GraphiCon 2022,
section 4.1 (mean and median filters; window size, passes; per-channel, vector or
single-physical-value criterion).
"""

from ._mean import mean_filter as mean_filter
from ._median import CRITERIA as CRITERIA, median_filter as median_filter
from ._strips import MODES as MODES

__all__ = ["CRITERIA", "MODES", "mean_filter", "median_filter"]
