"""Rendering of the report (snoworm/studies/paper/render.py): verdicts, escaping, the variant tables."""

from __future__ import annotations

from snoworm.studies import paper


def _report(holds=True, statement="a statement", variant_holds=None):
    c = paper.Claim("x.y", "Fig 6", statement, "paper", {"v": 1.0, "w": [1.5, None]}, "v <= 2 | w", holds)
    variants = (
        []
        if variant_holds is None
        else [
            paper.Variant(
                "alt reading",
                {"terrain.model.tau1": 0},
                [paper.Claim("x.y", "Fig 6", statement, "paper", {"v": 3.0}, "v <= 2", variant_holds)],
            )
        ]
    )
    sec = paper.Section(
        "x",
        "Figure X",
        "the paper <says> & more",
        scenarios=["tow6_uniform"],
        claims=[c],
        tables=["| a | b |\n|---|---|\n| 1 | <2> |"],
        notes=["a <note>"],
        variants=variants,
    )
    return paper.PaperReport([sec], True, 0.1)


def test_failing_claim_is_marked_in_markdown():
    ok = paper.render_markdown(_report(True))
    bad = paper.render_markdown(_report(False))
    assert "**1 of 1 claims hold.**" in ok and "- **x.y** (paper) - holds: a statement" in ok
    assert "**0 of 1 claims hold.**" in bad
    assert "| x.y | Fig 6 | paper | **NO** |" in bad and "| x.y | Fig 6 | paper | yes |" in ok
    assert "- **x.y** (paper) - **FAILS**: a statement" in bad
    assert "FAILS" not in ok
    # computed values and tolerance in the summary table, with the pipe escaped
    assert "v = 1; w = [1.5, n/a]" in ok and "v <= 2 \\| w" in ok


def test_variant_table_shows_default_and_alternative_verdicts():
    md = paper.render_markdown(_report(True, variant_holds=False))
    assert "**Alternative: alt reading** (`terrain.model.tau1=0`)" in md
    assert "| x.y | holds | FAILS | v = 3 |" in md
    html = paper.render_html(_report(True, variant_holds=False))
    assert "<h3>Alternative: alt reading</h3>" in html
    assert '<span class="ok">holds</span></td><td><span class="bad">FAILS</span>' in html


def test_html_escapes_every_text_field():
    html = paper.render_html(_report(False, statement="<script>alert(1)</script> & co"))
    assert "<script>" not in html
    assert "&lt;script&gt;alert(1)&lt;/script&gt; &amp; co" in html
    assert "the paper &lt;says&gt; &amp; more" in html
    assert "<td>&lt;2&gt;</td>" in html and "a &lt;note&gt;" in html
    assert '<span class="bad">FAILS</span>' in html
    assert html.startswith("<!DOCTYPE html>") and html.rstrip().endswith("</body></html>")
