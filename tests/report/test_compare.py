"""hdrjax.compare and ``hdrjax compare``: the table's values against direct calls of
hdrjax.metrics on the same renditions, sorting, the self-contained HTML page, JSON round
trips, one-line errors and atomic outputs.

One small image (data/rooitou_park_1k.hdr box-filtered to 32×64, written as PFM so the
Python API and the command line read the same pixels and share compiled programs) and
three cheap operators keep the file fast.
"""

import dataclasses
import html.parser
import json

import numpy as np
import pytest

import hdrjax
import hdrjax.display as hd
import hdrjax.metrics as hm
import hdrjax.targets as ht
from hdrjax.cli import main
from hdrjax.fit import downscale
from hdrjax.report import ComparisonTable, compare

from ..conftest import DATA, RTOL32

METHODS = ["reinhard2002", "drago2003", "exponential"]
PEAK, BLACK = 100.0, 0.1
ATOL_METRIC = 1e-5
"""float32 TMQI/PU-SSIM of two evaluations of one operator (the report's ahead-of-time
compiled program and the measured operator called again) differ by rounding only."""


@pytest.fixture(scope="module")
def image_file(tmp_path_factory):
    rgb = np.asarray(downscale(hdrjax.io.read(DATA / "rooitou_park_1k.hdr").rgb(), 64))
    path = tmp_path_factory.mktemp("compare") / "park.pfm"
    hdrjax.io.write(path, rgb)
    return path


@pytest.fixture(scope="module")
def rgb(image_file):
    return hdrjax.io.read(image_file).rgb()


@pytest.fixture(scope="module")
def reference(rgb):
    """A reference rendition: Reinhard et al. 2002 with another key, sRGB-encoded."""
    return np.asarray(hd.encode(hdrjax.tonemap(rgb, "reinhard2002", key=0.09), "srgb"))


@pytest.fixture(scope="module")
def table(image_file, reference):
    return compare(image_file, METHODS, reference=reference, peak=PEAK, black=BLACK, repeats=2)


def _display_luminance(encoded):
    return BLACK + (PEAK - BLACK) * hd.srgb_decode(encoded)


def test_values_equal_direct_metric_calls(table, rgb, reference):
    assert sorted(table.methods) == sorted(METHODS)
    assert table.shape == rgb.shape[:2] and table.source.endswith("park.pfm")
    for row in table:
        out = row.operator(rgb)  # the operator as it rendered, every parameter set
        enc = hd.encode(out, "srgb")
        q, s, n = (float(v) for v in hm.tmqi(rgb, enc))
        np.testing.assert_allclose([row.q, row.s, row.n], [q, s, n], atol=ATOL_METRIC)
        pu = float(hm.pu_ssim(_display_luminance(enc), _display_luminance(reference)))
        np.testing.assert_allclose(row.pu_ssim, pu, atol=ATOL_METRIC)
        mean = float(ht.MeanLuminance(0.5).statistics(out)[0])
        np.testing.assert_allclose(row.mean_luminance, mean, rtol=RTOL32)
        # clipped, recounted in NumPy from the definition
        o, x = np.asarray(out), np.asarray(rgb)
        low = np.any((o <= 0) & (x > 0), axis=-1)
        high = np.any(o >= 1, axis=-1)
        assert row.clipped_black == pytest.approx(low.mean())
        assert row.clipped_white == pytest.approx(high.mean())
        assert row.clipped == pytest.approx((low | high).mean())
        # the rendition shown is this output, in 8 bits
        diff = np.abs(row.rendition.astype(int) - hd.quantize(enc, 8).astype(int))
        assert row.rendition.shape == rgb.shape and diff.max() <= 1
        assert row.compile_s > 0 and row.warm_s > 0 and row.fit_s is None
    # the operators differ, and so do their scores (the check above is not vacuous)
    assert len({round(r.q, 6) for r in table}) == len(METHODS)
    # the reference's own operator is the closest to it
    assert table.best("pu_ssim").method == "reinhard2002"
    assert 0.5 < table["reinhard2002"].pu_ssim < 1.0


def test_parameters_are_the_estimated_ones(table, rgb):
    row = table["reinhard2002"]
    assert set(row.estimated) == {"key", "L_white", "log_average"} and row.fitted == ()
    op = hdrjax.operators.Reinhard2002().measure(rgb)
    for name in row.estimated:
        assert row.params[name] == pytest.approx(float(getattr(op, name)), rel=RTOL32)
    given = compare(rgb, ["reinhard2002"], params={"reinhard2002": {"key": 0.09}}, repeats=1)
    assert given[0].params["key"] == pytest.approx(0.09) and "key" not in given[0].estimated


def test_sorting(table):
    q = [r.q for r in table]
    assert q == sorted(q, reverse=True)  # best first by default
    assert [r.q for r in table.sorted("q", descending=False)] == sorted(q)
    clipped = [r.clipped for r in table.sorted("clipped")]
    assert clipped == sorted(clipped)  # less clipping is better: ascending
    assert table.sorted("method").methods == tuple(sorted(METHODS))
    # rows without a value come last in either direction
    rows = (dataclasses.replace(table.rows[0], pu_ssim=None), *table.rows[1:])
    partial = dataclasses.replace(table, rows=rows)
    for descending in (True, False):
        assert partial.sorted("pu_ssim", descending).rows[-1].pu_ssim is None
    with pytest.raises(ValueError, match="by: expected one of"):
        table.sorted("speed")


class _Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.srcs, self.hrefs, self.ids, self.headings, self.scripts = [], [], set(), 0, 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.srcs += [a["src"]] if "src" in a else []
        self.hrefs += [a["href"]] if "href" in a else []
        self.ids |= {a["id"]} if "id" in a else set()
        self.headings += tag == "th"
        self.scripts += tag == "script"


def test_html_is_self_contained_and_lists_every_method(table):
    page = table.to_html()
    assert "http:" not in page.lower() and "https:" not in page.lower()
    p = _Page()
    p.feed(page)
    # a thumbnail and a full rendition per method, all inline
    assert len(p.srcs) == 2 * len(table)
    assert all(s.startswith("data:image/jpeg;base64,") for s in p.srcs)
    # every link is to an overlay on the page (or closes it)
    assert all(h == "#" or h[1:] in p.ids for h in p.hrefs)
    assert p.scripts == 1 and p.headings == 2 + 9 - 1 + 1  # fit column absent: no fit
    for m in METHODS:
        assert f">{m}</td>" in page
    fragment = table._repr_html_()
    assert "http" not in fragment and all(f">{m}</td>" in fragment for m in METHODS)


def test_contact_sheet_shows_every_rendition_with_its_scores(table):
    fig = table.figure(columns=2)
    shown = [ax for ax in fig.axes if ax.images]
    assert len(shown) == len(table) and len(fig.axes) == 2 * -(-len(table) // 2)
    for ax, row in zip(shown, table, strict=True):
        title = ax.get_title(loc="left")
        assert title.startswith(f"{shown.index(ax) + 1}. {row.method}\n")
        assert f"Q {row.q:.3f}" in title and f"PU-SSIM {row.pu_ssim:.3f}" in title
        np.testing.assert_array_equal(ax.images[0].get_array(), row.rendition)
    with pytest.raises(ValueError, match="no renditions"):
        ComparisonTable.from_json(table.to_json()).figure()
    with pytest.raises(ValueError, match="columns"):
        table.figure(columns=0)


def test_json_round_trips(table):
    text = table.to_json()
    back = ComparisonTable.from_json(text)
    assert back.to_dicts() == table.to_dicts() and back.to_json() == text
    assert back.methods == table.methods and back.rows == table.rows
    d = json.loads(text)
    assert d["rows"][0]["method"] == table.rows[0].method and "rendition" not in d["rows"][0]
    assert "data:" not in back.to_html()  # no renditions in JSON: the page says so with "–"


@pytest.mark.parametrize(
    "kwargs,needle",
    [
        ({"methods": ["nope"]}, "nope"),
        ({"methods": ["reinhard2002"], "params": {"reinhard2002": {"nokey": 1.0}}}, "nokey"),
        ({"methods": ["reinhard2002"], "reference": np.zeros((4, 4, 3))}, "reference:"),
        ({"methods": ["reinhard2002"], "fit": "ssim"}, "fit:"),
        ({"methods": ["reinhard2002"], "all": True}, "not both"),
    ],
)
def test_bad_arguments_are_one_line_errors(rgb, kwargs, needle):
    with pytest.raises(ValueError) as e:
        compare(rgb, **kwargs)
    assert needle in str(e.value) and "\n" not in str(e.value)


def test_unreadable_image_names_the_file(tmp_path):
    bad = tmp_path / "bad.hdr"
    bad.write_bytes(b"not an image")
    with pytest.raises(ValueError, match="bad.hdr"):
        compare(bad, ["reinhard2002"])


def test_fit_without_the_target_is_a_one_line_error(rgb, monkeypatch):
    monkeypatch.delattr(ht, "TMQI", raising=False)
    with pytest.raises(ValueError, match=r"^fit: 'tmqi' needs hdrjax.targets.TMQI[^\n]*$"):
        compare(rgb, ["reinhard2002"], fit="tmqi")


def test_nan_pixels_leave_the_scores_finite(rgb):
    bad = np.array(rgb)
    bad[3, 5] = np.nan
    t = compare(bad, ["reinhard2002"], repeats=1)
    row = t[0]
    assert all(np.isfinite(v) for v in (row.q, row.s, row.n, row.clipped, row.mean_luminance))


# ------------------------------------------------------------------------------ command line


def test_cli_writes_the_report_and_json(image_file, table, tmp_path, capsys):
    out, js, sheet = tmp_path / "report.html", tmp_path / "report.json", tmp_path / "s.png"
    argv = ["compare", str(image_file), "--methods", "drago2003,reinhard2002", "-o", str(out)]
    assert main([*argv, "--json-out", str(js), "--sheet", str(sheet), "--repeats", "2"]) == 0
    text = capsys.readouterr().out
    assert f"wrote: {out}" in text and f"wrote: {js}" in text and f"wrote: {sheet}" in text
    from PIL import Image

    with Image.open(sheet) as im:  # two panels side by side, 12 inches at 100 dpi
        assert im.format == "PNG" and im.size[0] == 1200
    doc = json.loads(js.read_text())
    assert [r["method"] for r in doc["rows"]] == sorted(
        ["drago2003", "reinhard2002"], key=lambda m: -table[m].q
    )
    for r in doc["rows"]:  # the same pixels as the API's table: the same scores
        assert r["q"] == pytest.approx(table[r["method"]].q, abs=ATOL_METRIC)
    page = out.read_text()
    assert "drago2003" in page and "reinhard2002" in page and "https:" not in page
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.html", "report.json", "s.png"]


@pytest.mark.parametrize(
    "argv,code,needle",
    [
        (["IMG", "--methods", "reinhard2002,nope", "-o", "OUT"], 2, "--methods: unknown operator"),
        (["BAD", "--methods", "reinhard2002", "-o", "OUT"], 1, "bad.hdr"),
        (["IMG", "--methods", "reinhard2002", "-o", "IMG"], 2, "output is the input file"),
        (["IMG", "--methods", "reinhard2002", "-o", "r.png"], 2, "expected an .html file"),
        (["IMG", "-o", "OUT", "--json-out", "IMG"], 2, "output is the input file"),
        (
            ["IMG", "-o", "OUT", "--json-out", "OUT"],
            2,
            "-o, --json-out and --sheet must name different files",
        ),
        (["IMG", "-o", "OUT", "--reference", "IMG2"], 1, "no such file"),
        (["IMG", "-o", "OUT", "--sheet", "s.jpg"], 2, "expected a .png file for --sheet"),
        (["IMG", "-o", "OUT", "--sheet", "IMG"], 2, "output is the input file"),
    ],
)
def test_cli_errors_are_one_line_and_write_nothing(
    image_file, tmp_path, capsys, argv, code, needle
):
    bad = tmp_path / "bad.hdr"
    bad.write_bytes(b"#?RADIANCE\nnot really\n")
    subs = {
        "IMG": str(image_file),
        "BAD": str(bad),
        "OUT": str(tmp_path / "r.html"),
        "IMG2": str(tmp_path / "missing.png"),
    }
    before = sorted(p.name for p in tmp_path.iterdir())
    rc = main(["compare", *[subs.get(a, a) for a in argv]])
    err = capsys.readouterr().err.strip()
    assert rc == code and needle in err and "\n" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_cli_methods_and_all_exclude_each_other(image_file, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["compare", str(image_file), "--methods", "agx", "--all", "-o", "r.html"])
    err = capsys.readouterr().err.strip()
    assert e.value.code == 2 and "not allowed with" in err and "\n" not in err


def test_cli_failure_leaves_earlier_outputs_whole(image_file, tmp_path, capsys, monkeypatch):
    out, js = tmp_path / "r.html", tmp_path / "r.json"
    out.write_text("old page")
    js.write_text("old json")

    def broken(self, **kw):
        raise ValueError("rendering failed")

    monkeypatch.setattr(ComparisonTable, "to_html", broken)
    argv = ["compare", str(image_file), "--methods", "exponential", "-o", str(out)]
    assert main([*argv, "--json-out", str(js), "--repeats", "1"]) == 1
    assert "rendering failed" in capsys.readouterr().err
    assert out.read_text() == "old page" and js.read_text() == "old json"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.html", "r.json"]


def test_cli_all_lists_every_operator(image_file, table, tmp_path, capsys, monkeypatch):
    """``--all``: every registered operator is compared or listed as skipped, with the
    reason (one that needs a table, one that fails on the image). Each operator is then
    replaced by a copy of a row already computed (running every operator on an image is
    the conformance suite's job; compiling them all again here would take minutes)."""
    done = table["drago2003"]
    tried = []

    def row(name, *args):
        tried.append(name)
        if name == "linear":
            raise RuntimeError("rendering\nfailed")
        return dataclasses.replace(done, method=name)

    monkeypatch.setattr("hdrjax.report._compare._row", row)
    out, js = tmp_path / "all.html", tmp_path / "all.json"
    argv = ["compare", str(image_file), "--all", "-o", str(out), "--json-out", str(js)]
    assert main([*argv, "--repeats", "1"]) == 0
    doc = json.loads(js.read_text())
    compared = {r["method"] for r in doc["rows"]}
    assert compared | set(doc["skipped"]) == set(hdrjax.operator_names())
    assert not compared & set(doc["skipped"])
    assert doc["skipped"]["tabulated"].startswith("needs ") and "tabulated" not in tried
    assert doc["skipped"]["linear"] == "rendering failed"
    assert sorted(tried) == sorted(compared | {"linear"})
    page = out.read_text()
    assert all(f">{m}</td>" in page for m in compared)


def test_fit_tmqi_raises_the_quality(rgb):
    small = np.asarray(downscale(rgb, 16))
    plain = compare(small, ["exponential"], repeats=1)[0]
    fitted = compare(small, ["exponential"], fit="tmqi", repeats=1)[0]
    assert fitted.fitted == ("log_average",) and fitted.fit_s > 0 and fitted.fit_success
    assert "log_average" not in fitted.estimated
    # the fit works on the image as it is (<= 64 px): TMQI can only go up
    assert fitted.q >= plain.q - ATOL_METRIC


FAKE_DOM = r"""
function cell(v){return {getAttribute:function(k){return k==="data-v"?v:null;}};}
function head(cls,better){var a={};return {className:cls,
  getAttribute:function(k){return k==="data-better"?better:(k in a?a[k]:null);},
  setAttribute:function(k,v){a[k]=v;},removeAttribute:function(k){delete a[k];},
  addEventListener:function(e,f){this.click=f;}};}
var heads=[head("nosort text",""),head("text",""),head("num","high"),head("num","low")];
var rows=[["b","0.5","3"],["a","0.9",""],["c","0.7","1"]].map(function(r){
  return {id:r[0],cells:[cell(null)].concat(r.map(cell))};});
var body={rows:rows,appendChild:function(r){this.rows.splice(this.rows.indexOf(r),1);
  this.rows.push(r);}};
var document={getElementById:function(){return {tHead:{rows:[{cells:heads}]},tBodies:[body]};}};
"""
SORT_CLICKS = r"""
function order(){return body.rows.map(function(r){return r.id;}).join("");}
var out=[];
[2,2,3,3,1].forEach(function(i){heads[i].click();out.push(order());});
console.log(out.join(" "));
"""


def test_the_pages_script_sorts_rows():
    """The page's own script, run by a JavaScript engine (QuickJS, a test dependency) on a
    stand-in for the DOM: the better end first on the first click (high for Q, low for
    times), reversed on the second, empty cells always last."""
    import quickjs

    from hdrjax.report._html import SORT_SCRIPT

    ctx = quickjs.Context()
    ctx.eval("var printed = []; var console = {log: function (s) { printed.push(String(s)); }};")
    ctx.eval(FAKE_DOM + SORT_SCRIPT + SORT_CLICKS)
    assert ctx.eval("printed.join(' ')").split() == ["acb", "bca", "cba", "bca", "abc"]
