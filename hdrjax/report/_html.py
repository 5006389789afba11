"""The comparison table as HTML: one self-contained page, or a fragment for notebooks.

Everything is inline: renditions as base64 JPEG ``data:`` images, the style sheet, and a
few lines of script that sort the rows when a column heading is clicked. A thumbnail links
to its full rendition, shown over the page by CSS (``:target``), so the page needs no
script to show images and no network at all.
"""

import base64
import html
from typing import Any

import numpy as np

from .. import __version__
from ._columns import COLUMNS, image_bytes, milliseconds

THUMBNAIL_SIZE = 192
"""Pixels on the long side of a thumbnail."""
FULL_SIZE = 1600
"""Pixels on the long side of the full rendition shown on click (larger ones are
downscaled, to keep the page to a few MB)."""

_STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;font-size:14px}
th,td{border-bottom:1px solid #ddd;padding:4px 8px;text-align:right;vertical-align:middle}
th{cursor:pointer;background:#f4f4f4;position:sticky;top:0;user-select:none}
th.text,td.text{text-align:left}
th[data-dir=asc]::after{content:" \\25B2"}th[data-dir=desc]::after{content:" \\25BC"}
td.params{font-size:12px;text-align:left;white-space:nowrap}
img.thumb{display:block;max-width:192px;max-height:192px}
.full{display:none;position:fixed;inset:0;background:rgba(0,0,0,.85);z-index:9;
align-items:center;justify-content:center;flex-direction:column}
.full:target{display:flex}
.full img{max-width:96vw;max-height:90vh}
.full p{color:#eee}
p.note{font-size:13px;color:#555;max-width:60em}
"""

SORT_SCRIPT = """
(function(){
var table=document.getElementById("comparison");
var heads=table.tHead.rows[0].cells;
function key(row,i){var v=row.cells[i].getAttribute("data-v");return v===null?"":v;}
function sortBy(i){
  var th=heads[i],num=th.className.indexOf("num")>=0;
  var dir=th.getAttribute("data-dir")==="desc"?"asc":"desc";
  if(!th.getAttribute("data-dir")&&th.getAttribute("data-better")==="low")dir="asc";
  if(!num&&!th.getAttribute("data-dir"))dir="asc";
  for(var k=0;k<heads.length;k++)heads[k].removeAttribute("data-dir");
  th.setAttribute("data-dir",dir);
  var body=table.tBodies[0],rows=Array.prototype.slice.call(body.rows);
  rows.sort(function(a,b){
    var x=key(a,i),y=key(b,i);
    if(x===""||y==="")return (x==="")-(y==="");
    var c=num?parseFloat(x)-parseFloat(y):x.localeCompare(y);
    return dir==="asc"?c:-c;});
  rows.forEach(function(r){body.appendChild(r);});
}
for(var i=0;i<heads.length;i++){
  if(heads[i].className.indexOf("nosort")<0)
    heads[i].addEventListener("click",sortBy.bind(null,i));}
})();
"""


def _data_uri(rendition: np.ndarray, size: int | None, quality: int) -> str:
    data = base64.b64encode(image_bytes(rendition, size, quality)).decode("ascii")
    return f"data:image/jpeg;base64,{data}"


def _number(key: str, v: float | None) -> str:
    if v is None:
        return "–"
    if key == "clipped":
        return f"{100 * v:.2f}"
    if key == "warm_s":
        return milliseconds(v)
    if key in ("compile_s", "fit_s"):
        return f"{v:.3g}"
    return f"{v:.4f}"


def _params_cell(row: Any) -> str:
    lines = []
    for name, value in row.params.items():
        if isinstance(value, float):
            text = f"{value:.5g}"
        elif isinstance(value, list):
            text = "(" + ", ".join(f"{x:.4g}" if isinstance(x, float) else str(x) for x in value)
            text += ")"
        else:
            text = str(value)
        how = " (fitted)" if name in row.fitted else " (estimated)" if name in row.estimated else ""
        lines.append(f"{html.escape(name)} = {html.escape(text)}{how}")
    if row.fit_success is False:
        lines.append("fit did not converge")
    return "<br>".join(lines) or "none"


def _columns(table: Any):
    """The numeric columns this table has values for."""
    cols = []
    for c in COLUMNS:
        if c.key == "pu_ssim" and table.reference is None:
            continue
        if c.key == "fit_s" and table.fit is None:
            continue
        cols.append(c)
    return cols


def _table(table: Any, *, full_images: bool) -> tuple[str, str]:
    """``(the <table>, the full-image overlays)``."""
    cols = _columns(table)
    head = ['<th class="nosort text">rendition</th>', '<th class="text">method</th>']
    for c in cols:
        better = {True: "high", False: "low", None: ""}[c.higher_is_better]
        head.append(
            f'<th class="num" data-better="{better}" title="{html.escape(c.help)}">'
            f"{html.escape(c.label)}</th>"
        )
    head.append('<th class="nosort text">parameters</th>')
    body, overlays = [], []
    for i, row in enumerate(table.rows):
        name = html.escape(row.method)
        if row.rendition is not None:
            img = f'<img class="thumb" src="{_data_uri(row.rendition, THUMBNAIL_SIZE, 85)}"'
            img += f' alt="{name}">'
            if full_images:
                img = f'<a href="#full-{i}">{img}</a>'
                overlays.append(
                    f'<div class="full" id="full-{i}"><a href="#">'
                    f'<img src="{_data_uri(row.rendition, FULL_SIZE, 92)}" alt="{name}"></a>'
                    f"<p>{name} (click to close)</p></div>"
                )
        else:
            img = "–"
        cells = [f'<td class="text">{img}</td>', f'<td class="text" data-v="{name}">{name}</td>']
        for c in cols:
            v = getattr(row, c.key)
            title = ""
            if c.key == "clipped" and v is not None:
                title = (
                    f' title="black {100 * row.clipped_black:.2f} %, '
                    f'white {100 * row.clipped_white:.2f} %"'
                )
            data = "" if v is None else repr(float(v))
            cells.append(f'<td data-v="{data}"{title}>{_number(c.key, v)}</td>')
        cells.append(f'<td class="params">{_params_cell(row)}</td>')
        body.append("<tr>" + "".join(cells) + "</tr>")
    out = (
        '<table id="comparison"><thead><tr>'
        + "".join(head)
        + "</tr></thead><tbody>\n"
        + "\n".join(body)
        + "\n</tbody></table>"
    )
    return out, "\n".join(overlays)


def _summary(table: Any) -> str:
    h, w = table.shape
    parts = [f"{html.escape(table.source or 'an array')}, {w}×{h} pixels"]
    if table.reference is not None:
        parts.append(
            f"reference rendition {html.escape(table.reference)} (PU-SSIM on a display of "
            f"{table.peak:g} cd/m² white, {table.black:g} cd/m² black)"
        )
    if table.fit is not None:
        parts.append(f"parameters fitted to maximise {html.escape(table.fit.upper())}")
    parts.append(f"timed on {html.escape(table.device)}")
    return "; ".join(parts) + "."


_NOTE = (
    "TMQI: tone-mapped image quality index Q with its structural fidelity S and statistical "
    "naturalness N (Yeganeh &amp; Wang 2013, IEEE TIP 22(2), doi:10.1109/TIP.2012.2221725). "
    "PU-SSIM: SSIM (Wang et al. 2004) of PU21-encoded luminance (Mantiuk &amp; Azimi 2021, "
    "doi:10.1109/PCS50896.2021.9477471). Clipped: pixels with a channel at display white, or "
    "at black where the scene's channel is not (hover for the split). Mean L<sub>d</sub>: "
    "mean display luminance as a fraction of white. "
    "Warm: median time of the compiled operator, parameter estimation included; compile: "
    "its tracing and compilation, measured once per process and image shape. Click a "
    "heading to sort, a rendition to see it whole."
)


def render_page(table: Any, *, title: str | None, full_images: bool) -> str:
    """The whole page (see the module docstring)."""
    title = title or f"hdrjax compare: {table.source or 'image'}"
    body, overlays = _table(table, full_images=full_images)
    skipped = ""
    if table.skipped:
        items = "".join(
            f"<li>{html.escape(k)}: {html.escape(v)}</li>" for k, v in table.skipped.items()
        )
        skipped = f"<p>Not compared:</p><ul>{items}</ul>"
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>\n"
        f"<h1>{html.escape(title)}</h1>\n<p>{_summary(table)}</p>\n"
        f'<p class="note">{_NOTE}</p>\n{body}\n{skipped}\n{overlays}\n'
        f'<p class="note">hdrjax {__version__}</p>\n'
        f"<script>{SORT_SCRIPT}</script>\n</body></html>\n"
    )


def render_fragment(table: Any) -> str:
    """The table with thumbnails, for a notebook's output (no script, no overlays)."""
    body, _ = _table(table, full_images=False)
    style = "<style>#comparison td,#comparison th{text-align:right}</style>"
    return f"<div><p>{_summary(table)}</p>{style}{body}</div>"
