"""The inching cells of a mobility map (snoworm.studies.inching): the scenario of a cell, gait
labels, and the bisection of the runs over the grades."""

import pytest

from snoworm.config.scenario import load_scenario, scenario_from_dict
from snoworm.config.schema import ScenarioError
from snoworm.studies import inching
from snoworm.studies.inching import InchingRuns, gait_label, inch_cells, inching_scenario
from tests.conftest import SCENARIOS


def test_a_cells_scenario_is_the_inchworm_on_uniform_terrain_grade_and_tow():
    sc = load_scenario(SCENARIOS / "inchworm6.yaml")
    cell = scenario_from_dict(inching_scenario(sc, 0.5, 120.0, 4.0, grade_deg=5.0, gait=[[k] for k in range(6)]))
    assert cell.terrain.xt == 0.5 and cell.terrain.grade_deg == 5.0 and cell.tow.force_N == 120.0
    assert cell.mode.type == "inchworm" and cell.mode.start_time_s == 0.0 and cell.simulation.duration_s == 4.0
    assert [list(p) for p in cell.mode.gait] == [[k] for k in range(6)]
    assert cell.terrain.model == sc.terrain.model


def test_a_mode_that_does_not_inch_is_named():
    with pytest.raises(ScenarioError, match=r"^mode\.type: .* mode 'uniform' does not inch"):
        inching_scenario(load_scenario(SCENARIOS / "tow6_uniform.yaml"), 0.5, 0.0, 4.0)


def test_gait_labels():
    assert gait_label("six_segment") == "six_segment"
    assert gait_label([[0], [1, 2]]) == "[[0],[1,2]]"


def test_the_runs_are_bisected_over_the_grades(monkeypatch):
    # a stand-in run that inches on grades up to 10 deg: 3 runs decide 5 grades (ceil(log2(6)))
    ran = []

    def fake_run(task):
        raw, _ = task
        grade = raw["terrain"].get("grade_deg", 0.0)
        ran.append(grade)
        ok = grade <= 10.0
        return {
            "inching": ok,
            "inching_speed_mps": 0.1 if ok else 0.0,
            "inching_energy_per_metre_J_per_m": 50.0 if ok else None,
            "inching_note": "",
        }

    monkeypatch.setattr(inching, "_inch_run", fake_run)
    sc = load_scenario(SCENARIOS / "inchworm6.yaml")
    grades = [0.0, 5.0, 10.0, 15.0, 20.0]
    rows = [{"xt": 0.5, "tow_N": 0.0, "grade_deg": g, "rolling": False} for g in grades]
    seen = []
    inch_cells(InchingRuns(sc, grades, False, 2.0, 0.02), rows, progress=lambda d, t: seen.append((d, t)))
    assert len(ran) == 3 and seen[-1] == (3, 3)
    assert [r["inching"] for r in rows] == [True, True, True, False, False]
    inferred = [r for r in rows if r["inching_note"].startswith("not simulated")]
    assert len(inferred) == 2 and all(r["inching_speed_mps"] is None for r in inferred)
    # every_cell: every grade is run
    ran.clear()
    rows = [{"xt": 0.5, "tow_N": 0.0, "grade_deg": g, "rolling": g == 0.0} for g in grades]
    inch_cells(InchingRuns(sc, grades, True, 2.0, 0.02), rows)
    assert sorted(ran) == grades and all(r["inching_note"] == "" for r in rows)
