"""The renderers' view transforms (hdrjax/operators/_view_transforms.py) against float64
NumPy transcriptions of their published code, each written here from its source (named
in a comment), on a real photograph and a grey ramp over 1e-4 … 1e4.

One batch per operator and dtype (the photograph and the ramp stacked), evaluated at two
exposures with the same compiled function; the other tests reuse that batch, so the file
compiles each operator once per dtype.
"""

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax

from ..conftest import DATA, RTOL32, RTOL64

SHAPE = (32, 48)
EXPOSURES = (0.0, 3.0)
"""The photograph's median is 0.02: +3 EV puts it near middle grey (both ends exercised)."""
ATOL32 = 5e-6
"""float32 outputs near 0 carry an absolute rounding error that a relative tolerance cannot
bound: AgX's golden look subtracts nearly equal numbers (its saturation step, then the
outset matrix), 3e-6 of display white on channels near 1e-3; the others stay below 4e-7."""
ATOL64 = 1e-12

CASES = [
    ("aces_narkowicz2015", {}),
    ("aces_hill", {}),
    ("agx", {}),
    ("agx", {"look": "punchy"}),
    ("agx", {"look": "golden"}),
    ("pbr_neutral", {}),
    ("hable2010", {}),
    ("uchimura2017", {}),
    ("lottes2016", {}),
]


def _ids(case):
    name, kw = case
    return "-".join([name, *kw.values()])


_FRAMES: dict = {}


def _frames() -> np.ndarray:
    """(2, 32, 48, 3) float64: MtTamNorth.exr box-filtered 24× (values 1e-4 … 8), and a
    grey ramp of 1536 log-spaced values from 1e-4 to 1e4."""
    if "frames" not in _FRAMES:
        rgb = np.asarray(hdrjax.io.read(DATA / "MtTamNorth.exr").rgb(), np.float64)
        photo = rgb[: 32 * 24, : 48 * 24].reshape(32, 24, 48, 24, 3).mean(axis=(1, 3))
        ramp = np.logspace(-4, 4, SHAPE[0] * SHAPE[1]).reshape(SHAPE)
        _FRAMES["frames"] = np.stack([photo, np.repeat(ramp[..., None], 3, axis=-1)])
    return _FRAMES["frames"]


def _run(name, kw, dtype):
    """The operator's outputs for the frames at each of :data:`EXPOSURES` (the exposure is
    a traced parameter: one compiled function), and the frames as the operator saw them."""
    op = hdrjax.make_operator(name, **kw)
    x = _frames().astype(dtype)
    outs = [
        np.asarray(dataclasses.replace(op, exposure=jnp.asarray(e, dtype))(x)) for e in EXPOSURES
    ]
    return outs, x.astype(np.float64)


# ---------------------------------------------------------------- published formulas (float64)


def narkowicz(x):
    # Narkowicz 2016, "ACES Filmic Tone Mapping Curve",
    # https://knarkowicz.wordpress.com/2016/01/06/aces-filmic-tone-mapping-curve/ (ACESFilm)
    a, b, c, d, e = 2.51, 0.03, 2.43, 0.59, 0.14
    return np.clip((x * (a * x + b)) / (x * (c * x + d) + e), 0, 1)


def hill(x):
    # Hill, BakingLab/ACES.hlsl (ACESFitted): mul(ACESInputMat, color), RRTAndODTFit,
    # mul(ACESOutputMat, color), saturate; https://github.com/TheRealMJP/BakingLab
    m_in = np.array(
        [[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]]
    )
    m_out = np.array(
        [
            [1.60475, -0.53108, -0.07367],
            [-0.10208, 1.10813, -0.00605],
            [-0.00327, -0.07276, 1.07602],
        ]
    )
    v = x @ m_in.T
    a = v * (v + 0.0245786) - 0.000090537
    b = v * (0.983729 * v + 0.4329510) + 0.238081
    return np.clip((a / b) @ m_out.T, 0, 1)


def _rgb_to_xyz(xy):
    # SMPTE RP 177: primaries' XYZ as columns, scaled so that RGB = 1 is the white (Y = 1)
    c = np.asarray(xy, np.float64).reshape(4, 2)
    xyz = np.stack([c[:, 0] / c[:, 1], np.ones(4), (1 - c[:, 0] - c[:, 1]) / c[:, 1]])
    return xyz[:, :3] * np.linalg.solve(xyz[:, :3], xyz[:, 3])


# ITU-R BT.709 and BT.2020 primaries, D65
REC709_TO_2020 = np.linalg.solve(
    _rgb_to_xyz([0.708, 0.292, 0.170, 0.797, 0.131, 0.046, 0.3127, 0.3290]),
    _rgb_to_xyz([0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290]),
)


def agx(x, look="none"):
    # three.js AgXToneMapping (src/renderers/shaders/ShaderChunk/tonemapping_pars_fragment
    # .glsl.js: Rec.709 -> Rec.2020, max 0, inset, log2 encoding, agxDefaultContrastApprox,
    # outset, pow 2.2, Rec.2020 -> Rec.709; its GLSL mat3 are column-major, written here
    # row-major) with Filament's agxLook (filament/src/ToneMapper.cpp) between the sigmoid
    # and the outset; the final clamp is the display's. The Rec.709/2020 matrices are the
    # exact ones of the primaries (three.js rounds BT.2407's to 4 decimals).
    inset = np.array(
        [
            [0.856627153315983, 0.0951212405381588, 0.0482516061458583],
            [0.137318972929847, 0.761241990602591, 0.101439036467562],
            [0.11189821299995, 0.0767994186031903, 0.811302368396859],
        ]
    )
    outset_inv = np.array(
        [
            [0.899796955911611, 0.0871996192028351, 0.013003424885555],
            [0.11142098895748, 0.875575586156966, 0.0130034248855548],
            [0.11142098895748, 0.0871996192028349, 0.801379391839686],
        ]
    )
    min_ev, max_ev = -12.47393, 4.026069
    v = np.maximum(x @ REC709_TO_2020.T, 0.0) @ inset.T
    v = np.log2(np.maximum(v, 1e-10))
    v = np.clip((v - min_ev) / (max_ev - min_ev), 0.0, 1.0)
    v2 = v * v
    v4 = v2 * v2
    v = (
        15.5 * v4 * v2
        - 40.14 * v4 * v
        + 31.96 * v4
        - 6.868 * v2 * v
        + 0.4298 * v2
        + 0.1191 * v
        - 0.00232
    )
    if look != "none":
        slope, power, sat = {
            "golden": ((1.0, 0.9, 0.5), 0.8, 1.3),
            "punchy": ((1.0, 1.0, 1.0), 1.35, 1.4),
        }[look]
        luma = (v @ np.array([0.2126, 0.7152, 0.0722]))[..., None]
        # the published pow is undefined for the sigmoid's slightly negative toe: 0 there
        v = luma + sat * (np.maximum(v * np.array(slope), 0.0) ** power - luma)
    v = v @ np.linalg.inv(outset_inv).T
    v = np.maximum(v, 0.0) ** 2.2
    return np.clip(v @ np.linalg.inv(REC709_TO_2020).T, 0.0, 1.0)


def pbr_neutral(x):
    # Khronos PBR Neutral specification (README.md of
    # https://github.com/KhronosGroup/ToneMapping/tree/main/PBR_Neutral), its equations
    f90, ks, kd = 0.04, 0.8 - 0.04, 0.15
    m = x.min(axis=-1, keepdims=True)
    f = np.where(m <= 2 * f90, m - m * m / (4 * f90), f90)
    p = (x - f).max(axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):  # (the branch not taken)
        pn = 1 - (1 - ks) ** 2 / (p + 1 - 2 * ks)
        g = 1 / (kd * (p - pn) + 1)
        return np.where(p <= ks, x - f, (x - f) * (pn / p) * g + pn * (1 - g))


def hable(x, A=0.15, B=0.50, C=0.10, D=0.20, E=0.02, F=0.30, W=11.2, bias=2.0):
    # Hable 2010, "Filmic Tonemapping Operators" (Uncharted2Tonemap, ExposureBias 2,
    # whiteScale), http://filmicworlds.com/blog/filmic-tonemapping-operators/; the
    # display clamps
    def u2(v):
        return ((v * (A * v + C * B) + D * E) / (v * (A * v + B) + D * F)) - E / F

    return np.clip(u2(bias * x) / u2(W), 0, 1)


def uchimura(x, P=1.0, a=1.0, m=0.22, l=0.4, c=1.33, b=0.0):  # noqa: E741
    # Uchimura 2017, "HDR theory and practice" (CEDEC), as transcribed by Romain Guy
    # (https://www.desmos.com/calculator/gslcdxvipg; the GLSL of dmnsgn/glsl-tone-map)
    l0 = ((P - m) * l) / a
    S0 = m + l0
    S1 = m + a * l0
    C2 = (a * P) / (P - S1)
    CP = -C2 / P
    t = np.clip(x / m, 0, 1)
    w0 = 1 - t * t * (3 - 2 * t)
    w2 = (x >= S0).astype(np.float64)
    w1 = 1 - w0 - w2
    T = m * (x / m) ** c + b
    S = P - (P - S1) * np.exp(CP * (x - S0))
    L = m + a * (x - m)
    return T * w0 + L * w1 + S * w2


def lottes(x, a=1.6, d=0.977, hdr_max=8.0, mid_in=0.18, mid_out=0.267):
    # Lottes 2016, GDC, "Advanced Techniques and Optimization of HDR Color Pipelines",
    # as transcribed by Romain Guy (b and c from midIn -> midOut and hdrMax -> 1); the
    # display clamps
    b = (-(mid_in**a) + hdr_max**a * mid_out) / ((hdr_max ** (a * d) - mid_in ** (a * d)) * mid_out)
    c = (hdr_max ** (a * d) * mid_in**a - hdr_max**a * mid_in ** (a * d) * mid_out) / (
        (hdr_max ** (a * d) - mid_in ** (a * d)) * mid_out
    )
    return np.clip(x**a / (x ** (a * d) * b + c), 0, 1)


REFERENCE = {
    "aces_narkowicz2015": narkowicz,
    "aces_hill": hill,
    "agx": agx,
    "pbr_neutral": pbr_neutral,
    "hable2010": hable,
    "uchimura2017": uchimura,
    "lottes2016": lottes,
}


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("case", CASES, ids=_ids)
def test_matches_the_published_formula(case, dtype, request):
    """Every transform (and AgX look) equals its published formula, float32 to
    ``RTOL32`` and float64 to ``RTOL64`` (with :data:`ATOL32`/:data:`ATOL64` near 0), on
    the photograph and the grey ramp, at exposure 0 and +3 EV (the reference is given
    ``2^exposure · RGB``)."""
    if dtype == np.float64:
        request.getfixturevalue("x64")
    name, kw = case
    outs, x = _run(name, kw, dtype)
    rtol, atol = (RTOL32, ATOL32) if dtype == np.float32 else (RTOL64, ATOL64)
    for e, out in zip(EXPOSURES, outs, strict=True):
        assert out.dtype == dtype
        ref = REFERENCE[name](x * 2.0**e, **kw)
        for frame, what in enumerate(("photograph", "grey ramp")):
            np.testing.assert_allclose(
                out[frame], ref[frame], rtol=rtol, atol=atol, err_msg=f"{what}, exposure {e}"
            )


def test_pbr_neutral_is_exact_on_every_branch(x64):
    """PBR Neutral to 1e-6 (relative, float64) of the specification's equations on
    colours chosen for each branch (smallest channel below and above 2 F90 = 0.08, peak
    below and above K_s = 0.76, grey, saturated, huge); the specification's own claims:
    colours with every channel in [0.08, 0.8] come out as ``c − 0.04`` (to 1e-15), and no
    hue shifts (the output's chroma direction is the input's)."""
    rng = np.random.default_rng(5)
    special = np.array(
        [
            [0.0, 0.0, 0.0],
            [0.01, 0.02, 0.05],
            [0.07999, 0.5, 0.3],
            [0.08, 0.5, 0.7],
            [0.2, 0.75, 0.76],
            [0.2, 0.75, 0.761],
            [0.5, 0.5, 0.5],
            [0.9, 0.9, 0.9],
            [0.0, 0.0, 3.0],
            [0.05, 2.0, 40.0],
            [1e3, 2e3, 5e3],
            [1e12, 1.0, 0.0],
        ]
    )
    colours = np.concatenate([special, rng.uniform(0.0, 4.0, (52, 3))]).reshape(8, 8, 3)
    out = np.asarray(hdrjax.make_operator("pbr_neutral")(colours))
    np.testing.assert_allclose(out, pbr_neutral(colours), rtol=1e-6, atol=1e-15)
    assert out.min() >= 0.0 and out.max() <= 1.0
    base = rng.uniform(0.08, 0.8, (1, 64, 3))
    np.testing.assert_allclose(
        np.asarray(hdrjax.make_operator("pbr_neutral")(base)), base - 0.04, rtol=0, atol=1e-15
    )
    chroma_in = colours - colours.mean(axis=-1, keepdims=True)
    chroma_out = out - out.mean(axis=-1, keepdims=True)
    norm_in = np.linalg.norm(chroma_in, axis=-1)
    coloured = norm_in > 1e-9
    cos = np.sum(chroma_in * chroma_out, axis=-1)[coloured] / (
        norm_in[coloured] * np.linalg.norm(chroma_out, axis=-1)[coloured]
    )
    np.testing.assert_allclose(cos, 1.0, atol=1e-12)


def test_agx_looks_change_the_image_and_punchy_keeps_grey_neutral(x64):
    """Both looks differ from none (by more than 0.05 somewhere); punchy's uniform slope
    and power keep greys grey (to 1e-12 in float64; float32's matrices keep them to about
    3e-5); golden's slope (1, 0.9, 0.5) tints greys warm (R ≥ G > B), as published: a look
    that tints cannot keep grey neutral. (float64: the programs of the x64 test above.)"""
    base, _ = _run("agx", {}, np.float64)
    punchy, _ = _run("agx", {"look": "punchy"}, np.float64)
    golden, _ = _run("agx", {"look": "golden"}, np.float64)
    for look in (punchy, golden):
        assert np.abs(look[1] - base[1]).max() > 0.05
    ramp = punchy[0][1]  # exposure 0, the grey ramp
    np.testing.assert_allclose(ramp[..., 0], ramp[..., 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(ramp[..., 2], ramp[..., 1], rtol=0, atol=1e-12)
    assert np.ptp(ramp[..., 1]) > 0.99  # the ramp spans black to white
    warm = golden[0][1]
    mid = (warm[..., 1] > 0.05) & (warm[..., 1] < 0.95)
    assert mid.sum() > 300
    assert np.all(warm[mid][:, 0] >= warm[mid][:, 1])
    assert np.all(warm[mid][:, 1] > warm[mid][:, 2] + 0.01)


def blender_sigmoid(u):
    # Blender 4.x's AgX sigmoid: Sobotka's calculate_sigmoid (EaryChow/AgX_LUT_Gen,
    # sigmoid.py, after Jed Smith's tunable sigmoid) with AgXBaseRec2020.py's settings:
    # pivots (10/16.5, 0.18^(1/2.4)), slope 2.4, powers 1.5, no linear section, limits
    # (0, 0) and (1, 1); its output is for a 2.4 display
    xp, yp, s, p = 10 / 16.5, 0.18 ** (1 / 2.4), 2.4, 1.5

    def scale(tx, ty):  # limits at 1, 1
        return ((s * (1 - tx)) ** -p * ((s * (1 - tx) / (1 - ty)) ** p - 1)) ** (-1 / p)

    def curve(k):
        z = s * (u - xp) / k
        return k * z / (1 + z**p) ** (1 / p) + yp

    with np.errstate(invalid="ignore"):  # (each branch is NaN on the other's side)
        return np.where(u < xp, curve(-scale(1 - xp, 1 - yp)), curve(scale(xp, yp)))


def test_agx_closeness_to_blender_quoted_in_the_docstring():
    """The figures AgX's docstring quotes: on greys (which every matrix keeps grey), the
    published polynomial's encoded output (``agx^(1/2.2)``) differs from Blender 4.x's
    sigmoid by up to 0.030, the display-linear outputs (``sigmoid^2.4`` for Blender) by up
    to 0.05, and middle grey 0.18 comes out as 0.215 where Blender's gives 0.18."""
    grey = _frames()[1][..., 1].reshape(-1)
    out, _ = _run("agx", {}, np.float32)
    ours = out[0][1][..., 1].reshape(-1).astype(np.float64)
    u = np.clip((np.log2(grey) + 12.47393) / 16.5, 0, 1)
    blender = blender_sigmoid(u)
    np.testing.assert_allclose(blender_sigmoid(np.array([10 / 16.5])) ** 2.4, 0.18, rtol=1e-12)
    assert abs(blender_sigmoid(np.array([0.0]))[0]) < 1e-12
    np.testing.assert_allclose(blender_sigmoid(np.array([1.0])), 1.0, rtol=1e-12)
    encoded = np.abs(ours ** (1 / 2.2) - blender).max()
    assert 0.029 < encoded <= 0.0305, encoded
    assert 0.04 < np.abs(ours - blender**2.4).max() <= 0.05
    mid = hdrjax.make_operator("agx")(np.full((1, 1, 3), 0.18, np.float32))
    np.testing.assert_allclose(np.asarray(mid), 0.2145, atol=5e-4)


def test_hable2010_is_filmic_with_the_blog_constants():
    """filmic is Hable's curve (the same function): hable2010 given filmic's constants
    (A = 0.22, B = 0.30, E = 0.01) equals filmic clamped to [0, 1]; with its own (the blog
    post's) they differ, and filmic exceeds 1 above its white."""
    x = _frames().astype(np.float32)
    filmic = np.asarray(hdrjax.make_operator("filmic")(x))
    same = hdrjax.make_operator(
        "hable2010", shoulder_strength=0.22, linear_strength=0.30, toe_numerator=0.01
    )
    np.testing.assert_allclose(np.asarray(same(x)), np.clip(filmic, 0, 1), rtol=1e-6, atol=0)
    assert filmic.max() > 1.1
    own, _ = _run("hable2010", {}, np.float32)
    assert np.abs(own[0] - np.clip(filmic, 0, 1)).max() > 0.05


@pytest.mark.parametrize(
    "name,params,needle",
    [
        ("uchimura2017", dict(linear_start=0.6, max_display=0.5), "linear_start: expected"),
        ("lottes2016", dict(mid_in=9.0), "mid_in: expected a value below hdr_max"),
        ("lottes2016", dict(mid_out=0.95), "mid_out: expected a value in (0.0023, 0.8697)"),
        ("lottes2016", dict(mid_out=0.001), "mid_out: expected a value in"),
        ("agx", dict(look="sepia"), "look: expected one of none | punchy | golden (agx)"),
        ("aces_hill", dict(exposure=100.0), "exposure: expected a value in [-64, 64]"),
    ],
)
def test_invalid_settings_are_refused(name, params, needle):
    with pytest.raises(ValueError) as err:
        hdrjax.make_operator(name, **params)
    msg = str(err.value)
    assert needle in msg and "\n" not in msg, msg
