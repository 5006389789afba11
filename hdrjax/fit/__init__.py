"""Fitting operator parameters to target statistics with optimistix (see ``_fit``)."""

from ._fit import (
    FitResult as FitResult,
)
from ._fit import (
    downscale as downscale,
)
from ._fit import (
    fit as fit,
)
from ._fit import (
    fit_batch as fit_batch,
)
from ._fit import (
    fit_sequence as fit_sequence,
)
