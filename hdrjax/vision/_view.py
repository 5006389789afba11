"""Field of view: how many degrees of the visual field a pixel covers.

Acuity and glare are angular phenomena, so every spatial effect needs the image's field of
view. :class:`View` states it (horizontal/vertical field in degrees, or a pixel's angular
size) and :meth:`View.resolve` turns it into per-pixel angles for an image size.

Default (no field given), as Radiance ``pcond`` does for a picture without a view
(NREL/Radiance ``src/px/pcond.c``, ``getahead``): a perspective view 40° across the
*longer* image side (so 40° horizontal for landscape images), the other side derived from
the aspect ratio, ``2 atan(tan(20°) · short/long)``.
"""

import dataclasses
import math
from typing import Literal

DEFAULT_FOV = 40.0
"""pcond's field of view, in degrees, across the longer side of a picture without a view."""

Projection = Literal["perspective", "equiangular"]


@dataclasses.dataclass(frozen=True)
class ResolvedView:
    """A :class:`View` applied to an image of ``height × width`` pixels.

    Attributes:
        height, width: image size in pixels.
        hfov, vfov: horizontal and vertical field of view, degrees.
        projection: ``"perspective"`` (a planar image, angles exact at the centre) or
            ``"equiangular"`` (every pixel covers the same angle, e.g. a lat-long panorama).
        pixel_deg_x, pixel_deg_y: angular width and height of a pixel at the image centre,
            degrees. The spatial effects treat the image as equiangular with these sizes
            (exact at the centre of a perspective view; for a 90° view the corner pixels are
            half as large; on a panorama the horizontal size shrinks with cos(latitude)).
    """

    height: int
    width: int
    hfov: float
    vfov: float
    projection: Projection
    pixel_deg_x: float
    pixel_deg_y: float

    @property
    def samples_per_degree(self) -> float:
        """The image's sampling rate at the centre, ``(1/pixel_deg_x + 1/pixel_deg_y)/2``
        samples per degree (pcond ``check2do``: ``(xres/hfov + yres/vfov)/2``)."""
        return 0.5 * (1.0 / self.pixel_deg_x + 1.0 / self.pixel_deg_y)

    @property
    def fovea_block(self) -> tuple[int, int]:
        """Pixels per foveal sample ``(by, bx)``: about one sample per degree, as pcond's
        foveal image (``FOVDIA`` = 1°), at least 1 and at most the image size."""
        by = min(self.height, max(1, round(1.0 / self.pixel_deg_y)))
        bx = min(self.width, max(1, round(1.0 / self.pixel_deg_x)))
        return by, bx


@dataclasses.dataclass(frozen=True)
class View:
    """Field of view of an image (all angles in degrees).

    Give at most one of ``hfov``/``vfov`` pairs or ``pixel_deg``:

    - ``View()``: pcond's default, 40° across the longer side, perspective.
    - ``View(hfov=60)``: 60° horizontal; ``vfov`` from the aspect ratio (square pixels).
    - ``View(hfov=360, vfov=180, projection="equiangular")``: a lat-long panorama.
    - ``View(pixel_deg=0.02)``: every pixel covers 0.02° (equiangular).

    A float passed where a view is expected means ``View(hfov=that)``.

    Attributes:
        hfov: horizontal field of view, degrees, in (0, 180) for perspective and (0, 360] for
            equiangular views.
        vfov: vertical field of view, degrees (default: from the aspect ratio).
        pixel_deg: angular size of one pixel, degrees (implies ``"equiangular"``).
        projection: ``"perspective"`` (default) or ``"equiangular"``.
    """

    hfov: float | None = None
    vfov: float | None = None
    pixel_deg: float | None = None
    projection: Projection = "perspective"

    def __post_init__(self) -> None:
        if self.projection not in ("perspective", "equiangular"):
            raise ValueError(
                f"projection: expected 'perspective' or 'equiangular', got {self.projection!r}"
            )
        for name in ("hfov", "vfov", "pixel_deg"):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, int | float) and 0 < v < math.inf):
                raise ValueError(f"{name}: expected a finite angle > 0 degrees, got {v!r}")
        if self.pixel_deg is not None and (self.hfov is not None or self.vfov is not None):
            raise ValueError("give either pixel_deg or hfov/vfov, not both")
        persp = self.projection == "perspective"
        for name in ("hfov", "vfov"):
            v = getattr(self, name)
            if v is not None and (v >= 180.0 if persp else v > 360.0):
                raise ValueError(
                    f"{name}={v}: a perspective view must be under 180° (use "
                    "projection='equiangular' for panoramas)"
                    if persp
                    else f"{name}={v}: an equiangular view covers at most 360°"
                )

    def resolve(self, height: int, width: int) -> ResolvedView:
        """Angles for an image of ``height × width`` pixels."""
        H, W = int(height), int(width)
        if H < 1 or W < 1:
            raise ValueError(f"image size must be at least 1×1, got {H}×{W}")
        rad = math.pi / 180.0
        if self.pixel_deg is not None:
            p = float(self.pixel_deg)
            return ResolvedView(H, W, W * p, H * p, "equiangular", p, p)
        if self.projection == "equiangular":
            if self.hfov is None and self.vfov is None:
                raise ValueError("an equiangular view needs hfov, vfov or pixel_deg")
            px = self.hfov / W if self.hfov is not None else self.vfov / H  # type: ignore[operator]
            py = self.vfov / H if self.vfov is not None else px
            hfov = self.hfov if self.hfov is not None else px * W
            vfov = self.vfov if self.vfov is not None else py * H
            return ResolvedView(H, W, float(hfov), float(vfov), "equiangular", px, py)
        hfov, vfov = self.hfov, self.vfov
        if hfov is None and vfov is None:
            if H < W:  # pcond getahead: 40° on the longer side
                hfov = DEFAULT_FOV
            else:
                vfov = DEFAULT_FOV
        if hfov is None:
            hfov = 2.0 / rad * math.atan(math.tan(vfov * rad / 2) * W / H)  # type: ignore[operator]
        if vfov is None:
            vfov = 2.0 / rad * math.atan(math.tan(hfov * rad / 2) * H / W)
        if not (hfov < 180.0 and vfov < 180.0):
            raise ValueError(
                f"perspective view of {hfov:.4g}°×{vfov:.4g}° on {W}×{H} pixels reaches "
                "180°; use projection='equiangular'"
            )
        px = 2.0 * math.tan(hfov * rad / 2) / W / rad
        py = 2.0 * math.tan(vfov * rad / 2) / H / rad
        return ResolvedView(H, W, float(hfov), float(vfov), "perspective", px, py)


def as_view(view: "View | float | int | None") -> View:
    """``View`` from a view, a horizontal field of view in degrees, or ``None`` (default)."""
    if view is None:
        return View()
    if isinstance(view, View):
        return view
    if isinstance(view, int | float) and not isinstance(view, bool):
        # checked here, so that the message names the argument the caller passed
        if not 0 < view < 180:
            raise ValueError(
                "view: expected a horizontal field of view (hfov) in (0, 180) degrees, or a"
                f" View (projection='equiangular' for panoramas), got {view!r}"
            )
        return View(hfov=float(view))
    raise ValueError(f"view: expected a View, a field of view in degrees or None, got {view!r}")


def resolve_view(
    view: "View | ResolvedView | float | None", height: int, width: int
) -> ResolvedView:
    """A :class:`ResolvedView` for an image of ``height × width`` from any view form."""
    if isinstance(view, ResolvedView):
        if (view.height, view.width) != (int(height), int(width)):
            raise ValueError(
                f"view is resolved for {view.height}×{view.width} pixels, the image is "
                f"{height}×{width}"
            )
        return view
    return as_view(view).resolve(height, width)


__all__ = ["DEFAULT_FOV", "ResolvedView", "View", "as_view", "resolve_view"]
