"""Display: encoding for screens and files (and, from issue 4, false colour and desaturation)."""

from ._desaturate import (
    PERCENT_ABOVE as PERCENT_ABOVE,
    THRESHOLD_FACTOR as THRESHOLD_FACTOR,
    DesaturateHighlights as DesaturateHighlights,
    desaturate_highlights as desaturate_highlights,
    highlight_threshold as highlight_threshold,
)
from ._encode import (
    encode as encode,
    gamma_encode as gamma_encode,
    quantize as quantize,
    srgb_decode as srgb_decode,
    srgb_encode as srgb_encode,
)
from ._false_color import (
    FalseColor as FalseColor,
    FalseColorScale as FalseColorScale,
    false_color as false_color,
    false_color_scale as false_color_scale,
    render_figure as render_figure,
)
