"""Target statistics of tone-mapped images for :func:`hdrjax.fit.fit` (see ``_targets``)."""

from ._targets import (
    AbstractStatisticTarget as AbstractStatisticTarget,
)
from ._targets import (
    AbstractTarget as AbstractTarget,
)
from ._targets import (
    ClippedFraction as ClippedFraction,
)
from ._targets import (
    Combined as Combined,
)
from ._targets import (
    Histogram as Histogram,
)
from ._targets import (
    MeanLuminance as MeanLuminance,
)
from ._targets import (
    Percentiles as Percentiles,
)
from ._targets import (
    Reference as Reference,
)
from ._targets import (
    Scaled as Scaled,
)
