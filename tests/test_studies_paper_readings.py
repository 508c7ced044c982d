"""The alternative readings of the paper (snoworm/studies/paper/readings.py): under d = 1 and tau1 = 0 the
documented claims fail."""

from __future__ import annotations

import pytest

from snoworm.studies import paper


@pytest.fixture(scope="module")
def quick_report():
    """A quick report of the readings item only (the test below reads only that section)."""
    rep = paper.PaperReport(paper.evaluate(["readings"], quick=True), quick=True, wall_time_s=0.0)
    return rep, None, []


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
