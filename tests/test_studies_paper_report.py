"""The paper-reproduction report end to end (snoworm/studies/paper/report.py, `snoworm paper`).

The quick report runs end to end and every claim in it holds; a solver or input error in one
item becomes a failing claim; the CLI's exit status follows --strict.
"""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from snoworm.cli import main
from snoworm.studies import paper

FIGURES = (
    "fig3_terrain_curves.png",
    "table2.png",
    "fig5_speeds.png",
    "fig5_positions.png",
    "fig6_forces.png",
    "fig7_forces.png",
    "fig8_forces.png",
    "fig8_speeds.png",
    "fig9_forces.png",
    "fig9_speeds.png",
    "fig10_force_diagram.png",
    "fig11_forces.png",
    "fig11_speeds.png",
    "fig3_d1_terrain_curves.png",
)


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    lines = []
    rep = paper.run_paper(out, quick=True, progress=lines.append)
    return rep, out, lines


def test_quick_report_writes_everything(quick_report):
    rep, out, lines = quick_report
    for name in FIGURES + ("report.md", "report.html", "claims.json"):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    md = (out / "report.md").read_text(encoding="utf-8")
    html = (out / "report.html").read_text(encoding="utf-8")
    for c in rep.claims:
        assert c.id in md and c.id in html
    # self-contained: every figure embedded, no relative image links
    assert html.count("data:image/png;base64,") == len(FIGURES)
    assert "src='fig" not in html
    data = json.loads((out / "claims.json").read_text(encoding="utf-8"))
    assert data["quick"] is True and len(data["claims"]) == len(rep.claims)
    assert data["all_hold"] == rep.all_hold
    # one progress line per item
    assert len(lines) == len(paper.ITEMS)
    assert all(line.startswith(f"[{k}/{len(paper.ITEMS)}]") for k, line in enumerate(lines, 1))


def test_every_claim_holds_in_quick_mode(quick_report):
    rep = quick_report[0]
    failed = [(c.id, c.computed, c.tolerance) for c in rep.claims if not c.holds]
    assert not failed, failed
    assert rep.all_hold


def test_every_figure_has_claims_with_numbers(quick_report):
    rep = quick_report[0]
    figures = {c.figure for c in rep.claims}
    for fig in ("Fig 3", "Table 2", "Fig 5", "Fig 6", "Fig 7", "Fig 8", "Figs 9-10", "Fig 11"):
        assert fig in figures, fig
    ids = [c.id for c in rep.claims]
    assert len(ids) == len(set(ids))
    for c in rep.claims:
        assert c.computed and c.tolerance and c.source in ("paper", "model") and isinstance(c.holds, bool)


def _claims(items, **kw):
    return {c.id: c for s in paper.evaluate(items, **kw) for c in s.claims}


def test_solver_or_input_error_becomes_a_failing_claim():
    c = _claims(["fig6"], scenario_overrides={"tow6_uniform": ["tow.force_N=heavy"]})
    assert list(c) == ["fig6.ran"] and not c["fig6.ran"].holds and "error" in c["fig6.ran"].computed


def _plain_sections(sections):
    return [
        (
            s.key,
            s.title,
            s.scenarios,
            [c.to_dict() for c in s.claims],
            s.tables,
            s.notes,
            [(v.label, v.overrides, [c.to_dict() for c in v.claims]) for v in s.variants],
        )
        for s in sections
    ]


def test_parallel_items_give_the_serial_report(quick_report):
    """-j 2 (items on the process pool, Fig 5's runs as separate tasks) and -j 1 compute the same
    sections, claims and values, in the same order, with one progress line per item."""
    rep = quick_report[0]
    lines = []
    pooled = paper.evaluate(None, quick=True, jobs=2, progress=lines.append)
    assert [s.key for s in pooled] == list(paper.ITEMS)
    assert _plain_sections(pooled) == _plain_sections(rep.sections)
    assert len(lines) == len(paper.ITEMS)
    assert sorted(line.split("]")[0] for line in lines) == sorted(f"[{k}/{len(paper.ITEMS)}" for k in range(1, 10))
    assert all(s.wall_time_s > 0 for s in pooled)


def test_parallel_errors_become_failing_claims_too():
    bad = {"tow6_uniform": ["tow.force_N=heavy"], "inchworm6": ["terrain.xt=heavy"]}
    c = _claims(["fig5", "fig6", "fig3"], scenario_overrides=bad, quick=True, jobs=2)
    assert not c["fig5.ran"].holds and not c["fig6.ran"].holds  # a prefetched run and an item failed
    assert c["fig3.xt1_zero_crossing"].holds and c["fig3.xt05_never_positive"].holds  # the others still ran
    assert "heavy" in c["fig5.ran"].computed["error"]


def test_default_jobs_is_capped():
    assert 1 <= paper.default_jobs() <= paper.report.MAX_DEFAULT_JOBS


def test_unknown_item_is_rejected():
    from snoworm.config.schema import ScenarioError

    with pytest.raises(ScenarioError, match="unknown report item"):
        paper.evaluate(["fig99"])


@pytest.mark.parametrize(
    "fmt,shown", [("svg", "data:image/svg+xml;base64,"), ("pdf", "<a href='fig3_terrain_curves.pdf'>")]
)
def test_plot_format_of_the_figures_and_how_the_report_shows_them(tmp_path, fmt, shown):
    secs = paper.evaluate(["fig3"], out_dir=tmp_path, plot_format=fmt)
    figs = [p for s in secs for p in s.figures]
    assert figs and all(p.suffix == f".{fmt}" and p.exists() for p in figs)
    rep = paper.PaperReport(secs, True, 0.1)
    html, md = paper.render_html(rep), paper.render_markdown(rep)
    assert shown in html and "data:image/png" not in html
    assert (f"![fig3_terrain_curves](fig3_terrain_curves.{fmt})" in md) == (fmt == "svg")
    assert ("[fig3_terrain_curves.pdf](fig3_terrain_curves.pdf)" in md) == (fmt == "pdf")


def test_figure_size_of_the_report_figures(tmp_path):
    """paper --figure-size column: the figures are 3.5 in (252 pt) wide PDFs without Type 3 fonts
    (the fig3 item: Figure 3)."""
    import re

    secs = paper.evaluate(["fig3"], out_dir=tmp_path, plot_format="pdf", figure_size="column")
    figs = [p for s in secs for p in s.figures]
    assert figs
    for p in figs:
        data = p.read_bytes()
        assert float(re.search(rb"/MediaBox \[\s*0 0 ([0-9.]+) ", data).group(1)) == pytest.approx(252.0, abs=0.01)
        assert b"/Subtype /Type3" not in data


def test_unknown_plot_format_is_rejected():
    from snoworm.config.schema import ScenarioError

    with pytest.raises(ScenarioError, match="plot format 'gif'"):
        paper.evaluate(["fig3"], plot_format="gif")


# ------------------------------------------------------------------ CLI


def _fake_report(holds):
    c = paper.Claim("x.y", "Fig 6", "a statement", "paper", {"v": 1.0}, "v <= 2", holds)
    return paper.PaperReport([paper.Section("x", "X", "", claims=[c])], True, 0.1)


@pytest.mark.parametrize("holds,strict,code", [(True, True, 0), (False, False, 0), (False, True, 1)])
def test_cli_exit_status(monkeypatch, tmp_path, holds, strict, code):
    monkeypatch.setattr(
        paper,
        "run_paper",
        lambda out, quick=False, progress=None, overwrite=False, jobs=1, plot_format="png", figure_size=None, command=None: (
            _fake_report(holds)
        ),
    )
    args = ["paper", "--out", str(tmp_path), "--quick"] + (["--strict"] if strict else [])
    res = CliRunner().invoke(main, args)
    assert res.exit_code == code, res.output
    assert ("1 of 1 claims hold" if holds else "0 of 1 claims hold") in res.output
