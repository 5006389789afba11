"""Plug-in operators (issue 17.4): the example of docs/operators.md, read from the page's
code block (so the page and this test cannot drift) and written to a file outside the
package, works through ``HDRJAX_PLUGINS`` on the command line (``tonemap --set``,
``fit --param``, ``operators NAME``, ``batch`` with shared and smoothed parameters), the
Python API (``tonemap``, ``fit``, ``study.sweep``, ``tile``) and the ``hdrjax.operators``
entry-point group; ``register`` refuses a name taken by another class. In-process ``main``
calls on 8×8 images; the registry is restored after each test, so other tests' registry
iteration does not see the plug-in."""

import dataclasses
import importlib.metadata
import re
import sys
import warnings
from pathlib import Path

import equinox as eqx
import numpy as np
import pytest
from jaxtyping import Array

import hdrjax
import hdrjax.io as hio
from hdrjax.cli import main
from hdrjax.operators import _base

DOCS = Path(__file__).parents[2] / "docs" / "operators.md"
EXAMPLE = re.search(r"<!-- plugin-example -->\n```python\n(.*?)```", DOCS.read_text(), re.S)
NAME = "simple_photographic"
WEIGHTS = np.array([0.2126, 0.7152, 0.0722])
RTOL = 1e-4  # float32


def _restore(saved: dict, modules: set) -> None:
    _base._REGISTRY.clear()
    _base._REGISTRY.update(saved)
    for name in set(sys.modules) - modules:
        if name.startswith(("hdrjax_plugin_", "plugin_pkg")):
            del sys.modules[name]


@pytest.fixture
def registry(monkeypatch):
    """The registry, the entry-point flag and the imported modules as they were before the
    test (registrations and plug-in modules the test adds are dropped afterwards)."""
    saved, modules = dict(_base._REGISTRY), set(sys.modules)
    monkeypatch.setattr(_base, "_entry_points_loaded", _base._entry_points_loaded)
    yield _base._REGISTRY
    _restore(saved, modules)


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    """The docs example as ``simple_photographic.py`` outside the package, named by
    ``HDRJAX_PLUGINS`` (imported by the first ``main`` call; one class for the module's
    tests, so they share compiled functions), and an 8×8 image ``in.pfm`` in ``tmp``."""
    assert EXAMPLE is not None, "docs/operators.md: the plug-in example block is missing"
    assert NAME not in hdrjax.operator_names()  # the package does not know it
    tmp = tmp_path_factory.mktemp("plugin")
    path = tmp / "plugin" / "simple_photographic.py"
    path.parent.mkdir()
    path.write_text(EXAMPLE[1])
    rgb = np.random.default_rng(0).lognormal(0.0, 2.0, (8, 8, 3)).astype(np.float32)
    hio.write(tmp / "in.pfm", rgb)
    saved, modules = dict(_base._REGISTRY), set(sys.modules)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("HDRJAX_PLUGINS", f" {path} ,")  # spaces and empty entries are skipped
        yield path, tmp, hio.read(tmp / "in.pfm").rgb()
    _restore(saved, modules)


def _reference(rgb, key, log_average=None):
    """The docs' operator in float64 NumPy: ``L = key · L_w / L̄_w``, ``L_d = L / (1 + L)``,
    colour ratios kept; ``L̄_w`` with delta 1e-6 (Reinhard et al. 2002, Eqs. 1–3)."""
    rgb = np.asarray(rgb, np.float64)
    L = rgb @ WEIGHTS
    if log_average is None:
        log_average = np.exp(np.mean(np.log(L + 1e-6)))
    s = key * L / log_average
    return rgb * (s / (1 + s) / L)[..., None]


def test_plugin_through_tonemap_set_and_the_api(plugin, tmp_path, capsys):
    _, src, rgb = plugin
    out = tmp_path / "out.pfm"
    argv = ["tonemap", str(src / "in.pfm"), "-o", str(out), "--method", NAME]
    assert main([*argv, "--set", "key=0.3"]) == 0
    cli = hio.read(out).rgb()
    np.testing.assert_allclose(cli, _reference(rgb, 0.3), rtol=RTOL)
    # now registered in this process: the Python API finds it, case/separator-insensitive
    assert NAME in hdrjax.operator_names()
    api = hdrjax.tonemap(rgb, method="Simple-Photographic", key=0.3)
    np.testing.assert_allclose(np.asarray(api), cli, rtol=RTOL)
    # the metadata declared in the file reaches --set's range check: one line, exit 2
    capsys.readouterr()
    assert main([*argv, "--set", "key=-1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "key: expected a number in (0, inf) (simple_photographic" in err


def test_plugin_operators_page_and_listing(plugin, capsys):
    assert main(["operators", NAME]) == 0
    page = capsys.readouterr().out
    assert page.startswith(f"{NAME}: ")
    assert "https://doi.org/10.1145/566654.566575" in page
    assert "the key a: the scaled luminance of the log-average" in page
    assert "default: 0.18; range: (0, inf)" in page
    assert "default: estimated; range: (0, inf); estimated from the image" in page
    assert "fitted by default (hdrjax fit): key" in page
    assert main(["operators"]) == 0
    assert any(ln.startswith(NAME + " ") for ln in capsys.readouterr().out.splitlines())


def test_plugin_fit_param_on_the_command_line_and_in_python(plugin, tmp_path, capsys):
    _, src, rgb = plugin
    out = tmp_path / "fit.pfm"
    argv = ["fit", str(src / "in.pfm"), "-o", str(out), "--method", NAME]
    assert main([*argv, "--param", "key", "--target", "mean=0.3"]) == 0
    text = capsys.readouterr().out
    cli_key = float(re.search(r"\bkey[ =:]+([0-9.eE+-]+)", text)[1])
    mean = (np.clip(hio.read(out).rgb(), 0, 1) @ WEIGHTS).mean()  # MeanLuminance
    np.testing.assert_allclose(mean, 0.3, rtol=1e-3)
    import hdrjax.fit as hf
    import hdrjax.targets as ht

    # the command line's call (a measured start, the file's weights): compiled once
    img = hio.read(src / "in.pfm")
    start = hdrjax.get_operator(NAME)().measure(rgb)
    target = ht.MeanLuminance(0.3, weights=img.luminance_weights)
    res = hf.fit(start, rgb, target, params=("key",))
    assert bool(res.success)
    np.testing.assert_allclose(float(res.params["key"]), cli_key, rtol=1e-3)
    # the fitted operator is the plug-in class with the fitted key
    np.testing.assert_allclose(
        np.asarray(res.operator(rgb)), _reference(rgb, float(res.params["key"])), rtol=RTOL
    )


def test_plugin_batch_shares_the_pooled_log_average(plugin, tmp_path):
    _, src, rgb = plugin
    hio.write(tmp_path / "in2.pfm", 4 * rgb)
    frames = [str(src / "in.pfm"), str(tmp_path / "in2.pfm")]
    out = tmp_path / "batch"
    argv = ["batch", *frames, "-o", str(out), "--method", NAME, "--format", "pfm"]
    assert main([*argv, "--same-parameters", "--set", "key=0.3"]) == 0
    # one log-average over both frames' pixels (pooling "log_mean"): the brighter frame
    # comes out brighter, which per-frame estimates (scale invariance) would not give
    L = np.concatenate([rgb @ WEIGHTS, 4 * rgb @ WEIGHTS]).astype(np.float64)
    pooled = np.exp(np.mean(np.log(L + 1e-6)))
    for name, k in (("in", 1), ("in2", 4)):
        got = hio.read(out / f"{name}.pfm").rgb()
        np.testing.assert_allclose(got, _reference(k * rgb, 0.3, pooled), rtol=RTOL, err_msg=name)


def test_plugin_batch_smooths_the_log_average_over_time(plugin, tmp_path):
    """``--smooth``: each frame's log-average smoothed as its ``pooling="log_mean"``
    declares, a centred exponential moving average of ``ln L̄_w`` (time constant 1 frame)."""
    _, src, rgb = plugin
    hio.write(tmp_path / "in2.pfm", 4 * rgb)
    frames = [str(src / "in.pfm"), str(tmp_path / "in2.pfm")]
    out = tmp_path / "batch"
    argv = ["batch", *frames, "-o", str(out), "--method", NAME, "--format", "pfm"]
    assert main([*argv, "--smooth", "--smooth-frames", "1", "--set", "key=0.3"]) == 0
    L = rgb.astype(np.float64) @ WEIGHTS
    ln_avg = np.array([np.mean(np.log(k * L + 1e-6)) for k in (1, 4)])
    w = np.exp(-np.abs(np.subtract.outer(np.arange(2), np.arange(2))))
    smoothed = np.exp(w @ ln_avg / w.sum(axis=1))
    for name, k, avg in (("in", 1, smoothed[0]), ("in2", 4, smoothed[1])):
        got = hio.read(out / f"{name}.pfm").rgb()
        np.testing.assert_allclose(got, _reference(k * rgb, 0.3, avg), rtol=RTOL, err_msg=name)


def test_plugin_through_tiles(plugin):
    """``hdrjax.tile`` maps the plug-in tile by tile with the log-average of the merged
    tile statistics: the whole image's result."""
    path, _, rgb = plugin
    hdrjax.cli.load_plugins(str(path))
    op = hdrjax.make_operator(NAME, key=0.3)
    got = hdrjax.tile.apply(hdrjax.tile.Tonemap(op), rgb, tile=4)
    np.testing.assert_allclose(got, _reference(rgb, 0.3), rtol=RTOL)


def test_plugin_study_sweep(plugin):
    path, _, rgb = plugin
    hdrjax.cli.load_plugins(str(path))  # imported once: the class the other tests use
    res = hdrjax.study.sweep(NAME, rgb, {"key": [0.09, 0.36]}, max_size=None)
    for i, key in enumerate((0.09, 0.36)):
        want = (np.clip(_reference(rgb, key), 0, 1) @ WEIGHTS).mean()
        np.testing.assert_allclose(float(res.statistics[i, 0]), want, rtol=RTOL)


def test_hdrjax_plugins_bad_entry_exits_2_with_one_line(registry, monkeypatch, capsys):
    for entry in ("no_such_plugin_module", "/no/such/plugin.py"):
        monkeypatch.setenv("HDRJAX_PLUGINS", f"{entry}")
        assert main(["operators"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"HDRJAX_PLUGINS: cannot import {entry!r}" in err


def _dist(tmp_path, value: str, module: str, source: str):
    """A minimal installed distribution in ``tmp_path`` declaring ``value`` in the
    ``hdrjax.operators`` entry-point group."""
    (tmp_path / f"{module}.py").write_text(source)
    info = tmp_path / "plugin_pkg-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: plugin_pkg\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[hdrjax.operators]\n{value}\n")


def test_entry_point_plugins_load_once_and_a_broken_one_warns(
    registry, tmp_path, monkeypatch, recwarn
):
    """An installed package's module registers its operator on the registry's first use; a
    class entry point is registered under the entry point's name; a plug-in that fails to
    import is one warning line naming it, and the rest of the registry still works."""
    source = EXAMPLE[1].replace("simple_photographic", "plugin_pkg_op")
    _dist(
        tmp_path,
        "plugin_pkg_op = plugin_pkg_mod\nbroken = plugin_pkg_broken\n"
        "by_class = plugin_pkg_mod:SimplePhotographic",
        "plugin_pkg_mod",
        source,
    )
    (tmp_path / "plugin_pkg_broken.py").write_text("raise RuntimeError('bad\\nplug-in')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    monkeypatch.setattr(_base, "_entry_points_loaded", False)
    names = hdrjax.operator_names()
    assert "plugin_pkg_op" in names and "reinhard2002" in names
    # the class entry point names a class its module registered already: not twice
    assert "by_class" not in names
    warned = [str(w.message) for w in recwarn if issubclass(w.category, RuntimeWarning)]
    assert len(warned) == 1 and "\n" not in warned[0]
    assert "'broken' (plugin_pkg_broken) not loaded: bad plug-in" in warned[0]
    rgb = np.random.default_rng(1).lognormal(0.0, 1.0, (8, 8, 3)).astype(np.float32)
    out = hdrjax.tonemap(rgb, method="plugin_pkg_op", key=0.3)
    np.testing.assert_allclose(np.asarray(out), _reference(rgb, 0.3), rtol=RTOL)
    # loaded once: a second listing imports nothing again
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert hdrjax.operator_names() == names


def test_class_entry_point_is_registered_under_its_name(registry, tmp_path, monkeypatch):
    source = "\n".join(ln for ln in EXAMPLE[1].splitlines() if not ln.startswith('@register("'))
    _dist(tmp_path, "by_class = plugin_pkg_cls:SimplePhotographic", "plugin_pkg_cls", source)
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    monkeypatch.setattr(_base, "_entry_points_loaded", False)
    cls = hdrjax.get_operator("by-class")
    assert cls.__name__ == "SimplePhotographic" and cls.name == "by_class"


def test_register_refuses_a_name_taken_by_another_class(registry):
    class Other(_base.AbstractOperator):
        def _apply(self, p):
            return p.rgb

    with pytest.raises(ValueError) as e:
        hdrjax.operators.register("Reinhard-2002")(Other)
    msg = str(e.value)
    assert "\n" not in msg
    assert msg.startswith("name: 'Reinhard-2002' is already registered to")
    assert "hdrjax.operators._reinhard2002.Reinhard2002" in msg
    assert hdrjax.get_operator("reinhard2002").__name__ == "Reinhard2002"
    with pytest.raises(ValueError, match="expected a subclass of hdrjax.operators"):
        hdrjax.operators.register("not_an_operator")(dict)
    with pytest.raises(ValueError, match="name: expected an operator name"):
        hdrjax.operators.register(" _ ")


def test_plain_eqx_field_plugin_takes_help_from_its_docstring(registry, capsys):
    """A plug-in without :func:`parameter` metadata: help from the docstring's Attributes
    section, no range; ``--set`` and ``operators NAME`` still work."""

    @hdrjax.operators.register("plain_gain")
    class PlainGain(_base.AbstractLuminanceCurve):
        """``L_d = gain · L`` (a test operator).

        Attributes:
            gain: multiplier of the luminance.
            weights: luminance weights.
        """

        gain: Array = eqx.field(default=0.5, converter=_base.param)
        weights: tuple[float, float, float] = eqx.field(
            default=(0.2126, 0.7152, 0.0722), static=True
        )

        def _curve(self, L):
            return self.gain * L

    infos = {i.name: i for i in hdrjax.operators.parameter_info(PlainGain)}
    assert infos["gain"].help == "multiplier of the luminance"
    assert infos["gain"].range is None and infos["gain"].default == 0.5
    assert infos["gain"].shape == () and infos["weights"].shape is None
    assert dataclasses.asdict(infos["weights"])["static"] is True
    assert main(["operators", "plain_gain"]) == 0
    assert "multiplier of the luminance" in capsys.readouterr().out
    from hdrjax.cli import build_parser
    from hdrjax.cli._cmd_tonemap import build_operator

    args = build_parser().parse_args(
        ["tonemap", "in.exr", "-o", "o.png", "--method", "plain-gain", "--set", "gain=2"]
    )
    assert float(build_operator(args).gain) == 2.0
