"""snoworm.odds and `snoworm odds` (snoworm/studies/odds/run.py): the files, resuming, the same draws for
every strategy and worker count, the uncertainty: section, bad input (exit 2)."""

import json
import shutil

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from snoworm.cli import main
from snoworm.config.scenario import read_scenario_yaml
from snoworm.config.schema import ScenarioError
from snoworm.studies.odds import load_odds, odds
from snoworm.studies.odds.stats import wilson

STEADY = dict(
    vary=["terrain.xt=normal:0.75:0.05"],
    samples=40,
    strategies=["rolling"],
    rolling_speed=1.0,
    fidelity="steady",
    goal_m=20.0,
    progress=False,
    plot=False,
)


def test_files_and_summary(tmp_path):
    res = odds("climb", out_dir=tmp_path / "o", **STEADY)
    doc = load_odds(tmp_path / "o")
    st = doc["strategies"]["rolling"]
    go = [r["go"] for r in res.rows]
    assert st["n"] == 40 and st["n_go"] == sum(go) and st["p_go"] == sum(go) / 40
    assert st["p_go_ci"] == list(wilson(sum(go), 40))
    times = [r["time_s"] for r in res.rows if r["go"]]
    assert st["time_s"]["p50"] == pytest.approx(np.percentile(times, 50))
    assert doc["inputs"]["terrain.xt"]["dist"] == "normal" and doc["seed"] == 0 and doc["method"] == "random"
    lines = (tmp_path / "o" / "samples.csv").read_text().splitlines()
    assert len(lines) == 41 and lines[0].startswith("draw,strategy,terrain.xt,status,go")
    assert f"rolling gets through in {100 * st['p_go']:.0f} % of 40 draws" in res.text


def test_resume_after_an_interruption_gives_the_same_study(tmp_path):
    """samples.csv cut after three rows and half a line (an interrupted study): the re-run keeps the three
    rows, computes the rest and gives the same rows and summary as an uninterrupted study."""
    full = odds("climb", out_dir=tmp_path / "a", **STEADY)
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    path = tmp_path / "b" / "samples.csv"
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[:4]) + lines[4][:10])
    again = odds("climb", out_dir=tmp_path / "b", **STEADY)
    assert again.rows == full.rows
    assert again.summary == full.summary
    assert path.read_text() == (tmp_path / "a" / "samples.csv").read_text()


def test_another_study_in_the_folder_is_refused_unless_overwrite(tmp_path):
    odds("climb", out_dir=tmp_path / "o", **STEADY)
    with pytest.raises(ScenarioError, match="holds another odds study"):
        odds("climb", out_dir=tmp_path / "o", **{**STEADY, "seed": 1})
    res = odds("climb", out_dir=tmp_path / "o", overwrite=True, **{**STEADY, "seed": 1})
    assert load_odds(tmp_path / "o")["seed"] == 1 and len(res.rows) == 40


def test_same_draws_for_every_strategy_and_seeded():
    kw = {
        **STEADY,
        "strategies": ["rolling", "scenario"],
        "vary": ["terrain.xt=normal:0.8:0.05", "tow.force_N=uniform:0:50"],
    }
    kw["sets"] = ["mode={type: uniform, speed_mps: 1.0, start_time_s: 0.5}"]
    res = odds("climb", **kw)
    by = {}
    for r in res.rows:
        by.setdefault(r["draw"], []).append((r["terrain.xt"], r["tow.force_N"]))
    assert all(len(set(v)) == 1 for v in by.values())
    # rolling and the scenario's uniform mode are the same strategy here: the same outcomes
    go = {(r["draw"], r["strategy"]): r["go"] for r in res.rows}
    assert all(go[(k, "rolling")] == go[(k, "scenario")] for k in by)
    assert odds("climb", **kw).rows == res.rows


def test_results_do_not_depend_on_the_worker_count():
    kw = dict(
        vary=["terrain.xt=normal:0.75:0.05"],
        sets=["simulation.duration_s=4"],
        samples=3,
        strategies=["rolling"],
        rolling_speed=1.0,
        goal_m=1.0,
        progress=False,
    )
    one, two = odds("climb", jobs=1, **kw), odds("climb", jobs=2, **kw)
    assert one.rows == two.rows


def test_uncertainty_section_and_set_fixing_an_input(tmp_path):
    raw, _ = read_scenario_yaml("climb")
    raw["uncertainty"] = {"vary": {"terrain.xt": "normal:0.75:0.05", "tow.force_N": "uniform:0:100"}}
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(raw))
    kw = {k: v for k, v in STEADY.items() if k != "vary"}
    res = odds(str(path), **kw)
    assert set(res.summary["inputs"]) == {"terrain.xt", "tow.force_N"}
    fixed = odds(str(path), sets=["tow.force_N=0"], **kw)
    assert set(fixed.summary["inputs"]) == {"terrain.xt"}
    assert all("tow.force_N" not in r for r in fixed.rows)


def test_no_input_and_zero_draws_are_refused():
    with pytest.raises(ScenarioError, match="no uncertain input"):
        odds("climb", **{**STEADY, "vary": []})
    with pytest.raises(ScenarioError, match="--samples"):
        odds("climb", **{**STEADY, "samples": 0})
    with pytest.raises(ScenarioError, match="--strategy: unknown"):
        odds("climb", **{**STEADY, "strategies": ["crawl"]})


def test_cli_writes_and_prints_in_field_terms(tmp_path):
    out = tmp_path / "o"
    r = CliRunner().invoke(
        main,
        [
            "odds",
            "climb",
            "--out",
            str(out),
            "--vary",
            "terrain.xt=normal:0.75:0.05",
            "--samples",
            "30",
            "--strategy",
            "rolling",
            "--rolling-speed",
            "1",
            "--fidelity",
            "steady",
            "--goal-m",
            "20",
        ],
    )
    assert r.exit_code == 0, r.output
    doc = json.loads((out / "odds.json").read_text())
    p = doc["strategies"]["rolling"]["p_go"]
    assert f"rolling gets through in {100 * p:.0f} % of 30 draws" in r.output
    assert (out / "odds.png").exists() and (out / "stops.png").exists() and (out / "convergence.png").exists()


@pytest.mark.parametrize(
    "args,words",
    [
        (["--vary", "terrain.xt=normal:0.8:0"], "sd must be > 0"),
        (["--vary", "terrain.xt=normal:1.2:0.05"], "domain"),
        (["--vary", "terrain.xt=normal:0.8:0.05", "--samples", "0"], "--samples"),
        (["--xt-field", "sd=-1,corr=5"], "sd must be > 0"),
        (["--calibration", "nowhere"], "--calibration"),
    ],
)
def test_cli_bad_input_exits_2_naming_the_field(tmp_path, args, words):
    r = CliRunner().invoke(main, ["odds", "climb", "--out", str(tmp_path / "o"), *args])
    assert r.exit_code == 2, r.output
    assert words in r.output and "Traceback" not in r.output
    assert not (tmp_path / "o").exists()


def test_a_controller_that_may_not_run_refuses_the_study(tmp_path):
    """A scenario whose controller lies outside its folder and --allow-code: refused before any draw runs
    (as a sweep is), naming --allow-code; allowed, its draws run."""
    raw, _ = read_scenario_yaml("tow6_uniform")
    ctl = tmp_path / "code" / "ctl.py"
    ctl.parent.mkdir()
    ctl.write_text(
        "class C:\n    def __init__(self, params, scenario):\n        self.n = scenario.vehicle.segments\n"
        "    def __call__(self, obs):\n        return {'wheel_speed_mps': [1.0] * self.n}\n"
    )
    raw["mode"] = {"type": "controller", "controller": f"{ctl}:C", "period_s": 0.1}
    raw["simulation"]["duration_s"] = 1.0
    (tmp_path / "sc").mkdir()
    path = tmp_path / "sc" / "s.yaml"
    path.write_text(yaml.safe_dump(raw))
    kw = dict(vary=["terrain.xt=normal:0.9:0.01"], samples=1, progress=False)
    with pytest.raises(ScenarioError, match="--allow-code"):
        odds(str(path), **kw)
    res = odds(str(path), allow_code=[ctl.parent], **kw)
    assert res.rows[0]["status"] == "ok"


def test_cli_interrupted_says_where_the_finished_draws_are(tmp_path, monkeypatch):
    import snoworm.studies.odds as odds_pkg

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(odds_pkg, "odds", interrupted)
    r = CliRunner().invoke(
        main, ["odds", "climb", "--out", str(tmp_path / "o"), "--vary", "terrain.xt=normal:0.8:0.05"]
    )
    assert r.exit_code == 130
    assert "samples.csv" in r.output and "run the same command again to resume" in r.output


def test_python_api_takes_single_strings_as_the_cli_does():
    kw = {k: v for k, v in STEADY.items() if k not in ("vary", "strategies")}
    a = odds("climb", vary="terrain.xt=normal:0.75:0.05", strategies="rolling", **kw)
    b = odds("climb", **STEADY)
    assert a.rows == b.rows


def test_set_cannot_fix_one_of_the_jointly_drawn_coefficients(tmp_path):
    doc = {
        "parameters": [{"name": "b_tF", "value": 0.9, "stderr": 0.05}, {"name": "A", "value": 1.2, "stderr": 0.02}],
        "correlation": [[1.0, -0.5], [-0.5, 1.0]],
    }
    (tmp_path / "calibration.json").write_text(json.dumps(doc))
    kw = {k: v for k, v in STEADY.items() if k != "vary"}
    with pytest.raises(ScenarioError, match="--set terrain.model.A: --calibration draws this coefficient jointly"):
        odds("climb", calibration=str(tmp_path), sets=["terrain.model.A=1.0"], **kw)
    res = odds("climb", calibration=str(tmp_path), **{**kw, "samples": 8})
    assert {"terrain.model.b_tF", "terrain.model.A"} <= set(res.columns)
