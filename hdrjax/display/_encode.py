"""Display encoding: the separate last step after tone mapping.

Numeric contract: input is display-referred *linear* RGB (an operator's output, nominally
[0, 1], white = 1) or, for PQ and HLG with ``scene_referred=True``, scene-referred linear
RGB (an exposed image, reference white = 1, highlights above); output is encoded signal
values in [0, 1] (float) or integers (:func:`quantize`). NaN channels encode as black (0,
or the curve's value at 0: PQ's is 7.3e-7) and +Inf as the display's white (1; for PQ the
signal of its peak): a file cannot hold them. Finite input gives finite output and finite
gradients, up to the dtype's largest value.

Without a display, ``transfer`` applies one curve per value (any shape), after clipping to
[0, 1]. With a display (:func:`hdrjax.display.get_display`: a name or a
:class:`Display`), the display decides primaries and curve: the working-space RGB is
converted to the display's primaries (:func:`hdrjax.spaces.conversion_matrix`, computed
once in NumPy, applied in JAX), brought into its gamut (:func:`hdrjax.display.gamut_map`)
and encoded with its curve.

Curves:

- sRGB and Display P3: IEC 61966-2-1:1999, ``12.92 x`` for ``x ≤ 0.0031308``, else
  ``1.055 x^(1/2.4) − 0.055``.
- ITU-R BT.2020: the inverse of the ITU-R BT.1886 (2011) EOTF with a zero black level,
  ``V = L^(1/2.4)``.
- ITU-R BT.2100 PQ: SMPTE ST 2084:2014's inverse EOTF of ``L = x · peak`` cd/m² (white at
  the display's peak, 1000 cd/m² by default). Scene-referred input is placed with
  reference white at 203 cd/m² (ITU-R BT.2408: PQ signal 0.58) and its highlights rolled
  off onto the peak by the ITU-R BT.2390 EETF (:func:`hdrjax.display.bt2390_eetf`). The
  placement is linear, without a rendering OOTF: grey 0.18 lands at 36.5 cd/m², where
  BT.2408's grey card sits at 26 cd/m² through HLG's system gamma 1.2.
- ITU-R BT.2100 HLG: the BT.2100 HLG OETF of the relative scene-linear signal ``E``.
  HLG is relative: the display applies the OOTF for its own peak ``L_W`` (BT.2100-2,
  Table 5: system gamma ``1.2 + 0.42 log10(L_W / 1000)``), so ``peak`` does not enter.
  Display-referred input is taken as ``E`` itself (white 1 → signal 1); an HLG display
  then shows it with its system gamma (grey 0.18 at ``1000 · 0.18^1.2 = 128`` cd/m² on a
  1000 cd/m² display, where PQ shows 180), which is HLG's intended rendering and what the
  ICC profiles of :mod:`hdrjax.io` describe (inverse OETF). Scene-referred input is
  scaled so that reference white lands on signal 0.75 (ITU-R BT.2408), ``E = 0.2650 x``,
  leaving HLG's log segment for highlights up to 3.8 × white.
- ``"gamma"``: ``x^(1/γ)``; ``"linear"``: clipping only.
"""

from collections.abc import Sequence
from typing import Any, Literal

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .. import _check, spaces
from .._colour import channel_max
from .._scale import positive_power
from .._srgb import clip_unit, srgb_decode, srgb_encode
from ..spaces import SpaceLike
from ._displays import DEFAULT_PEAK, Display, get_display
from ._gamut import DEFAULT_GAMUT, GamutMethod, flush, map_gamut, method_name, sanitise
from ._hdr import (
    HLG_REFERENCE_WHITE,
    PQ_PEAK,
    REFERENCE_WHITE,
    eetf,
    hlg_oetf,
    pq_eotf,
    pq_inverse_eotf,
    pq_of,
)

_DISPLAY_TRANSFERS = ("srgb", "bt1886", "pq", "hlg", "gamma", "linear")


def gamma_encode(linear: Float[ArrayLike, "..."], gamma: float = 2.2) -> Float[Array, "..."]:
    """Plain power law ``x^(1/gamma)`` after clipping to [0, 1]."""
    _check.real(linear, "linear")
    if not gamma > 0:
        raise ValueError(f"gamma: expected a number > 0, got {gamma!r}")
    x = clip_unit(jnp.asarray(linear, jnp.result_type(float)))
    pos = x > 0
    return jnp.where(pos, positive_power(jnp.where(pos, x, 1.0), 1.0 / gamma), 0.0)


def quantize(encoded: ArrayLike, bits: Literal[8, 16] = 8) -> np.ndarray:
    """Round encoded [0, 1] values to ``uint8``/``uint16`` (NaN → 0), on the host."""
    _check.real(encoded, "encoded")
    if bits not in (8, 16):
        raise ValueError(f"bits: expected 8 or 16, got {bits!r}")
    top = (1 << bits) - 1
    x = np.nan_to_num(np.asarray(encoded, np.float64), nan=0.0, posinf=1.0, neginf=0.0)
    return np.rint(np.clip(x, 0.0, 1.0) * top).astype(np.uint8 if bits == 8 else np.uint16)


def _image_axes(ndim: int) -> tuple[int, ...]:
    # the H and W axes of (..., H, W); a single pixel or a row of pixels is its own image
    return tuple(range(max(ndim - 2, 0), ndim))


def _pq_scene(
    rgb: Array,
    finite: Array | None,
    method: str,
    weights: Sequence[float],
    peak: Any,
    scene_max: Any,
) -> Array:
    """Scene-referred RGB (display primaries) to PQ: reference white at 203 cd/m², the
    brightest channel of each pixel through the BT.2390 EETF, all three scaled alike."""
    rgb = map_gamut(rgb, method, weights, None)
    hi = channel_max(rgb)
    if finite is not None:
        # Inf pixels are not the source range: they clip to the peak (sanitised to 1e30)
        scene_max = jnp.max(jnp.where(finite, hi, 0.0), axis=_image_axes(hi.ndim), keepdims=True)
    white = REFERENCE_WHITE / PQ_PEAK
    # a source no brighter than the display needs no roll-off; PQ ends at 10000 cd/m²
    source = jnp.clip(jnp.asarray(scene_max, rgb.dtype) * REFERENCE_WHITE, peak, PQ_PEAK)
    black = pq_of(0.0, rgb)
    y = hi * white
    e, changed = eetf(
        pq_inverse_eotf(y), lb=black, lw=pq_of(source, rgb), lmin=black, lmax=pq_of(peak, rgb)
    )
    # below the knee the gain is exactly 1 (a PQ round trip would add float32 rounding);
    # the maxRGB gain keeps hue and saturation where a per-channel EETF would shift them
    moved = changed & (y > 0)
    gain = jnp.where(moved, pq_eotf(e) / jnp.where(moved, y, 1.0), 1.0)
    return jnp.clip(pq_inverse_eotf(rgb * (white * gain)[..., None]), 0.0, 1.0)


def _encode_for(
    x: Array,
    disp: Display,
    *,
    space: SpaceLike,
    gamut: str | None,
    peak: Any,
    scene_referred: bool,
    scene_max: Any,
) -> Array:
    if x.ndim < 1 or x.shape[-1] != 3:
        raise ValueError(
            f"linear: expected channels-last RGB (..., 3) to encode for a display, got shape"
            f" {x.shape}"
        )
    method = DEFAULT_GAMUT if gamut is None else method_name(gamut, "gamut")
    tf = disp.transfer
    if tf not in _DISPLAY_TRANSFERS:
        options = ", ".join(map(repr, _DISPLAY_TRANSFERS))
        raise ValueError(f"display: expected a transfer in {options}, got {tf!r}")
    if peak is not None and tf != "pq":
        raise ValueError(
            f"peak: expected None for the display {disp.name!r} (only PQ is absolute; an HLG"
            f" display applies its own peak), got {peak!r}"
        )
    peak = DEFAULT_PEAK if peak is None else peak
    _check.positive(peak, "peak")
    _check.in_range(peak, "peak", 0.0, PQ_PEAK)
    if scene_referred and tf not in ("pq", "hlg"):
        raise ValueError(
            f"scene_referred: expected False for the SDR display {disp.name!r} (tone-map first:"
            " hdrjax.tonemap), got True"
        )
    if scene_max is not None and not (scene_referred and tf == "pq"):
        raise ValueError(
            f"scene_max: expected None unless scene_referred=True for a PQ display, got"
            f" {scene_max!r}"
        )
    _check.positive(scene_max, "scene_max")
    dtype = x.dtype
    finite = jnp.all(jnp.isfinite(x), axis=-1) if scene_referred and scene_max is None else None
    # NaN/Inf are settled per channel before the matrix spreads them over the pixel
    x = sanitise(x)
    matrix = spaces.conversion_matrix(space, disp.space)
    if not spaces.is_identity(matrix):
        x = flush(spaces.convert(x, matrix))
    weights = spaces.space(disp.space).weights
    if tf == "pq" and scene_referred:
        return _pq_scene(x, finite, method, weights, peak, scene_max)
    if tf == "hlg" and scene_referred:
        x = x * HLG_REFERENCE_WHITE
    # below black the gamut method decides; above white each channel burns to white, as
    # the operators' white points intend (L_white: "the smallest luminance mapped to white")
    y = jnp.minimum(map_gamut(x, method, weights, None), 1.0)
    if tf == "pq":
        out = pq_inverse_eotf(y * (jnp.asarray(peak, dtype) / PQ_PEAK))
    elif tf == "hlg":
        out = hlg_oetf(y)
    elif tf == "srgb":
        out = srgb_encode(y)
    elif tf == "linear":
        out = y
    else:
        out = gamma_encode(y, disp.gamma if disp.gamma is not None else 2.2)
    # the SDR curves compute in JAX's default float; the display path keeps the input's
    return out.astype(dtype)


def encode(
    linear: Float[ArrayLike, "..."],
    transfer: Literal["srgb", "gamma", "linear"] | None = None,
    *,
    gamma: float = 2.2,
    display: str | Display | None = None,
    space: SpaceLike = spaces.DEFAULT_SPACE,
    gamut: GamutMethod | None = None,
    peak: float | None = None,
    scene_referred: bool = False,
    scene_max: float | None = None,
) -> Float[Array, "..."]:
    """Encode linear RGB for a display or with a transfer curve (see the module docstring).

    Args:
        linear: display-referred linear values (white = 1): any shape without a display,
            channels-last RGB ``(..., 3)`` with one (or with a gamut mapping).
        transfer: without a display: ``"srgb"`` (IEC 61966-2-1, the default), ``"gamma"``
            or ``"linear"``, per value after clipping to [0, 1]. ``None`` with a display.
        gamma: the exponent of ``transfer="gamma"`` and of the ``"gamma"`` display.
        display: a display name (``"sRGB"``, ``"Display P3"``, ``"ITU-R BT.2020"``,
            ``"ITU-R BT.2100 PQ"`` or ``"PQ"``, ``"ITU-R BT.2100 HLG"`` or ``"HLG"``,
            ``"linear"``, ``"gamma"``; case and separators do not matter) or a
            :class:`Display`; it decides primaries, curve and gamut.
        space: the working space ``linear`` is in (a :mod:`hdrjax.spaces` name or
            chromaticities; sRGB by default), converted to the display's primaries.
        gamut: ``"clip"``, ``"luminance"`` or ``"compress"``
            (:func:`hdrjax.display.gamut_map`) for channels below black. ``None``:
            ``"luminance"`` with a display (only colours the display cannot show change),
            per-value clipping without. Channels above white burn to white one by one,
            whatever the method (an operator's white point means exactly that; for
            display-referred input only, the scene-referred PQ roll-off keeps hue).
        peak: cd/m² of white for PQ (1000 by default, BT.2100's reference HLG display
            peak, also used for HLG monitoring); only PQ is absolute, so ``None`` for the
            others.
        scene_referred: the input is scene-referred (reference white = 1, highlights
            above; PQ and HLG only): PQ puts white at 203 cd/m² and rolls highlights off
            onto ``peak`` with the BT.2390 EETF (applied to each pixel's largest channel,
            all three scaled by one gain, so hue and saturation are kept); HLG puts white
            at signal 0.75.
        scene_max: scene-referred PQ only: the input value that reaches ``peak`` (the
            source peak of the EETF, at ``203 · scene_max`` cd/m², at most 10000).
            ``None``: each image's largest finite channel value (leading axes before
            ``(H, W, 3)`` are a batch).

    Returns:
        Signal values in [0, 1], the shape of ``linear``; float32, float64 under x64.

    Raises:
        ValueError: an unknown transfer, display or gamut method, a transfer given with a
            display, options that the display does not take (``peak`` for non-PQ,
            ``scene_referred`` for SDR, ``scene_max`` without scene-referred PQ), a bad
            ``peak`` (``(0, 10000]`` cd/m²) or ``gamma``, or not RGB where RGB is needed.

    >>> import jax.numpy as jnp
    >>> rgb = jnp.array([[1.0, 1.0, 1.0], [0.18, 0.18, 0.18]])
    >>> [round(v, 4) for v in encode(rgb, display="PQ")[:, 0].tolist()]  # 1000, 180 cd/m²
    [0.7518, 0.5682]
    >>> [round(v, 4) for v in encode(rgb, display="HLG", scene_referred=True)[:, 0].tolist()]
    [0.75, 0.3783]
    """
    _check.real(linear, "linear")
    if display is not None:
        if transfer is not None:
            raise ValueError(
                f"transfer: expected None when a display is given (the display decides the"
                f" curve), got {transfer!r}"
            )
        if scene_referred and scene_max is None:
            # the source peak is the image's brightest pixel: there must be one
            _check.nonempty(np.shape(linear), "linear", "(..., H, W, 3)")
        return _encode_for(
            _check.as_float(linear),
            get_display(display, gamma),
            space=space,
            gamut=gamut,
            peak=peak,
            scene_referred=scene_referred,
            scene_max=scene_max,
        )
    transfer = "srgb" if transfer is None else transfer
    if transfer not in ("srgb", "gamma", "linear"):
        raise ValueError(
            f"transfer: expected 'srgb', 'gamma' or 'linear' (PQ and HLG need a display:"
            f" display='PQ'), got {transfer!r}"
        )
    for name, value in (("peak", peak), ("scene_max", scene_max)):
        if value is not None:
            raise ValueError(f"{name}: expected None without a PQ display, got {value!r}")
    if scene_referred:
        raise ValueError(
            "scene_referred: expected False without an HDR display (display='PQ' or 'HLG');"
            " tone-map first (hdrjax.tonemap), got True"
        )
    method = "clip" if gamut is None else method_name(gamut, "gamut")
    if method != "clip":
        x = _check.as_float(linear)
        if x.ndim < 1 or x.shape[-1] != 3:
            raise ValueError(
                f"linear: expected channels-last RGB (..., 3) for gamut={gamut!r}, got shape"
                f" {x.shape}"
            )
        linear = map_gamut(sanitise(x), method, spaces.space(space).weights, 1.0)
    if transfer == "srgb":
        return srgb_encode(linear)
    if transfer == "gamma":
        return gamma_encode(linear, gamma)
    return clip_unit(jnp.asarray(linear, jnp.result_type(float)))


__all__ = ["encode", "gamma_encode", "quantize", "srgb_decode", "srgb_encode"]
