"""hdrjax: JIT-compiled, differentiable HDR tone mapping and analysis in JAX.

Numeric contract: images are linear-light RGB, channels last ``(..., H, W, 3)``, relative or
absolute (cd/m²); operators return display-referred linear RGB, nominally [0, 1], which
:func:`hdrjax.display.encode` turns into sRGB. float32 by default, float64 with x64 enabled.
"""

from . import (
    _stats as stats,
)
from . import (
    display as display,
)
from . import (
    filters as filters,
)
from . import (
    fit as fit,
)
from . import (
    io as io,
)
from . import (
    layers as layers,
)
from . import (
    lights as lights,
)
from . import (
    measure as measure,
)
from . import (
    operators as operators,
)
from . import (
    panorama as panorama,
)
from . import (
    targets as targets,
)
from . import (
    vision as vision,
)
from ._colour import (
    REC709_CHROMATICITIES as REC709_CHROMATICITIES,
)
from ._colour import (
    REC709_WEIGHTS as REC709_WEIGHTS,
)
from ._colour import (
    luminance as luminance,
)
from ._colour import (
    luminance_weights as luminance_weights,
)
from .display import (
    desaturate_highlights as desaturate_highlights,
)
from .display import (
    false_color as false_color,
)
from .filters import (
    mean_filter as mean_filter,
)
from .filters import (
    median_filter as median_filter,
)
from .operators import (
    get_operator as get_operator,
)
from .operators import (
    make_operator as make_operator,
)
from .operators import (
    operator_names as operator_names,
)
from .operators import (
    tonemap as tonemap,
)

__version__ = "0.1.0"
