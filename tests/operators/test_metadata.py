"""What every registered operator declares about itself (issue 17): parameter help, units,
ranges, estimated parameters and their pooling, reference, scale invariance, per-channel
mapping, default fit parameters, tile halo; and the range checks of ``make_operator``."""

import dataclasses
import math

import equinox as eqx
import jax
import numpy as np
import pytest

import hdrjax
from hdrjax.operators import get_operator, operator_names, parameter, parameter_info

from .cases import make

NAMES = operator_names()


@pytest.mark.parametrize("name", NAMES)
def test_every_parameter_is_described(name):
    cls = get_operator(name)
    infos = parameter_info(cls)
    init = [f.name for f in dataclasses.fields(cls) if f.init]
    assert [i.name for i in infos] == init
    for info in infos:
        where = f"{name}.{info.name}"
        assert info.help and "\n" not in info.help, where
        # settings that are not numbers: names (choices), tuples, models (a colour space)
        numeric = info.choices is None and not isinstance(info.default, (tuple, eqx.Module))
        if numeric:  # every number (scalar, vector or table) has a valid range
            assert info.range is not None and info.range[0] < info.range[1], where
            if not info.required and info.default is not None:
                assert info.contains(info.default), f"{where}: default outside its range"
        else:
            assert info.range is None, where
        if info.choices is not None:
            assert info.default in info.choices, where
        # an estimated parameter (None: measured) says how it pools over frames
        assert info.estimated == (info.pooling is not None), where
        if info.estimated:
            assert info.default is None and not info.static, where
            assert info.pooling in ("mean", "log_mean", "max", "min"), where
    assert cls.reference, name
    # the per-channel operators are the ones without luminance weights (or primaries,
    # which give the weights and the colour matrix: budak2005)
    assert cls.per_channel == ("weights" not in init and "chromaticities" not in init), name
    fields = {i.name: i for i in infos}
    for p in cls.default_fit_params:
        assert p in fields and not fields[p].static, f"{name}: fits {p}"


@pytest.mark.parametrize("name", NAMES)
def test_named_settings_refuse_other_names(name):
    """A setting declared with choices (compat, ceiling, look, …) refuses any other name
    when the class is constructed directly, as ``make_operator`` does: one message naming
    the setting, the operator and its choices."""
    cls = get_operator(name)
    required = {"luminance": [0.01, 1.0, 100.0], "display": [0.0, 0.5, 1.0]}
    needed = {i.name: required[i.name] for i in parameter_info(cls) if i.required}
    for info in parameter_info(cls):
        if info.choices is None:
            continue
        with pytest.raises(ValueError) as e:
            cls(**needed, **{info.name: "not-a-choice"})
        msg = str(e.value)
        assert msg.startswith(f"{info.name}: expected one of "), msg
        assert all(c in msg for c in info.choices) and f"({name}" in msg, msg
        assert "\n" not in msg


def test_declarations_that_other_modules_read():
    """Not vacuous: the values the CLI, fit, batch and tiles used to keep in their own
    tables (the issue's OPTION_PARAMS, DEFAULT_PARAMS, ESTIMATING, AUTO_EXPOSED)."""
    assert get_operator("reinhard2002").default_fit_params == ("key", "L_white")
    assert get_operator("tumblin1999").default_fit_params == ("L_wa", "L_max")
    assert get_operator("tumblin_reinhard").default_fit_params == ("L_wa", "L_white")
    assert get_operator("linear").default_fit_params == ("L_max",)
    assert get_operator("reinhard2002_local").default_fit_params == ("key",)
    view = {"aces_hill", "aces_narkowicz2015", "agx", "hable2010", "lottes2016", "pbr_neutral",
            "uchimura2017"}  # fmt: skip
    # ferradans2011 adapts and enhances each channel by itself (the paper's model)
    channels = {"simple", "gamma", "filmic", "ferradans2011"}
    assert {n for n in NAMES if get_operator(n).per_channel} == channels | view
    estimating = {n for n in NAMES if any(i.estimated for i in parameter_info(get_operator(n)))}
    assert {"reinhard2002", "reinhard2002_local", "tumblin_reinhard", "linear"} <= estimating
    assert not estimating & {"simple", "gamma", "filmic", "tabulated"}
    pooling = {i.name: i.pooling for i in parameter_info(get_operator("reinhard2004"))}
    assert pooling["L_max"] == "max" and pooling["L_min"] == "min"
    assert pooling["channel_average"] == "mean" and pooling["log_average"] == "log_mean"
    assert "10.1109/TVCG.2005.9" in get_operator("reinhard2004").reference


def test_halo_is_declared_by_the_operator():
    """The local operator reaches the radius of its largest Gaussian, ceil(4 s_max / (2√2))
    (39 pixels for the default scales 1 … 43 in 8 steps: s_max = 43^(7/8) = 26.87);
    pointwise operators 0."""
    s_max = 43.0 ** (7 / 8)
    r = math.ceil(4.0 * s_max / (2.0 * math.sqrt(2.0)))
    assert r == 39
    local = hdrjax.make_operator("reinhard2002_local")
    assert local.halo((64, 64, 3)) == (r, r)
    assert hdrjax.make_operator("reinhard2002_auto").halo((64, 64, 3)) == (r, r)
    small = hdrjax.make_operator("reinhard2002_local", s_high=10.0, num=4)
    r_small = math.ceil(4.0 * 10.0 ** (3 / 4) / (2.0 * math.sqrt(2.0)))
    assert small.halo((64, 64, 3)) == (r_small, r_small)
    assert hdrjax.make_operator("reinhard2002").halo((64, 64, 3)) == (0, 0)
    from hdrjax.tile import Tonemap

    assert Tonemap(small).halo((64, 64, 3)) == (r_small, r_small)


@pytest.mark.parametrize(
    "name,params,needle",
    [
        ("reinhard2002", {"key": -0.18}, "key: expected a value in (0, inf) (reinhard2002)"),
        ("reinhard2004", {"f": 9.0}, "f: expected a value in [-8, 8] (reinhard2004)"),
        (
            "reinhard2004",
            {"channel_average": [0.2, -1.0, 0.3]},
            "channel_average: expected a value in [0, inf) (reinhard2004, image units)",
        ),
        ("logarithmic", {"q": 0.5}, "q: expected a value in [1, inf) (logarithmic)"),
        ("tumblin1999", {"L_da": float("nan")}, "L_da: expected a value in (0, inf)"),
        (
            "reinhard2002",
            {"percentile_method": "median"},
            "percentile_method: expected one of histogram | exact (reinhard2002)",
        ),
    ],
)
def test_make_operator_checks_ranges(name, params, needle):
    with pytest.raises(ValueError) as err:
        hdrjax.make_operator(name, **params)
    msg = str(err.value)
    assert needle in msg and "\n" not in msg, msg


def test_range_checks_skip_traced_values():
    """Inside jit a parameter is a tracer: no check (its value is unknown), the operator is
    built; the same value given concretely is refused."""
    img = np.ones((2, 2, 3), np.float32)
    # traced only (eval_shape compiles nothing)
    out = jax.eval_shape(lambda k: hdrjax.make_operator("reinhard2002", key=k)(img), -1.0)
    assert out.shape == (2, 2, 3)
    with pytest.raises(ValueError, match="key: expected"):
        hdrjax.tonemap(img, "reinhard2002", key=-1.0)


def test_parameter_helper_refuses_inconsistent_declarations():
    with pytest.raises(ValueError, match="pooling: an estimated parameter needs one"):
        parameter(None, help="x", estimated=True)
    with pytest.raises(ValueError, match="pooling: expected one of"):
        parameter(None, help="x", estimated=True, pooling="median")
    with pytest.raises(ValueError, match="range: expected an interval"):
        parameter(1.0, help="x", range="0..1")
    info = parameter(1.0, help="x", range="(0, 1]").metadata["hdrjax"]
    assert info.contains(1.0) and not info.contains(0.0) and info.range_text() == "(0, 1]"


def _traces_forward_mode(op, x) -> bool:
    try:
        jax.jit(lambda v: jax.jvp(op, (v,), (v,))).lower(x)  # lowered, not compiled
    except TypeError as e:
        if "custom_vjp" not in str(e):
            raise
        return False
    return True


def test_forward_mode_is_declared():
    """``forward_mode`` says whether ``jax.jvp`` passes through the operator (fits choose
    their solver and Jacobian by it: chiu1993's custom VJP made every default fit of it a
    TypeError)."""
    x = np.random.default_rng(0).lognormal(0.0, 1.0, (6, 8, 3)).astype(np.float32)
    mismatched = []
    for name in NAMES:
        op = make(name)
        if _traces_forward_mode(op, x) != get_operator(name).forward_mode:
            mismatched.append(name)
    assert not mismatched, f"forward_mode declared wrongly: {mismatched}"
    assert not get_operator("chiu1993").forward_mode
