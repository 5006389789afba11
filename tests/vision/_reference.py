"""Reference formulas written out in float64 Python for the vision and Budak 2005 tests."""

import math

import numpy as np


def np_tvi(La):
    """pcond's combined rod/cone threshold ``htcontrs`` (pcond3.c; Ferwerda et al. 1996),
    cd/m², of a luminance or an array of them."""

    def one(L):
        if L < 1.148e-4:
            return 1.38e-3
        x = math.log10(L)
        if x < -1.44:
            y = (0.405 * x + 1.6) ** 2.18 - 2.86
        elif x < -0.0184:
            y = x - 0.395
        elif x < 1.9:
            y = (0.249 * x + 0.65) ** 2.7 - 0.72
        else:
            y = x - 1.255
        return 10.0**y

    if np.ndim(La) == 0:
        return one(float(La))
    return np.array([one(float(L)) for L in np.ravel(La)]).reshape(np.shape(La))
