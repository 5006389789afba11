"""The synthetic brackets every merge test relies on, and bracket validation (as_codes)."""

import numpy as np
import pytest

import hdrjax.merge as hm
from hdrjax.io import read

from ..conftest import DATA

RNG = np.random.default_rng(7)
SCENE = np.exp(RNG.normal(0.0, 2.0, (24, 32, 3)))


def srgb_inverse(v):
    """IEC 61966-2-1 decoding, written out independently of the simulator."""
    v = np.asarray(v, np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def test_true_response_is_the_inverse_curve():
    z = np.arange(1, 256) / 255.0
    g = hm.true_response("srgb", 256)
    np.testing.assert_allclose(np.exp(g[1:, 0]), srgb_inverse(z), rtol=1e-4)
    assert g[0, 0] == -np.inf and g[255, 0] == 0.0
    g = hm.true_response("per_channel", 65536)
    np.testing.assert_allclose(
        np.exp(g[1000]), (1000 / 65535) ** np.array([2.0, 2.2, 2.5]), rtol=1e-4
    )
    g = hm.true_response("scurve", 256)
    assert np.all(np.diff(g[1:], axis=0) > 0)


def test_codes_are_the_quantised_curve_of_the_exposure():
    b = hm.simulate_bracket(SCENE, curve="gamma", fill=0.4)
    assert b.codes.shape == (5, 24, 32, 3) and b.codes.dtype == np.uint8
    np.testing.assert_allclose(b.exposure_times, [1 / 16, 1 / 4, 1, 4, 16])
    # the middle member's 99th percentile (of the channel mean) sits at the requested fill
    assert np.percentile(b.radiance.mean(-1) * 1.0, 99) == pytest.approx(0.4)
    x = np.clip(b.radiance[None] * b.exposure_times[:, None, None, None], 0, 1)
    np.testing.assert_array_equal(b.codes, np.rint(x ** (1 / 2.2) * 255).astype(np.uint8))
    b16 = hm.simulate_bracket(SCENE, curve="linear", bits=16, exposure_times=[0.5, 2.0])
    assert b16.codes.dtype == np.uint16 and b16.response.shape == (65536, 3)
    x = np.clip(b16.radiance * 2.0, 0, 1)
    np.testing.assert_array_equal(b16.codes[1], np.rint(x * 65535).astype(np.uint16))


def test_shifts_translate_members_and_noise_is_seeded():
    img = np.asarray(read(DATA / "cornell_box.exr").rgb())
    scene = img[::8, ::8]
    b = hm.simulate_bracket(scene, stops=3, shifts=[[0, 0], [3, -2], [0, 0]])
    plain = hm.simulate_bracket(scene, stops=3)
    # member 1 moved 3 px right and 2 px up: away from the edges it is the unshifted one moved
    np.testing.assert_array_equal(b.codes[1, 5:-5, 5:-5], plain.codes[1, 7:-3, 2:-8])
    a = hm.simulate_bracket(scene, stops=3, read_noise=0.01, shot_noise=0.001, seed=3)
    c = hm.simulate_bracket(scene, stops=3, read_noise=0.01, shot_noise=0.001, seed=3)
    np.testing.assert_array_equal(a.codes, c.codes)
    assert np.abs(a.codes.astype(int) - plain.codes).mean() > 0.5


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"curve": "film"}, "curve"),
        ({"bits": 12}, "bits"),
        ({"shifts": [[0, 0]]}, "shifts"),
    ],
)
def test_simulator_rejects_bad_settings(kwargs, match):
    with pytest.raises(ValueError, match=match):
        hm.simulate_bracket(SCENE, **kwargs)


def test_as_codes_accepts_lists_and_arrays():
    b = hm.simulate_bracket(SCENE, stops=3)
    c = hm.as_codes(list(b.codes), b.exposure_times)
    np.testing.assert_array_equal(c.codes, b.codes)
    assert c.levels == 256 and c.exposure_times.dtype == np.float64
    assert hm.as_codes(b.codes.astype(np.uint16), [1, 2, 3]).levels == 65536


@pytest.mark.parametrize(
    ("images", "times", "match"),
    [
        (np.zeros((3, 4, 5, 3), np.float32), [1, 2, 3], "images: expected integer code values"),
        (np.zeros((3, 4, 5), np.uint8), [1, 2, 3], r"images: expected N exposures of \(H, W, 3\)"),
        (np.zeros((1, 4, 5, 3), np.uint8), [1], "at least 2 exposures"),
        (np.zeros((2, 0, 5, 3), np.uint8), [1, 2], "empty"),
        ([np.zeros((4, 5, 3), np.uint8), np.zeros((4, 6, 3), np.uint8)], [1, 2], "one size"),
        (np.zeros((2, 4, 5, 3), np.uint8), [1, 2, 3], "exposure_times: expected one time"),
        (np.zeros((2, 4, 5, 3), np.uint8), [1, -2], "exposure_times: expected positive"),
        (np.zeros((2, 4, 5, 3), np.uint8), [1, np.nan], "exposure_times: expected positive"),
        (np.zeros((2, 4, 5, 3), np.uint8), [2, 2], "distinct"),
        (np.zeros((2, 4, 5, 3), np.uint8), None, "exposure_times: required"),
        (42, [1, 2], "images: expected an"),
    ],
)
def test_as_codes_errors_are_one_line_and_name_the_argument(images, times, match):
    with pytest.raises(ValueError, match=match) as err:
        hm.as_codes(images, times)
    assert "\n" not in str(err.value)
