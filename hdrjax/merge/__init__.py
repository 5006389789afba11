"""HDR images from photographs: exposure brackets merged into linear radiance.

Recover a camera's inverse response (Debevec & Malik 1997; Robertson, Borman & Stevenson
2003; Mitsunaga & Nayar 1999), merge a bracket into radiance with the usual weighting
functions, align hand-held brackets (Ward 2003 median threshold bitmaps), fuse exposures
straight to a display image (Mertens, Kautz & Van Reeth 2007), and calibrate the result to
cd/m² from the exposure settings (ISO 12232; Lagarde & de Rousiers 2014).

Numeric contract: brackets are integer code values ``(N, H, W, 3)`` (uint8 or uint16, or
files: PNG, TIFF, JPEG, camera RAW), exposure times in seconds; responses are
``(levels, 3)`` natural-log sensor exposure per code value; merged radiance is linear RGB
``(H, W, 3)`` float32 (relative, or cd/m² once calibrated); fused images are display values
in [0, 1].
"""

from ._align import align_mtb as align_mtb, apply_shifts as apply_shifts
from ._bracket import Codes as Codes, as_codes as as_codes
from ._calibrate import (
    absolute_scale as absolute_scale,
    calibrate as calibrate,
    calibrate_illuminance as calibrate_illuminance,
)
from ._fuse import fuse as fuse
from ._ghost import ghost_mask as ghost_mask
from ._merge import merge as merge
from ._read import (
    RAW_EXTENSIONS as RAW_EXTENSIONS,
    BracketFiles as BracketFiles,
    read_bracket as read_bracket,
)
from ._response import (
    load_response as load_response,
    recover_response as recover_response,
    save_response as save_response,
)
from ._simulate import (
    CURVES as CURVES,
    Bracket as Bracket,
    camera_curve as camera_curve,
    simulate_bracket as simulate_bracket,
    true_response as true_response,
)
from ._weights import WEIGHTS as WEIGHTS, weight_function as weight_function
