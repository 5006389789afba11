"""The README is the user's manual: every Python example in it runs as written."""

import re

import pytest

from ..conftest import REPO

BLOCKS = re.findall(r"```python\n(.*?)```", (REPO / "README.md").read_text(), re.S)


def test_readme_has_examples():
    assert len(BLOCKS) >= 3
    assert "make demo" in (REPO / "README.md").read_text()
    assert "make test" in (REPO / "README.md").read_text()


@pytest.mark.parametrize("i", range(len(BLOCKS)))
def test_readme_example_runs(i, monkeypatch, capsys):
    monkeypatch.chdir(REPO)  # examples use data/ and out/ relative to the repository
    (REPO / "out").mkdir(exist_ok=True)  # as `make demo` creates it; a fresh clone has none
    exec(compile(BLOCKS[i], f"README.md example {i + 1}", "exec"), {"__name__": "__readme__"})
    assert capsys.readouterr().out.strip()  # each example prints what it computed


# -- figures the README quotes, checked against the tests and committed benchmark results -----

README = (REPO / "README.md").read_text()
RESULTS = REPO / "benchmarks" / "results" / "results-cpu.json"


def _records(**match) -> list[dict]:
    import json

    recs = json.loads(RESULTS.read_text())["records"]
    return [r for r in recs if all(r.get(k) == v for k, v in match.items())]


def _one(**match) -> dict:
    (rec,) = _records(**match)
    return rec


def _flat(text: str) -> str:
    """The README's text with its line breaks (and list indentation) as single spaces."""
    return re.sub(r"\s+", " ", text)


def test_colour_hdri_parity_figures_are_the_tests():
    """The operators table: 1e-7 with colour-hdri's weights (which it quotes in full), the
    Rec.709 differences as measured by tests/operators/test_colour_hdri_parity.py."""
    from ..operators import test_colour_hdri_parity as parity

    text = _flat(README)
    m = re.search(
        r"equal to colour-hdri to (\S+) \(float64, tested on images without black pixels\)"
        r" given colour-hdri's own luminance weights, derived from the sRGB primaries:"
        r" `weights=\(([^)]*)\)`; with the default Rec\.709 weights \(0\.2126, 0\.7152,"
        r" 0\.0722\) they differ by that rounding, up to (\S+) on the tests' natural image"
        r" and (\S+) on cornell_box\.exr's saturated walls",
        text,
    )
    assert m, "the colour-hdri family's row no longer states its figures"
    assert float(m[1]) == parity.TOLERANCE
    assert tuple(float(v) for v in m[2].split(",")) == parity.WEIGHTS
    assert float(m[3]) == parity.REC709_DIFFERENCE["natural"]
    assert float(m[4]) == parity.REC709_DIFFERENCE["cornell_box"]


def test_seed_median_figures_are_the_filters_benchmark():
    text = _flat(README)
    m = re.search(
        r"Birukov et al\. 2022's own timing \(5×5 median ≈ 1 s at 1366×768, 2\.5 min at"
        r" 15000² on a 12-core Ryzen\) is (\d+)× and (\d+)× these single-plane times\."
        r" With Birukov et al\.'s own criterion, RGB pixels ranked by their luminance"
        r" \(`criterion=\"luminance\"`\), the"
        r" 5×5 median at 1366×768 took ([\d.]+) ms \(fastest of (\d+) runs, measured alone on"
        r" the loaded VM; median ([\d.]+) ms; `median 5x5 luminance \(RGB\)` in the report\):"
        r" (\d+)× faster than Birukov et al\. 2022's timing",
        text,
    )
    assert m, "the filters section no longer states the comparison with Birukov et al. 2022"
    small = _one(benchmark="filters", case="median 5x5 1366x768", impl="hdrjax")
    big = _one(benchmark="filters", case="median 5x5 15000x15000", impl="hdrjax")
    rgb = _one(benchmark="filters", case="median 5x5 luminance (RGB) 1366x768", impl="hdrjax")
    # quoted to their rounding (300x, 200x: one significant figure)
    assert float(m[1]) == pytest.approx(1.0 / small["median_s"], rel=0.05)
    assert float(m[2]) == pytest.approx(150.0 / big["median_s"], rel=0.05)
    assert m[3] == f"{rgb['min_s'] * 1e3:.1f}" and int(m[4]) == rgb["repeats"]
    assert m[5] == f"{rgb['median_s'] * 1e3:.1f}"
    assert int(m[6]) == round(rgb["extra"]["seed_stated_s"] / rgb["min_s"])


def test_light_sampling_figures_are_the_accuracy_benchmark():
    text = _flat(README)
    m = re.search(
        r"the sun lands within ([\d.]+)° of the full-resolution answer at a third of its time"
        r" \(([\d.]+)° and ([\d.]+)° on the two sun maps\)\. More samples do not move the suns,"
        r" but they move the worst light of the five maps \(a lamp of studio_small_03\):"
        r" ([\d.]+)° at the default density, ([\d.]+)° at twice and ([\d.]+)° at four times it,"
        r" for ([\d.]+), ([\d.]+) and ([\d.]+) ms a map",
        text,
    )
    assert m, "the light detection note no longer states its figures"
    width = {r["setting"]: r for r in _records(benchmark="accuracy", curve="lights width")}
    samples = {r["setting"]: r for r in _records(benchmark="accuracy", curve="lights samples")}
    suns = [width["width 512"]["extra"]["per_image"][f] for f in SUN_MAPS]
    assert [float(m[2]), float(m[3])] == [pytest.approx(v, abs=0.005) for v in suns]
    assert max(suns) < float(m[1])
    assert width["width 512"]["time_s"] < width["width 1024"]["time_s"] / 2.5  # "a third"
    for i, k in enumerate(("1x", "2x", "4x")):
        rec = samples[f"{k} default samples"]
        assert float(m[4 + i]) == pytest.approx(rec["error"], abs=0.005)
        assert float(m[7 + i]) == pytest.approx(rec["time_s"] * 1e3, abs=0.005)
        per_image = rec["extra"]["per_image"]
        assert max(per_image, key=per_image.get) == "studio_small_03_1k.hdr"
        # the suns do not move
        assert [per_image[f] for f in SUN_MAPS] == [
            samples["0.25x default samples"]["extra"]["per_image"][f] for f in SUN_MAPS
        ]


SUN_MAPS = ("rooitou_park_1k.hdr", "venice_sunset_1k.hdr")
