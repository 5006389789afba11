"""Layered images: a main image plus named layers, as a lighting simulation writes them.

See :class:`LayeredImage`. Reading and writing files is in :mod:`hdrjax.io`.
"""

from ._errors import (
    LayerShapeError as LayerShapeError,
    MissingLayerError as MissingLayerError,
    ReadError as ReadError,
)
from ._model import (
    ALPHA as ALPHA,
    DEPTH as DEPTH,
    ERROR as ERROR,
    GRID as GRID,
    GRID_LAYERS as GRID_LAYERS,
    HITS as HITS,
    KNOWN_LAYERS as KNOWN_LAYERS,
    NON_GRID_LAYERS as NON_GRID_LAYERS,
    OBJECT_ID as OBJECT_ID,
    OBJECTS as OBJECTS,
    POSITION as POSITION,
    QUANTITIES as QUANTITIES,
    VIEW as VIEW,
    WAVELENGTHS as WAVELENGTHS,
    LayeredImage as LayeredImage,
    normalise_unit as normalise_unit,
)
