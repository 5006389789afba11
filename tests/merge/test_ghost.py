"""Ghost masks (Grosch 2006's consistency with a reference exposure): an object that moves
between exposures is flagged, and a merge that gives flagged pixels zero weight shows the
reference's version of the scene."""

import numpy as np
import pytest

import hdrjax.merge as hm
from hdrjax.io import read

from ..conftest import DATA

A = (slice(30, 60), slice(40, 80))  # the patch in the reference exposure
B = (slice(70, 100), slice(120, 160))  # where it is in the others
# measured with the default threshold: 0 % of the static pixels flagged without noise,
# 0.06 % with read noise 0.002
STATIC_FLAGGED_TOL = 0.002


def moving_patch_bracket(read_noise=0.0):
    img = np.asarray(read(DATA / "rooitou_park_1k.hdr").rgb())[::4, ::4][:128, :192]
    img = img.astype(np.float64)
    p99 = np.percentile(img.mean(-1), 99)
    still = img.copy()
    still[A] = np.array([1.2, 0.8, 0.5]) * p99  # well exposed in the middle member
    moved = still.copy()
    # the patch and the background at B swap places: the same pixel values, so the
    # simulator's exposure scale (from the 99th percentile) is the same for both
    moved[B], moved[A] = still[A], still[B]
    a = hm.simulate_bracket(still, read_noise=read_noise, seed=1)
    b = hm.simulate_bracket(moved, read_noise=read_noise, seed=1)
    np.testing.assert_allclose(a.radiance[B], b.radiance[A])
    codes = b.codes.copy()
    codes[2] = a.codes[2]  # the reference sees the patch at A, every other member at B
    return codes, a


def small_merge(codes, times, g, mask):
    """Debevec & Malik's weighted log-average with triangle weights, masked pixels weight 0."""
    z = codes.astype(np.float64)
    w = 1.0 - np.abs(2.0 * z / 255.0 - 1.0)
    w = w * mask[..., None]
    gz = np.take_along_axis(np.broadcast_to(g, (256, 3)), codes.reshape(-1, 3), 0)
    gz = np.where(w.reshape(-1, 3) > 0, gz, 0.0).reshape(codes.shape)
    lnt = np.log(times)[:, None, None, None]
    return np.exp((w * (gz - lnt)).sum(0) / np.maximum(w.sum(0), 1e-12))


@pytest.mark.parametrize("read_noise", [0.0, 0.002])
def test_moved_patch_is_flagged_and_merged_away(read_noise):
    codes, truth = moving_patch_bracket(read_noise)
    mask = np.asarray(hm.ghost_mask(codes, truth.exposure_times, truth.response))
    assert mask.shape == (5, 128, 192) and mask.dtype == bool and mask[2].all()
    # the members 2 EV either side lose the patch's place in the reference, and the patch
    # where the reference shows well-exposed background
    for j in (1, 3):
        assert (~mask[j][A]).mean() > 0.95
    static = np.ones((128, 192), bool)
    static[A] = static[B] = False
    assert (~mask[:, static]).mean() < STATIC_FLAGGED_TOL
    ghosted = small_merge(codes, truth.exposure_times, truth.response, np.ones_like(mask))
    clean = small_merge(codes, truth.exposure_times, truth.response, mask)
    rel = lambda e: np.median(np.abs(e[A] / truth.radiance[A] - 1))  # noqa: E731
    assert rel(ghosted) > 0.2 and rel(clean) < 0.02


def test_reference_and_settings():
    codes, truth = moving_patch_bracket()
    mask = np.asarray(hm.ghost_mask(codes, truth.exposure_times, truth.response, reference=1))
    # the reference (−2 EV) sees the patch at B, well exposed; member 2 shows background there
    assert mask[1].all() and (~mask[2][B]).mean() > 0.95
    # an infinite tolerance flags nothing; an empty trusted range tests nothing
    loose = hm.ghost_mask(codes, truth.exposure_times, truth.response, threshold=1e9)
    assert np.asarray(loose).all()
    none = hm.ghost_mask(codes, truth.exposure_times, truth.response, well_exposed=(0.99, 1.0))
    assert np.asarray(none).mean() > 0.99


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"response": np.zeros((255, 3))}, "response"),
        ({"response": np.full((256, 3), np.nan)}, "response"),
        ({"exposure_times": [1.0, 2.0]}, "exposure_times"),
        ({"reference": 7}, "reference"),
        ({"threshold": -0.1}, "threshold"),
        ({"well_exposed": (0.9, 0.1)}, "well_exposed"),
        ({"well_exposed": 0.5}, "well_exposed"),
    ],
)
def test_bad_input_is_named(kwargs, match):
    args = {
        "exposure_times": [0.25, 1.0, 4.0],
        "response": hm.true_response("srgb", 256),
    } | kwargs
    with pytest.raises(ValueError, match=match):
        hm.ghost_mask(np.zeros((3, 8, 8, 3), np.uint8), **args)
