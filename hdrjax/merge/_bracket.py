"""Exposure brackets: normalising what users pass (arrays, lists, file paths) to one form.

Numeric contract: a bracket is ``N`` exposures of one scene as integer code values
``(N, H, W, 3)`` (uint8: 256 levels; uint16: 65536 levels; camera RAW decoded linear to
uint16), with one exposure time per member in seconds. Functions of :mod:`hdrjax.merge`
accept a list of ``(H, W, 3)`` arrays, one ``(N, H, W, 3)`` array, or file paths.
"""

import os
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np


class Codes(NamedTuple):
    """A validated bracket: ``codes`` ``(N, H, W, 3)`` uint8/uint16, ``levels`` (256 or
    65536), ``exposure_times`` ``(N,)`` float64 seconds (``None`` when not given)."""

    codes: np.ndarray
    levels: int
    exposure_times: np.ndarray | None


def _is_path(x: Any) -> bool:
    return isinstance(x, str | os.PathLike)


def as_codes(
    images: Any, exposure_times: Any = None, *, name: str = "images", need_times: bool = True
) -> Codes:
    """Validate a bracket and return it as :class:`Codes`.

    Raises a one-line ``ValueError`` naming ``name`` (or ``exposure_times``) and the expected
    form: integer code values of one size and three channels, at least two members,
    positive finite distinct exposure times, one per member.
    """
    if _is_path(images) or (
        isinstance(images, Sequence) and len(images) > 0 and all(map(_is_path, images))
    ):
        from ._read import read_bracket

        bracket = read_bracket([images] if _is_path(images) else list(images))
        if exposure_times is None:
            exposure_times = bracket.exposure_times
        images = bracket.images
    if isinstance(images, np.ndarray | Sequence) or hasattr(images, "__array__"):
        if isinstance(images, Sequence) and not isinstance(images, np.ndarray):
            shapes = {np.shape(im) for im in images}
            if len(shapes) > 1:
                raise ValueError(
                    f"{name}: the exposures must all have one size, got shapes {sorted(shapes)}"
                )
            dtypes = {np.asarray(im).dtype for im in images}
            if len(dtypes) > 1:
                raise ValueError(f"{name}: the exposures must share one dtype, got {dtypes}")
        codes = np.asarray(images)
    else:
        raise ValueError(
            f"{name}: expected an (N, H, W, 3) uint8/uint16 array, a list of (H, W, 3) "
            f"arrays or file paths, got {type(images).__name__}"
        )
    if codes.ndim != 4 or codes.shape[-1] != 3:
        raise ValueError(
            f"{name}: expected N exposures of (H, W, 3) code values, got shape {codes.shape}"
        )
    if codes.dtype not in (np.uint8, np.uint16):
        raise ValueError(
            f"{name}: expected integer code values (uint8 or uint16), got dtype {codes.dtype}"
        )
    if codes.shape[0] < 2 and need_times:
        raise ValueError(f"{name}: a bracket needs at least 2 exposures, got {codes.shape[0]}")
    if 0 in codes.shape[1:3]:
        raise ValueError(f"{name}: the exposures are empty (shape {codes.shape})")
    levels = 256 if codes.dtype == np.uint8 else 65536
    times = None
    if exposure_times is not None:
        times = np.asarray(exposure_times, dtype=np.float64).reshape(-1)
        if times.shape[0] != codes.shape[0]:
            raise ValueError(
                f"exposure_times: expected one time per exposure ({codes.shape[0]}), "
                f"got {times.shape[0]}"
            )
        if not np.all(np.isfinite(times) & (times > 0)):
            raise ValueError(f"exposure_times: expected positive finite seconds, got {times}")
        if len(np.unique(times)) != len(times):
            raise ValueError(f"exposure_times: the exposures must be distinct, got {times}")
    elif need_times:
        raise ValueError(
            "exposure_times: required (one time in seconds per exposure) for arrays; "
            "files carry theirs in EXIF"
        )
    return Codes(codes, levels, times)


def reference_index(reference: Any, n: int) -> int:
    """The index of the reference exposure of a bracket of ``n``: the middle one
    (``n // 2``, OpenCV's pivot) for ``None``; negative indices count from the end."""
    if reference is None:
        return n // 2
    if isinstance(reference, bool) or not isinstance(reference, int | np.integer):
        raise ValueError(f"reference: expected an exposure index in [0, {n}), got {reference!r}")
    if not -n <= reference < n:
        raise ValueError(f"reference: expected an exposure index in [0, {n}), got {reference}")
    return int(reference) % n


def check_response(response: Any, levels: int | None = None, *, name: str = "response") -> Any:
    """Validate an inverse response ``g``: a ``(levels, 3)`` table of natural-log exposure per
    code value, finite or ``−inf`` (codes no exposure produces), no NaN or ``+inf``, each
    channel with at least one finite value; ``levels`` is checked when given (else ≥ 2).

    Returns the table as float64 NumPy, or unchanged when it is a JAX tracer (only its shape
    is checked then). Raises a one-line ``ValueError`` starting with ``name``.
    """
    import jax

    want = f"({levels}, 3)" if levels is not None else "(levels, 3)"
    what = f"{name}: expected a {want} table of ln exposure per code"
    if isinstance(response, jax.core.Tracer):
        shape = response.shape
        if len(shape) != 2 or shape[1] != 3 or shape[0] != (levels or shape[0]):
            raise ValueError(f"{what}, got shape {shape}")
        return response
    try:
        g = np.array(response, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{what}, got {type(response).__name__}") from None
    if levels is None and g.ndim == 2 and g.shape[0] >= 2:
        levels = g.shape[0]  # any number of levels: name the one the table has
        what = f"{name}: expected a ({levels}, 3) table of ln exposure per code"
    if g.ndim != 2 or g.shape[1] != 3 or g.shape[0] != levels:
        raise ValueError(f"{what}, got shape {g.shape}")
    if np.isnan(g).any() or np.isposinf(g).any() or not np.isfinite(g).any(axis=0).all():
        raise ValueError(
            f"{what} (finite, or -inf at dark codes), got NaN, +inf or a channel without values"
        )
    return g
