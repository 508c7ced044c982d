"""Figure 3 and Table 2 claims (snoworm/studies/paper/fig3_table2.py): a deliberately broken parameter
makes the corresponding claim fail, which shows the verdicts are derived from the computed numbers."""

from __future__ import annotations

from snoworm.studies import paper


def _claims(items, **kw):
    return {c.id: c for s in paper.evaluate(items, **kw) for c in s.claims}


def test_wrong_tau1_breaks_table2_torques():
    c = _claims(["table2"], model={"tau1": 1.0})
    assert not c["table2.torque_case5"].holds
    assert not c["table2.torque_case2"].holds
    assert c["table2.torque_case1"].holds  # X_t = 1: tau1 has no effect there
    assert c["table2.case5_slip"].holds  # slips do not depend on the torque law


def test_literal_d_breaks_fig3():
    c = _claims(["fig3"], model={"peak_exponent_d": 1})
    assert not c["fig3.xt05_never_positive"].holds
    assert c["fig3.xt1_zero_crossing"].holds
