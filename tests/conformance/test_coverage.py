"""Every public callable of hdrjax is in the conformance suite or in the exemption table.

The rule for "public": the modules are ``hdrjax`` and every module named in
``hdrjax.__all__`` (``hdrjax.display``, ..., ``hdrjax.stats`` — the public name of
``hdrjax._stats``; ``hdrjax.cli`` is the command line, covered by test_cli_errors.py); no
module is exempt as a whole. A module's public names are its ``__all__`` when it defines
one, otherwise every name in its namespace without a leading underscore that is not itself
a module (names a lazy package binds on import are thus never counted). A
public *callable* is such a name bound to a function or a class (constants, registries and
modules are not callables). The same object under two names
(``hdrjax.tonemap`` and ``hdrjax.operators.tonemap``) is covered once for both.

Covered means: named by a case of ``_table.py`` (images) or ``test_geometry.py``
(directions, sizes), or a registered tone-mapping operator (``hdrjax.operator_names()``),
which ``tests/operators/test_conformance.py`` runs through the same families without a list.
A new public function fails ``test_every_public_callable_is_covered`` until it gets a case or
an exemption with its reason.
"""

import inspect
import types

import hdrjax

from . import test_geometry
from ._table import covered_names

# Not image functions, so the families do not apply; each is tested where the comment says.
EXEMPT = {
    # registry access and dispatch: exercised for every operator by
    # tests/operators/test_conformance.py (make/get/tonemap/parameter_names/unknown names)
    "hdrjax.get_operator": "registry access (tests/operators/test_conformance.py)",
    "hdrjax.make_operator": "registry access (tests/operators/test_conformance.py)",
    "hdrjax.operator_names": "registry listing (tests/operators/test_conformance.py)",
    "hdrjax.tonemap": "dispatcher over the registry (tests/operators/test_conformance.py)",
    "hdrjax.operators.parameter_names": "registry metadata (tests/operators/test_conformance.py)",
    "hdrjax.operators.register": "registry decorator (every registered operator is tested)",
    "hdrjax.operators.parameter": "field declaration (tests/operators/test_metadata.py)",
    "hdrjax.operators.parameter_info": "registry metadata (tests/operators/test_metadata.py)",
    "hdrjax.operators.ParameterInfo": "metadata record (tests/operators/test_metadata.py)",
    "hdrjax.operators.AbstractOperator": "abstract base: its subclasses are the registry",
    # mergeable statistics: merge and bind over the registry (tests/operators/test_statistics.py)
    "hdrjax.stats.Statistics": "statistics record (tests/operators/test_statistics.py)",
    "hdrjax.stats.summarise": "luminance statistics (tests/operators/test_statistics.py)",
    "hdrjax.stats.summarise_histogram": "summarise's single pass (tests/core/test_stats_encode.py)",
    "hdrjax.stats.percentile_by_selection": "exact percentiles (tests/core/test_stats_encode.py)",
    "hdrjax.stats.selection_range": "percentile_by_selection's range (test_stats_encode.py)",
    "hdrjax.tile.operator_statistics": "merged tile statistics (tests/tile/test_registry.py)",
    "hdrjax.tile.dask_operator_statistics": "merged dask statistics (tests/tile/test_dask.py)",
    "hdrjax.operators.AbstractLuminanceCurve": "abstract base: its subclasses are the registry",
    # the plug-in author's helpers: every registered operator's bind uses them; the docs'
    # plug-in example runs through tests/operators/test_plugins.py
    "hdrjax.operators.StatisticsSettings": "bind's settings record (every operator's bind)",
    "hdrjax.operators.bound_stats": "bind's statistics check (every operator's bind)",
    "hdrjax.operators.fill": "bind's setter (every operator's bind)",
    "hdrjax.operators.weights_field": "field declaration (tests/operators/test_metadata.py)",
    # scalar camera formulas (exposure settings to luminance), no image input
    "hdrjax.operators.ev100_luminance": "tests/operators/test_linear_tabulated.py",
    "hdrjax.operators.saturation_luminance": "tests/operators/test_linear_tabulated.py",
    # abstract bases and plain result containers (dataclasses/NamedTuples/pytrees)
    "hdrjax.targets.AbstractStatisticTarget": "abstract base: its subclasses are cases",
    "hdrjax.vision.AbstractContrastSpace": "abstract base: ConeOpponentSpace is a case",
    "hdrjax.display.FalseColor": "result container of false_color (a case)",
    "hdrjax.display.FalseColorScale": "result container of false_color_scale (a case)",
    # figures: matplotlib, NumPy side, no numeric contract beyond the image cases
    "hdrjax.display.render_figure": "figure to pixels (tests/display/test_false_color.py)",
    "hdrjax.lights.plot_lights": "matplotlib figure (tests/lights/test_detect.py)",
    "hdrjax.show": "matplotlib figure of tone-mapped images (tests/core/test_show.py)",
    # process settings, no image
    "hdrjax.tune_memory": "allocator and dispatch settings, no image (tests/core/test_memory.py)",
    # files: the fuzz test accepts only ReadError or a correct image for every reader
    # (tests/io/test_io_errors_fuzz.py); round trips in tests/conformance/test_properties.py
    # exposure brackets: integer code values (N, H, W, 3) with exposure times, not linear
    # images, so the image families do not apply; each function's own bad-input, finite-
    # output, dtype and vmap tests are in tests/merge/
    "hdrjax.merge.merge": "bracket merge (tests/merge/test_merge.py)",
    "hdrjax.merge.recover_response": "response recovery (tests/merge/test_response.py)",
    "hdrjax.merge.align_mtb": "bracket alignment (tests/merge/test_align.py)",
    "hdrjax.merge.apply_shifts": "bracket alignment (tests/merge/test_align.py)",
    "hdrjax.merge.ghost_mask": "bracket ghost mask (tests/merge/test_align.py)",
    "hdrjax.merge.fuse": "exposure fusion of a bracket (tests/merge/test_fuse.py)",
    "hdrjax.merge.as_codes": "bracket validation (tests/merge/test_simulate.py)",
    "hdrjax.merge.Codes": "result container of as_codes (tests/merge/test_simulate.py)",
    "hdrjax.merge.simulate_bracket": "bracket simulator (tests/merge/test_simulate.py)",
    "hdrjax.merge.Bracket": "result container of simulate_bracket (test_simulate.py)",
    "hdrjax.merge.true_response": "a camera curve's inverse (tests/merge/test_simulate.py)",
    "hdrjax.merge.camera_curve": "camera curve lookup (tests/merge/test_simulate.py)",
    "hdrjax.merge.weight_function": "per-code weight tables (tests/merge/test_merge.py)",
    "hdrjax.merge.absolute_scale": "scalar camera formula (tests/merge/test_calibrate.py)",
    "hdrjax.merge.read_bracket": "file reader (tests/merge/test_read.py)",
    "hdrjax.merge.BracketFiles": "result container of read_bracket (tests/merge/test_read.py)",
    "hdrjax.merge.load_response": "file reader (tests/merge/test_response.py)",
    "hdrjax.merge.save_response": "file writer (tests/merge/test_response.py)",
    "hdrjax.io.read": "file reader (tests/io/test_io_errors_fuzz.py)",
    "hdrjax.io.write": "file writer (round trips: tests/conformance/test_properties.py)",
    "hdrjax.io.write_display": "file writer (tests/io/test_io_read_write.py)",
    "hdrjax.io.find_sidecars": "file discovery (tests/io/test_io_sidecars.py)",
    "hdrjax.io.atomic_path": "context manager for writes (tests/io/test_io_read_write.py)",
    "hdrjax.layers.ReadError": "error type (raised by every reader: fuzz test)",
    "hdrjax.layers.LayerShapeError": "error type (tests/io/test_io_errors_fuzz.py)",
    "hdrjax.layers.MissingLayerError": "error type (tests/io/test_io_read_write.py)",
    "hdrjax.layers.LayeredImage": "NumPy container validated on construction (tests/io)",
    "hdrjax.layers.normalise_unit": "unit-string normalisation (tests/io/test_layers_measure.py)",
    # compiled calls on pixels in other primaries: equal to the operator on converted
    # pixels, tested against colour-science's conversion
    "hdrjax.operators.measure_in_space": "tests/core/test_spaces.py (files, every operator)",
    "hdrjax.operators.apply_in_space": "tests/core/test_spaces.py (files, every operator)",
    # displays: a record and its name lookup (the encodings themselves are cases)
    "hdrjax.display.Display": "display record (tests/display/test_displays.py)",
    "hdrjax.display.get_display": "name lookup (tests/io/test_display_tags.py)",
    # working spaces and spectra: matrices made once in NumPy (their image functions,
    # convert and spectral_to_xyz, are cases)
    "hdrjax.spaces.Space": "space record (tests/core/test_spaces.py)",
    "hdrjax.spaces.space": "name lookup (tests/core/test_spaces.py)",
    "hdrjax.spaces.check_cat": "name lookup (tests/core/test_spaces.py)",
    "hdrjax.spaces.conversion_matrix": "3×3 matrix vs colour-science (tests/core/test_spaces.py)",
    "hdrjax.spaces.is_identity": "matrix predicate (tests/core/test_spaces.py)",
    "hdrjax.spaces.luminance_weights_in": "3 weights (tests/core/test_spaces.py)",
    "hdrjax.spectral.spectral_weights": "n×3 matrix vs colour-science (test_spectral.py)",
    "hdrjax.spectral.spectral_kind": "channel names (tests/core/test_spectral.py)",
    # measurement on layered images: NumPy side, pixel coordinates and JSON
    "hdrjax.measure.Distance": "result container (tests/io/test_layers_measure.py)",
    "hdrjax.measure.Region": "region geometry (tests/io/test_layers_measure.py)",
    "hdrjax.measure.distance": "layer readout (tests/io/test_layers_measure.py)",
    "hdrjax.measure.readout": "layer readout (tests/io/test_layers_measure.py)",
    "hdrjax.measure.region_stats": "region statistics (tests/io/test_layers_measure.py)",
    "hdrjax.measure.region_json": "JSON export (tests/io/test_layers_measure.py)",
    "hdrjax.measure.save_region": "JSON file (tests/io/test_layers_measure.py)",
    "hdrjax.measure.load_region": "JSON file (tests/io/test_layers_measure.py)",
    # batch: the file-level pipeline; its array function render_batch is a case (== its
    # operator), the rest reads, schedules and writes files (tests/batch/)
    "hdrjax.batch.run": "file pipeline over frames (tests/batch/test_batch_api.py)",
    "hdrjax.batch.expand_paths": "path globbing (tests/batch/test_batch_api.py)",
    "hdrjax.batch.read_frame": "file reader (tests/batch/test_batch_api.py)",
    "hdrjax.batch.FrameError": "error type (tests/batch/test_batch_api.py)",
    "hdrjax.batch.BatchSummary": "result container of run (tests/batch/test_batch_api.py)",
    "hdrjax.batch.Step": "pipeline step description (tests/batch/test_batch_api.py)",
    "hdrjax.batch.step": "pipeline step constructor (tests/batch/test_batch_api.py)",
    "hdrjax.batch.pooled_stats": "merges per-frame Statistics (tests/batch/test_batch_api.py)",
    "hdrjax.batch.smooth_series": "1-D series smoothing (tests/batch/test_batch_api.py)",
    # tile: apply of every step and statistics are cases (== the whole-image functions);
    # the dask graph builders need a scheduler (tests/tile/test_dask.py)
    "hdrjax.tile.to_dask": "dask graph of a step (tests/tile/test_dask.py)",
    "hdrjax.tile.dask_statistics": "dask statistics (tests/tile/test_dask.py)",
    # figures and parameter sweeps (matplotlib; solves over an operator)
    "hdrjax.plot.tone_curve": "matplotlib figure (tests/fit/test_study.py)",
    "hdrjax.plot.angular_grid": "matplotlib drawing (tests/panorama/test_grid.py)",
    "hdrjax.plot.with_angular_grid": "matplotlib drawing (tests/panorama/test_grid.py)",
    "hdrjax.study.sweep": "parameter sweep over an operator (tests/fit/test_study.py)",
    "hdrjax.study.plot_sweep": "matplotlib figure (tests/fit/test_study.py)",
    "hdrjax.study.SweepResult": "result container of sweep (tests/fit/test_study.py)",
    # comparison report: runs registered operators and hdrjax.metrics (both conformance
    # cases) over one image and tabulates them; NaN pixels in tests/report/test_compare.py
    "hdrjax.report.compare": "report over operators (tests/report/test_compare.py)",
    "hdrjax.report.ComparisonTable": "result container of compare (tests/report/)",
    "hdrjax.report.ComparisonRow": "row record of ComparisonTable (tests/report/)",
    "hdrjax.report.fit_target": "name lookup of compare's fit (tests/report/)",
    # fitting: optimistix solves over an operator; owned and tested in tests/fit/
    "hdrjax.fit.fit": "solver (tests/fit/test_fit.py)",
    "hdrjax.fit.fit_batch": "solver (tests/fit/test_fit.py)",
    "hdrjax.fit.fit_sequence": "solver (tests/fit/test_fit.py)",
    "hdrjax.fit.downscale": "fit preprocessing (tests/fit/test_fit.py)",
    "hdrjax.fit.FitResult": "result container (tests/fit/test_fit.py)",
}


def public_modules() -> dict[str, types.ModuleType]:
    mods = {"hdrjax": hdrjax}
    for name in hdrjax.__all__:
        obj = getattr(hdrjax, name)  # imports a lazily loaded subpackage
        if isinstance(obj, types.ModuleType):
            mods[f"hdrjax.{name}"] = obj
    return mods


def public_callables() -> dict[str, object]:
    out = {}
    for mname, mod in public_modules().items():
        names = getattr(mod, "__all__", None)
        if names is None:
            names = [n for n in vars(mod) if not n.startswith("_")]
        for n in names:
            obj = getattr(mod, n)
            if isinstance(obj, types.ModuleType):
                continue
            if inspect.isfunction(obj) or inspect.isclass(obj) or callable(obj):
                out[f"{mname}.{n}"] = obj
    return out


def _covered_objects() -> list[object]:
    pub = public_callables()
    names = covered_names() | test_geometry.COVERS
    unknown = sorted(n for n in names if n not in pub)
    assert not unknown, f"cases name callables that are not public: {unknown}"
    objs = [pub[n] for n in names]
    ops = hdrjax.operator_names()
    objs += [o for o in pub.values() if inspect.isclass(o) and getattr(o, "name", None) in ops]
    return objs


def _is_in(obj, objs):
    return any(obj is o for o in objs)


def test_every_public_callable_is_covered():
    pub = public_callables()
    covered = _covered_objects()
    exempt = [pub[n] for n in EXEMPT if n in pub]
    missing = sorted(n for n, o in pub.items() if not _is_in(o, covered) and not _is_in(o, exempt))
    assert not missing, (
        f"public callables with neither a conformance case nor an exemption: {missing}"
    )


def test_exemptions_are_current():
    """An exemption names an existing public callable that no case covers (stale entries
    would hide a function that later loses its test)."""
    pub = public_callables()
    covered = _covered_objects()
    stale = sorted(n for n in EXEMPT if n not in pub)
    assert not stale, f"exempt names that are not public: {stale}"
    both = sorted(n for n in EXEMPT if _is_in(pub[n], covered))
    assert not both, f"exempt names that are covered by a case: {both}"


def test_the_rule_finds_the_known_surface():
    """The enumeration is not vacuous: it sees functions, classes and the aliased names."""
    pub = public_callables()
    for n in (
        "hdrjax.tonemap",
        "hdrjax.operators.Reinhard2002",
        "hdrjax.stats.percentile",
        "hdrjax.vision.glare",
        "hdrjax.lights.detect",
        "hdrjax.targets.Histogram",
        "hdrjax.panorama.sample_bilinear",
    ):
        assert n in pub, n
    assert len(pub) > 120
