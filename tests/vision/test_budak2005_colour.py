"""Budak & Petrovichev 2005's colour path on a bright window in a dim interior, and on a
starlit street: the operator keeps a colour's hue and a near-white's neutrality while it
compresses brightness, rolls the window off to white without posterisation, and shows a
night scene dark.

The interior is set by hand (adaptation 10 cd/m², the warm colour of tungsten light as the
background), as a church adapts to its lit nave with a window too small to move the mean.
Before the fix, the opponent coordinates were CIELAB's chroma, which grows with the
cube root of luminance: kept while the Fechner law compressed the window's luminance
(exponent ``k_d/k_w`` = 0.58 at 10 cd/m²), they came back several times as saturated (a
near-white's saturation 0.20 → 0.86 at 1e5 cd/m²); blue glass left the display's gamut with
a negative red, shown as cyan (0, 1, 1), its red falling back to 0 as the window
brightened; and every scene's adaptation level was shown at half the display's maximum,
a starlit street as bright as a sunlit one.
"""

import jax.numpy as jnp
import numpy as np

import hdrjax.vision as hv
from hdrjax.display import gamma_encode
from hdrjax.operators import Budak2005

WARM = np.array([1.0, 0.85, 0.65])  # the interior's light (tungsten), relative RGB
NEAR_WHITE = np.array([0.9, 1.0, 1.12])  # daylight through the window: slightly cool
SKY = np.array([0.25, 0.55, 1.0])  # saturated blue glass / sky
WEIGHTS = np.array([0.2126, 0.7152, 0.0722])
LEVELS = np.geomspace(10.0, 1e5, 256)  # the window's luminance ramp, cd/m²
INTERIOR = dict(adaptation=jnp.asarray(10.0), background=jnp.asarray(10.0 * WARM))


def hue_saturation(rgb):
    """Hue (degrees, the direction from grey in linear RGB's opponent plane) and saturation
    ``(max - min)/max`` of linear RGB (negative channels count as they are)."""
    r, g, b = np.moveaxis(rgb, -1, 0)
    hue = np.degrees(np.arctan2(np.sqrt(3.0) * (g - b), 2.0 * r - g - b)) % 360.0
    top = rgb.max(-1)
    return hue, (top - rgb.min(-1)) / np.where(top > 0, top, 1.0)


MIX = np.array([0.0, 0.3, 0.6, 0.9])  # the window's rows, near-white to saturated


def hue_difference(h1, h2):
    """Absolute difference of hues in degrees, 0–180."""
    return np.abs((h1 - h2 + 180.0) % 360.0 - 180.0)


def shown(img):
    """The display values :class:`hdrjax.vision.Budak2005` gives (its gamma 2.2 on the
    operator's output) in the interior's adaptation, which it does not take as a field."""
    return np.asarray(gamma_encode(Budak2005(**INTERIOR)(jnp.asarray(img)), 2.2))


def window(mix):
    """Rows: colours from NEAR_WHITE (``mix`` 0) towards SKY (``mix`` 1), each at the
    luminances of ``LEVELS`` (columns): ``(len(mix), 256, 3)`` cd/m²."""
    colours = (1.0 - mix)[:, None] * NEAR_WHITE + mix[:, None] * SKY
    colours = colours / (colours @ WEIGHTS)[:, None]  # luminance 1
    return (colours[:, None, :] * LEVELS[None, :, None]).astype(np.float32)


def test_the_window_keeps_its_hue_and_a_near_white_stays_near_white():
    img = window(MIX)
    out = np.asarray(Budak2005(**INTERIOR)(jnp.asarray(img)))  # linear, before the display
    assert np.all(np.isfinite(out))
    h_in, s_in = hue_saturation(img)
    h_out, s_out = hue_saturation(out)
    # within the display (largest channel below 1), the window's luminance is compressed
    # but its chromaticity kept: hue to 0.5°, saturation to 0.01 (before: hue off by 1.4°
    # there and by 17° at 1e5 cd/m², the near-white's saturation 0.20 → 0.86)
    inside = out.max(-1) < 1.0
    assert hue_difference(h_out, h_in)[inside].max() < 0.5
    np.testing.assert_allclose(s_out[inside], s_in[inside], atol=0.01)
    assert inside.sum() > 300  # 1.65 of the ramp's 4 decades in each row (below)
    # beyond it, towards white at the same hue: less saturated, white at the end
    assert hue_difference(h_out, h_in)[~inside & (s_out > 0.01)].max() < 0.5
    assert np.all(s_out[~inside] <= s_in[~inside] + 0.01)
    np.testing.assert_allclose(out[:, -1], 1.0, rtol=1e-5)
    # displayed (the gamma only desaturates, and bends hue by up to 6°): never more
    # saturated than the scene, and coloured pixels keep their hue to 10° (before: the two
    # more saturated rows turned (0, 1, 1), cyan, 36° from the glass's blue)
    h_shown, s_shown = hue_saturation(shown(img))
    assert np.all(s_shown <= s_in + 0.01)
    coloured = s_shown > 0.2
    assert coloured.sum() > 100
    assert hue_difference(h_shown, h_in)[coloured].max() < 10.0


def test_the_window_rolls_off_to_white_without_posterisation():
    ramps = shown(window(MIX))
    # monotone in each channel along the luminance ramp (before: the red of the most
    # saturated row fell from 0.99 at 600 cd/m² to 0 at 3200), ending at the display's white
    assert np.all(np.diff(ramps, axis=1) >= 0.0)
    np.testing.assert_array_equal(ramps[:, -1], 1.0)
    # Fechner's law maps 10 cd/m² at 10 cd/m² adaptation to ΔL_d (10/ΔL_w)^0.58 = 11 cd/m²
    # and reaches the display's 100 cd/m² at 450 cd/m²: 1.65 of the ramp's 4 decades,
    # 106 samples, each a distinct 16-bit level but for the rounding of the darkest
    # steps; at least 96 of them (before: 26 to 42, the display's maximum at 33 cd/m²)
    levels = np.round(ramps[0] * 65535).astype(int)
    for c in range(3):
        assert len(np.unique(levels[:, c])) >= 96, (c, len(np.unique(levels[:, c])))


def street(level):
    """The street of ``notebooks/vision.ipynb`` (a wall, a pavement, red, green and blue
    signs, two 10 000 cd/m² lamps), lit to ``level`` cd/m²."""
    rng = np.random.default_rng(1)
    y, x = np.mgrid[0:60, 0:120] / np.array([60, 120])[:, None, None]
    wall = 0.5 + 0.1 * rng.standard_normal((60, 120))
    img = np.where(y[..., None] < 0.6, wall[..., None] * [0.9, 0.8, 0.7], [0.3, 0.3, 0.32])
    for cx, colour in [(0.2, [0.9, 0.1, 0.1]), (0.5, [0.1, 0.7, 0.1]), (0.8, [0.1, 0.2, 0.9])]:
        img[(abs(x - cx) < 0.07) & (abs(y - 0.35) < 0.1)] = colour
    img = img * level
    img[(x - 0.35) ** 2 * 4 + (y - 0.1) ** 2 < 0.0004] = 1e4
    return img.astype(np.float32)


def test_a_starlit_street_is_shown_dark_and_without_colour():
    night = np.asarray(hv.Budak2005()(street(0.005)))  # the wall at 2e-3 cd/m²
    day = np.asarray(hv.Budak2005()(street(2000.0)))
    # Starlight adapts to 1.8e-3 cd/m², below its own threshold ΔL_w = 2.2e-3 cd/m²: the
    # adaptation level lies below the display's threshold ΔL_d = 3.1 cd/m² (100 cd/m²
    # display), encoded (3.1/100)^(1/2.2) = 0.21, and the lamps, 6e6 times brighter, rise
    # only as (L/ΔL_w)^(k_d/k_w), k_d/k_w = 0.05, to 6.6 cd/m² (0.29). Before: 0.72, the
    # adaptation level at half the display's maximum, (1/2)^(1/2.2) = 0.73.
    assert night.mean() < 0.3, night.mean()
    assert np.ptp(night) < 0.15  # low contrast
    # below the mesopic range (5.6e-3 cd/m²) there is no colour vision: grey
    assert hue_saturation(night)[1].max() < 0.01
    # a daylight scene, adapted above the display, keeps its background at half the
    # display's maximum: encoded 0.73 around the wall, with colour
    assert 0.6 < day.mean() < 0.85
    assert hue_saturation(day)[1].max() > 0.5
