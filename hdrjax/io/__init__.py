"""Reading and writing HDR files (OpenEXR, Radiance RGBE, PFM) and display exports.

NumPy side, never jitted. :func:`read` returns a :class:`~hdrjax.layers.LayeredImage`;
:func:`write` stores one (or a plain array); :func:`write_display` exports tone-mapped,
display-encoded images to PNG (8/16 bit), JPEG and TIFF. All writes are atomic. Problems
with a file's content raise :class:`ReadError` (a ``ValueError``) whose one-line message
names the file.
"""

from ..layers._errors import (
    LayerShapeError as LayerShapeError,
    MissingLayerError as MissingLayerError,
    ReadError as ReadError,
)
from ._api import (
    READ_FORMATS as READ_FORMATS,
    find_sidecars as find_sidecars,
    read as read,
    write as write,
)
from ._atomic import atomic_path as atomic_path
from ._display import (
    DEFAULT_COMPRESSION as DEFAULT_COMPRESSION,
    DISPLAY_FORMATS as DISPLAY_FORMATS,
    write_display as write_display,
)
