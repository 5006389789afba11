"""Target statistics of tone-mapped images for :func:`hdrjax.fit.fit` (see ``_targets``), and
perceptual targets that maximise a quality metric (see ``_perceptual``)."""

from ._perceptual import PUSSIM as PUSSIM, TMQI as TMQI, Naturalness as Naturalness
from ._targets import (
    AbstractStatisticTarget as AbstractStatisticTarget,
    AbstractTarget as AbstractTarget,
    ClippedFraction as ClippedFraction,
    Combined as Combined,
    Histogram as Histogram,
    MeanLuminance as MeanLuminance,
    Percentiles as Percentiles,
    Reference as Reference,
    Scaled as Scaled,
)
