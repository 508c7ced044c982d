"""Figure 5 claims (snoworm/studies/paper/fig5.py): they follow the inchworm and rolling runs, and swapping
the terrains reverses them."""

from __future__ import annotations

import pytest

from snoworm.studies import paper


@pytest.fixture(scope="module")
def inchworm_runs():
    ctx = paper.Context(quick=True)
    dur = [f"simulation.duration_s={paper.QUICK_INCHWORM_DURATION_S:g}"]
    return (
        ctx.run("inchworm6", dur),
        ctx.run("inchworm6", dur + ["terrain.xt=0.5"]),
        ctx.run("rolling6_xt025", dur),
        ctx.run("rolling6_xt025", dur + ["terrain.xt=0.9"]),
    )


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
