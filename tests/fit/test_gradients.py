"""Gradients of every registered operator with respect to every differentiable parameter
agree with central finite differences in float64 on a real image (the Cornell box,
data/cornell_box.exr, box-filtered to 32 × 32).

The scalar differentiated is ``s(op) = mean(op(x) · w)`` with fixed random weights ``w``
(so each output channel and pixel counts differently). ``jax.grad`` of ``s`` with respect
to the operator (all parameters at once, compiled once per case) is compared with
``(s(p + h) − s(p − h)) / 2h``, ``h = 1e-6 · |p|``, element by element for vector parameters.

Registry-driven: a new operator, or a new parameter, fails :func:`test_every_parameter_is_covered`
until it has a case here (with a concrete value for parameters that default to ``None``) or
is listed in ``NOT_DIFFERENTIABLE`` with the reason.
"""

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax.operators import get_operator, make_operator, parameter_names

from ..conftest import DATA, enable_x64

RTOL = 1e-5
REL_STEP = 1e-6

# Static settings (equinox static fields: not pytree leaves, so not differentiable by
# construction), with the reason each is a setting rather than a parameter.
NOT_DIFFERENTIABLE = {
    "weights": "luminance weights of the file's primaries (a tuple fixed by the file)",
    "delta": "offset inside the *measured* log-average; no effect once log_average is set",
    "percentile_method": "algorithm choice (string)",
    "bins": "histogram size (integer)",
    "zones": "threshold of the discrete local/global switch of reinhard2002_auto",
    "phi": "reference-code sharpening constant; it moves the discrete scale selection",
    "epsilon": "threshold of the discrete scale selection (argmax over |V_i| > ε)",
    "s_low": "smallest Gaussian scale: sets integer kernel radii",
    "s_high": "largest Gaussian scale: sets integer kernel radii and the padding",
    "num": "number of scales (integer)",
    "adaptation": "choice of the adaptation estimate (string)",
    "gamma_log": "choice of logarithm in formula 1 (string)",
    "interpolation": "choice of interpolant (string)",
    "q": "linear: ISO 12232 lens constant (a static float; other operators' q is a parameter)",
    "space": "budak2005: the colour-contrast model (a module, not a number)",
    "chromaticities": "budak2005: the file's primaries (a tuple fixed by the file)",
    "look": "agx: choice of ASC CDL look (string)",
    "chroma": "reinhard2002: how colour is put back, ratio or ycbcr (string)",
    "white": "reinhard2002: how L_white is estimated, JGT Eq. 5 or the maximum (string)",
    "n_bins": "ward1997: histogram size (integer)",
    "ceiling": "ward1997: choice of the linear or human-contrast ceiling (string)",
    "compat": "choice of the peer whose departures from the paper are reproduced (string)",
    "display": "mantiuk2008: choice of pfstmo's named display (string)",
    "visual_model": "mantiuk2008: choice of the visual model's components (string)",
    "tol": "an iterative solver's stopping tolerance (a static float)",
    "max_iterations": "an iterative solver's iteration cap (integer)",
    "offset": "lischinski2006: luminance offset of the zones' origin and the log luminance"
    " (a static float, HDR Toolbox's)",
    "zone_quantile": "lischinski2006: quantile of each zone from the histogram (constant for"
    " jax.grad)",
    "sigma_s": "durand2002: spatial scale; sets the integer kernel radius and the halo",
    "max_segments": "durand2002: static bound on the bilateral filter's segments (integer)",
    "mode": "mantiuk2006: contrast mapping or contrast equalisation (string)",
    "detail_level": "fattal2002: number of pyramid levels left unattenuated (integer)",
    "black_point": "fattal2002: percent of pixels below black; static, it sizes the percentile's"
    " partial selection",
    "white_point": "fattal2002: percent of pixels above white; static, it sizes the percentile's"
    " partial selection",
    "kernel_grid": "ferradans2011: fewest samples of the convolutions' grid (integer; it sets"
    " the box factors)",
    "s_max": "ashikhmin2002: number of blur scales (integer)",
    "threshold": "ashikhmin2002: threshold of the discrete scale selection",
    "sigma": "chiu1993: blur scale in pixels; sets the integer kernel width and the halo",
    "passes": "chiu1993: number of smoothing passes (integer)",
    "glare_size": "chiu1993: glare kernel width in pixels (integer)",
    "range_sigma": "krawczyk2005: bilateral grid's range sampling; sets the grid's depth",
    "anchor_percentile": "krawczyk2005: histogram percentile (a rank: constant for jax.grad)",
    "merge_distance": "krawczyk2005: threshold of the discrete merging of frameworks",
    "min_probability": "krawczyk2005: threshold of the discrete merging of frameworks",
    "surround": "kuang2007: choice of the viewing surround's lightness exponent (string)",
    "references": "paris2011: number of reference intensities (integer; the scan's length)",
    "clip_percent": "paris2011: percent of pixels outside the display range; static, it sizes"
    " the percentile's partial selection",
}

# Array parameters that select a branch: their derivative is 0 (a step), checked as
# exactly 0 rather than against central differences.
DISCRETE = {
    ("reinhard2002_auto", "local"): "the local/global choice (1 or 0) of the JGT switch",
    ("mantiuk2008", "white_y"): "selects the curve node pulled to the display's peak",
    ("lischinski2006", "zone_origin"): "moves the pixels' discrete zone assignment only",
}

# Vector parameters only some of whose elements reach the output on the test image: an
# element without effect (zero central difference) must have a gradient of exactly 0, the
# others are compared as usual.
SPARSE = {
    ("mai2011", "curve"): "tone-curve nodes outside the image's luminances (and below"
    " pfstmo's floor of 1e-5) map no pixel",
    ("ward1997", "cdf"): "tone-curve points between the bins the image's luminances fill",
    ("mantiuk2008", "curve"): "tone-curve nodes outside the image's luminances map no pixel",
    ("lischinski2006", "zone_exposures"): "zones outside the image's luminances hold no pixel",
}

R2004 = dict(f=0.5, m=0.6, a=0.3, c=0.4, channel_average=[0.2, 0.3, 0.25], log_average=0.05,
             L_min=1e-3, L_max=12.0)  # fmt: skip

# operator, settings/values, the parameters differentiated in this case (all of them
# matter here: the test also checks each gradient is non-zero). Values are away from the
# kinks of max(q, 1), where(m > 0) and where(L_wa > 100).
CASES = [
    ("aces_hill", dict(exposure=0.5), ("exposure",)),
    ("aces_narkowicz2015", dict(exposure=0.5), ("exposure",)),
    (
        "ashikhmin2002",
        dict(L_dmax=90.0, L_min=1e-3, L_max=20.0),
        ("L_dmax", "L_min", "L_max"),
    ),
    ("agx", dict(exposure=0.5), ("exposure",)),
    (
        "drago2003",
        dict(bias=0.8, L_dmax=90.0, log_average=0.05, L_max=12.0),
        ("bias", "L_dmax", "log_average", "L_max"),
    ),
    (
        "fattal2002",
        dict(alpha=1.2, beta=0.85, gamma=0.7, saturation=0.6, noise=0.01),
        ("alpha", "beta", "gamma", "saturation", "noise"),
    ),
    (  # through the solve (converged: the gradient is the solution's)
        "mantiuk2006",
        dict(
            contrast_factor=0.15, saturation=0.7, detail_factor=1.2, max_iterations=500, tol=1e-12
        ),
        ("contrast_factor", "saturation", "detail_factor"),
    ),
    (
        "paris2011",
        dict(sigma_r=0.8, alpha=0.8, beta=0.3, contrast=80.0),
        ("sigma_r", "alpha", "beta", "contrast"),
    ),
    (
        "durand2002",
        dict(
            sigma_r=0.5,
            base_contrast=4.0,
            saturation=0.8,
            L_min=1e-3,
            L_max=20.0,
            L_low=0.01,
            L_high=5.0,
        ),
        ("sigma_r", "base_contrast", "saturation", "L_min", "L_max", "L_low", "L_high"),
    ),
    ("chiu1993", dict(k=6.0, glare=0.7, glare_power=6.0), ("k", "glare", "glare_power")),
    # a fixed number of iterations (tol 0): the stopping iteration is piecewise constant
    (
        "ferradans2011",
        dict(rho=-1.5, inv_alpha=4.0, tol=0.0, max_iterations=3),
        ("rho", "inv_alpha"),
    ),
    ("krawczyk2005", dict(articulation_sigma=1.0), ("articulation_sigma",)),
    (
        "lischinski2006",
        dict(
            alpha=1.3,
            lambda_=0.3,
            epsilon=0.05,
            constraint_weight=0.1,
            zone_origin=1e-3,
            zone_exposures=np.linspace(-4.0, 1.0, 144),
            tol=1e-14,
        ),
        ("alpha", "lambda_", "epsilon", "constraint_weight", "zone_origin", "zone_exposures"),
    ),
    # the key and log-average reach the output through the zones' targets measured from
    # the histogram (the case compiles the statistics pass)
    (
        "lischinski2006",
        dict(key=0.2, log_average=0.05, zone_origin=1e-3, tol=1e-13),
        ("key", "log_average"),
    ),
    (
        "kuang2007",
        dict(L_peak=15000.0, p=0.7, sigma_r=0.4, L_max=20.0),
        ("L_peak", "p", "sigma_r", "L_max"),
    ),
    ("ferwerda1996", dict(L_wa=0.5, L_dmax=100.0), ("L_wa", "L_dmax")),
    ("ferwerda1996", dict(L_wa=0.5, L_dmax=100.0, compat="hdrtoolbox"), ("L_wa", "L_dmax")),
    (
        "hable2010",
        dict(
            exposure=0.5,
            shoulder_strength=0.15,
            linear_strength=0.5,
            linear_angle=0.1,
            toe_strength=0.2,
            toe_numerator=0.02,
            toe_denominator=0.3,
            exposure_bias=2.0,
            linear_whitepoint=11.2,
        ),  # fmt: skip
        (
            "exposure",
            "shoulder_strength",
            "linear_strength",
            "linear_angle",
            "toe_strength",
            "toe_numerator",
            "toe_denominator",
            "exposure_bias",
            "linear_whitepoint",
        ),  # fmt: skip
    ),
    (
        "lottes2016",
        dict(exposure=0.5, contrast=1.5, shoulder=0.97, hdr_max=9.0, mid_in=0.2, mid_out=0.25),
        ("exposure", "contrast", "shoulder", "hdr_max", "mid_in", "mid_out"),
    ),
    (
        "pbr_neutral",
        dict(exposure=0.5, start_compression=0.7, desaturation=0.2),
        ("exposure", "start_compression", "desaturation"),
    ),
    (
        "reinhard2005",
        dict(
            f=0.5, c=0.4, l=0.6, m=0.6, channel_average=[0.2, 0.3, 0.25], V_min=0.02, V_max=0.9
        ),  # fmt: skip
        ("f", "c", "l", "m", "channel_average", "V_min", "V_max"),
    ),
    (
        "reinhard2005",
        dict(
            f=0.5,
            c=0.4,
            l=0.6,
            channel_average=[0.2, 0.3, 0.25],
            log_average=0.05,
            L_min=1e-3,
            L_max=12.0,
            V_min=0.02,
            V_max=0.9,
            compat="pfstmo",
        ),  # fmt: skip
        ("log_average", "L_min", "L_max", "V_min", "V_max"),
    ),
    (
        "tumblin_rushmeier1993",
        dict(L_wa=0.5, L_dmax=100.0, C_max=100.0),
        ("L_wa", "L_dmax", "C_max"),
    ),
    (
        "uchimura2017",
        dict(
            exposure=0.5,
            max_display=0.95,
            contrast=1.1,
            linear_start=0.25,
            linear_length=0.35,
            black_tightness=1.3,
            pedestal=0.01,
        ),  # fmt: skip
        (
            "exposure",
            "max_display",
            "contrast",
            "linear_start",
            "linear_length",
            "black_tightness",
            "pedestal",
        ),  # fmt: skip
    ),
    ("ward1994", dict(L_wa=0.5, L_dmax=100.0), ("L_wa", "L_dmax")),
    (
        "vanhateren2006",
        dict(pupil_area=12.0, k_beta=1.5e-4, c_beta=3e-3, a_C=0.1),
        ("pupil_area", "k_beta", "c_beta", "a_C"),
    ),
    (
        "kimkautz2008",
        dict(
            L_dmax=280.0,
            L_dmin=0.4,
            c1=2.5,
            c2=0.6,
            log_average=0.05,
            L_min=3e-3,
            L_max=12.0,
            L_low=5e-3,
            L_high=0.8,
        ),
        ("L_dmax", "L_dmin", "c1", "c2", "log_average", "L_min", "L_max", "L_low", "L_high"),
    ),
    (
        "pattanaik2000",
        dict(display_adaptation=30.0, A_cone=0.5, A_rod=0.2),
        ("display_adaptation", "A_cone", "A_rod"),
    ),
    ("mai2011", dict(curve=np.linspace(0.0, 0.95, 151) ** 0.8 + 0.01), ("curve",)),
    (
        "mantiuk2008",
        dict(
            curve=np.linspace(-0.05, 2.0, 161) + 0.1 * np.sin(np.linspace(0.0, 6.0, 161)),
            gamma=2.4,
            peak=150.0,
            black=0.5,
            ambient=40.0,
            reflectivity=0.02,
            saturation=0.9,
        ),
        ("curve", "gamma", "peak", "black", "ambient", "reflectivity", "saturation"),
    ),
    (  # through the solver's fixed point (converged: the gradient is the fixed point's)
        "mantiuk2008",
        dict(contrast_enhancement=1.2, scene_luminance=500.0, white_y=0.5, tol=1e-10),
        ("contrast_enhancement", "scene_luminance", "white_y"),
    ),
    (
        "ward1997",
        dict(
            L_min=0.01, L_max=50.0, cdf=np.linspace(0.001, 1, 101) ** 0.7, L_dmin=1.0, L_dmax=100.0
        ),
        ("L_dmin", "L_dmax", "L_min", "L_max", "cdf"),
    ),
    (
        "budak2005",
        dict(display_max=80.0, adaptation=0.5, background=[0.3, 0.25, 0.2]),
        ("display_max", "adaptation", "background"),
    ),
    ("exponential", dict(q=1.5, k=1.2, log_average=0.05), ("q", "k", "log_average")),
    ("exponentiation_mapping", dict(p=0.8, q=1.3, L_max=12.0), ("p", "q", "L_max")),
    (
        "filmic",
        dict(
            shoulder_strength=0.22,
            linear_strength=0.3,
            linear_angle=0.1,
            toe_strength=0.2,
            toe_numerator=0.01,
            toe_denominator=0.3,
            exposure_bias=2.0,
            linear_whitepoint=11.2,
        ),
        (
            "shoulder_strength",
            "linear_strength",
            "linear_angle",
            "toe_strength",
            "toe_numerator",
            "toe_denominator",
            "exposure_bias",
            "linear_whitepoint",
        ),
    ),
    ("gamma", dict(gamma=2.2, EV=0.5), ("gamma", "EV")),
    ("linear", dict(L_max=5.0), ("L_max",)),
    ("linear", dict(ev100=3.0), ("ev100",)),
    (
        "linear",
        dict(exposure_time=1.0, f_number=2.0, iso=100.0),
        ("exposure_time", "f_number", "iso"),
    ),
    ("logarithmic", dict(q=2.0, k=1.5, L_max=12.0), ("q", "k", "L_max")),
    ("logarithmic_mapping", dict(p=2.0, q=1.3, L_max=12.0), ("p", "q", "L_max")),
    ("normalisation", dict(L_max=12.0), ("L_max",)),
    (
        "reinhard2002",
        dict(key=0.2, L_white=3.0, log_average=0.05),
        ("key", "L_white", "log_average"),
    ),
    # zones=1000 forces the global branch, where L_white counts (the Cornell box spans
    # > 11 zones: by default the local branch runs, which is reinhard2002_local's code)
    (
        "reinhard2002_auto",
        # local=0: the global branch (the choice itself is a step: its derivative is 0)
        dict(key=0.2, L_white=3.0, log_average=0.05, local=0.0),
        ("key", "L_white", "log_average", "local"),
    ),
    ("reinhard2002_local", dict(key=0.2, log_average=0.05), ("key", "log_average")),
    ("reinhard2004", R2004, ("f", "m", "a", "c", "channel_average", "log_average")),
    # m ≤ 0 selects the automatic contrast, which uses L_min and L_max
    ("reinhard2004", {**R2004, "m": -1.0}, ("L_min", "L_max", "log_average")),
    ("schlick1994", dict(p=3.0, L_max=12.0), ("p", "L_max")),
    (
        "tabulated",
        dict(luminance=[1e-3, 1e-2, 0.1, 1.0, 10.0], display=[0.02, 0.1, 0.35, 0.7, 0.95]),
        ("luminance", "display"),
    ),
    (
        "tabulated",
        dict(
            luminance=[1e-3, 1e-2, 0.1, 1.0, 10.0],
            display=[0.02, 0.1, 0.35, 0.7, 0.95],
            interpolation="linear",
        ),
        ("luminance", "display"),
    ),
    (
        "tumblin1999",
        dict(L_da=20.0, C_max=100.0, L_max=100.0, L_wa=0.5),
        ("L_da", "C_max", "L_max", "L_wa"),
    ),  # fmt: skip
    (
        "tumblin_reinhard",
        dict(L_wa=0.5, L_white=0.8, L_da=20.0, C_max=100.0, L_dmax=100.0),
        ("L_wa", "L_white", "L_da", "C_max", "L_dmax"),
    ),
    # L_white left to the operator (T(L_max) / L_dmax): L_max counts through it
    (
        "tumblin_reinhard",
        dict(L_wa=0.5, L_max=8.0, L_da=20.0, C_max=100.0, L_dmax=100.0),
        ("L_wa", "L_max", "L_da", "C_max", "L_dmax"),
    ),
]

NO_PARAMETERS = ("simple",)  # RGB / (RGB + 1): nothing to differentiate


def _case_id(case):
    name, values, _ = case
    tags = {"local": "global", "interpolation": "linear"}
    if name == "linear" or (name == "tumblin_reinhard" and "L_white" not in values):
        return f"{name}-{next(iter(values)) if name == 'linear' else 'L_max'}"
    if name == "reinhard2004" and values["m"] <= 0:
        return f"{name}-auto_m"
    return "-".join([name, *[t for k, t in tags.items() if k in values]])


@pytest.fixture(scope="module")
def image():
    rgb = np.asarray(hdrjax.io.read(DATA / "cornell_box.exr").rgb(), np.float64)
    return rgb.reshape(32, 16, 32, 16, 3).mean(axis=(1, 3))


def _params_of(cls):
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    diff = [n for n, f in fields.items() if not f.metadata.get("static", False)]
    static = [n for n, f in fields.items() if f.metadata.get("static", False)]
    return diff, static


def test_every_parameter_is_covered():
    covered: dict[str, set[str]] = {}
    for name, _, names in CASES:
        covered.setdefault(name, set()).update(names)
    for name in hdrjax.operator_names():
        cls = get_operator(name)
        diff, static = _params_of(cls)
        assert set(diff) | set(static) == set(parameter_names(cls))
        missing = sorted(set(static) - set(NOT_DIFFERENTIABLE))
        assert not missing, f"{name}: static settings {missing} need a reason here"
        if name in NO_PARAMETERS:
            assert diff == [], name
            continue
        assert covered.get(name) == set(diff), f"{name}: parameters without a gradient case"


@pytest.mark.parametrize("case", CASES, ids=[_case_id(c) for c in CASES])
def test_gradient_matches_central_differences(case, image):
    name, values, names = case
    with enable_x64():
        x = jnp.asarray(image)
        w = jnp.asarray(np.random.default_rng(0).uniform(0.5, 1.5, image.shape))
        op = make_operator(name, **values)
        assert not set(names) & set(op.unset())  # concrete values for automatic ones

        def scalar(o):
            return jnp.mean(o(x) * w)

        value = eqx.filter_jit(scalar)
        grads = eqx.filter_jit(eqx.filter_grad(scalar))(op)
        for n in names:
            p = np.asarray(getattr(op, n), np.float64)
            g = np.asarray(getattr(grads, n), np.float64)
            assert g.shape == p.shape and np.all(np.isfinite(g)), n
            if (name, n) in DISCRETE:
                assert np.all(g == 0), f"{name}.{n}: a branch choice has derivative 0"
                continue
            fd = np.zeros_like(p)
            for i in np.ndindex(p.shape):
                h = REL_STEP * abs(p[i])
                s = []
                for sign in (1.0, -1.0):
                    q = p.copy()
                    q[i] += sign * h
                    moved = eqx.tree_at(lambda o, n=n: getattr(o, n), op, jnp.asarray(q))
                    s.append(float(value(moved)))
                fd[i] = (s[0] - s[1]) / (2 * h)
            if (name, n) in SPARSE:
                reached = fd != 0
                assert reached.sum() > 1, f"{name}.{n} has no effect here"
                assert np.all(g[~reached] == 0), f"{name}.{n}: gradient without effect"
                g, fd = g[reached], fd[reached]
            assert np.all(np.abs(fd) > 0), f"{name}.{n} has no effect here: {fd}"
            np.testing.assert_allclose(g, fd, rtol=RTOL, atol=1e-10, err_msg=f"{name}.{n}")
