"""Measurement on layered images: pixel distances (3D from positions, 2D on a sensor),
readouts at a pixel, and regions exported as JSON with their statistics.

NumPy side, never jitted. See :func:`distance`, :func:`readout`, :class:`Region`.
"""

from ._measure import (
    Distance as Distance,
    Region as Region,
    distance as distance,
    load_region as load_region,
    readout as readout,
    region_json as region_json,
    region_stats as region_stats,
    save_region as save_region,
)
