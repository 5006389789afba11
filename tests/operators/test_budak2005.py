"""The registered ``budak2005`` operator (Budak & Petrovichev 2005): the Fechner power law
recomputed in NumPy, the vision display step it underlies, what it measures (pcond's
visible-range log-average, the mean colour) and the file's primaries on the command line.
The colour space's own formulas are checked in ``tests/vision/test_budak2005.py``."""

import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
import hdrjax.io as hio
import hdrjax.vision as hv
from hdrjax._stats import rel_error_bound
from hdrjax.cli import main
from hdrjax.layers import LayeredImage
from hdrjax.operators import Budak2005

from ..conftest import RTOL32
from ..vision._reference import np_tvi
from .cases import natural

AP0 = (0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.077, 0.32168, 0.33767)


@pytest.mark.usefixtures("x64")
@pytest.mark.parametrize("La", [1.5, 400.0])
def test_grey_follows_the_fechner_power_law(La):
    # a grey scene keeps its chromaticity. Its brightness in JNDs above the threshold ΔL,
    # (L_a/ΔL(L_a)) ln(L/ΔL(L_a)), is kept: luminance maps as ΔL_d (L/ΔL_w)^(k_d/k_w),
    # k = ΔL/L_a the Weber fractions; but a scene adapted above the display's L_da shows its
    # adaptation level at L_da (the paper's background at half the display's maximum):
    # L_da (L/L_a)^(k_d/k_w)
    L = La * np.array([0.013, 0.2, 1.0, 1.5])[None, :, None] * np.ones((1, 1, 3))
    Ldmax = 80.0
    out = np.asarray(hdrjax.tonemap(L, "budak2005", adaptation=La, display_max=Ldmax))
    Lda = Ldmax / 2
    k_w, k_d = np_tvi(La) / La, np_tvi(Lda) / Lda
    if La < Lda:
        expect = np_tvi(Lda) * (L[..., 1] / np_tvi(La)) ** (k_d / k_w) / Ldmax
    else:
        expect = Lda * (L[..., 1] / La) ** (k_d / k_w) / Ldmax
    assert expect.max() < 1.0  # inside the display: no roll-off to white
    np.testing.assert_allclose(out[..., 1], expect, rtol=1e-9)
    np.testing.assert_allclose(out, out[..., :1].repeat(3, -1), rtol=1e-9)


def test_is_the_vision_display_step_before_its_gamma():
    rgb = natural((12, 16), seed=3).astype(np.float32) * 40.0  # cd/m²
    out = np.asarray(Budak2005(display_max=120.0)(rgb))
    step = np.asarray(hv.Budak2005(display_max=120.0, gamma=1.0)(rgb))
    np.testing.assert_allclose(step, np.clip(out, 0.0, 1.0), rtol=RTOL32, atol=2e-6)
    assert out.max() > 1.0 or out.min() < 0.0 or np.ptp(out) > 0.1  # not a constant image


def test_measures_the_visible_log_average_and_the_mean_colour():
    rgb = natural((16, 16), seed=4).astype(np.float64) * 20.0
    rgb[0, :4] = 1e-9  # below pcond's visible range: left out of the adaptation
    rgb[1, :4] = 1e6  # above it: left out too
    m = Budak2005().measure(rgb.astype(np.float32))
    L = rgb @ np.asarray(hdrjax.REC709_WEIGHTS)
    inside = (L > 1e-7) & (L < 1e5)
    want = np.exp(np.mean(np.log(L[inside])))
    bound = rel_error_bound(10, np.float32)  # the histogram's bins (8192: 10 bits)
    np.testing.assert_allclose(float(m.adaptation), want, rtol=2 * bound)
    np.testing.assert_allclose(np.asarray(m.background), rgb.mean(axis=(0, 1)), rtol=1e-5)
    # a scene entirely outside the range adapts to its nearer end, not to 1e-7 cd/m²
    assert float(Budak2005().measure(np.full((4, 4, 3), 1e7, np.float32)).adaptation) == 1e5
    dark = Budak2005().measure(np.full((4, 4, 3), 1e-9, np.float32))
    assert float(dark.adaptation) == pytest.approx(1e-7, rel=1e-6)
    # no light in, no light out
    np.testing.assert_array_equal(np.asarray(Budak2005()(np.zeros((4, 4, 3)))), 0.0)


def test_the_files_primaries_reach_it_on_the_command_line(tmp_path, capsys):
    """An ACES AP0 file is converted into the sRGB working space (colour-science's
    RGB_to_RGB, CAT02) and mapped with sRGB's colour matrix, by tonemap and batch alike;
    with --working-space ACES2065-1 (its own primaries) it is mapped with AP0's."""
    import colour

    rgb = natural((8, 8), seed=5).astype(np.float32) * 30.0
    rgb[0, 0] = (60.0, 2.0, 2.0)  # saturated: the primaries matter most
    path = tmp_path / "ap0.exr"
    hio.write(path, LayeredImage(image=rgb, chromaticities=AP0))
    ap0 = colour.RGB_Colourspace("AP0", np.reshape(AP0[:6], (3, 2)), AP0[6:])
    srgb = colour.RGB_to_RGB(rgb.astype(np.float64), ap0, "sRGB").astype(np.float32)
    want = np.asarray(Budak2005()(jnp.asarray(srgb)))
    own = np.asarray(Budak2005(chromaticities=AP0)(jnp.asarray(rgb)))
    assert np.max(np.abs(want - own)) > 1e-3
    out = tmp_path / "t.pfm"
    assert main(["tonemap", str(path), "-o", str(out), "--method", "budak2005"]) == 0
    np.testing.assert_allclose(hio.read(out).image, want, rtol=1e-4, atol=2e-5)
    argv = ["--method", "budak2005", "--working-space", "ACES2065-1"]
    exr = tmp_path / "t.exr"  # keeps the working space's primaries (PFM has none: sRGB)
    assert main(["tonemap", str(path), "-o", str(exr), *argv]) == 0
    np.testing.assert_allclose(hio.read(exr).native_rgb(), own, rtol=1e-4, atol=2e-5)
    capsys.readouterr()
    folder = tmp_path / "batch"
    argv = ["--method", "budak2005", "--format", "pfm", "-q"]
    assert main(["batch", str(path), "-o", str(folder), *argv]) == 0
    np.testing.assert_allclose(hio.read(folder / "ap0.pfm").image, want, rtol=1e-4, atol=2e-5)
