"""``hdrjax fit``: the written image meets the targets (decoded independently here), the
printed report, exit codes for non-convergence, and one-line usage errors."""

import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import hdrjax
from hdrjax.cli import main
from hdrjax.cli._cmd_fit import EXIT_NOT_CONVERGED

from ..conftest import DATA

W = np.array([0.2126, 0.7152, 0.0722])


def srgb_to_linear(code: np.ndarray, bits: int = 8) -> np.ndarray:
    """IEC 61966-2-1 sRGB decoding of integer code values (written out, not hdrjax's)."""
    v = code.astype(np.float64) / (2**bits - 1)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def display_luminance(path, bits=8) -> np.ndarray:
    return srgb_to_linear(np.asarray(Image.open(path)), bits) @ W


@pytest.fixture(scope="module")
def small_exr(tmp_path_factory):
    """The Cornell box box-filtered to 64 × 64, as an EXR (fits run at full resolution)."""
    rgb = np.asarray(hdrjax.io.read(DATA / "cornell_box.exr").rgb(), np.float64)
    small = rgb.reshape(64, 8, 64, 8, 3).mean(axis=(1, 3)).astype(np.float32)
    path = tmp_path_factory.mktemp("fit") / "cornell64.exr"
    hdrjax.io.write(path, small)
    return str(path)


def test_fit_mean_target_and_report(small_exr, tmp_path, capsys):
    out = tmp_path / "fit.png"
    argv = ["fit", small_exr, "--target", "mean=0.4", "--max-size", "0", "-o", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    for needle in ("operator: reinhard2002", "fitted parameters:", "  key: ", "  L_white: ",
                   "loss: ", "steps: ", "status: converged", f"wrote: {out}"):  # fmt: skip
        assert needle in text
    assert "(start " in text  # the automatic estimate the fit started from
    L = display_luminance(out)
    assert L.shape == (64, 64)
    # 8-bit quantisation moves the mean by well under 1/510
    np.testing.assert_allclose(L.mean(), 0.4, atol=3e-3)


def test_python_m_hdrjax_fit_tumblin_reinhard_two_targets(small_exr, tmp_path):
    out = tmp_path / "tr.png"
    cmd = [sys.executable, "-m", "hdrjax", "fit", small_exr, "--method", "tumblin_reinhard",
           "--target", "mean=0.4", "--target", "p99=0.95", "--max-size", "0",
           "-o", str(out)]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True, env={"HDRJAX_CACHE": "0", **_env()})
    assert proc.returncode == 0, proc.stderr
    assert "  L_wa: " in proc.stdout and "  L_white: " in proc.stdout
    assert "status: converged" in proc.stdout
    L = display_luminance(out)
    np.testing.assert_allclose(L.mean(), 0.4, atol=3e-3)
    # numpy.percentile over the positive pixels (as the target); 8-bit steps near 0.95
    # are 0.0075 in linear light
    np.testing.assert_allclose(np.percentile(L[L > 0], 99), 0.95, atol=8e-3)


def _env():
    import os

    return {k: v for k, v in os.environ.items() if k != "HDRJAX_CACHE"}


def test_non_convergence_exit_code_and_force(small_exr, tmp_path, capsys):
    out = tmp_path / "nc.png"
    argv = ["fit", small_exr, "--target", "mean=0.4", "--target", "p99=0.95", "--max-size",
            "0", "--max-steps", "1", "-o", str(out)]  # fmt: skip
    assert main(argv) == EXIT_NOT_CONVERGED
    text = capsys.readouterr().out
    assert "status: not converged: The maximum number of steps" in text
    assert not out.exists()
    assert main([*argv, "--force"]) == EXIT_NOT_CONVERGED
    assert out.exists() and f"wrote: {out}" in capsys.readouterr().out
    out.unlink()
    assert main([*argv, "--throw", "--force"]) == EXIT_NOT_CONVERGED
    err = capsys.readouterr().err
    assert "hdrjax fit: error: the fit did not converge: The maximum number" in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_reference_target_recovers_parameters(small_exr, tmp_path, capsys):
    # a display-referred linear reference made by tonemap with known parameters; fit back to
    # them from a start set with --set (JGT's white, 1.8e8 here, leaves no gradient: L ≪ L_white)
    ref = tmp_path / "ref.exr"
    assert main(["tonemap", small_exr, "--key", "0.3", "--white", "2.5", "-o", str(ref)]) == 0
    capsys.readouterr()
    out = tmp_path / "back.png"
    argv = ["fit", small_exr, "--target", f"reference={ref}", "--max-size", "0", "-o", str(out),
            "--set", "key=0.18", "--set", "L_white=10"]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    key = float(text.split("  key: ")[1].split()[0])
    white = float(text.split("  L_white: ")[1].split()[0])
    np.testing.assert_allclose([key, white], [0.3, 2.5], rtol=1e-3)  # float32 fit
    # the written PNG is the reference, sRGB-encoded
    ref_lin = np.clip(np.asarray(hdrjax.io.read(ref).rgb(), np.float64), 0, 1)
    # half an 8-bit step near white is 0.0044 in linear light
    np.testing.assert_allclose(display_luminance(out), ref_lin @ W, atol=5e-3)
    # 8-bit references are decoded (sRGB); 16-bit PNGs are refused, not truncated
    ref8 = tmp_path / "ref8.png"
    assert main(["tonemap", small_exr, "--key", "0.3", "--white", "2.5", "-o", str(ref8)]) == 0
    assert main([*argv[:3], f"reference={ref8}", *argv[4:]]) == 0
    text = capsys.readouterr().out
    np.testing.assert_allclose(float(text.split("  key: ")[1].split()[0]), 0.3, rtol=2e-2)
    ref16 = tmp_path / "ref16.png"
    assert main(["tonemap", small_exr, "--bits", "16", "-o", str(ref16)]) == 0
    assert main([*argv[:3], f"reference={ref16}", *argv[4:]]) == 1
    assert "16-bit PNG references are not supported" in capsys.readouterr().err


@pytest.mark.parametrize(
    "target,why",
    [
        ("mean", "expected STAT=VALUE"),
        ("mean=abc", "is not a number"),
        ("mean=2", "outside [0, 1]"),
        ("p101=0.5", "outside [0, 100]"),
        ("median=0.5", "unknown statistic"),
        ("tmqi=1", "tmqi is maximised and takes no value"),
        ("pu-ssim", "expected STAT=VALUE"),
    ],
)
def test_bad_target_is_a_usage_error(small_exr, tmp_path, capsys, target, why):
    argv = ["fit", small_exr, "--target", target, "-o", str(tmp_path / "x.png")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"--target {target!r}" in err and why in err and "valid forms: mean=V" in err
    assert len(err.strip().splitlines()) == 1


def test_other_usage_and_data_errors(small_exr, tmp_path, capsys):
    out = str(tmp_path / "x.png")
    assert main(["fit", small_exr, "--target", "mean=0.4", "--param", "nope", "-o", out]) == 2
    assert "nope" in capsys.readouterr().err
    assert main(["fit", small_exr, "--target", "mean=0.4", "--set", "key", "-o", out]) == 2
    assert "--set 'key'" in capsys.readouterr().err
    missing = str(tmp_path / "missing.png")
    assert main(["fit", small_exr, "--target", f"reference={missing}", "-o", out]) == 1
    assert "missing.png" in capsys.readouterr().err


def _printed(text: str, label: str) -> float:
    return float(text.split(f"  {label}: ")[1].split()[0])


def test_tmqi_target_maximises_the_quality_of_the_written_image(small_exr, tmp_path, capsys):
    """``--target tmqi``: the fitted key is a maximum of TMQI Q (neighbouring keys score
    lower), and the printed Q is that of the written 8-bit image."""
    out = tmp_path / "tmqi.png"
    argv = ["fit", small_exr, "--param", "key", "--target", "tmqi", "--max-size", "0",
            "-o", str(out)]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "status: converged" in text
    key, q = _printed(text, "key"), _printed(text, "tmqi Q (maximised)")
    white = _printed(text, "L_white")
    hdr = np.asarray(hdrjax.io.read(small_exr).rgb(), np.float64)

    def quality(k):
        shown = np.asarray(hdrjax.tonemap(hdr, "reinhard2002", key=k, L_white=white), np.float64)
        shown = np.clip(shown, 0, 1)
        encoded = np.where(shown <= 0.0031308, 12.92 * shown, 1.055 * shown ** (1 / 2.4) - 0.055)
        return float(hdrjax.metrics.tmqi(hdr, encoded).q)

    assert 0.05 < key < 0.3  # an interior maximum (TMQI: 0.816 at 0.1, 0.799 at 0.18)
    assert quality(key) > max(quality(0.8 * key), quality(1.25 * key))
    np.testing.assert_allclose(quality(key), q, atol=1e-4)
    written = np.asarray(Image.open(out), np.float64) / 255.0
    np.testing.assert_allclose(float(hdrjax.metrics.tmqi(hdr, written).q), q, atol=2e-3)


def test_pu_ssim_target_recovers_the_reference_renditions_key(small_exr, tmp_path, capsys):
    ref = tmp_path / "ref.png"
    assert main(["tonemap", small_exr, "--key", "0.3", "--white", "2.5", "-o", str(ref)]) == 0
    capsys.readouterr()
    argv = ["fit", small_exr, "--param", "key", "--set", "key=0.18", "--set", "L_white=2.5",
            "--target", f"pu-ssim={ref}", "--max-size", "0",
            "-o", str(tmp_path / "pu.png")]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    np.testing.assert_allclose(_printed(text, "key"), 0.3, rtol=2e-2)  # an 8-bit reference
    assert _printed(text, f"pu-ssim={ref} (PU21 SSIM, maximised)") > 0.999
    # a reference is an input: never the output
    assert main([*argv[:-1], str(ref)]) == 2
