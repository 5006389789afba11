"""The layered-image model: a main image plus named layers, as a lighting simulation writes.

NumPy side, never jitted. A :class:`LayeredImage` holds

- the main image, ``(H, W, C)`` float32: RGB (``C = 3``), a single-channel quantity
  (``C = 1``, channel ``Y``), luminance/chroma (``Y, RY, BY``, chroma upsampled to full
  resolution) or a spectral image (``C = n_wavelengths``, the wavelengths in nm in the
  non-grid layer ``wavelengths``);
- its physical quantity and unit (luminance in cd/m², illuminance in lx, radiance in
  W/(sr·m²), or ``"relative"`` with no unit);
- its colour primaries (OpenEXR ``chromaticities`` order, ``None`` = Rec.709/D65);
- a dict of named layers. Grid layers have the image's height and width (``(H, W)`` or
  ``(H, W, k)``); non-grid layers (wavelengths, per-object tables, a camera description)
  have any shape, or are a JSON-like dict.

Known layer names are module constants (:data:`POSITION`, :data:`ERROR`, ...); free names
are allowed. Asking for a layer that is not there raises :class:`MissingLayerError` naming
the layer and the file; a missing layer is never replaced by zeros.
"""

import dataclasses
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from jaxtyping import Float

from .. import spaces as _spaces
from ._errors import LayerShapeError, MissingLayerError, ReadError

# Layer names fixed for the known kinds of data (Birukov et al. 2022, section 3).
ERROR = "error"
"""Per-pixel estimate of the calculation error (grid, ``(H, W)``, same unit as the image
unless the file says it is relative)."""
HITS = "hits"
"""Number of rays that hit each pixel (grid, ``(H, W)``, uint32 or float32)."""
POSITION = "position"
"""3D scene coordinates behind each pixel (grid, ``(H, W, 3)``: X, Y, Z, scene units)."""
OBJECT_ID = "object_id"
"""Index of the scene object behind each pixel (grid, ``(H, W)``, uint32)."""
GRID = "grid"
"""Grid image drawn over the result (grid, ``(H, W)`` or ``(H, W, 3)``)."""
WAVELENGTHS = "wavelengths"
"""Wavelengths of a spectral image's channels (non-grid, ``(n,)``, nm)."""
ALPHA = "alpha"
"""Coverage (grid, ``(H, W)``); EXR channel ``A``."""
DEPTH = "depth"
"""Distance along the view axis (grid, ``(H, W)``); EXR channel ``Z``."""
VIEW = "view"
"""Camera / virtual sensor description (non-grid, a dict)."""
OBJECTS = "objects"
"""Per-object table (non-grid, e.g. ``(n_objects, k)``)."""

KNOWN_LAYERS: tuple[str, ...] = (
    ERROR,
    HITS,
    POSITION,
    OBJECT_ID,
    GRID,
    WAVELENGTHS,
    ALPHA,
    DEPTH,
    VIEW,
    OBJECTS,
)
"""Layer names with a fixed meaning; any other name is a free layer."""

GRID_LAYERS: frozenset[str] = frozenset({ERROR, HITS, POSITION, OBJECT_ID, GRID, ALPHA, DEPTH})
"""Known layers that must have the image's height and width."""
NON_GRID_LAYERS: frozenset[str] = frozenset({WAVELENGTHS, VIEW, OBJECTS})
"""Known layers that are not on the pixel grid."""

QUANTITIES: dict[str, str | None] = {
    "luminance": "cd/m²",
    "illuminance": "lx",
    "radiance": "W/(sr·m²)",
    "irradiance": "W/m²",
    "relative": None,
}
"""Physical quantities and their SI units; ``relative`` means unscaled (no unit)."""

_UNIT_ALIASES = {
    "cd/m2": "cd/m²",
    "cd/m^2": "cd/m²",
    "nit": "cd/m²",
    "nits": "cd/m²",
    "lux": "lx",
    "w/(sr m2)": "W/(sr·m²)",
    "w/(sr*m^2)": "W/(sr·m²)",
    "w/(sr·m^2)": "W/(sr·m²)",
    "w.m^-2.sr^-1": "W/(sr·m²)",
    "w/m2": "W/m²",
    "w/m^2": "W/m²",
}


def normalise_unit(unit: str | None) -> str | None:
    """Canonical spelling of a unit string (``"cd/m2"`` → ``"cd/m²"``); unknown units pass."""
    if unit is None:
        return None
    u = unit.strip()
    return _UNIT_ALIASES.get(u.lower(), u) if u else None


def _default_channels(c: int) -> tuple[str, ...]:
    if c == 1:
        return ("Y",)
    if c == 3:
        return ("R", "G", "B")
    return tuple(f"c{i}" for i in range(c))


def _label(path: Path | str | None) -> str:
    return Path(path).name if path is not None else "image"


@dataclasses.dataclass(eq=False)
class LayeredImage:
    """A main image with its quantity, primaries and named layers (see the module doc).

    Attributes:
        image: ``(H, W, C)`` float32 main image (C-contiguous).
        channels: names of the image channels: ``("R", "G", "B")``, ``("Y",)``,
            ``("Y", "RY", "BY")`` or one name per wavelength for spectral images.
        quantity: ``"luminance"`` (cd/m²), ``"illuminance"`` (lx), ``"radiance"``
            (W/(sr·m²)), ``"irradiance"`` (W/m²) or ``"relative"``.
        unit: the unit of the pixel values, ``None`` for relative images.
        chromaticities: ``(x_r, y_r, x_g, y_g, x_b, y_b, x_w, y_w)`` or ``None`` for
            Rec.709/sRGB primaries with a D65 white.
        layers: named layers: grid layers as ``(H, W)`` / ``(H, W, k)`` arrays, non-grid
            layers as arrays of any shape or JSON-like dicts.
        layer_channels: for multi-channel layers, the channel names (``("X", "Y", "Z")``).
        attributes: other file metadata (EXR header attributes, Radiance header lines).
        path: the file the image was read from, if any.
        white_luminance: cd/m² of RGB (1, 1, 1) for relative images that declare it (EXR
            ``whiteLuminance``); :meth:`to_absolute` applies it.
        data_window: ``(x_min, y_min, x_max, y_max)`` of the pixels, inclusive (EXR).
        display_window: ``(x_min, y_min, x_max, y_max)`` of the frame, inclusive (EXR).
        pixel_types: storage type per item read from an EXR (``"image"`` or a layer name
            → ``"half"``, ``"float"`` or ``"uint"``); the writer keeps them by default.
        sensor_size: physical ``(width, height)`` of a virtual sensor, in metres, when
            known; used by 2D distance measurement.
        projection: how the pixels map to directions: ``None`` (a flat image),
            ``"equirectangular"``, ``"polar"``, ``"fisheye"`` or ``"cubemap"``.
        siblings: other quantity files of the same simulation, quantity → path.
    """

    image: np.ndarray
    channels: tuple[str, ...] = ()
    quantity: str = "relative"
    unit: str | None = None
    chromaticities: tuple[float, ...] | None = None
    layers: dict[str, Any] = dataclasses.field(default_factory=dict)
    layer_channels: dict[str, tuple[str, ...]] = dataclasses.field(default_factory=dict)
    attributes: dict[str, Any] = dataclasses.field(default_factory=dict)
    path: Path | None = None
    white_luminance: float | None = None
    data_window: tuple[int, int, int, int] | None = None
    display_window: tuple[int, int, int, int] | None = None
    pixel_types: dict[str, str] = dataclasses.field(default_factory=dict)
    sensor_size: tuple[float, float] | None = None
    projection: str | None = None
    siblings: dict[str, Path] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        name = _label(self.path)
        img = np.asarray(self.image)
        if img.ndim == 2:
            img = img[:, :, None]
        if img.ndim != 3 or img.shape[2] < 1:
            raise ReadError(f"{name}: expected an (H, W, C) image, got shape {img.shape}")
        if not np.issubdtype(img.dtype, np.number) or np.issubdtype(img.dtype, np.complexfloating):
            raise ReadError(f"{name}: expected a real-valued image, got dtype {img.dtype}")
        self.image = np.ascontiguousarray(img, dtype=np.float32)
        if not self.channels:
            self.channels = _default_channels(self.image.shape[2])
        self.channels = tuple(self.channels)
        if len(self.channels) != self.image.shape[2]:
            raise LayerShapeError(
                f"{name}: {len(self.channels)} channel names for an image with "
                f"{self.image.shape[2]} channels"
            )
        if self.path is not None:
            self.path = Path(self.path)
        if self.quantity not in QUANTITIES:
            raise ReadError(
                f"{name}: unknown quantity {self.quantity!r}; expected one of "
                + ", ".join(QUANTITIES)
            )
        self.unit = (
            normalise_unit(self.unit) if self.unit is not None else QUANTITIES[self.quantity]
        )
        if self.chromaticities is not None:
            c = tuple(float(v) for v in np.asarray(self.chromaticities, dtype=np.float64).ravel())
            if len(c) != 8 or not all(math.isfinite(v) for v in c):
                raise ReadError(f"{name}: chromaticities must be 8 finite numbers, got {c}")
            self.chromaticities = c
        if self.sensor_size is not None:
            w, h = (float(v) for v in self.sensor_size)
            if not (w > 0 and h > 0 and math.isfinite(w) and math.isfinite(h)):
                raise ReadError(f"{name}: sensor_size must be two positive sizes, got {w, h}")
            self.sensor_size = (w, h)
        self.layers = dict(self.layers)
        for key, value in list(self.layers.items()):
            self.layers[key] = self._check_layer(key, value)
        if self.wavelengths is not None and self.wavelengths.shape != (self.image.shape[2],):
            raise LayerShapeError(
                f"{name}: 'wavelengths' layer has {self.wavelengths.shape[0]} entries "
                f"for an image with {self.image.shape[2]} channels"
            )

    # -- shape and layers ---------------------------------------------------------------

    @property
    def height(self) -> int:
        """Image height in pixels."""
        return int(self.image.shape[0])

    @property
    def width(self) -> int:
        """Image width in pixels."""
        return int(self.image.shape[1])

    @property
    def name(self) -> str:
        """The file name for messages (``"image"`` when not read from a file)."""
        return _label(self.path)

    def _check_layer(self, key: str, value: Any) -> Any:
        if not isinstance(key, str) or not key:
            raise ReadError(f"{self.name}: layer names must be non-empty strings, got {key!r}")
        if isinstance(value, Mapping):
            if key in GRID_LAYERS:
                raise LayerShapeError(
                    f"{self.name}: layer {key!r} must be an (H, W) array, got a dict"
                )
            return dict(value)
        arr = np.asarray(value)
        if arr.dtype == object or not (
            np.issubdtype(arr.dtype, np.number) or arr.dtype == np.bool_
        ):
            raise ReadError(f"{self.name}: layer {key!r} has unsupported dtype {arr.dtype}")
        hw = self.image.shape[:2]
        if key in GRID_LAYERS:
            want = {POSITION: 3}.get(key)
            ok = arr.ndim in (2, 3) and arr.shape[:2] == hw
            if ok and want is not None:
                ok = arr.ndim == 3 and arr.shape[2] == want
            if ok and key in (ERROR, HITS, OBJECT_ID, ALPHA, DEPTH):
                ok = arr.ndim == 2 or arr.shape[2] == 1
                arr = arr.reshape(hw) if ok else arr
            if not ok:
                shape = "(H, W, 3)" if key == POSITION else "(H, W)"
                raise LayerShapeError(
                    f"{self.name}: layer {key!r} has shape {arr.shape}, expected {shape} "
                    f"with (H, W) = {hw}"
                )
        elif key == WAVELENGTHS:
            if arr.ndim != 1 or not np.issubdtype(arr.dtype, np.number):
                raise LayerShapeError(
                    f"{self.name}: layer 'wavelengths' must be a 1-D array of nm, "
                    f"got shape {arr.shape}"
                )
        if key == OBJECT_ID and not np.issubdtype(arr.dtype, np.integer):
            if not np.all(np.isfinite(arr)) or np.any(arr < 0) or np.any(arr != np.round(arr)):
                raise ReadError(f"{self.name}: layer 'object_id' must hold integers >= 0")
            arr = arr.astype(np.uint32)
        return np.ascontiguousarray(arr)

    def is_grid_layer(self, key: str) -> bool:
        """Whether layer ``key`` lies on the pixel grid (shape ``(H, W, ...)``)."""
        value = self.layer(key)
        if key in GRID_LAYERS:
            return True
        if key in NON_GRID_LAYERS or isinstance(value, dict):
            return False
        return value.ndim in (2, 3) and value.shape[:2] == self.image.shape[:2]

    def layer(self, key: str) -> Any:
        """The layer ``key``.

        Raises:
            MissingLayerError: the layer is not present; the message names the file and
                lists the layers that are.
        """
        try:
            return self.layers[key]
        except KeyError:
            present = ", ".join(sorted(self.layers)) or "none"
            raise MissingLayerError(
                f"{self.name} has no {key!r} layer; layers present: {present}"
            ) from None

    def has_layer(self, key: str) -> bool:
        """Whether layer ``key`` is present."""
        return key in self.layers

    def with_layer(
        self, key: str, value: Any, channels: Sequence[str] | None = None
    ) -> "LayeredImage":
        """A copy with layer ``key`` set (shape checked as at construction)."""
        layers = dict(self.layers)
        layers[key] = value
        lc = dict(self.layer_channels)
        if channels is not None:
            lc[key] = tuple(channels)
        else:
            lc.pop(key, None)
        return dataclasses.replace(self, layers=layers, layer_channels=lc)

    def select(self, key: str) -> "LayeredImage":
        """A copy whose main image is grid layer ``key`` (the old image is dropped).

        Channel names come from :attr:`layer_channels` (``("X", "Y", "Z")`` for
        positions); the quantity becomes ``"relative"``. Other layers are kept.

        Raises:
            MissingLayerError: no such layer.
            ValueError: the layer is not on the pixel grid.
        """
        value = self.layer(key)
        if not self.is_grid_layer(key):
            raise ValueError(f"{self.name}: layer {key!r} is not on the pixel grid")
        arr = np.asarray(value, dtype=np.float32)
        if arr.ndim == 2:
            arr = arr[:, :, None]
        names = self.layer_channels.get(key)
        if key == POSITION:
            names = ("X", "Y", "Z")
        if names is None or len(names) != arr.shape[2]:
            names = (key,) if arr.shape[2] == 1 else _default_channels(arr.shape[2])
        layers = {k: v for k, v in self.layers.items() if k != key}
        lc = {k: v for k, v in self.layer_channels.items() if k != key}
        pt = dict(self.pixel_types)
        if key in pt:
            pt["image"] = pt.pop(key)
        return dataclasses.replace(
            self,
            image=arr,
            channels=tuple(names),
            quantity="relative",
            unit=None,
            layers=layers,
            layer_channels=lc,
            pixel_types=pt,
            white_luminance=None,
        )

    def replace(self, **changes: Any) -> "LayeredImage":
        """A copy with the given fields changed (``dataclasses.replace``)."""
        return dataclasses.replace(self, **changes)

    @property
    def wavelengths(self) -> np.ndarray | None:
        """Wavelengths in nm of a spectral image's channels, or ``None``."""
        w = self.layers.get(WAVELENGTHS)
        return None if w is None else np.asarray(w)

    # -- colour -------------------------------------------------------------------------

    @property
    def luminance_weights(self) -> tuple[float, float, float]:
        """Luminance weights of :meth:`native_rgb` (the Y row of its RGB→XYZ matrix:
        ``hdrjax.luminance_weights`` of the file's primaries; (0, 1, 0) for XYZ)."""
        return self.space.weights

    @property
    def kind(self) -> str:
        """``"rgb"``, ``"y"`` (single channel), ``"ych"`` (Y, RY, BY), ``"spectral"`` or
        ``"other"``: how the main image channels are to be interpreted."""
        ch = self.channels
        if ch == ("R", "G", "B"):
            return "rgb"
        if len(ch) == 1:
            return "y"
        if ch == ("Y", "RY", "BY"):
            return "ych"
        if self.wavelengths is not None and len(self.wavelengths) == len(ch):
            return "spectral"
        return "other"

    @property
    def space(self) -> "_spaces.Space":
        """The linear RGB space of :meth:`native_rgb` (the file's primaries and white):
        :attr:`chromaticities`, or sRGB/BT.709 with D65 when the file declares none; CIE
        XYZ for a spectral image."""
        if self.kind == "spectral":
            return _spaces.space(_spaces.XYZ_SPACE)
        return _spaces.space(self.chromaticities)

    def native_rgb(self) -> Float[np.ndarray, "H W 3"]:
        """Linear RGB in the file's own primaries (:attr:`space`), ``(H, W, 3)`` float32,
        same unit as the image: no conversion.

        A spectral image is integrated to CIE XYZ (:func:`hdrjax.spectral.spectral_to_xyz`,
        CIE 1931 2° observer): emissive channels (``S0.<λ>nm``, radiance per nm) give Y in
        cd/m² (683 lm/W); reflective ones (``T.<λ>nm``) give XYZ under D65 with a white
        reflector at Y = 1. A single-channel image is replicated to grey. A
        luminance/chroma image is rebuilt as OpenEXR does: ``R = (RY + 1) Y``,
        ``B = (BY + 1) Y`` and ``G = (Y - w_r R - w_b B) / w_g`` with the image's luminance
        weights.

        Raises:
            ValueError: the image has no RGB interpretation (channels that are not R, G,
                B / Y / Y, RY, BY / wavelengths), or a spectral sampling that cannot be
                integrated.
        """
        kind = self.kind
        img = self.image
        if kind == "rgb":
            return img
        if kind == "y":
            return np.ascontiguousarray(np.repeat(img, 3, axis=2))
        if kind == "ych":
            wr, wg, wb = self.luminance_weights
            y = img[:, :, 0]
            r = (img[:, :, 1] + 1.0) * y
            b = (img[:, :, 2] + 1.0) * y
            g = (y - np.float32(wr) * r - np.float32(wb) * b) / np.float32(wg)
            return np.stack([r, g, b], axis=2).astype(np.float32, copy=False)
        if kind == "spectral":
            from ..spectral import spectral_kind, spectral_to_xyz

            try:
                xyz = spectral_to_xyz(img, self.wavelengths, kind=spectral_kind(self.channels))
            except ValueError as e:
                raise ValueError(f"{self.name}: {e}") from None
            return np.ascontiguousarray(xyz, dtype=np.float32)
        raise ValueError(
            f"{self.name}: has no RGB interpretation (channels {', '.join(self.channels)}); "
            "expected R, G, B or Y or Y, RY, BY or spectral channels"
        )

    def conversion(
        self, space: "_spaces.SpaceLike" = _spaces.DEFAULT_SPACE, *, cat: str = _spaces.DEFAULT_CAT
    ) -> np.ndarray:
        """The 3×3 matrix taking :meth:`native_rgb` to ``space``
        (:func:`hdrjax.spaces.conversion_matrix`)."""
        return _spaces.conversion_matrix(self.space, space, cat=cat)

    def rgb(
        self, space: "_spaces.SpaceLike" = _spaces.DEFAULT_SPACE, *, cat: str = _spaces.DEFAULT_CAT
    ) -> Float[np.ndarray, "H W 3"]:
        """Linear RGB in a working space, ``(H, W, 3)`` float32, same unit as the image.

        Args:
            space: the working space: a colour-science RGB colourspace name (``"sRGB"``,
                the default: BT.709 primaries, D65; ``"ACEScg"``, ``"ITU-R BT.2020"``,
                ``"Display P3"``…), ``"CIE XYZ"``, or chromaticities. The file's pixels
                (:meth:`native_rgb`, in :attr:`space`) are converted as colour-science's
                ``RGB_to_RGB`` does (see :mod:`hdrjax.spaces`).
            cat: the chromatic adaptation transform between different whites (CAT02).

        Luminance stays the file's: use :meth:`luminance_weights_in` with the converted
        pixels, or :meth:`luminance`.

        Raises:
            ValueError: no RGB interpretation (see :meth:`native_rgb`), an unknown space or
                transform.
        """
        m = self.conversion(space, cat=cat)
        rgb = self.native_rgb()
        if _spaces.is_identity(m):
            return rgb
        return np.ascontiguousarray(rgb @ m.T.astype(np.float32), dtype=np.float32)

    def luminance_weights_in(
        self, space: "_spaces.SpaceLike" = _spaces.DEFAULT_SPACE, *, cat: str = _spaces.DEFAULT_CAT
    ) -> tuple[float, float, float]:
        """Weights that give, from :meth:`rgb` in ``space``, the file's own luminance
        (:func:`hdrjax.spaces.luminance_weights_in`)."""
        return _spaces.luminance_weights_in(self.space, space, cat=cat)

    def luminance(self) -> Float[np.ndarray, "H W"]:
        """Per-pixel luminance Y in the image's unit, ``(H, W)`` float32.

        ``Y`` itself for single-channel and luminance/chroma images; the weighted sum with
        :attr:`luminance_weights` for RGB.

        Raises:
            ValueError: the image has no RGB or Y interpretation.
        """
        kind = self.kind
        if kind in ("y", "ych"):
            return self.image[:, :, 0]
        rgb = self.native_rgb()
        wr, wg, wb = (np.float32(w) for w in self.luminance_weights)
        return rgb[:, :, 0] * wr + rgb[:, :, 1] * wg + rgb[:, :, 2] * wb

    def to_absolute(self) -> "LayeredImage":
        """A copy in cd/m² for a relative image that declares its ``white_luminance``.

        Returns the image unchanged when it is already in a physical unit.

        Raises:
            ValueError: the image is relative and does not declare ``white_luminance``.
        """
        if self.quantity != "relative":
            return self
        if self.white_luminance is None:
            raise ValueError(
                f"{self.name}: relative image without whiteLuminance; its absolute scale is unknown"
            )
        return dataclasses.replace(
            self,
            image=self.image * np.float32(self.white_luminance),
            quantity="luminance",
            unit=QUANTITIES["luminance"],
            white_luminance=None,
        )

    def _layer_kinds(self) -> list[tuple[str, str]]:
        out = []
        for key in sorted(self.layers):
            v = self.layers[key]
            if isinstance(v, dict):
                out.append((key, f"dict ({len(v)} keys)"))
            else:
                kind = "grid" if self.is_grid_layer(key) else "non-grid"
                out.append((key, f"{kind} {v.dtype} {'×'.join(map(str, v.shape))}"))
        return out

    def _primaries(self) -> str:
        if self.kind == "spectral":
            return f"spectral ({len(self.channels)} bands, CIE 1931 XYZ)"
        try:
            return self.space.name if self.space.name != "file" else str(self.chromaticities)
        except ValueError:
            return str(self.chromaticities)

    def __repr__(self) -> str:
        unit = f" [{self.unit}]" if self.unit else ""
        layers = ", ".join(k for k, _ in self._layer_kinds())
        return (
            f"LayeredImage({self.name!r}, {self.width}×{self.height}, "
            f"channels {','.join(self.channels[:6])}{'…' if len(self.channels) > 6 else ''}, "
            f"{self.quantity}{unit}, {self._primaries()}"
            + (f", layers: {layers}" if layers else "")
            + ")"
        )

    def _repr_html_(self) -> str:
        """A notebook's view: a tone-mapped thumbnail (Reinhard et al. 2002) and a table of
        size, quantity and unit, primaries, projection and layers."""
        import html

        from .. import _repr
        from .._show import display_image

        try:
            thumb = _repr.thumbnail(display_image(self))
        except (ValueError, TypeError) as e:  # an image with no RGB interpretation
            thumb = f"<i>no thumbnail: {html.escape(str(e))}</i>"
        rows = [
            ("size", f"{self.width} × {self.height}"),
            ("channels", ", ".join(self.channels)),
            ("quantity", f"{self.quantity}" + (f" [{self.unit}]" if self.unit else "")),
            ("primaries", self._primaries()),
        ]
        if self.projection:
            rows.append(("projection", self.projection))
        if self.white_luminance is not None:
            rows.append(("white luminance", f"{self.white_luminance:g} cd/m²"))
        rows += [(f"layer {k}", v) for k, v in self._layer_kinds()]
        return _repr.view(self.name, _repr.table(rows), image=thumb)

    def describe(self) -> str:
        """A short multi-line summary (size, channels, quantity, layers) for listings."""
        lines = [
            f"{self.name}: {self.width}x{self.height}, channels {', '.join(self.channels)}, "
            f"{self.quantity}" + (f" [{self.unit}]" if self.unit else "")
        ]
        for key in sorted(self.layers):
            v = self.layers[key]
            if isinstance(v, dict):
                lines.append(f"  layer {key}: dict ({len(v)} keys)")
            else:
                kind = "grid" if self.is_grid_layer(key) else "non-grid"
                lines.append(f"  layer {key}: {kind} {v.dtype} {tuple(v.shape)}")
        return "\n".join(lines)


__all__ = [
    "ALPHA",
    "DEPTH",
    "ERROR",
    "GRID",
    "GRID_LAYERS",
    "HITS",
    "KNOWN_LAYERS",
    "LayeredImage",
    "NON_GRID_LAYERS",
    "OBJECTS",
    "OBJECT_ID",
    "POSITION",
    "QUANTITIES",
    "VIEW",
    "WAVELENGTHS",
    "normalise_unit",
]
