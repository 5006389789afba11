"""Display: encoding for screens and files (and, from issue 4, false colour and desaturation)."""

from ._encode import (
    encode as encode,
    gamma_encode as gamma_encode,
    quantize as quantize,
    srgb_decode as srgb_decode,
    srgb_encode as srgb_encode,
)
