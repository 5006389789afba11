"""Spherical panoramas, cube maps, fisheye and polar (goniometric) images, in JAX.

Conversions to displayable views with bilinear sampling; the axis conventions are in the
module doc of ``hdrjax.panorama._projections`` (Y up, looking along −Z, equirect centre
straight ahead, top row the zenith).
"""

from ._projections import cubemap_directions as cubemap_directions
from ._projections import cubemap_to_equirect as cubemap_to_equirect
from ._projections import direction_to_equirect as direction_to_equirect
from ._projections import equirect_directions as equirect_directions
from ._projections import equirect_to_cubemap as equirect_to_cubemap
from ._projections import equirect_to_fisheye as equirect_to_fisheye
from ._projections import fisheye_directions as fisheye_directions
from ._projections import fisheye_to_equirect as fisheye_to_equirect
from ._projections import polar_to_cartesian as polar_to_cartesian
from ._projections import sample_bilinear as sample_bilinear
from ._projections import sample_equirect as sample_equirect
