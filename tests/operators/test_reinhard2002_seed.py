"""Reinhard 2002 in the form of GPU shader versions (issue 20): key 0.18, the log-average
with the offset 1e-5, ``L_white = "max"`` (the largest luminance in scaled units), the
luma of YCbCr mapped with Cb and Cr kept (``chroma="ycbcr"``); ``L_white = "inf"``
(``L / (1 + L)``); the names' errors; ``--set L_white=max`` on the command line; gradients.

The reference is a float64 NumPy transcription of such a shader's passes (a log-luminance
and maximum pass, reductions, the final per-pixel pass with an explicit RGB → YCbCr → RGB
matrix), written here; the shader's 4×4 reductions are a plain mean and maximum."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import hdrjax
from hdrjax.cli import main
from hdrjax.operators import Reinhard2002, apply_in_space, make_operator
from hdrjax.operators._base import maps_luminance_ratio

from ..conftest import DATA, RTOL32, RTOL64
from .cases import natural

BT601 = (0.299, 0.587, 0.114)
"""The shader's luma weights (its ``RGB2Y``)."""
SEED = dict(key=0.18, L_white="max", chroma="ycbcr", delta=1e-5)
"""The shader's settings."""
SHADER_YCBCR = np.array(
    [[0.29900, 0.58700, 0.11400], [-0.16874, -0.33126, 0.50000], [0.50000, -0.41869, -0.08131]]
)
SHADER_RGB = np.array([[1.0, 0.0, 1.40200], [1.0, -0.34414, -0.71414], [1.0, 1.77200, 0.0]])
"""The shader's matrices, its constants as printed (5 decimals)."""


def ycbcr_matrix(w):
    """RGB → (Y, Cb, Cr) with luma weights ``w`` (ITU-R BT.601's construction; BT.709's
    with its weights): ``Cb = (B − Y) / (2 (1 − w_B))``, ``Cr = (R − Y) / (2 (1 − w_R))``."""
    w = np.asarray(w, np.float64)
    cb = (np.array([0.0, 0.0, 1.0]) - w) / (2 * (1 - w[2]))
    cr = (np.array([1.0, 0.0, 0.0]) - w) / (2 * (1 - w[0]))
    return np.stack([w, cb, cr])


def shader_reference(rgb, w=BT601, key=0.18, eps=1e-5, to_ycbcr=None, to_rgb=None):
    """Float64 transcription of the shader, per frame ``(H, W, 3)``: the log-average of
    ``ln(eps + Y)``, ``coeff = key / L̄_w``, ``L_white = coeff · max(Y)``, the curve on
    ``coeff · Y`` replacing Y, Cb and Cr of the unscaled pixel kept."""
    rgb = np.asarray(rgb, np.float64)
    m = ycbcr_matrix(w) if to_ycbcr is None else to_ycbcr
    inv = np.linalg.inv(m) if to_rgb is None else to_rgb
    ycc = rgb @ m.T
    Y = ycc[..., 0]
    coeff = key * np.exp(-np.mean(np.log(eps + Y)))
    l_max = coeff * Y.max()
    lum = coeff * Y
    ycc[..., 0] = lum * (1 + lum / (l_max * l_max)) / (1 + lum)
    return ycc @ inv.T


def box(x, f):
    h, w = (s // f * f for s in x.shape[:2])
    return x[:h, :w].reshape(h // f, f, w // f, f, 3).mean(axis=(1, 3))


@pytest.fixture(scope="module")
def images():
    """Two real images in relative units, box-downscaled and cropped to 96×128."""
    tam = box(hdrjax.io.read(DATA / "MtTamNorth.exr").rgb(), 8)[:96, :128]
    cornell = box(hdrjax.io.read(DATA / "cornell_box.exr").rgb(), 4)[:96, :128]
    return np.stack([tam, np.maximum(cornell, 0.0)]).astype(np.float32)


def _tolerance(rgb, out, rtol):
    """``rtol`` of each value, plus 16 ulps of the pixel's largest channel: the output is
    the pixel plus ``L_d − Y``, whose rounding is relative to the pixel where the two
    nearly cancel (measured: ~1e-6 absolute in float32 on these images, 4e-15 in
    float64)."""
    eps = np.finfo(rgb.dtype).eps
    return rtol * np.abs(out) + 16 * eps * np.abs(rgb).max(axis=-1, keepdims=True)


@pytest.mark.parametrize("weights", [BT601, None])
def test_shader_form_matches_float64_reference_float32(images, weights):
    kw = {} if weights is None else {"weights": weights}
    got = np.asarray(hdrjax.tonemap(images, "reinhard2002", **SEED, **kw), np.float64)
    w = weights or (0.2126, 0.7152, 0.0722)
    want = np.stack([shader_reference(x, w) for x in images])
    assert np.all(np.abs(got - want) <= _tolerance(images, want, RTOL32))


def test_shader_form_matches_float64_reference_x64(images, x64):
    rgb = images.astype(np.float64)
    got = np.asarray(hdrjax.tonemap(rgb, "reinhard2002", **SEED, weights=BT601))
    assert got.dtype == np.float64
    want = np.stack([shader_reference(x) for x in rgb])
    assert np.all(np.abs(got - want) <= _tolerance(rgb, want, RTOL64))
    # the shader's own 5-decimal constants: their rounding alone (≤ 1e-5 of the chroma)
    printed = np.stack([shader_reference(x, to_ycbcr=SHADER_YCBCR, to_rgb=SHADER_RGB) for x in rgb])
    assert np.all(
        np.abs(got - printed) <= 2e-5 * (np.abs(printed) + np.abs(rgb).max(-1, keepdims=True))
    )
    assert np.abs(got - printed).max() > 1e-7  # not vacuous: the constants do differ


def test_max_white_is_the_largest_scaled_luminance_and_merges(images, x64):
    """``L_white = (key / L̄_w) · max(Y)``: the brightest pixel maps to 1 (ratio mapping);
    statistics of two tiles merged give the whole image's white."""
    rgb = images[0].astype(np.float64)
    op = Reinhard2002(key=0.18, L_white="max", delta=1e-5, weights=BT601)
    assert op.white == "max" and op.L_white is None and op.chroma == "ratio"
    m = op.measure(rgb)
    Y = rgb @ np.asarray(BT601)
    lbar = np.exp(np.mean(np.log(1e-5 + Y)))
    np.testing.assert_allclose(float(m.L_white), 0.18 / lbar * Y.max(), rtol=RTOL64)
    out = np.asarray(m(rgb)) @ np.asarray(BT601)
    np.testing.assert_allclose(out.max(), 1.0, rtol=RTOL64)
    assert out.flat[np.argmax(Y)] == out.max()
    top, bottom = rgb[:40], rgb[40:]
    merged = op.bind(op.statistics(top).merge(op.statistics(bottom)))
    np.testing.assert_allclose(float(merged.L_white), float(m.L_white), rtol=RTOL64)
    # a numeric L_white or the default white are unaffected by white="max"
    assert float(Reinhard2002(L_white=4.0, white="max").measure(rgb).L_white) == 4.0


def test_inf_white_is_exactly_l_over_one_plus_l():
    op = make_operator("reinhard2002", key=0.18, L_white="inf", log_average=1.0)
    assert float(op.L_white) == np.inf and op.white == "jgt"
    x = np.float32(np.finfo(np.float32).max)
    L = jnp.asarray([0.0, 1e-38, 1e-30, 1e-3, 0.5, 1.0, 7.0, 1e20, 1e30, x], jnp.float32)
    s = op.key * L  # the scaled luminance (log_average 1)
    np.testing.assert_array_equal(np.asarray(op.curve(L)), np.asarray(s / (1 + s)))
    rgb = natural((12, 16))
    simple = np.asarray(hdrjax.tonemap(rgb, "reinhard2002", key=0.18, L_white=np.inf))
    np.testing.assert_array_equal(
        np.asarray(hdrjax.tonemap(rgb, "reinhard2002", key=0.18, L_white="inf")), simple
    )


@pytest.mark.parametrize(
    "kw,needles",
    [
        (dict(L_white="maximum"), ("L_white", "max | inf", "'maximum'")),
        (dict(L_white=""), ("L_white", "max | inf")),
        (dict(chroma="yuv"), ("chroma", "ratio | ycbcr", "'yuv'")),
        (dict(white="inf"), ("white", "jgt | max", "'inf'")),
    ],
)
def test_bad_names_are_rejected_in_one_line(kw, needles):
    for build in (lambda: hdrjax.tonemap(natural((4, 4)), "reinhard2002", **kw),
                  lambda: Reinhard2002(**kw)):  # fmt: skip
        with pytest.raises(ValueError) as e:
            build()
        text = str(e.value)
        assert "\n" not in text and text.startswith(needles[0] + ":"), text
        assert all(n in text for n in needles[1:]), text


def test_command_line_sets_l_white_max(tmp_path, capsys):
    """``--set L_white=max --set chroma=ycbcr ...`` builds the shader form: the written
    linear image equals the Python API's, and the printed white is the measured one."""
    rgb = np.maximum(box(hdrjax.io.read(DATA / "cornell_box.exr").rgb(), 8), 0.0)
    src, out = tmp_path / "in.pfm", tmp_path / "out.pfm"
    hdrjax.io.write(src, hdrjax.layers.LayeredImage(rgb.astype(np.float32)))
    sets = ["L_white=max", "key=0.18", "chroma=ycbcr", "delta=1e-5"]
    argv = ["tonemap", str(src), "-o", str(out), *(a for s in sets for a in ("--set", s))]
    assert main(argv) == 0
    text = capsys.readouterr().out
    back = hdrjax.io.read(out).rgb()
    want = np.asarray(hdrjax.tonemap(rgb, "reinhard2002", **SEED))
    np.testing.assert_allclose(back, want, rtol=RTOL32, atol=1e-6)
    white = float(Reinhard2002(**SEED).measure(rgb).L_white)
    line = next(x for x in text.splitlines() if x.strip().startswith("L_white:"))
    assert "estimated" in line
    np.testing.assert_allclose(float(line.split(":")[1].split()[0]), white, rtol=1e-3)
    # a word that is not one of the names: usage error (exit 2) naming L_white
    assert main([*argv[:4], "--set", "L_white=maximum"]) == 2
    err = capsys.readouterr().err
    assert "L_white" in err and "max | inf" in err


@pytest.mark.parametrize("chroma", ["ratio", "ycbcr"])
@pytest.mark.parametrize("white", ["max", "inf"])
def test_gradients_with_respect_to_key_are_finite(chroma, white):
    """At ordinary, very bright and very dim scales (the white's logarithms keep
    ``key / L̄_w · L_max`` and its derivative finite near the float maximum)."""
    base = natural((8, 8))
    imgs = jnp.asarray(np.stack([base, base * 1e35, base * 1e-30]))

    def loss(k):
        return jnp.sum(Reinhard2002(key=k, L_white=white, chroma=chroma)(imgs))

    g = jax.grad(loss)(jnp.float32(0.18))
    assert np.isfinite(float(g)) and float(g) != 0.0


def test_default_operator_keeps_its_settings_and_mapping():
    """The default is the ratio mapping with JGT's white, folded with a colour matrix;
    YCbCr is not a ratio, so a working space converts the pixels first."""
    op = Reinhard2002()
    assert (op.white, op.chroma, op.L_white) == ("jgt", "ratio", None)
    assert maps_luminance_ratio(op)
    ycc = Reinhard2002(**SEED)
    assert not maps_luminance_ratio(ycc)
    rgb = natural((6, 8))
    m = np.eye(3)
    np.testing.assert_allclose(
        np.asarray(apply_in_space(ycc, rgb, m)), np.asarray(ycc(rgb)), rtol=RTOL32
    )
