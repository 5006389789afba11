"""Tone-mapping operators: equinox Modules, a registry and the ``tonemap`` dispatcher.

Numeric contract: input is linear-light RGB ``(..., H, W, 3)`` (relative, or cd/m² where an
operator says so); output is display-referred linear RGB, nominally [0, 1], before display
encoding (:mod:`hdrjax.display`). Every operator works under ``jit``, ``vmap`` and ``grad``.
"""

from ._base import (
    AbstractLuminanceCurve as AbstractLuminanceCurve,
)
from ._base import (
    AbstractOperator as AbstractOperator,
)
from ._base import (
    get_operator as get_operator,
)
from ._base import (
    make_operator as make_operator,
)
from ._base import (
    operator_names as operator_names,
)
from ._base import (
    parameter_names as parameter_names,
)
from ._base import (
    register as register,
)
from ._base import (
    tonemap as tonemap,
)
from ._classic import (
    Exponential as Exponential,
)
from ._classic import (
    ExponentiationMapping as ExponentiationMapping,
)
from ._classic import (
    Filmic as Filmic,
)
from ._classic import (
    Gamma as Gamma,
)
from ._classic import (
    Logarithmic as Logarithmic,
)
from ._classic import (
    LogarithmicMapping as LogarithmicMapping,
)
from ._classic import (
    Normalisation as Normalisation,
)
from ._classic import (
    Reinhard2004 as Reinhard2004,
)
from ._classic import (
    Schlick1994 as Schlick1994,
)
from ._classic import (
    Simple as Simple,
)
from ._linear import (
    Q_FACTOR as Q_FACTOR,
)
from ._linear import (
    Linear as Linear,
)
from ._linear import (
    ev100_luminance as ev100_luminance,
)
from ._linear import (
    saturation_luminance as saturation_luminance,
)
from ._reinhard2002 import Reinhard2002 as Reinhard2002
from ._reinhard2002_local import (
    Reinhard2002Auto as Reinhard2002Auto,
)
from ._reinhard2002_local import (
    Reinhard2002Local as Reinhard2002Local,
)
from ._tabulated import Tabulated as Tabulated
from ._tumblin import Tumblin1999 as Tumblin1999
from ._tumblin import TumblinReinhard as TumblinReinhard
