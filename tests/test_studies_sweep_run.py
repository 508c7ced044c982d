"""snoworm.studies.sweep.run: the plan (every case validated up front, invalid ones recorded, the
resume key, how many validated scenarios are kept for the executor) and run_sweep end to end, the
CLI, files, plots and progress."""

from __future__ import annotations

import json
import math

import pytest
from click.testing import CliRunner

from snoworm.cli import main
from snoworm.config.scenario import load_scenario
from snoworm.config.schema import ScenarioError
from snoworm.studies.sweep import run as run_mod, run_sweep
from snoworm.studies.sweep.run import plan_sweep
from tests.sweep_helpers import SHORT, SMALL, TOW6, csv_rows


def test_cli_writes_summary_plot_and_cases(tmp_path):
    out = tmp_path / "o"
    r = CliRunner().invoke(
        main, ["sweep", TOW6, "--set", "terrain.xt=0.7,0.9", "--set", SHORT, "--out", str(out), "--save-cases"]
    )
    assert r.exit_code == 0, r.output
    assert "2 cases: 2 ok" in r.output
    assert "sweep [" not in r.output  # no progress bar when not a terminal
    assert (out / "sweep.png").stat().st_size > 1000
    s = json.loads((out / "cases" / "0001" / "summary.json").read_text())
    rows = sorted(csv_rows(out / "summary.csv"), key=lambda r: r["case_id"])
    assert float(rows[1]["distance_m"]) == pytest.approx(s["distance_m"], rel=1e-12)


def test_two_keys_write_a_heatmap(tmp_path):
    table = run_sweep(TOW6, SMALL, out_dir=tmp_path)
    assert (tmp_path / "heatmap.png").stat().st_size > 1000
    assert not (tmp_path / "sweep.png").exists()
    assert math.isfinite(table.rows[0]["mean_speed_mps"])


def test_progress_line_reports_cases_and_failures(capsys):
    run_sweep(TOW6, ["terrain.xt=-1,0.9", SHORT], progress=True, plot=False)
    err = capsys.readouterr().err
    assert "2/2 cases" in err and "1 failed" in err


def test_a_scenario_object_sweeps_like_its_file():
    from_file = run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], plot=False)
    from_obj = run_sweep(load_scenario(TOW6), ["terrain.xt=0.7,0.9", SHORT], plot=False)
    for a, b in zip(from_file, from_obj):
        assert b["distance_m"] == pytest.approx(a["distance_m"], rel=1e-9)
        assert b["case_key"] == a["case_key"]


@pytest.mark.parametrize(
    "kwargs, needle",
    [
        ({"save_cases": True}, "--save-cases needs --out"),
        ({"jobs": 0}, "at least 1, got 0"),
        ({"sets": ["terrain.xt=-1,-2", SHORT]}, "every case of the sweep is invalid, e.g. case 0000 (terrain.xt=-1"),
    ],
)
def test_bad_arguments_are_refused_before_anything_runs(tmp_path, kwargs, needle):
    sets = kwargs.pop("sets", ["terrain.xt=0.7,0.9", SHORT])
    with pytest.raises(ScenarioError) as err:
        run_sweep(TOW6, sets, plot=False, **kwargs)
    assert needle in str(err.value)


def test_cli_sweeps_the_grade(tmp_path):
    """`--set terrain.grade_deg=0:10:3` (docs/model.md section 7): one case per grade; steeper is
    slower; a grade beyond the 40 deg limit is an invalid case with the one-line message."""
    r = CliRunner().invoke(
        main,
        [
            "sweep",
            str(TOW6),
            "--set",
            "terrain.grade_deg=0:10:3",
            "--set",
            "simulation.duration_s=6",
            "--no-plot",
            "--out",
            str(tmp_path / "g"),
        ],
    )
    assert r.exit_code == 0, r.output
    rows = sorted(csv_rows(tmp_path / "g" / "summary.csv"), key=lambda x: float(x["terrain.grade_deg"]))
    assert [float(x["terrain.grade_deg"]) for x in rows] == [0.0, 5.0, 10.0]
    speeds = [float(x["late_speed_mps"]) for x in rows]
    assert speeds[0] > speeds[1] > speeds[2]
    bad = CliRunner().invoke(
        main,
        [
            "sweep",
            str(TOW6),
            "--set",
            "terrain.grade_deg=0,45",
            "--no-plot",
            "--set",
            "simulation.duration_s=1",
            "--out",
            str(tmp_path / "b"),
        ],
    )
    assert bad.exit_code == 0, bad.output
    status = {x["terrain.grade_deg"]: (x["status"], x["error"]) for x in csv_rows(tmp_path / "b" / "summary.csv")}
    assert status["0"][0] == "ok" and status["45"][0] == "invalid" and "at most 40 deg" in status["45"][1]


# ------------------------------------------------------------------------------------ the plan


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
    monkeypatch.setattr(run_mod, "KEEP_VALIDATED_MAX", 1)  # more cases than that: none kept
    assert plan_sweep(TOW6, ["terrain.xt=0.8,0.9", SHORT], False, False, None, 1, keep=True).scenarios == {}
