"""hdrjax.spectral: spectral images integrated to CIE XYZ, against colour-science.

References: colour-science's ``msds_to_XYZ(..., method="Integration")`` and ``sd_to_XYZ``
(called directly), its tabulated CIE 1931 / 1964 colour-matching functions, CIE 1924
V(λ) and D65, and the 24 ColorChecker reflectances of Ohta (colour-science's
``"ColorChecker N Ohta"``, 380-780 nm at 5 nm) written to spectral OpenEXR files in the
layout of Fichet, Pacanowski & Wilkie 2021.
"""

import warnings

import colour
import jax
import jax.numpy as jnp
import numpy as np
import OpenEXR
import pytest

import hdrjax.io as hio
from hdrjax.layers import LayeredImage
from hdrjax.spaces import convert_to
from hdrjax.spectral import K_M, spectral_kind, spectral_to_xyz, spectral_weights

from ..conftest import RTOL32, RTOL64

CMFS_1931 = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
CMFS_1964 = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"]
D65 = colour.SDS_ILLUMINANTS["D65"]
E = colour.SDS_ILLUMINANTS["E"]
WL31 = np.arange(400.0, 701.0, 10.0)
"""31 bands, 400-700 nm at 10 nm: the usual sampling of measured reflectances."""

DELTA_E_MAX = 0.5
"""ΔE2000 allowed against colour-science's sRGB (its default ASTM E308 method; hdrjax
follows its "Integration" method). Largest measured: 0.02 against the same 31 bands, 0.09
against the full 5 nm spectra."""
LUMINANCE_RTOL = 1e-3
"""Relative luminance difference allowed against colour-science's ASTM E308 Y of the same
31 bands (largest measured: 6e-5 reflective, 2.4e-4 emissive, where hdrjax interpolates
the product of reflectance and D65 sampled at 10 nm)."""
BAND_FLATNESS = 5e-3
"""ȳ stays within 0.5 % of 1 over 551-559 nm (CIE 1931 tables: 0.9967 at 551 nm)."""

D65_XY = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]


def _quiet(fn, *args, **kwargs):
    """colour-science warns about each alignment it performs."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*args, **kwargs)


def _msds_xyz(samples, wavelengths, cmfs=CMFS_1931, illuminant=D65, **kwargs):
    """colour-science's own integration of spectra ``(n, bands)``: ``(n, 3)``."""
    msds = colour.MultiSpectralDistributions(np.asarray(samples, np.float64).T, wavelengths)
    return np.asarray(
        _quiet(colour.msds_to_XYZ, msds, cmfs, illuminant, method="Integration", **kwargs)
    ).reshape(-1, 3)


def _lab_of_srgb(rgb):
    xyz = colour.sRGB_to_XYZ(np.asarray(rgb, np.float64), apply_cctf_decoding=False)
    return colour.XYZ_to_Lab(xyz, D65_XY)


@pytest.fixture(scope="module")
def checker():
    """``(reflectance (4, 6, 31), {name: (reference sRGB (24, 3), reference Y (24,))})``:
    the Ohta reflectances sampled at :data:`WL31`, and colour-science's
    ``XYZ_to_sRGB(sd_to_XYZ(sd, cmfs, D65) / 100)`` (default ASTM E308 method, white
    Y = 1) of those 31 samples (``"31 bands"``) and of the full 5 nm spectra (``"full"``)."""
    sds = list(colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"].values())
    refl = np.array([[sd[w] for w in WL31] for sd in sds])
    refs = {}
    for name, spectra in (
        ("31 bands", [colour.SpectralDistribution(r, WL31) for r in refl]),
        ("full", sds),
    ):
        xyz = np.array([_quiet(colour.sd_to_XYZ, sd, CMFS_1931, D65) for sd in spectra]) / 100
        refs[name] = (colour.XYZ_to_sRGB(xyz, apply_cctf_encoding=False), xyz[:, 1])
    return refl.reshape(4, 6, 31), refs


def _check_srgb(xyz, refs):
    """sRGB of ``xyz`` within ΔE2000 0.5 of both references; Y within 0.1 % of the same
    31 bands' (against the full spectra the 400-700 nm truncation alone costs 0.097 %)."""
    rgb = np.asarray(convert_to(jnp.asarray(xyz).reshape(24, 3), "CIE XYZ", "sRGB"))
    for srgb_ref, _ in refs.values():
        d_e = colour.delta_E(_lab_of_srgb(rgb), _lab_of_srgb(srgb_ref), method="CIE 2000")
        assert d_e.max() < DELTA_E_MAX, d_e.max()
    y_ref = refs["31 bands"][1]
    np.testing.assert_allclose(np.asarray(xyz)[..., 1].ravel(), y_ref, rtol=LUMINANCE_RTOL)


def _check_layered_rgb(img, xyz):
    """The file as every command reads it (``LayeredImage.rgb()``, the sRGB working
    space) is the XYZ checked above, converted; its luminance is Y."""
    want = np.asarray(convert_to(jnp.asarray(xyz), "CIE XYZ", "sRGB"))
    np.testing.assert_allclose(img.rgb(), want, rtol=RTOL32, atol=1e-6 * np.abs(want).max())
    np.testing.assert_allclose(img.luminance(), np.asarray(xyz)[..., 1], rtol=RTOL32)


def test_colorchecker_reflective_exr(tmp_path, checker):
    """Reflectances stored as Fichet et al. 2021's ``T.<λ>nm`` channels (written with the
    OpenEXR bindings, as another program would), read back and integrated under D65."""
    refl, refs = checker
    channels = {
        "T." + f"{w:.6f}".replace(".", ",") + "nm": np.ascontiguousarray(refl[..., i], np.float32)
        for i, w in enumerate(WL31)
    }
    header = {
        "compression": OpenEXR.ZIP_COMPRESSION,
        "type": OpenEXR.scanlineimage,
        "spectralLayoutVersion": "1.0",
    }
    path = tmp_path / "checker_reflective.exr"
    OpenEXR.File(header, channels).write(str(path))
    img = hio.read(path)
    assert img.kind == "spectral" and spectral_kind(img.channels) == "reflective"
    np.testing.assert_array_equal(img.wavelengths, WL31.astype(np.float32))
    xyz = spectral_to_xyz(img.image, img.wavelengths, kind="reflective")
    # the same 31 samples through colour-science's own path: equal to float32 rounding
    ref31 = _msds_xyz(refl.reshape(24, 31), WL31) / 100
    np.testing.assert_allclose(np.asarray(xyz).reshape(24, 3), ref31, rtol=RTOL32)
    _check_srgb(xyz, refs)
    _check_layered_rgb(img, xyz)


def test_colorchecker_emissive_exr(tmp_path, checker):
    """The same patches lit by D65 as spectral radiance (white at 100 cd/m²), written by
    hdrjax.io.write in the Fichet layout and read back: Y in cd/m²."""
    refl, refs = checker
    d65_1nm = _quiet(D65.copy().align, CMFS_1931.shape)
    white = K_M * np.sum(CMFS_1931.values[:, 1] * d65_1nm.values)  # cd/m² per unit D65
    radiance = refl * np.array([D65[w] for w in WL31]) * (100.0 / white)
    img = LayeredImage(
        image=radiance.astype(np.float32), layers={"wavelengths": WL31}, quantity="radiance"
    )
    path = hio.write(tmp_path / "checker_emissive.exr", img)
    with OpenEXR.File(str(path), separate_channels=True) as f:
        head = f.parts[0].header
        assert "S0.400,000000nm" in f.parts[0].channels and len(f.parts[0].channels) == 31
        assert head["spectralLayoutVersion"] == "1.0"
        assert head["emissiveUnits"] == "W.m^-2.sr^-1"
    got = hio.read(path)
    assert got.kind == "spectral" and spectral_kind(got.channels) == "emissive"
    assert got.quantity == "radiance"
    xyz = spectral_to_xyz(got.image, got.wavelengths, kind="emissive")
    ref31 = _msds_xyz(got.image.reshape(24, 31), WL31, illuminant=E, k=K_M)
    np.testing.assert_allclose(np.asarray(xyz).reshape(24, 3), ref31, rtol=RTOL32)
    _check_srgb(np.asarray(xyz) / 100.0, refs)
    _check_layered_rgb(got, xyz)


def test_flat_spectrum_photometry(x64):
    """1 W/(sr·m²·nm) over 360-830 nm (5 nm samples) is 683 lm/W × ∫V(λ)dλ cd/m² (CIE 1924
    V(λ) = CIE 1931 ȳ, summed at 1 nm); sampled at 400-700 nm only, colour-science's
    constant extrapolation continues it to 360-830 nm, so the same value."""
    V = colour.SDS_LEFS["CIE 1924 Photopic Standard Observer"]
    assert V.shape.interval == 1
    expected = K_M * np.sum(V.values) * V.shape.interval
    full = spectral_to_xyz(np.ones(95), np.arange(360.0, 831.0, 5.0))
    coarse = spectral_to_xyz(np.ones(31), WL31)
    assert full.dtype == jnp.float64
    np.testing.assert_allclose(float(full[1]), expected, rtol=RTOL64)
    np.testing.assert_allclose(float(coarse[1]), expected, rtol=RTOL64)
    np.testing.assert_allclose(float(expected), 72983.27, rtol=1e-7)


def test_narrow_band_at_555nm(x64):
    """2 W/(sr·m²·nm) over 551-559 nm (1 nm samples, zero from 540 to 570 nm and so,
    extrapolated, beyond) gives 683 × 2 × Σ ȳ cd/m², within 0.5 % of 683 lm/W × radiance ×
    9 nm since ȳ ≈ 1 there."""
    wl = np.arange(540.0, 571.0)
    spectrum = np.where((wl >= 551) & (wl <= 559), 2.0, 0.0)
    Y = float(spectral_to_xyz(spectrum, wl)[1])
    ybar = np.array([CMFS_1931[w][1] for w in range(551, 560)])
    np.testing.assert_allclose(Y, K_M * 2.0 * ybar.sum(), rtol=RTOL64)
    np.testing.assert_allclose(Y, K_M * 2.0 * 9.0, rtol=BAND_FLATNESS)


@pytest.mark.parametrize(
    "wavelengths",
    [WL31, np.arange(380.0, 781.0, 5.0), np.arange(300.0, 901.0, 10.0)],
    ids=["400-700/10", "380-780/5", "300-900/10"],
)
def test_regular_bands_equal_colour(x64, wavelengths):
    """Regular bands (Sprague 1880 alignment in colour-science; the last case reaches past
    the CMFs' 360-830 nm): spectrum @ W is colour-science's msds_to_XYZ, so its alignment
    is linear in the samples."""
    spectra = np.random.default_rng(2).uniform(0.0, 1.0, (6, wavelengths.size))
    ref = _msds_xyz(spectra, wavelengths) / 100
    got = spectral_to_xyz(spectra, wavelengths, kind="reflective", illuminant="d65")
    np.testing.assert_allclose(np.asarray(got), ref, rtol=RTOL64)


IRREGULAR_ON_GRID = np.array([405.0, 441.0, 470.0, 512.0, 555.0, 590.0, 640.0, 700.0])
IRREGULAR_OFF_GRID = np.array([403.7, 441.2, 470.0, 512.5, 555.0, 590.3, 640.0, 699.9])


@pytest.mark.parametrize("kind", ["reflective", "emissive"])
def test_irregular_eight_bands_equal_colour(x64, kind):
    """8 uneven bands (cubic-spline alignment in colour-science) equal msds_to_XYZ."""
    spectra = np.random.default_rng(3).uniform(0.0, 1.0, (5, 8))
    extra = {"illuminant": D65} if kind == "reflective" else {"illuminant": E, "k": K_M}
    scale = 100.0 if kind == "reflective" else 1.0
    # first and last band on the CMFs' 1 nm grid: colour-science's own call, unaided
    ref = _msds_xyz(spectra, IRREGULAR_ON_GRID, **extra) / scale
    got = spectral_to_xyz(spectra, IRREGULAR_ON_GRID, kind=kind)
    np.testing.assert_allclose(np.asarray(got), ref, rtol=RTOL64)
    # off the grid: colour-science's interpolation onto the 1 nm samples between the bands,
    # then its extrapolation to 360-830 nm, then its integration
    msds = colour.MultiSpectralDistributions(spectra.T, IRREGULAR_OFF_GRID)
    _quiet(msds.interpolate, colour.SpectralShape(404, 699, 1))
    _quiet(msds.extrapolate, CMFS_1931.shape)
    assert msds.shape == CMFS_1931.shape
    ref = _quiet(colour.msds_to_XYZ, msds, CMFS_1931, method="Integration", **extra) / scale
    got = spectral_to_xyz(spectra, IRREGULAR_OFF_GRID, kind=kind)
    np.testing.assert_allclose(np.asarray(got), ref, rtol=RTOL64)


def test_1964_observer(checker):
    """The 10° observer by short or full name; its XYZ are colour-science's, not 1931's."""
    refl = checker[0].reshape(24, 31)
    w64 = spectral_weights(WL31, observer="1964", kind="reflective")
    np.testing.assert_array_equal(
        w64,
        spectral_weights(WL31, observer="cie 1964 10 degree standard OBSERVER", kind="reflective"),
    )
    ref64 = _msds_xyz(refl, WL31, cmfs=CMFS_1964) / 100
    np.testing.assert_allclose(refl @ w64, ref64, rtol=RTOL64, atol=1e-12)
    w31 = spectral_weights(WL31, observer="1931", kind="reflective")
    np.testing.assert_allclose(w64[:, 1].sum(), 1.0, rtol=RTOL64)  # white Y = 1 for both
    assert np.abs(refl @ w64 - refl @ w31).max() > 0.01


def test_gradient_jit_vmap_and_nan():
    """Linear in the spectrum: dΣY/dL is ȳ's weights; jit(vmap) gives the per-image result;
    a NaN band makes its own pixel NaN and no other."""
    w = spectral_weights(WL31)
    spectra = np.random.default_rng(5).uniform(0.0, 0.01, (2, 3, 4, 31)).astype(np.float32)
    grad = jax.grad(lambda s: spectral_to_xyz(s, WL31)[..., 1].sum())(jnp.asarray(spectra[0]))
    assert bool(jnp.all(jnp.isfinite(grad)))
    np.testing.assert_allclose(np.asarray(grad), np.broadcast_to(w[:, 1], (3, 4, 31)), rtol=RTOL32)
    batched = jax.jit(jax.vmap(lambda s: spectral_to_xyz(s, WL31)))(spectra)
    np.testing.assert_allclose(
        np.asarray(batched[1]), np.asarray(spectral_to_xyz(spectra[1], WL31)), rtol=RTOL32
    )
    spectra[0, 1, 2, 17] = np.nan
    out = np.asarray(spectral_to_xyz(spectra, WL31))
    assert np.all(np.isnan(out[0, 1, 2]))
    mask = np.ones(out.shape[:-1], bool)
    mask[0, 1, 2] = False
    assert np.all(np.isfinite(out[mask]))
    np.testing.assert_allclose(out[mask], np.asarray(batched)[mask], rtol=RTOL32)


@pytest.mark.parametrize(
    ("image_bands", "wavelengths", "kwargs", "message"),
    [
        (31, WL31[::-1], {}, r"^wavelengths: expected strictly increasing nm"),
        (31, np.r_[400.0, 400.0, WL31[2:]], {}, r"^wavelengths: expected strictly increasing"),
        (30, WL31, {}, r"^image: expected shape \(\.\.\., 31\) with one channel per wavelength"),
        (31, WL31 + 600.0, {}, r"^wavelengths: expected bands spanning .* \(outside it\)"),
        (31, np.full((31, 1), 500.0), {}, r"^wavelengths: expected a non-empty 1-D array"),
        (4, WL31[:4], {}, r"^wavelengths: expected at least 6 regularly spaced bands"),
        (3, [420.0, 530.0, 610.0], {}, r"^wavelengths: .* or 4 irregular ones"),
        (31, WL31, {"illuminant": "D65"}, r"^illuminant: an emissive image is its own light"),
        (31, WL31, {"kind": "reflective", "illuminant": "D66"}, r"^illuminant: unknown"),
        (31, WL31, {"observer": "1965"}, r"^observer: unknown standard observer '1965'"),
        (31, WL31, {"kind": "absorptive"}, r"^kind: expected 'emissive' or 'reflective'"),
    ],
)
def test_bad_input_one_line_value_error(image_bands, wavelengths, kwargs, message):
    with pytest.raises(ValueError, match=message) as info:
        spectral_to_xyz(np.ones((2, 2, image_bands), np.float32), wavelengths, **kwargs)
    assert "\n" not in str(info.value)


def test_spectral_kind_from_channel_names():
    """Fichet et al. 2021: ``T.<λ>nm`` bands are reflective, ``S0.<λ>nm`` (read without
    the prefix) and bare ``<λ>nm`` emissive."""
    assert spectral_kind(("T.400,000000nm", "T.410.5nm")) == "reflective"
    assert spectral_kind(("400,000000nm", "410,000000nm")) == "emissive"
    assert spectral_kind(("T.400,000000nm", "410,000000nm")) == "emissive"
    assert spectral_kind(()) == "emissive"


def test_spectral_files_work_where_rgb_files_do(tmp_path, capsys):
    """A small emissive spectral EXR through tonemap, falsecolor, info and batch: each
    reads it as XYZ converted to sRGB (tonemap's linear output is that, halved)."""
    from hdrjax.cli import main

    rng = np.random.default_rng(3)
    radiance = rng.uniform(0.0005, 0.002, (6, 8, 31)).astype(np.float32)
    img = LayeredImage(image=radiance, layers={"wavelengths": WL31}, quantity="radiance")
    path = hio.write(tmp_path / "spec.exr", img)
    xyz = spectral_to_xyz(radiance, WL31)
    srgb = np.asarray(convert_to(xyz, "CIE XYZ", "sRGB"))
    out = tmp_path / "t.exr"
    argv = ["--method", "linear", "--set", f"L_max={2 * float(np.asarray(xyz)[..., 1].max())}"]
    assert main(["tonemap", str(path), "-o", str(out), *argv]) == 0
    assert "spectral: 31 bands, 400-700 nm, integrated to CIE XYZ" in capsys.readouterr().out
    y_max = float(np.asarray(xyz)[..., 1].max())
    np.testing.assert_allclose(hio.read(out).image, srgb / (2 * y_max), rtol=1e-4, atol=1e-7)
    assert main(["falsecolor", str(path), "-o", str(tmp_path / "f.png")]) == 0
    capsys.readouterr()
    # info's description of the file (its statistics are the RGB path's, tested there)
    from hdrjax.cli._cmd_tonemap import describe_conversion

    assert describe_conversion(hio.read(path)).startswith("spectral: 31 bands, 400-700 nm")
    folder = tmp_path / "batch"
    assert main(["batch", str(path), "-o", str(folder), *argv, "--format", "exr", "-q"]) == 0
    np.testing.assert_allclose(hio.read(folder / "spec.exr").image, hio.read(out).image, rtol=1e-5)
