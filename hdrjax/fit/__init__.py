"""Fitting operator parameters to target statistics with optimistix (see ``_fit``).

The module is itself callable: ``hdrjax.fit(operator, image, target, params=...)`` is
``hdrjax.fit.fit(...)``; batches and sequences are ``hdrjax.fit.fit_batch`` and
``hdrjax.fit.fit_sequence``.
"""

import sys
import types

from ._fit import (
    FitResult as FitResult,
    downscale as downscale,
    fit as fit,
    fit_batch as fit_batch,
    fit_sequence as fit_sequence,
)


class _CallableModule(types.ModuleType):
    def __call__(self, *args, **kwargs) -> FitResult:
        return fit(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
