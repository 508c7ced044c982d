"""Tests of parameter sweeps (snoworm.sweep and the `snoworm sweep` command)."""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

import snoworm.sweep as sweep_mod
from snoworm.cli import main
from snoworm.scenario import load_scenario
from snoworm.schema import ScenarioError
from snoworm import SolverError, simulate
from snoworm.sweep import build_cases, case_metrics, parse_spec, parse_sweep_option, run_sweep

ROOT = Path(__file__).resolve().parents[1]
TOW6 = str(ROOT / "scenarios" / "tow6_uniform.yaml")
SHORT = "simulation.duration_s=6"
#: 4 cases: a 2 x 2 grid, one of them immobilised-free, all fast (6 s simulated each)
SMALL = ["terrain.xt=0.7,0.9", "tow.force_N=0,200", SHORT]


def _comparable(table):
    """Rows without the wall time (the only column allowed to differ between executors)."""
    return [{k: v for k, v in r.items() if k != "wall_time_s"} for r in table.rows]


def _csv_rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


# ------------------------------------------------------------------ SPEC parsing
def test_list_spec_parses_numbers_and_yaml():
    assert parse_spec("tow.force_N", "0,100,200") == (0, 100, 200)
    assert parse_spec("terrain.xt", "0.5") == (0.5,)
    assert parse_spec("simulation.rtol", "1e-5,1e-6") == (1e-5, 1e-6)
    assert parse_spec("mode.speed_mps", "[1.8, 1.5],[1.0, 1.0]") == ([1.8, 1.5], [1.0, 1.0])
    assert parse_spec("simulation.method", "LSODA,BDF") == ("LSODA", "BDF")


def test_range_spec_is_inclusive_with_count_values():
    v = parse_spec("terrain.xt", "0.3:1.0:15")
    assert len(v) == 15
    assert v[0] == 0.3 and v[-1] == 1.0
    assert v[1] == pytest.approx(0.35, abs=1e-12)
    assert parse_spec("terrain.xt", "0.6:1.0:9")[2] == 0.7          # linspace noise rounded away
    ints = parse_spec("tow.force_N", "0:200:3")
    assert ints == (0, 100, 200) and all(isinstance(x, int) for x in ints)
    assert parse_spec("terrain.xt", "0.5:0.5:1") == (0.5,)


def test_grid_and_zip_cases():
    axes = [parse_sweep_option("terrain.xt=0.6:1.0:9"), parse_sweep_option("tow.force_N=0,100,200")]
    grid = build_cases(axes)
    assert len(grid) == 27
    assert grid[0].values == (0.6, 0) and grid[1].values == (0.6, 100) and grid[-1].values == (1.0, 200)
    assert len({c.key for c in grid}) == 27 and [c.case_id for c in grid][:2] == ["0000", "0001"]
    # stable keys: same values give the same key whatever else is in the sweep
    again = build_cases([parse_sweep_option("terrain.xt=0.6,1.0"), parse_sweep_option("tow.force_N=0,100,200")])
    assert again[0].key == grid[0].key
    zipped = build_cases([parse_sweep_option("terrain.xt=0.6,0.7"), parse_sweep_option("tow.force_N=0,100")], zip_=True)
    assert [c.values for c in zipped] == [(0.6, 0), (0.7, 100)]


@pytest.mark.parametrize("sets, needle", [
    (["terrain.xt=0.3:1.0"], "START:STOP:COUNT"),
    (["terrain.xt=0.3:1.0:0"], "COUNT must be at least 1"),
    (["terrain.xt=0.3:1.0:x"], "COUNT must be a whole number"),
    (["terrain.xt=a:b:3"], "START and STOP must be numbers"),
    (["terrain.xt=0,,1"], "empty item"),
    (["terrain.xt=0.5,0.5"], "appears twice"),
    (["terrain.xt"], "expected KEY=SPEC"),
    (["terrain.xt=0.5", "terrain.xt=0.6"], "more than once"),
    (["terrain.xtt=0.5,0.6"], "Did you mean 'xt'"),
    (["terrain.xt=0.5,0.6", "tow.force_N=1,2,3", "--zip"], "same number of values"),
])
def test_bad_spec_exits_2_with_a_clear_message(tmp_path, sets, needle):
    args = ["sweep", TOW6, "--out", str(tmp_path / "o")]
    for s in sets:
        args += ["--zip"] if s == "--zip" else ["--set", s]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2, r.output
    assert needle in r.output
    assert "Traceback" not in r.output
    assert not (tmp_path / "o" / "summary.csv").exists()


# ------------------------------------------------------------------ executors agree
def test_serial_and_two_processes_give_identical_rows(tmp_path):
    serial = run_sweep(TOW6, SMALL, out_dir=tmp_path / "s", plot=False)
    par = run_sweep(TOW6, SMALL, out_dir=tmp_path / "p", jobs=2, plot=False)
    assert len(serial) == 4 and all(r["status"] == "ok" for r in serial)
    assert _comparable(serial) == _comparable(par)
    # the files hold the same rows too (the CSV may be in completion order)
    a = sorted(_csv_rows(tmp_path / "s" / "summary.csv"), key=lambda r: r["case_id"])
    b = sorted(_csv_rows(tmp_path / "p" / "summary.csv"), key=lambda r: r["case_id"])
    for r in a + b:
        r.pop("wall_time_s")
    assert a == b
    # towing costs speed; fresher snow gives speed
    v = {(r["terrain.xt"], r["tow.force_N"]): r["mean_speed_mps"] for r in serial}
    assert v[(0.9, 200)] < v[(0.9, 0)] and v[(0.7, 0)] < v[(0.9, 0)]


def test_dask_cluster_gives_identical_rows(tmp_path):
    distributed = pytest.importorskip("distributed", reason="dask[distributed] not installed (pip install snoworm[dask])")
    serial = run_sweep(TOW6, SMALL, plot=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        table = run_sweep(TOW6, SMALL, out_dir=tmp_path / "d", scheduler=cluster.scheduler_address, plot=False)
    assert _comparable(table) == _comparable(serial)
    assert len(_csv_rows(tmp_path / "d" / "summary.csv")) == 4


def test_missing_dask_gives_an_install_hint(monkeypatch):
    monkeypatch.setitem(__import__("sys").modules, "distributed", None)
    with pytest.raises(ScenarioError, match=r"snoworm\[dask\]"):
        run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], scheduler="tcp://127.0.0.1:1", plot=False)


# ------------------------------------------------------------------ metrics
def test_case_metrics_match_a_direct_run():
    table = run_sweep(TOW6, ["terrain.xt=0.8", "tow.force_N=100", SHORT], plot=False)
    direct = case_metrics(simulate(load_scenario(TOW6, [("terrain.xt", 0.8), ("tow.force_N", 100),
                                                       ("simulation.duration_s", 6)])))
    row = table.rows[0]
    for k in ("distance_m", "mean_speed_mps", "late_speed_mps", "mean_slip", "max_slip", "max_link_force_N",
              "energy_per_m_J"):
        assert row[k] == pytest.approx(direct[k], rel=1e-12), k
    for j, f in enumerate(direct["final_link_forces_N"]):
        assert row[f"final_link_force_{j}_N"] == pytest.approx(f, rel=1e-12)
    # steady state after 6 s: link tensions close to 100 N * (j+1)/6 (force balance)
    assert row["final_link_force_4_N"] == pytest.approx(100 * 5 / 6, rel=0.05)
    assert row["immobilised"] is False and row["n_segments"] == 6


# ------------------------------------------------------------------ robustness
def test_a_failing_case_does_not_stop_the_others(tmp_path, monkeypatch):
    import sys
    simmod = sys.modules["snoworm.sweep"]        # the function the sweep's cases call
    real = simmod.simulate

    def flaky(sc):
        if sc.terrain.xt == 0.8:
            raise SolverError("forced failure for the test")
        return real(sc)

    monkeypatch.setattr(simmod, "simulate", flaky)
    table = run_sweep(TOW6, ["terrain.xt=-1,0.8,0.9", SHORT], out_dir=tmp_path, plot=False)
    st = {r["terrain.xt"]: r for r in table}
    assert st[-1]["status"] == "invalid" and "terrain.xt" in st[-1]["error"]
    assert st[0.8]["status"] == "solver_failure" and "forced failure" in st[0.8]["error"]
    assert st[0.9]["status"] == "ok" and st[0.9]["distance_m"] > 1.0
    assert st[-1]["distance_m"] is None and st[-1]["immobilised"] is None
    assert len(_csv_rows(tmp_path / "summary.csv")) == 3


def test_interrupted_sweep_resumes_without_recomputing(tmp_path, monkeypatch):
    sets = ["terrain.xt=0.7,0.8,0.9", "tow.force_N=0,200", SHORT]
    full = run_sweep(TOW6, sets, out_dir=tmp_path, plot=False)
    summary = tmp_path / "summary.csv"
    lines = summary.read_text().splitlines(keepends=True)
    assert len(lines) == 7
    # an interrupted sweep: header, two finished rows and half of the third
    summary.write_text("".join(lines[:3]) + lines[3][: len(lines[3]) // 2])
    kept = {next(csv.reader([ln]))[0] for ln in lines[1:3]}

    calls = []
    real = sweep_mod.run_case

    def counting(task):
        calls.append(task["index"])
        return real(task)

    monkeypatch.setattr(sweep_mod, "run_case", counting)
    resumed = run_sweep(TOW6, sets, out_dir=tmp_path, plot=False)
    assert len(calls) == 4                                   # 6 cases - 2 kept
    assert not {f"{i:04d}" for i in calls} & kept
    assert _comparable(resumed) == _comparable(full)
    rows = _csv_rows(summary)
    assert sorted(r["case_id"] for r in rows) == [f"{i:04d}" for i in range(6)]
    # complete now: a third run computes nothing
    calls.clear()
    run_sweep(TOW6, sets, out_dir=tmp_path, plot=False)
    assert calls == []


def test_another_sweep_in_the_same_directory_is_refused(tmp_path):
    run_sweep(TOW6, ["terrain.xt=0.8,0.9", SHORT], out_dir=tmp_path, plot=False)
    r = CliRunner().invoke(main, ["sweep", TOW6, "--set", "terrain.xt=0.7,0.9", "--set", SHORT,
                                  "--out", str(tmp_path)])
    assert r.exit_code == 2 and "holds another sweep" in r.output
    assert json.loads((tmp_path / "sweep.json").read_text())["definition"]["axes"][0]["values"] == [0.8, 0.9]


# ------------------------------------------------------------------ the documented trend
def test_rolling_speed_falls_with_xt_and_immobilised_below_0586():
    xts = [0.5, 0.55, 0.62, 0.7, 0.8, 0.9, 1.0]
    table = run_sweep(TOW6, [f"terrain.xt={','.join(map(str, xts))}", "tow.force_N=0", "vehicle.segments=1",
                             "simulation.duration_s=10"], plot=False)
    assert [r["terrain.xt"] for r in table] == xts
    speed = table["mean_speed_mps"]
    assert all(a < b for a, b in zip(speed, speed[1:]))
    imm = dict(zip(xts, table["immobilised"]))
    assert imm[0.5] and imm[0.55]
    assert not any(imm[x] for x in xts if x >= 0.62)
    late = dict(zip(xts, table["late_speed_mps"]))
    assert late[0.55] < 0.05 and late[0.62] > 0.5
    # free rolling on neve: slip ~2 % (MODEL.md section 2), the wheels near 1.8 m/s
    assert table.rows[-1]["mean_slip"] == pytest.approx(0.0213, abs=0.003)


# ------------------------------------------------------------------ CLI, files, progress
def test_cli_writes_summary_plot_and_cases(tmp_path):
    out = tmp_path / "o"
    r = CliRunner().invoke(main, ["sweep", TOW6, "--set", "terrain.xt=0.7,0.9", "--set", SHORT,
                                  "--out", str(out), "--save-cases"])
    assert r.exit_code == 0, r.output
    assert "2 cases: 2 ok" in r.output
    assert "sweep [" not in r.output                     # no progress bar when not a terminal
    assert (out / "sweep.png").stat().st_size > 1000
    s = json.loads((out / "cases" / "0001" / "summary.json").read_text())
    rows = sorted(_csv_rows(out / "summary.csv"), key=lambda r: r["case_id"])
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


def test_table_round_trips_through_csv(tmp_path):
    table = run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], out_dir=tmp_path, plot=False)
    back = sweep_mod.SweepTable.from_csv(tmp_path / "summary.csv")
    assert _comparable(back) == _comparable(table)
    assert table.to_csv().splitlines()[0].startswith("case_id,case_key,terrain.xt,simulation.duration_s,status")


def test_executor_failure_is_reported_and_rows_kept(tmp_path):
    class Dying:
        def map_unordered(self, fn, tasks):
            it = iter(tasks)
            yield fn(next(it))
            raise OSError("worker lost")

        def close(self):
            pass

    with pytest.raises(sweep_mod.SweepExecutionError, match="worker lost.*1 finished cases"):
        run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], out_dir=tmp_path, executor=Dying(), plot=False)
    assert len(_csv_rows(tmp_path / "summary.csv")) == 1
    assert len(run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], out_dir=tmp_path, plot=False)) == 2


def test_a_scenario_object_sweeps_like_its_file():
    from_file = run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], plot=False)
    from_obj = run_sweep(load_scenario(TOW6), ["terrain.xt=0.7,0.9", SHORT], plot=False)
    for a, b in zip(from_file, from_obj):
        assert b["distance_m"] == pytest.approx(a["distance_m"], rel=1e-9)
        assert b["case_key"] == a["case_key"]
