"""Display: encoding for screens and files (SDR and HDR displays, gamut mapping, the BT.2390
EETF), false colour and highlight desaturation."""

from ._desaturate import (
    PERCENT_ABOVE as PERCENT_ABOVE,
    THRESHOLD_FACTOR as THRESHOLD_FACTOR,
    DesaturateHighlights as DesaturateHighlights,
    desaturate_highlights as desaturate_highlights,
    highlight_threshold as highlight_threshold,
)
from ._displays import (
    DEFAULT_DISPLAY as DEFAULT_DISPLAY,
    DEFAULT_PEAK as DEFAULT_PEAK,
    DISPLAYS as DISPLAYS,
    Display as Display,
    get_display as get_display,
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
from ._gamut import (
    DEFAULT_GAMUT as DEFAULT_GAMUT,
    GAMUT_METHODS as GAMUT_METHODS,
    gamut_map as gamut_map,
)
from ._hdr import (
    HLG_REFERENCE_WHITE as HLG_REFERENCE_WHITE,
    REFERENCE_WHITE as REFERENCE_WHITE,
    bt2390_eetf as bt2390_eetf,
)
