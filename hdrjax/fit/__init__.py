"""Fitting operator parameters to target statistics with optimistix (see ``_fit``)."""

from ._fit import (
    FitResult as FitResult,
    downscale as downscale,
    fit as fit,
    fit_batch as fit_batch,
    fit_sequence as fit_sequence,
)
