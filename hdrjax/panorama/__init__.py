"""Spherical panoramas, cube maps, fisheye and polar (goniometric) images, in JAX.

Conversions to displayable views with bilinear sampling, and pinhole (perspective) views
of a panorama; the axis conventions are in the
module doc of ``hdrjax.panorama._projections`` (Y up, looking along −Z, equirect centre
straight ahead, top row the zenith).
"""

from ._perspective import (
    camera_basis as camera_basis,
    equirect_to_perspective as equirect_to_perspective,
    perspective_directions as perspective_directions,
)
from ._projections import (
    cubemap_directions as cubemap_directions,
    cubemap_to_equirect as cubemap_to_equirect,
    direction_to_equirect as direction_to_equirect,
    equirect_directions as equirect_directions,
    equirect_to_cubemap as equirect_to_cubemap,
    equirect_to_fisheye as equirect_to_fisheye,
    fisheye_directions as fisheye_directions,
    fisheye_to_equirect as fisheye_to_equirect,
    polar_to_cartesian as polar_to_cartesian,
    sample_bilinear as sample_bilinear,
    sample_equirect as sample_equirect,
)
