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


# ------------------------------------------------------------------ the rolling limits in field terms
def test_rolling_sentence_reads_the_limits():
    """The sentence states each limit with its number, and a negative limit as the downhill grade needed."""
    from snoworm.studies.gradeability import rolling_sentence

    s = rolling_sentence(0.8, 14.54, 12.72, 13.65, 0.3)
    assert s == "rolling: climbs up to 14.5 deg once moving, 12.7 deg from rest, 13.7 deg below 30 % slip"
    s = rolling_sentence(0.4, -12.66, -12.66, -14.71, 0.3)
    assert s.startswith("rolling: cannot start on level snow at X_t 0.4 (it would need 12.7 deg downhill)")
    assert "once moving" not in s  # the same limit: said once
    assert s.endswith("below 30 % slip only from 14.7 deg downhill")
    s = rolling_sentence(0.62, 2.5, -1.0, -3.0, 0.25)
    assert "it would need 1.0 deg downhill); once moving it climbs up to 2.5 deg" in s and "25 %" in s
    assert rolling_sentence(0.1, None, None, None, 0.3) == "rolling: cannot move at X_t 0.1, not even 40 deg downhill"
    assert "40 deg (the steepest grade modelled)" in rolling_sentence(1.0, 40.0, 11.4, 40.0, 0.3)


def test_map_limits_and_the_cli_table(scenario_path, tmp_path):
    """mobility-map with several grades: per X_t the three rolling limits (steady functions, with the
    scenario's sled and each segment's share of the tow), the sentence in the printed report and
    gradeability.csv; --slip-cap sets the cap and is checked (exit 2)."""
    import csv

    from click.testing import CliRunner

    from snoworm import load_scenario, steady
    from snoworm.cli import main

    args = ["mobility-map", "tow6_uniform", "--xt", "0.4,0.8", "--grade", "0:20:3", "--tow", "0,200"]
    args += ["--no-inching", "--no-plot", "--set", "tow.mass_kg=100", "--set", "tow.friction=0.1"]
    r = CliRunner().invoke(main, args + ["--slip-cap", "0.2", "--out", str(tmp_path / "m")])
    assert r.exit_code == 0, r.output
    sc = load_scenario("tow6_uniform")
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    rows = list(csv.DictReader((tmp_path / "m" / "gradeability.csv").read_text().splitlines()))
    assert [(float(x["tow_N"]), float(x["xt"])) for x in rows] == [(0, 0.4), (0, 0.8), (200, 0.4), (200, 0.8)]
    for row in rows:
        f, x = float(row["tow_N"]), float(row["xt"])
        sled = {"segments": 6, "sled_mass_kg": 100.0, "sled_friction": 0.1}
        on = steady.max_grade_deg(x, seg, tp, 1.8, f / 6, **sled)
        rest = steady.max_grade_from_rest_deg(x, seg, tp, f / 6, **sled)
        capped = steady.max_grade_below_slip_deg(x, seg, tp, 1.8, 0.2, f / 6, **sled)
        got = [float(row[k]) for k in ("rolling_max_grade_deg", "rolling_from_rest_grade_deg")]
        got.append(float(row["rolling_slip_capped_grade_deg"]))
        assert got == pytest.approx([on, rest, capped], rel=1e-5)  # 6 significant digits
        assert float(row["slip_cap"]) == 0.2
        assert row["rolling_sentence"] in r.output
        if x == 0.8:
            assert f"{rest:.1f} deg from rest" in row["rolling_sentence"]
        else:
            assert f"it would need {-rest:.1f} deg downhill" in row["rolling_sentence"]
    bad = CliRunner().invoke(main, args + ["--slip-cap", "0", "--out", str(tmp_path / "b")])
    assert bad.exit_code == 2 and "--slip-cap" in bad.output and not (tmp_path / "b").exists()
