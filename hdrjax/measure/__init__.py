"""Measurement on layered images: pixel distances (3D from positions, 2D on a sensor),
readouts at a pixel, and regions exported as JSON with their statistics.

NumPy side, never jitted. See :func:`distance`, :func:`readout`, :class:`Region`.
"""

from ._measure import Distance as Distance
from ._measure import Region as Region
from ._measure import distance as distance
from ._measure import load_region as load_region
from ._measure import readout as readout
from ._measure import region_json as region_json
from ._measure import region_stats as region_stats
from ._measure import save_region as save_region
