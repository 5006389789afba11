"""Median threshold bitmap alignment (Ward 2003): exact shifts on synthetic hand-held
brackets, the sign convention shared with simulate_bracket, OpenCV's AlignMTB as peer."""

import cv2
import numpy as np
import pytest

import hdrjax.merge as hm
from hdrjax.io import read

from ..conftest import DATA

# (dx, dy) per member of a 5-exposure bracket (2 EV apart), the middle one unmoved
SHIFTS = np.array([[-2, 1], [17, 29], [0, 0], [21, 29], [-16, -12]])
# the extreme members of a ±4 EV bracket are mostly black or white at 256 × 384 px: the
# 32-px shifts are tested on a ±2 EV bracket
LARGE = np.array([[32, -32], [0, 0], [-32, 31]])


def scene(name, h, w):
    img = np.asarray(read(DATA / name).rgb())
    step = max(1, min(img.shape[0] // h, img.shape[1] // w))
    return img[::step, ::step][:h, :w]


@pytest.mark.parametrize(
    "name", ["rooitou_park_1k.hdr", "Carrots.exr", "empty_warehouse_01_512.hdr"]
)
def test_shifts_up_to_32_px_are_recovered_exactly(name):
    img = scene(name, 256, 384)
    for shifts in (SHIFTS, LARGE, -LARGE):
        b = hm.simulate_bracket(img, stops=len(shifts), shifts=shifts)
        np.testing.assert_array_equal(hm.align_mtb(b.codes), shifts - shifts[len(shifts) // 2])


def test_reference_noise_and_16_bit():
    img = scene("rooitou_park_1k.hdr", 128, 192)
    sh = np.array([[3, -2], [0, 0], [-5, 4]])
    b = hm.simulate_bracket(img, stops=3, shifts=sh, read_noise=0.002, seed=1)
    np.testing.assert_array_equal(hm.align_mtb(b.codes, reference=0), sh - sh[0])
    np.testing.assert_array_equal(hm.align_mtb(list(b.codes), max_shift=8), sh - sh[1])
    b16 = hm.simulate_bracket(img, stops=3, shifts=sh, bits=16)
    np.testing.assert_array_equal(hm.align_mtb(b16.codes), sh - sh[1])
    # max_shift bounds the search: nothing beyond it, and 0 means no search at all
    assert np.abs(hm.align_mtb(b.codes, max_shift=2)).max() <= 2
    np.testing.assert_array_equal(hm.align_mtb(b.codes, max_shift=0), np.zeros((3, 2)))


def test_opencv_alignmtb_finds_the_opposite_sign():
    """OpenCV's calculateShift returns the correction, ours the displacement."""
    img = scene("rooitou_park_1k.hdr", 256, 384)
    sh = SHIFTS
    b = hm.simulate_bracket(img, shifts=sh)
    grey = [cv2.cvtColor(np.ascontiguousarray(c[..., ::-1]), cv2.COLOR_BGR2GRAY) for c in b.codes]
    mtb = cv2.createAlignMTB()
    theirs = np.array([mtb.calculateShift(grey[2], g) for g in grey])
    np.testing.assert_array_equal(hm.align_mtb(b.codes), sh)
    np.testing.assert_array_equal(theirs, -sh)


def test_apply_shifts_undoes_simulated_camera_shake():
    img = scene("Carrots.exr", 128, 192)
    sh = np.array([[4, -3], [0, 0], [-7, 5]])
    plain = hm.simulate_bracket(img, stops=3)
    b = hm.simulate_bracket(img, stops=3, shifts=sh)
    est = hm.align_mtb(b.codes)
    out = hm.apply_shifts(b.codes, est)
    assert out.dtype == b.codes.dtype and out.shape == b.codes.shape
    # away from the replicated border strips the aligned bracket is the unshaken one
    np.testing.assert_array_equal(out[:, 8:-8, 8:-8], plain.codes[:, 8:-8, 8:-8])
    # borders repeat the edge pixel; single-channel stacks and float arrays work alike
    grey = hm.apply_shifts(b.codes[..., 0].astype(np.float32), est)
    np.testing.assert_array_equal(grey, out[..., 0])
    # member 2 moved back 7 px right: its first 7 columns repeat its first column
    np.testing.assert_array_equal(out[2, :, 0], out[2, :, 6])


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda b: hm.align_mtb(b, max_shift=-1), "max_shift"),
        (lambda b: hm.align_mtb(b, max_shift=2.5), "max_shift"),
        (lambda b: hm.align_mtb(b, exclude=-1), "exclude"),
        (lambda b: hm.align_mtb(b, reference=3), "reference"),
        (lambda b: hm.align_mtb(b.astype(np.float32)), "images"),
        (lambda b: hm.align_mtb(b[..., :2]), "images"),
        (lambda b: hm.apply_shifts(b, [[0, 0]]), "shifts"),
        (lambda b: hm.apply_shifts(b, np.full((3, 2), 0.5)), "shifts"),
        (lambda b: hm.apply_shifts(b[0, 0], np.zeros((3, 2), int)), "images"),
    ],
)
def test_bad_input_is_named(call, match):
    b = np.zeros((3, 16, 24, 3), np.uint8)
    with pytest.raises(ValueError, match=match):
        call(b)
