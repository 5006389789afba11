"""Objects show their values (issue 24, point 1): operators, fit and sweep results,
luminance statistics, lights and scene reports print numbers with units (never equinox's
``f32[]`` shapes, never a full array) and give a notebook an HTML table.

The objects are built from their fields (no compile): the repr is the point, not the
computation that usually fills them."""

import base64
import html.parser
import io
import math
import re

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from PIL import Image

from hdrjax import operators as ops
from hdrjax._stats import LuminanceStats, Statistics
from hdrjax.fit import FitResult
from hdrjax.lights import Lights
from hdrjax.study import SweepResult
from hdrjax.vision import SceneReport
from hdrjax.vision._view import ResolvedView

SHAPE = re.compile(r"\b(?:weak_)?[fiub](?:8|16|32|64)\[")  # equinox's f32[] / i32[3]
LONGEST = 400
"""Characters a one-line repr may take (LayeredImage's is about 80; a dump is thousands)."""


class _Checker(html.parser.HTMLParser):
    """Well-formed HTML: every element closed in order (``img`` is void)."""

    VOID = {"img", "br", "hr", "meta", "input"}

    def __init__(self):
        super().__init__()
        self.open: list[str] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag not in self.VOID:
            self.open.append(tag)

    def handle_endtag(self, tag):
        assert self.open and self.open[-1] == tag, f"</{tag}> closes {self.open[-1:]}"
        self.open.pop()

    def handle_data(self, data):
        self.text.append(data)


def _html_text(page: str) -> str:
    """The text of a well-formed HTML fragment (raises when it is not well formed)."""
    checker = _Checker()
    checker.feed(page)
    checker.close()
    assert not checker.open, f"unclosed {checker.open}"
    assert "<table>" in page
    return " ".join(checker.text)


def _one_line(text: str) -> str:
    assert "\n" not in text and len(text) <= LONGEST, text
    assert not SHAPE.search(text), text
    return text


def _thumbnail(page: str) -> np.ndarray:
    (uri,) = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    return np.asarray(Image.open(io.BytesIO(base64.b64decode(uri))))


# ----------------------------------------------------------------------------- operators


def test_operator_shows_its_parameter_values_and_units():
    op = ops.Reinhard2002(key=0.18)
    text = _one_line(repr(op))
    assert text.startswith("Reinhard2002(key=0.18, L_white=None, log_average=None")
    assert "weights=(0.2126, 0.7152, 0.0722)" in text
    assert "L_dmax=80 cd/m²" in repr(ops.Ward1994(L_dmax=80.0))
    page = _html_text(op._repr_html_())
    for needle in ("Reinhard2002 (reinhard2002)", "key", "0.18", "measured from the image"):
        assert needle in page
    assert "10.1145/566654.566575" in page  # the paper's DOI (the operator's reference)


def test_every_registered_operator_shows_values():
    for name in ops.operator_names():
        cls = ops.get_operator(name)
        if ops._base.required_parameters(cls):
            continue  # tabulated: needs its table
        op = ops.make_operator(name)
        _one_line(repr(op))
        _html_text(op._repr_html_())


def test_repr_of_a_traced_operator_says_so():
    seen = []
    jax.eval_shape(lambda k: seen.append(repr(ops.Reinhard2002(key=k))) or k, 0.2)
    assert seen and "key=traced float32 ()" in seen[0]


# ----------------------------------------------------------------------------- results


def _fit(result=optx.RESULTS.successful) -> FitResult:
    return FitResult(
        operator=ops.Reinhard2002(key=0.2134),
        params={"key": jnp.asarray(0.2134)},
        loss=jnp.asarray(3.2e-7),
        statistics=jnp.asarray([0.3]),
        residuals=jnp.asarray([5.6e-4]),
        jacobian={"key": jnp.asarray([1.2])},
        steps=jnp.asarray(12),
        result=result,
        names=("key",),
    )


def test_fit_result_shows_the_fitted_values():
    fit = _fit()
    assert (
        _one_line(repr(fit))
        == "FitResult(reinhard2002: key=0.2134; loss 3.2e-07, 12 steps, converged)"
    )
    page = _html_text(fit._repr_html_())
    for needle in ("key", "0.2134", "3.2e-07", "12", "converged", "Reinhard2002"):
        assert needle in page
    failed = repr(_fit(optx.RESULTS.max_steps_reached))
    assert failed.endswith("The maximum number of solver steps was reached)")


def test_sweep_result_shows_its_grid_and_best_point():
    grid = jnp.asarray([0.09, 0.18, 0.36])
    stats = jnp.stack([grid * k for k in (1.0, 0.1, 0.8, 2.0, 0.01)], axis=-1)
    res = SweepResult(
        axes=(grid,),
        statistics=stats,
        loss=(grid - 0.18) ** 2,
        operator=ops.Reinhard2002(),
        params=("key",),
    )
    text = _one_line(repr(res))
    assert text.startswith("SweepResult(reinhard2002 over key: 3 values, 0.09 to 0.36; mean 0.09")
    assert text.endswith("least loss at key=0.18)")
    page = _html_text(res._repr_html_())
    assert "0.72" in page and "least loss at" in page  # p99 at key 0.36: every value shown


def test_luminance_statistics_show_numbers_and_the_range_in_stops():
    one = lambda v, dtype=jnp.float32: jnp.asarray(v, dtype)  # noqa: E731
    st = LuminanceStats(
        n_pixels=one(1024, jnp.int32),
        n_nonfinite=one(0, jnp.int32),
        n_positive=one(1024, jnp.int32),
        min=one(0.25),
        min_positive=one(0.25),
        max=one(1024.0),
        log_average=one(0.18),
        p01=one(0.3),
        p99=one(900.0),
        log_average_trimmed=one(0.17),
        rel_error_bound=one(2.0**-10),
    )
    text = _one_line(repr(st))
    assert "log_average=0.18" in text and "max=1024" in text
    assert text.endswith("dynamic_range=12 stops)")
    assert "12 stops" in _html_text(st._repr_html_())
    counts = Statistics(
        n_pixels=one(4, jnp.int32),
        n_finite=one(4, jnp.int32),
        n_positive=one(4, jnp.int32),
        min=one(0.5),
        max=one(8.0),
        min_positive=one(0.5),
        log_sum=one(2.0),
        counts=jnp.zeros(261120, jnp.int32).at[9000].set(4),
    )
    assert "counts=int32 (261120,), 0 to 4" in _one_line(repr(counts))


def _lights() -> Lights:
    """Two lights in a 64 × 32 lat-long map (labels at 16 × 32), the first at
    az +36°, el +10.4° with 63 % of the energy."""
    az, el = np.radians([36.0, -100.0]), np.radians([10.4, 40.0])
    d = np.stack([np.cos(el) * np.sin(az), np.sin(el), -np.cos(el) * np.cos(az)], -1)
    labels = np.full((16, 32), -1, np.int32)
    labels[6:8, 22:24], labels[3:5, 3:5] = 0, 1
    f = lambda *v: jnp.asarray(v, jnp.float32)  # noqa: E731
    return Lights(
        count=jnp.asarray(2),
        n_found=jnp.asarray(2),
        truncated=jnp.asarray(False),
        valid=jnp.asarray([True, True]),
        direction=jnp.asarray(d, jnp.float32),
        pixel=f([46.4, 13.6], [14.2, 7.0]),
        peak_pixel=f([46.0, 13.0], [14.0, 7.0]),
        peak_luminance=f(5000.0, 80.0),
        mean_luminance=f(2500.0, 40.0),
        colour=f([1.0, 0.9, 0.8], [0.5, 0.5, 0.6]),
        irradiance=f([1.0, 0.9, 0.8], [0.1, 0.1, 0.1]),
        solid_angle=f(6e-4, 2e-3),
        area=f(4.0, 16.0),
        energy=f(1.5, 0.2),
        energy_share=f(0.63, 0.08),
        n_samples=jnp.asarray([5, 2]),
        labels=jnp.asarray(labels),
        samples=jnp.zeros((4, 2)),
        sample_light=jnp.asarray([0, 0, 1, -1]),
        threshold=jnp.asarray(50.0),
        projection="equirectangular",
        input_shape=(32, 64),
    )


def test_lights_show_a_table_and_an_overlay():
    lights = _lights()
    text = _one_line(repr(lights))
    assert text.startswith(
        "Lights(2 lights in an equirectangular 64×32 map: #1 az +36.0°, el +10.4°, "
    )
    assert "63 % of the energy; #2 az -100.0°, el +40.0°" in text
    page = lights._repr_html_()
    words = _html_text(page)
    for needle in ("+36.0", "+10.4", "5000", "63", "Lights: 2"):
        assert needle in words
    thumb = _thumbnail(page)
    assert thumb.shape == (32, 64, 3)
    assert (thumb[13, 46] == 255).all()  # the first light's centre: a white cross
    assert tuple(thumb[12, 44]) != tuple(thumb[0, 0])  # its region in colour on grey
    batch = jax.tree.map(lambda a: np.stack([a, a]), lights)
    assert _one_line(repr(batch)) == "Lights(batch (2,): [2, 2] lights, equirectangular 64×32 maps)"
    assert batch._repr_html_() == f"<pre>{repr(batch)}</pre>"


def test_scene_report_shows_measurements_without_computing_a_deferred_percentile():
    view = ResolvedView(16, 32, 40.0, 20.6, "perspective", 1.25, 1.25)
    calls = []
    report = SceneReport(
        view=view,
        adaptation_global=15.55,
        adaptation_centre=8.93,
        adaptation_foveal=np.full((2, 3), 9.5),
        p05_rel_error=0.0,
        luminance_min=0.7,
        luminance_max=536.7,
        dynamic_range=math.log(536.7 / 0.7),
        n_pixels=512,
        n_nonfinite=0,
        glare_variant="photopic",
        selected=("glare",),
        p05_source=lambda: calls.append(1) or 3.04,
    )
    text = _one_line(repr(report))
    assert "adaptation 15.55 cd/m² (global)" in text and "effects: glare)" in text
    assert not calls and "L_5%" not in text
    page = _html_text(report._repr_html_())
    assert "3.04 cd/m²" in page and "float64 (2, 3), all 9.5 cd/m²" in page
    assert "L_5% 3.04 cd/m²" in repr(report)  # known now


def test_pipelines_targets_vision_lights_estimates_and_desaturation_show_values():
    """The remaining Modules users print in notebooks show numbers and names, not
    equinox's ``f32[]`` shapes, and have an HTML table."""
    import hdrjax.estimate as he
    import hdrjax.lights as hl
    import hdrjax.targets as ht
    from hdrjax import batch
    from hdrjax.display import DesaturateHighlights
    from hdrjax.vision import HumanVision

    x = np.random.default_rng(0).lognormal(0.0, 2.0, (16, 32, 3)).astype(np.float32)
    objects = {
        "MeanLuminance(value=0.3": ht.MeanLuminance(0.3),
        "Percentiles(q=[0.5, 0.99], value=[0.2, 0.9]": ht.Percentiles((0.5, 0.99), (0.2, 0.9)),
        "Pipeline(operator=Reinhard2002(key=None": batch.Pipeline("reinhard2002"),
        "DesaturateHighlights(threshold=0.8": DesaturateHighlights(threshold=0.8),
        "HumanVision(effects=(": HumanVision.build((16, 32), 40.0, ("glare",)),
        "MedianCutLights(": hl.median_cut(x, n_lights=4),
        "Estimate(value=": he.jgt_key(x),
    }
    for head, obj in objects.items():
        text = repr(obj)
        assert text.startswith(head), text
        assert "f32[" not in text and "\n" not in text, text
        page = obj._repr_html_()
        assert "<table>" in page and type(obj).__name__ in page, type(obj).__name__
    assert "value=0.3" in repr(ht.MeanLuminance(0.3))
