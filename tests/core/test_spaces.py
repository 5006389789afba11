"""Working spaces (hdrjax.spaces, LayeredImage.rgb(space=...), the command line's
--working-space): conversions equal colour-science's RGB_to_RGB / XYZ_to_RGB, luminance stays
the file's, and files with non-sRGB chromaticities tone-map as colour-science's conversion
followed by the same operator."""

import subprocess
import sys

import colour
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from hdrjax import spaces
from hdrjax.cli import main
from hdrjax.io import read
from hdrjax.layers import LayeredImage

from ..conftest import DATA, SHARED_HDR, enable_x64

# chromaticities as the sample files store them (float32 in the EXR header)
XYZ_FILE = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.3333333432674408, 0.3333333432674408)
CARROTS = (0.7347, 0.2653, 0.0, 1.0, 9.9999997e-05, -0.077, 0.32168001, 0.33766999)
TREE = (0.62955, 0.341, 0.2867, 0.6108, 0.1489, 0.07125, 0.3155, 0.33165)  # Tree.exr
RNG = np.random.default_rng(7)
COLOURS = np.concatenate([RNG.uniform(0, 2, (64, 3)), np.eye(3), [[1e-3, 5.0, 0.2]]])


def _colourspace(c):
    return colour.RGB_Colourspace("file", np.reshape(c[:6], (3, 2)), c[6:])


@pytest.mark.parametrize("source", [CARROTS, TREE, "ACEScg", "sRGB", "Display P3"])
@pytest.mark.parametrize("target", ["sRGB", "ACEScg", "ITU-R BT.2020", "Display P3"])
@pytest.mark.parametrize("cat", ["CAT02", "Bradford"])
def test_matrices_equal_colour_science(source, target, cat):
    if source == target:  # colour-science goes through XYZ and back with rounded matrices
        assert np.array_equal(spaces.conversion_matrix(source, target, cat=cat), np.eye(3))
        return
    src = colour.RGB_COLOURSPACES[source] if isinstance(source, str) else _colourspace(source)
    want = colour.RGB_to_RGB(COLOURS, src, target, chromatic_adaptation_transform=cat)
    got = COLOURS @ spaces.conversion_matrix(source, target, cat=cat).T
    # 1e-6: files store chromaticities in float32, and within 1e-6 whites count as one
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6 * np.abs(want).max())


def test_xyz_is_converted_colorimetrically():
    """XYZ stored as RGB (OpenEXR's XYZ.exr: white E) goes to sRGB as colour-science's
    XYZ_to_RGB with no adaptation, and to "CIE XYZ" unchanged."""
    want = colour.XYZ_to_RGB(COLOURS, "sRGB")
    got = COLOURS @ spaces.conversion_matrix(XYZ_FILE, "sRGB").T
    np.testing.assert_allclose(got, want, atol=1e-12)
    np.testing.assert_allclose(spaces.conversion_matrix(XYZ_FILE, "CIE XYZ"), np.eye(3))
    back = COLOURS @ spaces.conversion_matrix("sRGB", "xyz").T
    np.testing.assert_allclose(back, colour.sRGB_to_XYZ(COLOURS, apply_cctf_decoding=False))


@pytest.mark.parametrize("source", [CARROTS, TREE, XYZ_FILE, None])
@pytest.mark.parametrize("target", ["sRGB", "ACEScg"])
def test_luminance_stays_the_files_own(source, target):
    """Y of the converted pixels with luminance_weights_in equals Y of the file's pixels
    with the file's own weights (the Y row of its RP 177 matrix, recomputed here with
    colour-science), across different whites too."""
    c = spaces.REC709_CHROMATICITIES if source is None else source
    own = colour.normalised_primary_matrix(np.reshape(c[:6], (3, 2)), c[6:])[1]
    if source is None:
        own = np.array([0.2126, 0.7152, 0.0722])  # BT.709's rounded weights
    if source is XYZ_FILE:
        own = np.array([0.0, 1.0, 0.0])  # colour-science cannot build y = 0 primaries
    converted = COLOURS @ spaces.conversion_matrix(source, target).T
    w = np.asarray(spaces.luminance_weights_in(source, target))
    np.testing.assert_allclose(converted @ w, COLOURS @ own, rtol=1e-9, atol=1e-12)


def test_weights_are_the_working_spaces_own_when_whites_agree():
    assert spaces.luminance_weights_in(None) == (0.2126, 0.7152, 0.0722)
    # colour-science's BT.2020 matrix and IEC 61966-2-1's rounded sRGB ones agree to 3e-5
    np.testing.assert_allclose(
        spaces.luminance_weights_in("ITU-R BT.2020", "sRGB"), (0.2126, 0.7152, 0.0722), atol=1e-4
    )
    # across whites CAT02 moves Y by per cents: the weights undo it (see the test above)
    w = spaces.luminance_weights_in(CARROTS, "sRGB")
    assert abs(w[0] - 0.2126) > 1e-3


def test_names_are_forgiving_and_errors_name_the_argument():
    assert spaces.space("aces cg").name == "ACEScg"
    assert spaces.space("itu-r bt.2020") == spaces.space("ITU-R BT.2020")
    assert spaces.space("srgb").is_rec709
    with pytest.raises(ValueError, match=r"working space: unknown name .*'ACEScg'"):
        spaces.space("AdobeRGB98x")
    with pytest.raises(ValueError, match="chromaticities: expected 8 finite numbers"):
        spaces.space((0.64, 0.33))
    with pytest.raises(ValueError, match="degenerate"):
        spaces.space((0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3127, 0.329))
    with pytest.raises(ValueError, match="cat: unknown chromatic adaptation transform 'CAT99'"):
        spaces.conversion_matrix(CARROTS, cat="CAT99")
    assert spaces.check_cat("bradford") == "Bradford"


def test_convert_is_differentiable_and_keeps_nan_in_its_pixel():
    m = spaces.conversion_matrix(XYZ_FILE)
    x = jnp.asarray(RNG.uniform(0, 1, (4, 5, 3)), jnp.float32).at[1, 2, 0].set(jnp.nan)
    y = jax.jit(spaces.convert)(x, m)
    bad = ~np.isfinite(np.asarray(y)).all(-1)
    assert bad[1, 2] and bad.sum() == 1
    g = np.asarray(jax.grad(lambda v: jnp.nansum(spaces.convert(v, m) ** 2))(x))
    assert np.isfinite(g[~bad]).all()
    assert spaces.convert(x.astype(jnp.float16), m).dtype == jnp.float32
    with enable_x64():
        assert spaces.convert(np.ones((2, 3)), m).dtype == jnp.float64


def test_conversion_is_one_expression_per_channel_for_the_fused_loop():
    """The matrix is applied as channel slices times its columns, broadcast: no concatenate
    and no dot, which in the operator's fused mapping loop branched on the channel (an XYZ
    file tone-mapped 1.3–1.5× slower than sRGB pixels; ``benchmarks/bench_colour.py``) or
    wrote the converted image out first. Equal to ``x @ m.T``."""
    from hdrjax._colour import apply_matrix

    m = spaces.conversion_matrix(XYZ_FILE).astype(np.float32)
    x = RNG.uniform(0, 1, (4, 5, 3)).astype(np.float32)
    prims = {e.primitive.name for e in jax.make_jaxpr(apply_matrix)(x, m).jaxpr.eqns}
    assert not prims & {"concatenate", "dot_general"}, prims
    np.testing.assert_allclose(np.asarray(apply_matrix(x, m)), x @ m.T, rtol=1e-6, atol=1e-7)


def test_srgb_files_do_not_import_colour_science():
    """sRGB needs no colour-science (its import costs ~2 s of every command's start-up)."""
    code = (
        "import sys; import hdrjax.spaces as s; import numpy as np;"
        "assert np.allclose(s.conversion_matrix(None), np.eye(3));"
        "s.conversion_matrix((1,0,0,1,0,0,1/3,1/3)); print('colour' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_layered_image_rgb_converts_into_the_working_space():
    xyz = RNG.uniform(0.01, 1, (3, 4, 3)).astype(np.float32)
    img = LayeredImage(xyz, chromaticities=XYZ_FILE)
    np.testing.assert_allclose(img.rgb(), colour.XYZ_to_RGB(xyz, "sRGB"), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(
        img.rgb("ACEScg"), colour.XYZ_to_RGB(xyz, "ACEScg"), rtol=1e-5, atol=1e-6
    )
    np.testing.assert_array_equal(img.native_rgb(), xyz)
    np.testing.assert_allclose(img.luminance(), xyz[..., 1], rtol=1e-6)  # Y is G
    plain = LayeredImage(xyz)  # no chromaticities: sRGB, nothing to convert
    assert plain.rgb() is plain.image


FIXED = {"key": 0.18, "L_white": 8.0, "log_average": 0.25}
"""Reinhard 2002's estimates set, so that the comparison is of the colours alone (measured,
they agree within the histogram's stated bound, not to 1e-5)."""


def _file_reference(path, c, method="reinhard2002"):
    """colour-science's conversion to sRGB, then the same operator with the weights that
    give the file's own luminance."""
    import hdrjax

    native = read(path).image.astype(np.float64)
    if c is XYZ_FILE:
        x = colour.XYZ_to_RGB(native, "sRGB")
    else:
        x = colour.RGB_to_RGB(native, _colourspace(c), "sRGB")
    w = spaces.luminance_weights_in(c)
    return np.asarray(hdrjax.tonemap(x.astype(np.float32), method, weights=w, **FIXED))


@pytest.mark.parametrize(
    "path, c",
    [
        (DATA / "XYZ.exr", XYZ_FILE),
        (DATA / "Carrots.exr", CARROTS),
        (SHARED_HDR / "Tree.exr", TREE),
    ],
    ids=["XYZ", "Carrots", "Tree"],
)
def test_files_tone_map_as_colour_science_then_the_operator(tmp_path, path, c):
    if not path.exists():
        pytest.skip(f"{path} needs ../shared")
    np.testing.assert_allclose(read(path).chromaticities, c, rtol=1e-6, atol=1e-7)
    out = tmp_path / "out.exr"
    sets = [a for k, v in FIXED.items() for a in ("--set", f"{k}={v}")]
    assert main(["tonemap", str(path), "-o", str(out), *sets]) == 0
    got = read(out).image
    np.testing.assert_allclose(got, _file_reference(path, c), rtol=0, atol=1e-5)


def test_xyz_flower_is_saturated_as_in_srgb():
    """The banana flower of XYZ.exr: converted, its mean saturation (HSV, linear values)
    is that of colour-science's sRGB version, 0.68 (README), not the 0.50 of XYZ shown
    as RGB."""
    native = read(DATA / "XYZ.exr").image
    rgb = read(DATA / "XYZ.exr").rgb()

    def saturation(x):
        x = np.clip(x, 0, None)
        mx, mn = x.max(-1), x.min(-1)
        return float(np.mean(np.where(mx > 0, (mx - mn) / np.where(mx > 0, mx, 1), 0)))

    want = saturation(colour.XYZ_to_RGB(native.astype(np.float64), "sRGB"))
    assert saturation(rgb) == pytest.approx(want, abs=1e-4)
    assert round(want, 2) == 0.68 and round(saturation(native), 2) == 0.50


SAMPLE_OPERATORS = ("reinhard2002", "tumblin_reinhard", "linear", "reinhard2002_local")
"""The default, the lighting-simulation operator, the simplest, and one whose statistics
alone take the luminance path (each check compiles four programs)."""


def test_every_operator_takes_the_folded_path_only_when_it_commutes():
    """The folded mapping is used exactly for operators whose mapping is
    AbstractLuminanceCurve's own (a ratio of luminance) and whose statistics are luminance
    alone: Schlick 1994 (own mapping), Budak 2005 and the per-channel curves do not."""
    import hdrjax
    from hdrjax.operators import AbstractLuminanceCurve
    from hdrjax.operators._base import maps_luminance_ratio

    ops = {n: hdrjax.make_operator(n) for n in hdrjax.operator_names() if n != "tabulated"}
    folded = {n for n, op in ops.items() if maps_luminance_ratio(op)}
    for name in folded:
        cls = hdrjax.get_operator(name)
        assert cls._apply is AbstractLuminanceCurve._apply, name
    assert {"reinhard2002", "tumblin_reinhard", "linear"} <= folded
    assert not folded & {"schlick1994", "budak2005", "gamma", "filmic", "reinhard2004"}


@pytest.mark.parametrize("name", SAMPLE_OPERATORS)
def test_operators_in_another_space_equal_them_on_converted_pixels(name):
    """measure_in_space/apply_in_space (the command line's path: statistics of the file's
    own luminance, conversion folded into the mapping) equal measure/apply on pixels
    converted first; a NaN pixel stays in its pixel."""
    import hdrjax
    from hdrjax.operators import apply_in_space, measure_in_space

    x = (RNG.lognormal(0.0, 1.5, (12, 16, 1)) * RNG.uniform(0.5, 1.5, (12, 16, 3))).astype(
        np.float32
    )
    m = spaces.conversion_matrix(CARROTS)
    op = hdrjax.make_operator(name).for_primaries(spaces.luminance_weights_in(CARROTS), None)
    converted = jnp.asarray(spaces.convert(x, m))
    want = np.asarray(op(converted))
    got = np.asarray(apply_in_space(measure_in_space(op, x, m), x, m))
    # statistics of the two luminance images agree to their rounding (~1e-7), which may
    # move a histogram estimate by a bin (2^-10): 1e-3 of a display value
    np.testing.assert_allclose(got, want, rtol=1e-3, atol=1e-4)
    bad = x.copy()
    bad[3, 4, 1] = np.nan
    out = np.asarray(apply_in_space(measure_in_space(op, bad, m), bad, m))
    nonfinite = ~np.isfinite(out).all(-1)
    assert nonfinite[3, 4] and nonfinite.sum() == 1


@pytest.mark.parametrize("ext", [".hdr", ".exr"])
def test_files_keep_their_primaries_with_their_pixels(tmp_path, ext):
    """An image in XYZ primaries written to Radiance (PRIMARIES line) or OpenEXR
    (chromaticities) reads back with the same primaries and the same pixels (not the
    working space's: the tag and the pixels agree)."""
    import hdrjax.io as hio

    xyz = RNG.uniform(0.05, 2.0, (4, 6, 3)).astype(np.float32)
    path = hio.write(tmp_path / f"xyz{ext}", LayeredImage(xyz, chromaticities=XYZ_FILE))
    got = read(path)
    np.testing.assert_allclose(got.chromaticities, XYZ_FILE, rtol=1e-5)
    # RGBE: 8-bit mantissas under one exponent per pixel
    tol = xyz.max(-1, keepdims=True) / 128 if ext == ".hdr" else 1e-6
    assert np.all(np.abs(got.native_rgb() - xyz) <= tol)
    assert np.all(np.abs(got.rgb() - colour.XYZ_to_RGB(xyz, "sRGB")) <= 5 * tol)
