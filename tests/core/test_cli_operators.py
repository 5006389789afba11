"""The command line reaches every parameter of every operator (issue 17): ``--set
PARAM=VALUE`` on tonemap/fit/batch, ``hdrjax operators [NAME]``, one-line errors with exit
status 2 naming the parameter and its valid range, and the file's luminance weights
reaching ``reinhard2004``. In-process ``main`` calls on 8×8 images."""

import equinox as eqx
import numpy as np
import pytest

import hdrjax
import hdrjax.io as hio
from hdrjax.cli import build_parser, main
from hdrjax.cli._cmd_tonemap import build_operator
from hdrjax.layers import LayeredImage
from hdrjax.operators import get_operator, operator_names, parameter_info

from ..operators.cases import natural

NAMES = operator_names()
AP0 = (0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.077, 0.32168, 0.33767)
"""ACES AP0 chromaticities: luminance weights (0.34397, 0.72817, -0.07213)."""


def _set_case(name: str) -> tuple[str, object] | None:
    """A parameter of ``name`` and a valid value other than its default: the first scalar
    array parameter (a setting with choices for the table operator); ``None`` for an
    operator without parameters."""
    infos = parameter_info(get_operator(name))
    scalars = [i for i in infos if i.shape == () and not i.static and i.choices is None]
    for info in scalars:
        d = info.default
        for v in (2.0,) if d is None else (d * 1.5, d * 0.5, 0.5) if d else (0.5,):
            if info.contains(v):
                return info.name, v
    for info in infos:
        if info.choices:
            return info.name, next(c for c in info.choices if c != info.default)
    return None


CASES = {n: _set_case(n) for n in NAMES}


def _cli_operator(argv: list[str]):
    return build_operator(build_parser().parse_args(["tonemap", "in.exr", "-o", "o.png", *argv]))


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    path = tmp_path_factory.mktemp("table") / "t.csv"
    path.write_text("luminance,display\n0.01,0.05\n1,0.5\n100,1\n")
    return str(path)


def test_set_reaches_one_parameter_of_every_operator(table):
    """``--set`` builds exactly the operator the Python API builds with that parameter
    (equal pytrees, hence equal outputs), and not the default one. That each parameter
    moves the output is tests/fit/test_gradients.py's (a derivative per parameter of every
    operator); evaluating 17 operators twice here would cost ~30 s of compiles."""
    assert CASES["simple"] is None and all(CASES[n] for n in NAMES if n != "simple")
    extra = {"tabulated": ["--table", table]}
    for name in NAMES:
        if CASES[name] is None:
            continue
        param, value = CASES[name]
        argv = ["--method", name, *extra.get(name, [])]
        op = _cli_operator([*argv, "--set", f"{param}={value}"])
        if name == "tabulated":
            api = hdrjax.operators.Tabulated.from_file(table, **{param: value})
        else:
            api = hdrjax.make_operator(name, **{param: value})
        assert bool(eqx.tree_equal(op, api)), name
        assert not bool(eqx.tree_equal(op, _cli_operator(argv))), name
        got = getattr(op, param)
        assert (got == value) if isinstance(value, str) else float(got) == pytest.approx(value)


def test_set_parses_integers_vectors_and_names():
    op = _cli_operator(
        ["--method", "reinhard2002_local", "--set", "num=5", "--set", "percentile_method=exact"]
    )
    assert op.num == 5 and isinstance(op.num, int) and op.percentile_method == "exact"
    op = _cli_operator(["--method", "reinhard2004", "--set", "channel_average=0.1,0.2,0.3"])
    np.testing.assert_allclose(op.channel_average, [0.1, 0.2, 0.3], rtol=1e-6)
    op = _cli_operator(["--method", "reinhard2002", "--set", "L_white=inf", "--key", "0.1"])
    assert float(op.L_white) == np.inf and float(op.key) == pytest.approx(0.1)


def test_tonemap_set_writes_what_the_api_computes(tmp_path, capsys):
    """End to end: the written image is the operator's with that parameter."""
    src = natural((8, 8), seed=4) * 10.0
    path = tmp_path / "in.pfm"
    hio.write(path, src)
    out = tmp_path / "out.pfm"
    argv = ["tonemap", str(path), "-o", str(out), "--method", "gamma", "--set", "EV=-1.5"]
    assert main(argv) == 0
    assert "EV: -1.5" in capsys.readouterr().out
    # colour-hdri's gamma operator with gamma = 1: 2^EV · RGB
    np.testing.assert_allclose(hio.read(out).image, src * 2.0**-1.5, rtol=1e-6)


@pytest.mark.parametrize(
    "argv,needle",
    [
        (
            ["--method", "reinhard2002", "--set", "key=-1"],
            "--set 'key=-1': key: expected a number in (0, inf) (reinhard2002), got '-1'",
        ),
        (
            ["--method", "reinhard2004", "--set", "f=nine"],
            "--set 'f=nine': f: expected a number in [-8, 8] (reinhard2004), got 'nine'",
        ),
        (
            ["--method", "schlick1994", "--set", "q=2"],
            "--set 'q=2': schlick1994 has no parameter 'q'; valid: p, L_max",
        ),
        (
            ["--method", "tumblin1999", "--set", "adaptation=median"],
            "adaptation: expected one of log_average | trimmed (tumblin1999), got 'median'",
        ),
        (
            ["--method", "reinhard2004", "--set", "channel_average=0.1,0.2"],
            "channel_average: expected a number in [0, inf) (reinhard2004, image units), 3"
            " comma-separated, got '0.1,0.2'",
        ),
        (["--method", "reinhard2002", "--set", "weights=1,0,0"], "weights is not set with --set"),
        (["--method", "reinhard2002", "--set", "key"], "--set 'key': expected PARAM=VALUE"),
        (
            ["--method", "reinhard2002", "--set", "key=0.1", "--set", "key=0.2"],
            "key is given twice",
        ),
        (
            ["--method", "tumblin1999", "--L-da", "1e-30", "--set", "C_max=0.5"],
            "--set 'C_max=0.5': C_max: expected a number in [1, inf) (tumblin1999), got '0.5'",
        ),
        (
            ["--method", "logarithmic", "--L-max", "5", "--set", "L_max=6"],
            "L_max is also given by its named option",
        ),
        (
            ["--method", "nope"],
            "method: unknown operator 'nope'; valid: aces_hill, aces_narkowicz2015",
        ),
    ],
)
def test_set_errors_exit_2_with_one_line(tmp_path, capsys, argv, needle):
    src = tmp_path / "in.pfm"
    hio.write(src, np.ones((2, 2, 3), np.float32))
    code = main(["tonemap", str(src), "-o", str(tmp_path / "o.png"), *argv])
    err = capsys.readouterr().err
    assert code == 2, err
    assert needle in err and err.count("\n") == 1, err


def test_named_options_are_checked_against_the_operators_range(tmp_path, capsys):
    """The shortcuts are ``--set`` in disguise: ``--L-max`` goes through the same range
    check, and one that the operator lacks is refused by name."""
    src = tmp_path / "in.pfm"
    hio.write(src, np.ones((2, 2, 3), np.float32))
    argv = ["tonemap", str(src), "-o", str(tmp_path / "o.png"), "--method", "linear"]
    assert main([*argv, "--key", "0.2"]) == 2
    assert "--key does not apply to --method linear" in capsys.readouterr().err
    assert main([*argv, "--ev100", "nan"]) == 2
    assert "--ev100: ev100: expected a number in (-inf, inf) (linear, EV)" in (
        capsys.readouterr().err
    )


def test_fit_and_batch_take_set(tmp_path, capsys):
    """``fit --set`` fixes a parameter (its value is reported among the others) and errors
    like tonemap; ``batch --set`` reaches the pipeline's operator."""
    src = tmp_path / "in.pfm"
    hio.write(src, np.ones((2, 2, 3), np.float32))
    bad = ["fit", str(src), "--target", "mean=0.3", "-o", str(tmp_path / "o.png")]
    assert main([*bad, "--method", "tumblin1999", "--set", "L_da=-2"]) == 2
    assert "L_da: expected a number in (0, inf) (tumblin1999, cd/m²)" in capsys.readouterr().err
    assert main([*bad, "--method", "gamma"]) == 2
    assert "--param: gamma has no parameters fitted by default" in capsys.readouterr().err
    from hdrjax.cli._cmd_batch import build_pipeline

    args = build_parser().parse_args(
        ["batch", str(src), "-o", str(tmp_path), "--method", "filmic", "--set", "exposure_bias=3"]
    )
    assert float(build_pipeline(args).operator.exposure_bias) == 3.0
    args = build_parser().parse_args(
        ["batch", str(src), "-o", str(tmp_path), "--method", "filmic", "--set", "A=3"]
    )
    with pytest.raises(hdrjax.cli.UsageError, match="filmic has no parameter 'A'"):
        build_pipeline(args)


def test_operators_lists_every_operator_and_one_operators_parameters(capsys):
    assert main(["operators"]) == 0
    text = capsys.readouterr().out
    lines = text.splitlines()
    for name in NAMES:
        assert any(ln.startswith(name + " ") for ln in lines), name
        ref = get_operator(name).reference
        assert ref.split(",")[0] in text, name
    assert "https://doi.org/10.1145/566654.566575" in text
    assert main(["operators", "Tumblin-Reinhard"]) == 0
    page = capsys.readouterr().out
    assert page.startswith("tumblin_reinhard: ")
    for info in parameter_info(get_operator("tumblin_reinhard")):
        assert f"\n  {info.name}" in page, info.name
    assert "  L_da [cd/m²]\n" in page and "default: 20; range: (0, inf)" in page
    assert "default: estimated; range: (0, inf); estimated from the image" in page
    assert "fitted by default (hdrjax fit): L_wa, L_white" in page
    assert "choices: log_average | trimmed" in page


def test_operators_unknown_name_exits_2(capsys):
    assert main(["operators", "nosuch2002"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "unknown operator 'nosuch2002'; valid: aces_hill, aces_narkowicz2015" in err


def _reinhard2004(rgb, weights, a):
    """Reinhard & Devlin 2005 as colour-hdri computes it (f = 0, m = 0.3, c = 0), in
    float64 NumPy: ``RGB / (RGB + I_a^m)``, ``I_a = a L + (1 − a) L_lav``."""
    rgb = rgb.astype(np.float64)
    L = rgb @ np.asarray(weights, np.float64)
    L_lav = np.exp(np.mean(np.log(np.maximum(L, 0.0) + np.finfo(np.float64).eps)))
    I_a = (a * L + (1 - a) * L_lav)[..., None]
    return rgb / (rgb + I_a**0.3)


def test_reinhard2004_uses_the_files_weights(tmp_path, capsys):
    """A file with ACES AP0 primaries is converted into the sRGB working space
    (colour-science's RGB_to_RGB, CAT02) and mapped with the luminance of its own
    primaries (0.34397 R + 0.72817 G − 0.07213 B of the file's pixels) on the command line,
    tonemap and batch alike — not with Rec.709's weights of the converted pixels."""
    import colour

    rgb = natural((8, 8), seed=5) * 5.0
    rgb[0, 0] = (4.0, 0.1, 0.1)  # a saturated red: its luminance differs most between primaries
    path = tmp_path / "ap0.exr"
    hio.write(path, LayeredImage(image=rgb, chromaticities=AP0))
    weights = hio.read(path).luminance_weights
    np.testing.assert_allclose(weights, (0.34397, 0.72817, -0.07213), atol=5e-6)
    ap0 = colour.RGB_Colourspace("AP0", np.reshape(AP0[:6], (3, 2)), AP0[6:])
    srgb = colour.RGB_to_RGB(np.asarray(rgb, np.float64), ap0, "sRGB")
    # the weights that give, from the converted pixels, the file's own luminance
    w_in, *_ = np.linalg.lstsq(srgb.reshape(-1, 3), rgb.reshape(-1, 3) @ weights, rcond=None)
    # converted, the saturated red has a negative channel: the operator maps it to 0
    want = np.where(srgb > 0, _reinhard2004(srgb, w_in, 0.5), 0.0)
    rec709 = np.where(srgb > 0, _reinhard2004(srgb, hdrjax.REC709_WEIGHTS, 0.5), 0.0)
    assert np.max(np.abs(want - rec709)) > 5e-4  # the weights matter (7e-4; rtol 1e-4)
    out = tmp_path / "t.pfm"
    argv = ["--method", "reinhard2004", "--set", "a=0.5"]
    assert main(["tonemap", str(path), "-o", str(out), *argv]) == 0
    assert "converted to sRGB (CAT02)" in capsys.readouterr().out
    np.testing.assert_allclose(hio.read(out).image, want, rtol=1e-4, atol=1e-6)
    folder = tmp_path / "batch"
    assert main(["batch", str(path), "-o", str(folder), *argv, "--format", "pfm", "-q"]) == 0
    np.testing.assert_allclose(hio.read(folder / "ap0.pfm").image, want, rtol=1e-4, atol=1e-6)
