"""Light sources in environment maps and images (issue 6).

- :func:`detect` — Loghin 2019 (seed 001) detection on an equirectangular map, vectorised
  and compiled; :func:`detect_image` on a plain image; :func:`detect_cubemap` on a cube map.
- :func:`median_cut` — Debevec 2005 median-cut light extraction, for comparison.
- :func:`plot_lights` — the seed's figures (local maxima, light positions, joined samples).
- Directions: hdrjax's convention is :mod:`hdrjax.panorama`'s (Y-up, looking along −Z,
  +X right; azimuth/elevation as in ``SOURCES.md``); :func:`convert_direction` gives
  Blender, pbrt, Mitsuba and OpenEXR directions, :func:`to_z_up` / :func:`to_y_up` swap
  the up axis.
"""

from ._cubemap import cubemap_equirect as cubemap_equirect
from ._cubemap import detect_cubemap as detect_cubemap
from ._debevec2005 import median_cut as median_cut
from ._geometry import CONVENTIONS as CONVENTIONS
from ._geometry import angle_between as angle_between
from ._geometry import azel_to_direction as azel_to_direction
from ._geometry import azimuth_elevation as azimuth_elevation
from ._geometry import convert_direction as convert_direction
from ._geometry import direction_to_uv as direction_to_uv
from ._geometry import to_y_up as to_y_up
from ._geometry import to_z_up as to_z_up
from ._geometry import uv_to_direction as uv_to_direction
from ._loghin2019 import DEFAULT_BLUR as DEFAULT_BLUR
from ._loghin2019 import DEFAULT_MAX_LIGHTS as DEFAULT_MAX_LIGHTS
from ._loghin2019 import DEFAULT_MAX_RADIUS as DEFAULT_MAX_RADIUS
from ._loghin2019 import DEFAULT_SAMPLES_PER_PIXEL as DEFAULT_SAMPLES_PER_PIXEL
from ._loghin2019 import DEFAULT_WIDTH as DEFAULT_WIDTH
from ._loghin2019 import detect as detect
from ._loghin2019 import detect_image as detect_image
from ._overlay import display_image as display_image
from ._overlay import plot_lights as plot_lights
from ._result import Lights as Lights
from ._result import MedianCutLights as MedianCutLights
from ._sequences import halton as halton
from ._sequences import hammersley as hammersley
from ._sequences import van_der_corput as van_der_corput
