"""A sweep's plan (snoworm.studies.sweep.plan): every case validated up front, invalid ones
recorded, the resume key, and how many validated scenarios are kept for the executor."""

import pytest

from snoworm.config.schema import ScenarioError
from snoworm.studies.sweep import plan as plan_mod
from snoworm.studies.sweep.plan import plan_sweep
from tests.conftest import SCENARIOS

TOW6 = SCENARIOS / "tow6_uniform.yaml"
SHORT = "simulation.duration_s=1"


def test_invalid_cases_are_recorded_and_the_others_kept():
    plan = plan_sweep(TOW6, ["terrain.xt=-1,0.8,0.9", SHORT], False, False, None, 1, keep=True)
    assert [c.index for c in plan.cases] == [0, 1, 2]
    assert list(plan.invalid) == [0] and plan.invalid[0].startswith("terrain.xt:")
    assert sorted(plan.scenarios) == [1, 2] and plan.scenarios[1].terrain.xt == 0.8
    assert plan.keys == ["terrain.xt", "simulation.duration_s"] and plan.n_links == 5


def test_every_case_invalid_is_one_error_naming_a_case():
    with pytest.raises(ScenarioError, match=r"^every case of the sweep is invalid, e\.g\. case .*terrain\.xt=-1"):
        plan_sweep(TOW6, ["terrain.xt=-1,-2", SHORT], False, False, None, 1)


def test_the_every_case_invalid_error_quotes_a_huge_key_short():
    """A 100 000-character swept key is cut in the message (it printed all of it before)."""
    with pytest.raises(ScenarioError) as err:
        plan_sweep(TOW6, [SHORT, "x" * 100_000 + "=1"], False, False, None, 1)
    assert str(err.value).startswith("every case of the sweep is invalid") and len(str(err.value)) < 400


def test_the_resume_key_depends_on_the_axes_and_validated_scenarios_are_bounded(monkeypatch):
    a = plan_sweep(TOW6, ["terrain.xt=0.8,0.9", SHORT], False, False, None, 1)
    b = plan_sweep(TOW6, ["terrain.xt=0.8,0.95", SHORT], False, False, None, 1)
    assert a.definition["scenario_sha256"] == b.definition["scenario_sha256"] and a.definition != b.definition
    assert a.scenarios == {}  # keep=False: validated again where they run
    monkeypatch.setattr(plan_mod, "KEEP_VALIDATED_MAX", 1)  # more cases than that: none kept
    assert plan_sweep(TOW6, ["terrain.xt=0.8,0.9", SHORT], False, False, None, 1, keep=True).scenarios == {}
