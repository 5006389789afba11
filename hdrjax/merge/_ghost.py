"""Ghost removal: pixels of a bracket that disagree with a reference exposure (Grosch 2006).

Grosch, T. (2006). Fast and robust high dynamic range image generation with camera and
object movement. *Vision, Modeling, and Visualization (VMV) 2006*, 277–284.

Something that moved between exposures shows up where it does not belong in all but one of
them and leaves a semi-transparent "ghost" in the merge. Grosch predicts each exposure from a
reference exposure through the camera response and the exposure ratio, and keeps from the
other exposures only the pixels whose colour matches the prediction. With the inverse
response ``g(z) = ln X`` and exposure times ``t``, the code of exposure ``j`` predicted from
the reference code ``z_r`` is

    ẑ_j = g⁻¹(g(z_r) + ln(t_j / t_r))

(clipped to the code range: a prediction beyond the top code is the top code, as the sensor
saturates). A pixel of exposure ``j`` is a ghost when, in any channel where the reference is
well exposed, its code lies outside the predicted interval widened by a tolerance:

    z_j < ẑ_j(z_r − ½) − τ  or  z_j > ẑ_j(z_r + ½) + τ,   τ = threshold · (levels − 1).

Deviation from Grosch, who compares with one predicted colour and a fixed threshold: the
interval ``[ẑ_j(z_r − ½), ẑ_j(z_r + ½)]`` is what the reference's own quantisation allows
(one code of a dark reference spans many codes of a longer exposure), so the test is as
strict as the data permit in every part of the range and ``τ`` only has to cover sensor
noise. Pixels whose reference code is outside ``well_exposed`` (fractions of the top code)
are not tested (nothing reliable predicts from them) and stay usable. The reference is
always usable. Grosch goes on to fill ghost regions from the reference; here the mask is
handed to :func:`hdrjax.merge.merge` (``mask=``), where an unusable pixel gets zero weight —
the same result where the reference is well exposed.

The response is made finite and non-decreasing before it is inverted: ``-inf`` entries (a
code zero exposure gives) become 10 below the smallest finite value, then a running maximum.
"""

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool

from ._bracket import as_codes, check_response, reference_index


@jax.jit
def _ghosts(
    codes: Array, log_ratio: Array, g: Array, ref: Array, tol: Array, lo: Array, hi: Array
) -> Array:
    levels = g.shape[0]
    grid = jnp.arange(levels, dtype=g.dtype)
    z = codes.astype(g.dtype)
    zr = jnp.take(z, ref, axis=0)  # (H, W, 3)

    def per_channel(zr_c: Array, zj_c: Array, g_c: Array, lr: Array) -> Array:
        lnx_lo = jnp.interp(zr_c - 0.5, grid, g_c)
        lnx_hi = jnp.interp(zr_c + 0.5, grid, g_c)
        pred_lo = jnp.interp(lnx_lo + lr, g_c, grid)
        pred_hi = jnp.interp(lnx_hi + lr, g_c, grid)
        tested = (zr_c >= lo) & (zr_c <= hi)
        return tested & ((zj_c < pred_lo - tol) | (zj_c > pred_hi + tol))

    def per_exposure(zj: Array, lr: Array) -> Array:
        bad = jax.vmap(per_channel, in_axes=(-1, -1, -1, None), out_axes=-1)(zr, zj, g, lr)
        return jnp.any(bad, axis=-1)

    ghost = jax.vmap(per_exposure)(z, log_ratio)
    return ~ghost.at[ref].set(False)


def ghost_mask(
    images: Any,
    exposure_times: Any,
    response: Any,
    *,
    reference: int | None = None,
    threshold: float = 0.1,
    well_exposed: tuple[float, float] = (0.1, 0.95),
) -> Bool[Array, "N H W"]:
    """Usable pixels of a bracket: ``False`` where an exposure contradicts the reference.

    Grosch (2006)'s consistency test through the camera response (see the module text).

    Args:
        images: ``(N, H, W, 3)`` uint8/uint16 codes, a list of arrays, or file paths
            (:func:`hdrjax.merge.as_codes`); aligned already (:func:`align_mtb`).
        exposure_times: seconds, one per exposure.
        response: inverse response ``(levels, 3)`` ``g(z) = ln X``
            (:func:`hdrjax.merge.recover_response`).
        reference: the exposure whose content is kept; default ``N // 2``.
        threshold: tolerance ``τ`` beyond the predicted interval, as a fraction of the
            code range (0.1: 26 codes of 8-bit), for sensor noise. It is one tolerance for
            the whole range: dark codes of an sRGB-like curve are the noisiest, and a
            threshold of 0.05 with ``well_exposed=(0.05, 0.95)`` flagged 5 % of the static
            pixels of a bracket with read noise 0.002 (of the saturating exposure), the
            defaults 0.06 %.
        well_exposed: ``(low, high)`` fractions of the top code between which a reference
            pixel is trusted to predict the others.

    Returns:
        ``(N, H, W)`` bool, ``True`` for usable pixels (pass as ``merge(..., mask=)``).
    """
    c = as_codes(images, exposure_times)
    n = c.codes.shape[0]
    ref = reference_index(reference, n)
    g = check_response(response, c.levels)
    finite = np.isfinite(g)
    floor = np.where(finite, g, np.inf).min(axis=0) - 10.0
    g = np.maximum.accumulate(np.where(finite, g, floor), axis=0)
    if not (np.isscalar(threshold) and np.isfinite(threshold) and threshold >= 0):
        raise ValueError(f"threshold: expected a non-negative fraction, got {threshold!r}")
    try:
        lo, hi = (float(v) for v in well_exposed)
    except (TypeError, ValueError):
        raise ValueError(
            f"well_exposed: expected (low, high) fractions, got {well_exposed!r}"
        ) from None
    if not 0 <= lo < hi <= 1:
        raise ValueError(f"well_exposed: expected 0 ≤ low < high ≤ 1, got {well_exposed!r}")
    top = c.levels - 1
    times = c.exposure_times
    assert times is not None
    dt = jnp.zeros(()).dtype
    return _ghosts(
        jnp.asarray(c.codes),
        jnp.asarray(np.log(times / times[ref]), dt),
        jnp.asarray(g, dt),
        jnp.asarray(ref),
        jnp.asarray(threshold * top, dt),
        jnp.asarray(lo * top, dt),
        jnp.asarray(hi * top, dt),
    )
