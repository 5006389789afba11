"""Display: encoding for screens and files (and, from issue 4, false colour and desaturation)."""

from ._desaturate import PERCENT_ABOVE as PERCENT_ABOVE
from ._desaturate import THRESHOLD_FACTOR as THRESHOLD_FACTOR
from ._desaturate import DesaturateHighlights as DesaturateHighlights
from ._desaturate import desaturate_highlights as desaturate_highlights
from ._desaturate import highlight_threshold as highlight_threshold
from ._encode import (
    encode as encode,
)
from ._encode import (
    gamma_encode as gamma_encode,
)
from ._encode import (
    quantize as quantize,
)
from ._encode import (
    srgb_decode as srgb_decode,
)
from ._encode import (
    srgb_encode as srgb_encode,
)
from ._false_color import FalseColor as FalseColor
from ._false_color import FalseColorScale as FalseColorScale
from ._false_color import false_color as false_color
from ._false_color import false_color_scale as false_color_scale
from ._false_color import render_figure as render_figure
