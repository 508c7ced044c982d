"""Figures 6 to 11 claims (snoworm/studies/paper/fig6_11.py): a wrong tow or wrong force targets make the
corresponding claims fail, which shows the verdicts are derived from the computed numbers."""

from __future__ import annotations

import pytest

from snoworm.studies import paper


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


def test_wrong_targets_break_force_control_claims():
    c = _claims(
        ["fig8", "fig9", "fig11"],
        scenario_overrides={
            "pi2_zero": ["mode.targets.link_forces_N=[50]"],
            "pi3_equal": ["mode.targets.net_connector_N.1=60"],
            "pi3_middle_positive": ["mode.targets.link_forces_N=[-50, 50]"],
        },
    )
    assert not c["fig8.link_force_zero"].holds
    assert not c["fig9.link_tensions"].holds
    assert not c["fig11.middle_positive_connector"].holds
