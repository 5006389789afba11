"""Light sources in environment maps and images (issue 6).

- :func:`detect` — Loghin 2019 detection on an equirectangular map, vectorised
  and compiled; :func:`detect_image` on a plain image; :func:`detect_cubemap` on a cube map.
- :func:`median_cut` — Debevec 2005 median-cut light extraction, for comparison.
- :func:`plot_lights` — Loghin 2019's figures (local maxima, light positions, joined samples).
- Directions: hdrjax's convention is :mod:`hdrjax.panorama`'s (Y-up, looking along −Z,
  +X right; azimuth 0° at the image centre, positive to the right, elevation +90° at the
  top row); :func:`convert_direction` gives
  Blender, pbrt, Mitsuba and OpenEXR directions, :func:`to_z_up` / :func:`to_y_up` swap
  the up axis.
"""

from ._cubemap import cubemap_equirect as cubemap_equirect, detect_cubemap as detect_cubemap
from ._debevec2005 import median_cut as median_cut
from ._geometry import (
    CONVENTIONS as CONVENTIONS,
    angle_between as angle_between,
    azel_to_direction as azel_to_direction,
    azimuth_elevation as azimuth_elevation,
    convert_direction as convert_direction,
    direction_to_uv as direction_to_uv,
    to_y_up as to_y_up,
    to_z_up as to_z_up,
    uv_to_direction as uv_to_direction,
)
from ._loghin2019 import (
    DEFAULT_BLUR as DEFAULT_BLUR,
    DEFAULT_MAX_LIGHTS as DEFAULT_MAX_LIGHTS,
    DEFAULT_MAX_RADIUS as DEFAULT_MAX_RADIUS,
    DEFAULT_SAMPLES_PER_PIXEL as DEFAULT_SAMPLES_PER_PIXEL,
    DEFAULT_WIDTH as DEFAULT_WIDTH,
    detect as detect,
    detect_image as detect_image,
)
from ._overlay import display_image as display_image, plot_lights as plot_lights
from ._result import Lights as Lights, MedianCutLights as MedianCutLights
from ._sequences import halton as halton, hammersley as hammersley, van_der_corput as van_der_corput
