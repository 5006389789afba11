"""Layered images: a main image plus named layers, as a lighting simulation writes them.

See :class:`LayeredImage`. Reading and writing files is in :mod:`hdrjax.io`.
"""

from ._errors import LayerShapeError as LayerShapeError
from ._errors import MissingLayerError as MissingLayerError
from ._errors import ReadError as ReadError
from ._model import ALPHA as ALPHA
from ._model import DEPTH as DEPTH
from ._model import ERROR as ERROR
from ._model import GRID as GRID
from ._model import GRID_LAYERS as GRID_LAYERS
from ._model import HITS as HITS
from ._model import KNOWN_LAYERS as KNOWN_LAYERS
from ._model import NON_GRID_LAYERS as NON_GRID_LAYERS
from ._model import OBJECT_ID as OBJECT_ID
from ._model import OBJECTS as OBJECTS
from ._model import POSITION as POSITION
from ._model import QUANTITIES as QUANTITIES
from ._model import VIEW as VIEW
from ._model import WAVELENGTHS as WAVELENGTHS
from ._model import LayeredImage as LayeredImage
from ._model import normalise_unit as normalise_unit
