"""Benchmark: two-parameter fits (hdrjax.fit) against scipy.optimize.least_squares on NumPy.

Run: ``.venv/bin/python benchmarks/bench_fit.py [--quick]``

**Image.** ``data/venice_sunset_1k.hdr`` (1024×512, 25.9 stops) upscaled 2× by pixel
repetition to 2048×1024 (``--quick``: the 1024×512 original).

**Problem.** Fit ``reinhard2002`` (``key``, ``L_white``; ``log_average`` measured) and
``tumblin_reinhard`` (``L_wa``, ``L_white``) so that the display image has mean luminance
0.2 and 99th luminance percentile 0.95 (:class:`hdrjax.targets.MeanLuminance` +
:class:`~hdrjax.targets.Percentiles`; with mean 0.4, the CLI example, tumblin_reinhard
cannot reach P99 = 0.95 on this image: its P99 clips at 1 first). Both sides start from
the same values (reinhard2002 ``key = 0.18``, ``L_white = 10``; tumblin_reinhard
``L_wa = 0.1``, ``L_white = 0.5``; from ``L_wa = 1`` both solvers stall where P99 is
clipped and has no gradient), optimise
``ln p``, and fit on the same image: the full-resolution input box-filtered to 64 pixels on
the long side (64×32, hdrjax.fit's default ``max_size``), after measuring what the
operator needs from the full-resolution image (reinhard2002's log-average; since session 5
hdrjax no longer measures tumblin_reinhard's ``L_max``, which its output does not use once
``L_white`` is set, and which the peer never measured); the timed call includes that
measuring and the downscale on both sides. Both sides box-filter the same way: sum the
rows, then the columns of that smaller result. (Until session 4 the peer used one strided
``reshape(h, f, w, f, 3).mean(axis=(1, 3))``: at 2048×1024 ~15× slower than the two-step
sum, min 42 against 2.7 ms in one process, which made the whole peer 2–9× slower than it
needs to be on a loaded machine.) A second pair of records, *solve only*, gives both sides
the 64×32 image and the log-average and times the least-squares solve alone.

**Peer.** A NumPy float64 implementation of the same operators and targets written here
(:func:`np_reinhard`, :func:`np_tumblin_reinhard`, :func:`np_statistics`: luminance
clipped to [0, 1], ``numpy.percentile`` over the positive pixels, as the targets define
them), solved by ``scipy.optimize.least_squares(method="lm")`` (MINPACK ``lmder``,
Levenberg–Marquardt, forward-difference Jacobian) with ``xtol = ftol = 1e-5`` (``gtol``
1e-8, its default). hdrjax runs float32 (its default) with optimistix Levenberg–Marquardt,
``rtol = 1e-5``, ``atol = 1e-6`` (its float32 defaults).

**Tolerances, side by side.** Both work on ``z = ln p``. MINPACK stops when the trust
radius ``Δ ≤ xtol·‖D z‖`` (a relative step in scaled ``z``), or when the actual and the
predicted relative reductions of ``‖r‖²`` are both ``≤ ftol``; optimistix stops after an
accepted step with ``max|Δz| < atol + rtol·max|z|`` *and* ``max|Δr| < atol + rtol·max|r|``.
The step tests are the same quantity (relative change of ``ln p`` below 1e-5); on these
zero-residual problems the ``ftol`` test never fires (each step removes most of ``‖r‖²``)
and scipy stops on ``xtol`` (status 3), optimistix on both tests once ``|Δr| < 1e-6``
(float32 resolves these statistics to ~1e-7, so the test can fire). Both end within ~2e-6 of each
other (``max_rel_param_diff``). What differs is the path: MINPACK tries the full
Gauss–Newton step first (radius ``100‖D z₀‖``); hdrjax's LM starts with damping
``λ = 1`` in ``z`` units (short gradient-like steps when ``JᵀJ ≪ 1``, as here) and divides
it by 3.5 after a step whose reduction of ``Σ r²`` is ≥ 0.75 of the predicted one
(optimistix's own default asks 0.99, which took 21 / 12 steps here against 18 / 11), so
it spends several steps shrinking ``λ``. Counted as work: an hdrjax step is one residual
and one Jacobian (one forward sweep with 2 tangents); scipy's ``nfev`` counts trial points
only, and ``residual_calls`` counts every call of the NumPy residual, including the two per
finite-difference Jacobian (reinhard2002: 8 trial points, 22 calls; tumblin_reinhard: 5,
15). A full Gauss–Newton first step (``optx.IndirectLevenbergMarquardt``, ``optx.Dogleg``)
halves hdrjax's steps here but jumps to ``L_white → ∞`` (no gradient) on the Cornell-box
recovery test. A first damping scaled to the problem (``λ₀ = 0.01·max diag JᵀJ``) takes
9 / 8 steps here, but leaves more fits stuck in saturated regions (no gradient) on other
images and starts. Neither is the default.

**Batch.** 64 frames of 256×128, a slow pan: frame ``k`` is the window of ¾ the image's
width and height whose corner moves linearly from the top left to the bottom right,
box-filtered to 256×128 (``--quick``: 16 frames from the 1024×512 image). Every frame can
meet the targets (plain tiles of the sky cannot: P99/mean is too small there). Each frame
is fitted independently (reinhard2002, same targets and start; box-filtered to 64×32 by the
fit): one ``hdrjax.fit.fit_batch`` call (default, and ``vectorize=True``) against a loop of
``hdrjax.fit.fit`` calls and a loop of scipy fits; all reported per frame.

**Not benchmarked: fits at full resolution with percentile targets.** A percentile needs an
order statistic. :class:`hdrjax.targets.Percentiles` selects the few largest (or smallest)
values with ``jax.lax.top_k`` for percentiles away from the median (P99 of the 64×32 fit:
~15 µs against ~220 µs for XLA:CPU's sort), but a percentile near the median still sorts,
~0.4 Mpixel/s on XLA:CPU (``numpy.percentile``'s partial sort is ~10× faster), several
seconds per step on 2 Mpixels — the reason ``hdrjax.fit`` works on a downscaled image by
default. In ``full`` mode a
full-resolution fit with sort-free targets (mean 0.2, soft clipped fraction 0.01) is timed
instead, both sides at 2048×1024.

**Batch modes.** ``fit_batch`` on CPU solves the frames one after another inside one
compiled call (``jax.lax.map``, its default there); ``vectorize=True`` vmaps the solve, so
every frame iterates until the slowest converges and the solver's ``lax.cond`` branches
become selects that evaluate both sides — both are recorded.

Compile time (hdrjax's first call minus a steady call) is reported separately and never
enters the ratios.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import scipy.optimize

import hdrjax
import hdrjax.fit as hf
import hdrjax.targets as ht

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _harness as H  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
W = np.array([0.2126, 0.7152, 0.0722])
MEAN, Q, P = 0.2, 99.0, 0.95
CLIPPED = 0.01
RTOL, ATOL = 1e-5, 1e-6
MAX_SIZE = 64
BENCH = "fit"

# ----------------------------------------------------------------------------- NumPy model


def np_downscale(rgb: np.ndarray, max_size: int | None) -> np.ndarray:
    """Box filter by the smallest integer factor giving a long side ≤ max_size (as hdrjax)."""
    if max_size is None:
        return rgb
    h, w = rgb.shape[:2]
    f = -(-max(h, w) // max_size)
    if f <= 1:
        return rgb
    hh, ww = h // f, w // f
    # rows first (contiguous), then the columns of the f-times smaller result, as hdrjax
    # does: one strided ``reshape(hh, f, ww, f, 3).mean(axis=(1, 3))`` is ~10x slower
    x = rgb[: hh * f, : ww * f].reshape(hh, f, ww * f * 3).sum(axis=1)
    return x.reshape(hh, ww, f, 3).sum(axis=2) / (f * f)


def _scale_rgb(rgb: np.ndarray, L: np.ndarray, Ld: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(L > 0, Ld / L, 0.0)
    return rgb * ratio[..., None]


def np_reinhard_curve(L: np.ndarray, L_white: float) -> np.ndarray:
    return (L / (1.0 + L)) * (1.0 + (L / L_white) / L_white)


def np_reinhard(rgb: np.ndarray, key: float, L_white: float, lbar: float) -> np.ndarray:
    """Reinhard et al. 2002 global operator (Eqs. 2–4), colour scaled by L_d / L_w."""
    L = rgb @ W
    return _scale_rgb(rgb, L, np_reinhard_curve(key / lbar * np.maximum(L, 0.0), L_white))


def np_stevens_gamma(L):
    return np.where(L > 100, 2.655, 1.855 + 0.4 * np.log10(np.maximum(L, 0.0) + 2.3e-5))


def np_tumblin_reinhard(
    rgb: np.ndarray, L_wa: float, L_white: float, L_da=20.0, C_max=100.0, L_dmax=100.0
) -> np.ndarray:
    """Tumblin 1999 (revised, formula 1; ln in γ_wd as colour-hdri) then Reinhard's formula 2."""
    L = rgb @ W
    g_w, g_d = np_stevens_gamma(L_wa), np_stevens_gamma(L_da)
    g_wd = g_w / (1.855 + 0.4 * np.log(L_da))
    m = C_max ** ((g_wd - 1.0) / 2.0)
    ratio = np.maximum(L, 0.0) / L_wa
    with np.errstate(divide="ignore"):
        powed = np.where(ratio > 0, np.exp((g_w / g_d) * np.log(ratio)), 0.0)
    Ld = m * L_da * powed / L_dmax
    return _scale_rgb(rgb, L, np_reinhard_curve(Ld, L_white))


def np_log_average(rgb: np.ndarray, delta: float = 1e-6) -> float:
    """Eq. 1 on the full image, in the image's dtype (float32, as hdrjax)."""
    L = rgb @ W.astype(rgb.dtype)
    return float(np.exp(np.mean(np.log(rgb.dtype.type(delta) + np.maximum(L, 0)))))


def np_statistics(display: np.ndarray, kind: str = "percentile") -> np.ndarray:
    """[mean display luminance, P99] (or [mean, soft clipped fraction]) as the targets."""
    Ld = np.clip(display, 0.0, 1.0) @ W
    if kind == "percentile":
        return np.array([Ld.mean(), np.percentile(Ld[Ld >= np.finfo(Ld.dtype).tiny], Q)])
    m = display.max(axis=-1)
    return np.array([Ld.mean(), np.mean(1.0 / (1.0 + np.exp(-(m - 1.0) / 0.01)))])


def scipy_fit(method: str, rgb: np.ndarray, start, max_size, kind="percentile", lbar=None):
    """The peer: measure on the full image (unless ``lbar`` is given), downscale,
    least_squares in ln p."""
    want = np.array([MEAN, P if kind == "percentile" else CLIPPED])
    if method == "reinhard2002":
        lbar = np_log_average(rgb) if lbar is None else lbar

        def model(x, p):
            return np_reinhard(x, p[0], p[1], lbar)
    else:

        def model(x, p):
            return np_tumblin_reinhard(x, p[0], p[1])

    small = np_downscale(rgb, max_size).astype(np.float64)  # box filter in float32

    calls = [0]

    def residuals(z):
        calls[0] += 1
        with np.errstate(all="ignore"):  # trial steps may under/overflow exp(z)
            return np_statistics(model(small, np.exp(z)), kind) - want

    sol = scipy.optimize.least_squares(
        residuals, np.log(np.asarray(start, np.float64)), method="lm", xtol=RTOL, ftol=RTOL
    )
    sol.residual_calls = calls[0]
    return sol


# ----------------------------------------------------------------------------- hdrjax side

START = {"reinhard2002": (("key", 0.18), ("L_white", 10.0)),
         "tumblin_reinhard": (("L_wa", 0.1), ("L_white", 0.5))}  # fmt: skip


def _target(kind="percentile"):
    if kind == "percentile":
        return ht.MeanLuminance(MEAN) + ht.Percentiles(Q, P)
    return ht.MeanLuminance(MEAN) + ht.ClippedFraction(CLIPPED)


def hdrjax_fit(method, x, max_size, kind="percentile", fixed=None, **batch):
    """``hdrjax.fit.fit``, or ``fit_batch`` when ``batch`` options (``vectorize``) are given;
    ``fixed``: further operator parameters set (not measured, not fitted)."""
    op = hdrjax.make_operator(method, **dict(START[method]), **(fixed or {}))
    names = tuple(n for n, _ in START[method])
    fn = hf.fit_batch if batch else hf.fit
    kw = dict(params=names, rtol=RTOL, atol=ATOL, max_size=max_size, **batch)
    return fn(op, x, _target(kind), **kw)


def _params(res, names):
    return {n: float(np.asarray(res.params[n]).reshape(-1)[0]) for n in names}


def load(quick: bool) -> tuple[np.ndarray, str]:
    rgb = np.asarray(hdrjax.io.read(REPO / "data" / "venice_sunset_1k.hdr").rgb(), np.float32)
    if quick:
        return rgb, "venice_sunset_1k.hdr (1024x512, as shipped)"
    big = np.repeat(np.repeat(rgb, 2, axis=0), 2, axis=1)
    return big, "venice_sunset_1k.hdr upscaled 2x by pixel repetition to 2048x1024"


def pan_frames(rgb: np.ndarray, n: int, size=(128, 256)) -> list[np.ndarray]:
    """``n`` windows of ¾ the image, moving from the top left to the bottom right corner,
    each box-filtered to ``size`` (float32)."""
    H_, W_ = rgb.shape[:2]
    ch, cw = 3 * H_ // 4, 3 * W_ // 4
    out = []
    for k in range(n):
        y, x = round(k * (H_ - ch) / (n - 1)), round(k * (W_ - cw) / (n - 1))
        out.append(np_downscale(rgb[y : y + ch, x : x + cw], max(size)).astype(np.float32))
    assert out[0].shape[:2] == size, out[0].shape
    return out


def _per_frame(t: dict, n: int) -> dict:
    """Timing divided per frame; the compile time (first − median) stays whole."""
    per = {"median_s": t["median_s"] / n, "spread_s": t["spread_s"] / n, "repeats": t["repeats"]}
    per["first_s"] = per["median_s"] + (t["first_s"] - t["median_s"])
    return per


def _res(shape) -> str:
    return f"{shape[1]}x{shape[0]}"


def fit_pair(
    case, method, rgb, x, max_size, kind="percentile", repeats=(7, 7), lbar=None, **common
):
    """Time one fit on both sides (hdrjax on ``x``, the scipy peer on ``rgb``) and record
    steps, loss, convergence and the fitted parameters of each. ``lbar``: reinhard2002's
    log-average given to both sides (not measured)."""
    names = tuple(n for n, _ in START[method])
    start = [v for _, v in START[method]]
    fixed = {"log_average": lbar} if lbar is not None else None
    t = H.measure(lambda: hdrjax_fit(method, x, max_size, kind, fixed=fixed), repeats[0])
    res = hdrjax_fit(method, x, max_size, kind, fixed=fixed)
    ours = _params(res, names)
    rec = H.record(
        BENCH,
        case,
        "hdrjax",
        timing=t,
        compiled=True,
        **common,
        dtype="float32",
        steps=int(res.steps),
        tolerance=f"optimistix LM rtol={RTOL:g} atol={ATOL:g} (max|dz|, max|dr|; λ÷3.5 at ρ≥0.75)",
        loss=float(res.loss),
        converged=bool(res.success),
        params=ours,
    )
    t = H.measure(lambda: scipy_fit(method, rgb, start, max_size, kind, lbar), repeats[1])
    sol = scipy_fit(method, rgb, start, max_size, kind, lbar)
    theirs = dict(zip(names, map(float, np.exp(sol.x)), strict=True))
    peer = H.record(
        BENCH,
        case,
        "scipy least_squares lm (NumPy)",
        timing=t,
        **common,
        dtype="float64",
        nfev=int(sol.nfev),
        residual_calls=int(sol.residual_calls),
        tolerance=f"MINPACK lm xtol=ftol={RTOL:g} gtol=1e-8",
        loss=float(np.sum(sol.fun**2)),
        converged=bool(sol.success),
        params=theirs,
        max_rel_param_diff=max(abs(ours[n] / theirs[n] - 1) for n in names),
    )
    return [rec, peer]


def solve_only(rgb: np.ndarray, source: str, repeats: int) -> list[dict]:
    """The solves alone: both sides get the 64×32 box-filtered image (float32) and, for
    reinhard2002, the log-average of the full image; the timed call is the least-squares
    solve (hdrjax: ``fit(..., max_size=None)``, one compiled call)."""
    import jax.numpy as jnp

    small = np_downscale(rgb, MAX_SIZE).astype(np.float32)
    xs = jnp.asarray(small)
    lbar = np_log_average(rgb)
    records = []
    for method in ("reinhard2002", "tumblin_reinhard"):
        case = f"{method} 2 params, solve only at {_res(small.shape)} (given image and log-average)"
        records += fit_pair(
            case,
            method,
            small,
            xs,
            None,
            repeats=(repeats, repeats),
            lbar=lbar if method == "reinhard2002" else None,
            image=source,
            fit_resolution=_res(small.shape),
        )
    return records


def single_fits(rgb: np.ndarray, source: str, repeats: int) -> list[dict]:
    """The two-parameter fits of both operators on ``rgb``, at ``MAX_SIZE``."""
    import jax.numpy as jnp

    x = jnp.asarray(rgb)
    fit_res = _res(np_downscale(rgb, MAX_SIZE).shape)
    common = dict(image=source, input_resolution=_res(rgb.shape), fit_resolution=fit_res)
    records = []
    for method in ("reinhard2002", "tumblin_reinhard"):
        case = f"{method} 2 params, {_res(rgb.shape)} input, fit at {fit_res}"
        records += fit_pair(case, method, rgb, x, MAX_SIZE, repeats=(repeats, repeats), **common)
    return records


def run(quick: bool = False) -> list[dict]:
    import jax.numpy as jnp

    repeats = 3 if quick else 7
    rgb, source = load(quick)
    x = jnp.asarray(rgb)
    records = single_fits(rgb, source, repeats)
    records += solve_only(rgb, source, repeats)

    # ---- batch: one call for all frames (sequential on CPU, vmapped) vs one call per frame
    tiles = pan_frames(rgb, 16 if quick else 64)
    frames = jnp.asarray(np.stack(tiles))
    n = frames.shape[0]
    fres = _res(np_downscale(tiles[0], MAX_SIZE).shape)
    case = f"reinhard2002 batch of {n} frames {_res(tiles[0].shape)}, fit at {fres} (per frame)"
    for impl, vec in (("hdrjax fit_batch (default: lax.map on CPU)", None),
                      ("fit_batch(vectorize=True) (vmapped)", True)):  # fmt: skip
        t = H.measure(lambda v=vec: hdrjax_fit("reinhard2002", frames, MAX_SIZE, vectorize=v),
                      repeats)  # fmt: skip
        res = hdrjax_fit("reinhard2002", frames, MAX_SIZE, vectorize=vec)
        records.append(
            H.record(
                BENCH,
                case,
                impl,
                timing=_per_frame(t, n),
                compiled=True,
                frames=n,
                converged=int(jnp.sum(res.success)),
                steps_max=int(jnp.max(res.steps)),
                steps_mean=float(jnp.mean(res.steps)),
                batch_s=t["median_s"],
            )  # fmt: skip
        )

    def loop():
        return [hdrjax_fit("reinhard2002", frames[i], MAX_SIZE) for i in range(n)]

    t = H.measure(loop, max(1, repeats // 2))
    singles = loop()
    per = _per_frame(t, n)
    records.append(
        H.record(
            BENCH,
            case,
            "one frame per call (hdrjax.fit loop)",
            timing=per,
            frames=n,
            steps_mean=float(np.mean([int(r.steps) for r in singles])),
            converged=int(sum(bool(r.success) for r in singles)),
        )  # fmt: skip
    )
    start = [v for _, v in START["reinhard2002"]]
    t = H.measure(lambda: [scipy_fit("reinhard2002", tl, start, MAX_SIZE) for tl in tiles], 1)
    per = _per_frame(t, n)
    records.append(H.record(BENCH, case, "scipy least_squares lm, one frame per call",
                            timing=per, frames=n))  # fmt: skip

    # ---- full resolution, sort-free targets (full mode only)
    if not quick:
        method = "reinhard2002"
        case = f"{method} 2 params at full resolution {_res(rgb.shape)}, mean + clipped"
        common = dict(image=source, input_resolution=_res(rgb.shape))
        records += fit_pair(case, method, rgb, x, None, "clipped", repeats=(3, 1),
                            fit_resolution=_res(rgb.shape), **common)  # fmt: skip
    import jax

    jax.clear_caches()
    return records


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, few repeats")
    ap.add_argument("--json", help="also write the records to this file")
    args = ap.parse_args()
    recs = run(quick=args.quick)
    if args.json:
        Path(args.json).write_text(json.dumps(recs, indent=2))
