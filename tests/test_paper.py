"""The paper-reproduction report (snoworm/paper.py, `snoworm paper`).

Two halves: the quick report runs end to end and every claim in it holds; and a deliberately
broken parameter makes the corresponding claim fail, which shows the verdicts are derived from
the computed numbers rather than written down.
"""
from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from snoworm import paper
from snoworm.cli import main

FIGURES = ("fig3_terrain_curves.png", "table2.png", "fig5_speeds.png", "fig5_positions.png", "fig6_forces.png",
           "fig7_forces.png", "fig8_forces.png", "fig8_speeds.png", "fig9_forces.png", "fig9_speeds.png",
           "fig10_force_diagram.png", "fig11_forces.png", "fig11_speeds.png", "fig3_d1_terrain_curves.png")


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


def test_variants_show_the_d1_failures(quick_report):
    rep = quick_report[0]
    readings = next(s for s in rep.sections if s.key == "readings")
    d1 = next(v for v in readings.variants if v.overrides == {"terrain.model.peak_exponent_d": 1})
    verdict = {c.id: c.holds for c in d1.claims}
    # docs/model.md section 2: at d = 1 these two fail, the X_t = 1 crossing and the torques do not
    assert verdict["fig3.xt05_never_positive"] is False
    assert verdict["table2.case5_slip"] is False
    assert verdict["fig3.xt1_zero_crossing"] is True
    assert verdict["table2.torque_case5"] is True
    tau = next(v for v in readings.variants if v.overrides == {"terrain.model.tau1": 0})
    assert not next(c for c in tau.claims if c.id == "table2.torque_case5").holds


# ------------------------------------------------------------------ broken parameters make claims fail

def _claims(items, **kw):
    return {c.id: c for s in paper.evaluate(items, **kw) for c in s.claims}


def test_wrong_tow_breaks_fig6():
    c = _claims(["fig6"], scenario_overrides={"tow6_uniform": ["tow.force_N=300"]})
    assert not c["fig6.link_tensions"].holds
    assert not c["fig6.net_forces_uniform"].holds
    assert c["fig6.link_tensions"].computed["link_forces_N"][-1] == pytest.approx(250.0, abs=1.0)


def test_wrong_tow_breaks_fig7():
    c = _claims(["fig7"], scenario_overrides={"tow6_staggered": ["tow.force_N=250"]})
    assert not c["fig7.same_steady_state"].holds


def test_wrong_tau1_breaks_table2_torques():
    c = _claims(["table2"], model={"tau1": 1.0})
    assert not c["table2.torque_case5"].holds
    assert not c["table2.torque_case2"].holds
    assert c["table2.torque_case1"].holds          # X_t = 1: tau1 has no effect there
    assert c["table2.case5_slip"].holds            # slips do not depend on the torque law


def test_literal_d_breaks_fig3():
    c = _claims(["fig3"], model={"peak_exponent_d": 1})
    assert not c["fig3.xt05_never_positive"].holds
    assert c["fig3.xt1_zero_crossing"].holds


def test_wrong_targets_break_force_control_claims():
    c = _claims(["fig8", "fig9", "fig11"], scenario_overrides={
        "pi2_zero": ["mode.targets.link_forces_N=[50]"],
        "pi3_equal": ["mode.targets.net_connector_N.1=60"],
        "pi3_middle_positive": ["mode.targets.link_forces_N=[-50, 50]"]})
    assert not c["fig8.link_force_zero"].holds
    assert not c["fig9.link_tensions"].holds
    assert not c["fig11.middle_positive_connector"].holds


@pytest.fixture(scope="module")
def inchworm_runs():
    ctx = paper.Context(quick=True)
    dur = [f"simulation.duration_s={paper.QUICK_INCHWORM_DURATION_S:g}"]
    return (ctx.run("inchworm6", dur), ctx.run("inchworm6", dur + ["terrain.xt=0.5"]),
            ctx.run("rolling6_xt025", dur), ctx.run("rolling6_xt025", dur + ["terrain.xt=0.9"]))


def test_fig5_claims_follow_the_runs(inchworm_runs):
    lo, hi, roll, roll_good = inchworm_runs
    ok = {c.id: c.holds for c in paper.check_fig5(lo, roll, hi)}
    assert all(ok.values()), ok
    # rolling on X_t = 0.9 is not immobilised; swapping the terrains reverses every X_t comparison
    swapped = {c.id: c.holds for c in paper.check_fig5(hi, roll_good, lo)}
    assert not swapped["fig5.rolling_immobilised"]
    assert not swapped["fig5.higher_xt_faster"]
    assert not swapped["fig5.higher_xt_less_sliding"]
    assert not swapped["fig5.higher_xt_lower_joint_force"]
    # the pair measure separates the paper's pairs from every other pair of segments
    ov = paper.pair_overlap(lo)
    assert max(ov["pairs"].values()) < min(ov["others"].values())
    assert paper.pair_overlap(lo, pairs=((0, 1),))["pairs"]["0&1"] > paper.FIG5_PAIR_RMS_MAX


def test_solver_or_input_error_becomes_a_failing_claim():
    c = _claims(["fig6"], scenario_overrides={"tow6_uniform": ["tow.force_N=heavy"]})
    assert list(c) == ["fig6.ran"] and not c["fig6.ran"].holds and "error" in c["fig6.ran"].computed


def test_unknown_item_is_rejected():
    from snoworm.schema import ScenarioError
    with pytest.raises(ScenarioError, match="unknown report item"):
        paper.evaluate(["fig99"])


# ------------------------------------------------------------------ CLI

def _fake_report(holds):
    c = paper.Claim("x.y", "Fig 6", "a statement", "paper", {"v": 1.0}, "v <= 2", holds)
    return paper.PaperReport([paper.Section("x", "X", "", claims=[c])], True, 0.1)


@pytest.mark.parametrize("holds,strict,code", [(True, True, 0), (False, False, 0), (False, True, 1)])
def test_cli_exit_status(monkeypatch, tmp_path, holds, strict, code):
    monkeypatch.setattr(paper, "run_paper", lambda out, quick=False, progress=None: _fake_report(holds))
    args = ["paper", "--out", str(tmp_path), "--quick"] + (["--strict"] if strict else [])
    res = CliRunner().invoke(main, args)
    assert res.exit_code == code, res.output
    assert ("1 of 1 claims hold" if holds else "0 of 1 claims hold") in res.output
