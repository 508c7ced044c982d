"""Rendering a report: ``report.md`` (relative figure links) and ``report.html`` (self-contained).

Both take a :class:`snoworm.studies.paper.report.PaperReport` (anything with ``sections``, ``claims``,
``quick`` and ``wall_time_s``).
"""

from __future__ import annotations

import base64
import html
from pathlib import Path

from ..._version import __version__
from .claims import STEADY_WINDOW_S, Claim, find_claim

__all__ = ["render_markdown", "render_html"]


def _fmt(v):
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, list):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k}: {_fmt(x)}" for k, x in v.items()) + "}"
    return "n/a" if v is None else str(v)


def _computed_text(c: Claim) -> str:
    return "; ".join(f"{k} = {_fmt(v)}" for k, v in c.computed.items())


def _md_cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _header(rep) -> list:
    n_ok = sum(c.holds for c in rep.claims)
    return [
        f"snoworm {__version__}, {'quick' if rep.quick else 'full'} mode, {rep.wall_time_s:.1f} s wall time. "
        f"**{n_ok} of {len(rep.claims)} claims hold.**",
        "Every verdict is computed from the simulation results by a check function in `snoworm/studies/paper/` "
        "with the tolerance shown; source 'paper' = stated in the paper, 'model' = a reference-model number "
        "(docs/model.md) the paper does not print. Steady values are means over the last "
        f"{STEADY_WINDOW_S:g} s of a run.",
    ]


def _summary_rows(rep):
    return [
        (c.id, c.figure, c.source, "yes" if c.holds else "**NO**", _computed_text(c), c.tolerance) for c in rep.claims
    ]


#: MIME types of the figure formats a page can show inline (others, i.e. PDF, are linked).
_INLINE = {".png": "image/png", ".svg": "image/svg+xml"}


def render_markdown(rep) -> str:
    """``report.md``: summary table of claims, then one section per figure/table (relative figure links)."""
    L = ["# snoworm reproduction of Elliott, Lines & Ray (SnoWorm)", ""] + [p + "\n" for p in _header(rep)]
    L += ["## Summary", "", "| claim | figure | source | holds | computed | tolerance |", "|---|---|---|---|---|---|"]
    L += ["| " + " | ".join(_md_cell(x) for x in row) + " |" for row in _summary_rows(rep)]
    for s in rep.sections:
        L += [
            "",
            f"## {s.title}",
            "",
            f"**The paper:** {s.paper_says}",
            "",
            "**Computed from:** " + ", ".join(f"`{x}`" for x in s.scenarios) + f" ({s.wall_time_s:.1f} s)",
            "",
        ]
        for c in s.claims:
            L += [
                f"- **{c.id}** ({c.source}) - {'holds' if c.holds else '**FAILS**'}: {c.statement}  ",
                f"  computed: {_computed_text(c)}  ",
                f"  tolerance: {c.tolerance}",
            ]
        for t in s.tables:
            L += ["", t]
        for v in s.variants:
            L += [
                "",
                f"**Alternative: {v.label}** (`{', '.join(f'{k}={x}' for k, x in v.overrides.items())}`)",
                "",
                "| claim | default reading | alternative | alternative computed |",
                "|---|---|---|---|",
            ]
            for c in v.claims:
                base = _find_default(rep, c.id)
                L.append(f"| {c.id} | {_verdict(base)} | {_verdict(c)} | {_md_cell(_computed_text(c))} |")
        for n in s.notes:
            L += ["", f"*Note:* {n}"]
        for p in s.figures:  # PNG and SVG shown, PDF linked
            p = Path(p)
            L += ["", f"![{p.stem}]({p.name})" if p.suffix.lower() in _INLINE else f"[{p.name}]({p.name})"]
    return "\n".join(L) + "\n"


def _find_default(rep, cid):
    try:
        return find_claim(rep.sections, cid)
    except KeyError:
        return None


def _verdict(c):
    return "-" if c is None else ("holds" if c.holds else "FAILS")


_CSS = (
    "body{font-family:sans-serif;max-width:70em;margin:1em auto;padding:0 1em;line-height:1.4}"
    "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #bbb;padding:3px 6px;"
    "vertical-align:top;font-size:90%}th{background:#eee}.ok{color:#070}.bad{color:#b00;font-weight:bold}"
    "img{max-width:100%;border:1px solid #ddd;margin:0.5em 0}pre{background:#f6f6f6;padding:0.5em}"
    "blockquote{color:#333;border-left:3px solid #ccc;margin-left:0;padding-left:1em}"
)


def _h(x) -> str:
    return html.escape(str(x))


def _html_table(header, rows, raw_cols=()) -> str:
    out = ["<table><tr>" + "".join(f"<th>{_h(x)}</th>" for x in header) + "</tr>"]
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{x if j in raw_cols else _h(x)}</td>" for j, x in enumerate(r)) + "</tr>")
    return "\n".join(out) + "</table>"


def _verdict_html(c):
    if c is None:
        return "-"
    return '<span class="ok">holds</span>' if c.holds else '<span class="bad">FAILS</span>'


def _md_table_to_html(md: str) -> str:
    lines = [ln for ln in md.strip().splitlines()]
    if lines and lines[0].startswith("```"):
        return "<pre>" + _h("\n".join(lines[1:-1])) + "</pre>"
    rows = [[c.strip() for c in ln.strip().strip("|").split("|")] for ln in lines if not set(ln) <= set("|-: ")]
    return _html_table(rows[0], rows[1:])


def _html_figure(path: Path) -> str:
    """One figure of report.html: inline as a data URI, or a link for PDF."""
    name = _h(path.name)
    mime = _INLINE.get(path.suffix.lower())
    if mime is None:
        return f"<figure><a href='{name}'>{name}</a><figcaption>{name}</figcaption></figure>"
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return (
        f"<figure><img alt='{_h(path.stem)}' src='data:{mime};base64,{data}'><figcaption>{name}</figcaption></figure>"
    )


def render_html(rep) -> str:
    """``report.html``: the same content as ``report.md``, self-contained (PNG and SVG figures as
    base64 data URIs; PDF figures, which browsers do not show inline, as links beside the report)."""
    B = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>snoworm paper reproduction</title>",
        f"<style>{_CSS}</style></head><body>",
        "<h1>snoworm reproduction of Elliott, Lines &amp; Ray (SnoWorm)</h1>",
    ]
    hdr = _header(rep)
    B.append("<p>" + _h(hdr[0]).replace("**", "") + "</p><p>" + _h(hdr[1]) + "</p>")
    B.append("<h2>Summary</h2>")
    rows = [
        (
            f"<a href='#{_h(c.id)}'>{_h(c.id)}</a>",
            _h(c.figure),
            _h(c.source),
            _verdict_html(c),
            _h(_computed_text(c)),
            _h(c.tolerance),
        )
        for c in rep.claims
    ]
    B.append(_html_table(["claim", "figure", "source", "holds", "computed", "tolerance"], rows, raw_cols=range(6)))
    for s in rep.sections:
        B += [
            f"<h2 id='{_h(s.key)}'>{_h(s.title)}</h2>",
            f"<blockquote><b>The paper:</b> {_h(s.paper_says)}</blockquote>",
            f"<p><b>Computed from:</b> {_h(', '.join(s.scenarios))} ({s.wall_time_s:.1f} s)</p>",
            "<ul>",
        ]
        for c in s.claims:
            B.append(
                f"<li id='{_h(c.id)}'><b>{_h(c.id)}</b> ({_h(c.source)}) - {_verdict_html(c)}: {_h(c.statement)}"
                f"<br>computed: {_h(_computed_text(c))}<br>tolerance: {_h(c.tolerance)}</li>"
            )
        B.append("</ul>")
        B += [_md_table_to_html(t) for t in s.tables]
        for v in s.variants:
            B.append(f"<h3>Alternative: {_h(v.label)}</h3>")
            vrows = [
                (_h(c.id), _verdict_html(_find_default(rep, c.id)), _verdict_html(c), _h(_computed_text(c)))
                for c in v.claims
            ]
            B.append(
                _html_table(
                    ["claim", "default reading", "alternative", "alternative computed"], vrows, raw_cols=range(4)
                )
            )
        B += [f"<p><i>Note:</i> {_h(n)}</p>" for n in s.notes]
        B += [_html_figure(Path(p)) for p in s.figures]
    B.append("</body></html>")
    return "\n".join(B) + "\n"
