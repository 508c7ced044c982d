"""Gradeability from a mobility map with a grade axis (snoworm.studies.gradeability)."""

import math

import pytest

from snoworm.studies.gradeability import grade_text, gradeability


def _cell(xt, grade, rolling, e_roll=None, inching=None, e_inch=None, by_gait=None):
    r = {
        "xt": xt,
        "tow_N": 0.0,
        "grade_deg": grade,
        "rolling": rolling,
        "rolling_energy_per_metre_J_per_m": e_roll,
        "inching": inching,
        "inching_energy_per_metre_J_per_m": e_inch,
        "inching_speed_mps": None,
        "inching_note": "",
    }
    if by_gait:
        r["inching_by_gait"] = by_gait
    return r


def _map(rows, labels=None):
    res = {
        "rows": rows,
        "xts": [0.5, 0.8],
        "tows": [0.0],
        "grades": [0.0, 10.0, 20.0],
        "wall_time_s": 1.0,
        "rolling_max_grade_deg": {0.0: {0.5: None, 0.8: 14.5}},
        "gait_labels": labels,
    }
    res["gradeability"] = {0.0: gradeability(res, 0.0)}
    return res


def test_steepest_grade_and_energy_per_metre_climbed():
    rows = [
        _cell(0.5, 0.0, False, inching=True, e_inch=5e3),
        _cell(0.5, 10.0, False, inching=True, e_inch=9e3),
        _cell(0.5, 20.0, False, inching=False),
        _cell(0.8, 0.0, True, e_roll=2e3),
        _cell(0.8, 10.0, True, e_roll=4e3),
        _cell(0.8, 20.0, False, inching=True),
    ]
    g = _map(rows)["gradeability"][0.0]
    assert g["rolling_grid_deg"] == [None, 10.0]
    assert g["rolling_J_per_m_climbed"][1] == pytest.approx(4e3 / math.sin(math.radians(10.0)))
    assert g["inching"]["inching"]["grid_deg"] == [10.0, 20.0]
    assert g["inching"]["inching"]["J_per_m_climbed"] == [pytest.approx(9e3 / math.sin(math.radians(10.0))), None]
    assert g["rolling_max_grade_deg"] == [None, 14.5]


def test_one_curve_per_gait_and_the_text():
    a = {"inching": True, "inching_energy_per_metre_J_per_m": 1e3, "inching_speed_mps": 0.1, "inching_note": ""}
    no = {"inching": False, "inching_energy_per_metre_J_per_m": None, "inching_speed_mps": 0.0, "inching_note": ""}
    rows = [
        _cell(x, g, False, by_gait={"six_segment": a if g < 10 else no, "[[0],[1]]": a if g < 20 else no})
        for x in (0.5, 0.8)
        for g in (0.0, 10.0, 20.0)
    ]
    res = _map(rows, ["six_segment", "[[0],[1]]"])
    g = res["gradeability"][0.0]
    assert g["inching"]["six_segment"]["grid_deg"] == [0.0, 0.0]
    assert g["inching"]["[[0],[1]]"]["grid_deg"] == [10.0, 10.0]
    text = grade_text("s", res, inching=True, every_cell=False)
    assert "X_t = 0.8: rolling 14.5, six_segment 0, [[0],[1]] 10" in text
    assert "X_t = 0.5: rolling none" in text
