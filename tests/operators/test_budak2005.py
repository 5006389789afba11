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
def test_grey_follows_the_fechner_power_law():
    # a grey scene keeps its chromaticity; luminance maps as L_da (L/L_a)^(k_d/k_w) / L_dmax
    L = np.array([0.02, 0.3, 2.0, 40.0])[None, :, None] * np.ones((1, 1, 3))
    La, Ldmax = 1.5, 80.0
    out = np.asarray(hdrjax.tonemap(L, "budak2005", adaptation=La, display_max=Ldmax))
    Lda = Ldmax / 2
    k_w, k_d = np_tvi(La) / La, np_tvi(Lda) / Lda
    expect = Lda * (L[..., 1] / La) ** (k_d / k_w) / Ldmax
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
    rgb = natural((8, 8), seed=5).astype(np.float32) * 30.0
    rgb[0, 0] = (60.0, 2.0, 2.0)  # saturated: the primaries matter most
    path = tmp_path / "ap0.exr"
    hio.write(path, LayeredImage(image=rgb, chromaticities=AP0))
    out = tmp_path / "t.pfm"
    assert main(["tonemap", str(path), "-o", str(out), "--method", "budak2005"]) == 0
    want = np.asarray(Budak2005(chromaticities=AP0)(jnp.asarray(rgb)))
    rec709 = np.asarray(Budak2005()(jnp.asarray(rgb)))
    assert np.max(np.abs(want - rec709)) > 1e-2
    np.testing.assert_allclose(hio.read(out).image, want, rtol=1e-5, atol=2e-5)
    capsys.readouterr()
    # batch passes only the frames' luminance weights: it refuses rather than guess
    folder = tmp_path / "batch"
    code = main(["batch", str(path), "-o", str(folder), "--method", "budak2005", "-q"])
    err = capsys.readouterr().err
    assert code != 0 and "primaries" in err
