"""Mobility map (snoworm.studies.mobility): which modes move the vehicle over X_t and tow (beyond the paper);
its inching cells: the scenario of a cell, gait labels, and the bisection of the runs over the grades."""

import math

import numpy as np
import pytest
from click.testing import CliRunner

from snoworm import steady
from snoworm.cli import main
from snoworm.config.scenario import load_scenario, scenario_from_dict
from snoworm.config.schema import ScenarioError
from snoworm.simulation.driver import chain_model
from snoworm.studies import mobility
from snoworm.studies.mobility import InchingRuns, gait_label, inch_cells, inching_scenario, mobility_map
from tests.conftest import SCENARIOS


def test_map_rolling_boundary_matches_steady_limit(scenario_path):
    sc = load_scenario(scenario_path("traverse_patch"))
    xts = np.linspace(0.2, 1.0, 33)  # grid step 0.025
    dx = xts[1] - xts[0]
    m = mobility_map(sc, xts, [0.0, 200.0], wheel_speed_mps=1.8, inching=False)
    for tow, expected in ((0.0, 0.586), (200.0, m["rolling_limit_xt"][200.0])):
        roll = [r["xt"] for r in m["rows"] if r["tow_N"] == tow and r["rolling"]]
        first = min(roll)
        assert first - dx < expected <= first + 1e-12  # boundary within one grid step
        assert all(x >= first for x in roll) and len(roll) == sum(xts >= first - 1e-12)  # one boundary
    # docs/model.md section 2: 0.586 without tow; a 200 N tow (33 N per segment) raises it
    assert m["rolling_limit_xt"][0.0] == pytest.approx(0.586, abs=5e-4)
    seg = sc.vehicle.segment_params()[0]
    assert m["rolling_limit_xt"][200.0] == pytest.approx(
        steady.immobilisation_limit_xt(seg, chain_model(sc).tp, drawbar_N=200.0 / 6, wheel_speed_mps=1.8), abs=1e-9
    )
    assert m["rolling_limit_xt"][200.0] > m["rolling_limit_xt"][0.0] + 0.01


def test_cli_mobility_map_regions(scenario_path, tmp_path):
    r = CliRunner().invoke(
        main,
        [
            "mobility-map",
            str(scenario_path("traverse_patch")),
            "--xt",
            "0.3,0.9",
            "--tow",
            "0",
            "--inch-duration",
            "4",
            "--out",
            str(tmp_path),
        ],
    )
    assert r.exit_code == 0, r.output
    assert (tmp_path / "mobility_map.png").stat().st_size > 10000
    lines = (tmp_path / "mobility_map.csv").read_text().splitlines()
    rows = [dict(zip(lines[0].split(","), ln.split(","))) for ln in lines[1:]]
    assert [(float(x["xt"]), x["region"]) for x in rows] == [(0.3, "inching only"), (0.9, "rolling")]
    assert float(rows[0]["inching_speed_mps"]) > 0.02
    assert float(rows[1]["rolling_speed_mps"]) == pytest.approx(1.8 * (1 - 0.039), abs=0.01)  # slip 3.9 %


def test_cli_mobility_map_bad_grid(scenario_path, tmp_path):
    r = CliRunner().invoke(
        main, ["mobility-map", str(scenario_path("traverse_patch")), "--xt", "0.2:1.0", "--out", str(tmp_path)]
    )
    assert r.exit_code == 2 and "START:STOP:COUNT" in r.output


def test_progress_counts_the_inching_runs(scenario_path):
    sc = load_scenario(scenario_path("traverse_patch"))
    seen = []
    m = mobility_map(
        sc,
        [0.3, 0.9],
        [0.0],
        wheel_speed_mps=1.8,
        inch_duration_s=1.0,
        every_cell=True,
        progress=lambda n, total: seen.append((n, total)),
    )
    assert seen == [(1, 2), (2, 2)] and len(m["rows"]) == 2
    seen.clear()  # default: the rolling cell is not run
    m = mobility_map(
        sc,
        [0.3, 0.9],
        [0.0],
        wheel_speed_mps=1.8,
        inch_duration_s=1.0,
        progress=lambda n, total: seen.append((n, total)),
    )
    assert seen == [(1, 1)] and [r["rolling"] for r in m["rows"]] == [False, True]


def test_cli_mobility_map_replaces_its_folder_and_refuses_a_foreign_one(scenario_path, tmp_path):
    out = tmp_path / "m"
    args = ["mobility-map", str(scenario_path("traverse_patch")), "--xt", "0.9", "--no-inching", "--out", str(out)]
    assert CliRunner().invoke(main, args).exit_code == 0
    assert CliRunner().invoke(main, args + ["--no-plot"]).exit_code == 0
    assert sorted(p.name for p in out.iterdir()) == [".snoworm-manifest.json", "mobility_map.csv"]
    (out / "mine.txt").write_text("x")
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2 and "--overwrite" in r.output


def _cells(m):
    return {(round(r["xt"], 9), r["tow_N"]): r for r in m["rows"]}


@pytest.mark.slow
def test_default_map_equals_the_every_cell_map_on_the_issue_grid(scenario_path):
    """Skipping the inching runs of rolling cells leaves every region and every computed number
    as the full computation has them (the grid of issue 16 and docs/beyond.md)."""
    sc = load_scenario(scenario_path("traverse_patch"))
    xts, tows = np.linspace(0.2, 1.0, 9), [0.0, 100.0, 200.0]
    full = _cells(mobility_map(sc, xts, tows, wheel_speed_mps=1.8, jobs=2, every_cell=True))
    fast = _cells(mobility_map(sc, xts, tows, wheel_speed_mps=1.8, jobs=2))
    assert full.keys() == fast.keys() and len(full) == 27
    # all three regions on the grid: with a 100-200 N tow on X_t 0.2-0.4 the gait hangs after its first
    # phase (its run's verdict: immobilised), which a mean speed over the 8 s run (>= 0.02 m/s) hid
    assert {r["region"] for r in full.values()} == {"rolling", "inching only", "immobile"}
    assert full[(0.3, 100.0)]["region"] == "immobile" and full[(0.3, 0.0)]["region"] == "inching only"
    assert full[(0.3, 100.0)]["inching_note"].startswith("immobilised at x = ")
    skipped = 0
    for key, f in full.items():
        g = fast[key]
        assert g["region"] == f["region"], key
        assert g["rolling_speed_mps"] == f["rolling_speed_mps"]  # steady state: same code path
        if g["inching"] is None:  # skipped: only rolling cells
            assert f["rolling"] and g["inching_cheaper"] is None and g["inching_speed_mps"] is None
            skipped += 1
            continue
        assert g["inching"] == f["inching"] and g["inching_note"] == f["inching_note"]
        assert g["inching_speed_mps"] == pytest.approx(f["inching_speed_mps"], rel=1e-9, abs=0)
        energy = f["inching_energy_per_metre_J_per_m"]  # None where the gait does not move
        assert g["inching_energy_per_metre_J_per_m"] == (
            None if energy is None else pytest.approx(energy, rel=1e-9, abs=0)
        )
        assert g["inching_cheaper"] == f["inching_cheaper"]
    assert skipped == sum(r["rolling"] for r in full.values()) > 0
    # the full map still answers where inching is cheaper than rolling (docs/beyond.md): next to the limit
    assert full[(0.6, 0.0)]["inching_cheaper"] and not full[(1.0, 0.0)]["inching_cheaper"]


def test_order_of_the_runs_does_not_change_the_map(scenario_path):
    sc = load_scenario(scenario_path("traverse_patch"))
    kw = dict(wheel_speed_mps=1.8, inch_duration_s=1.0, every_cell=True)
    serial = mobility_map(sc, [0.3, 0.5, 0.9], [0.0], jobs=1, **kw)["rows"]
    pooled = mobility_map(sc, [0.3, 0.5, 0.9], [0.0], jobs=2, **kw)["rows"]  # started highest X_t first
    assert [r["xt"] for r in pooled] == [0.3, 0.5, 0.9]
    for a, b in zip(serial, pooled):
        assert a["inching_speed_mps"] == pytest.approx(b["inching_speed_mps"], rel=1e-12, abs=0)
        assert a["region"] == b["region"]


def test_cli_every_cell_simulates_the_rolling_cells_too(scenario_path, tmp_path):
    base = [
        "mobility-map",
        str(scenario_path("traverse_patch")),
        "--xt",
        "0.3,0.9",
        "--tow",
        "0",
        "--inch-duration",
        "2",
        "--no-plot",
    ]
    r = CliRunner().invoke(main, base + ["--out", str(tmp_path / "a")])
    assert r.exit_code == 0, r.output
    assert "--every-cell" in r.output
    rows = (tmp_path / "a" / "mobility_map.csv").read_text().splitlines()
    hdr = rows[0].split(",")
    rolling = dict(zip(hdr, rows[2].split(",")))
    assert rolling["region"] == "rolling" and rolling["inching"] == "" and rolling["inching_cheaper"] == ""
    r = CliRunner().invoke(main, base + ["--every-cell", "--out", str(tmp_path / "b")])
    assert r.exit_code == 0, r.output
    assert "--every-cell" not in r.output
    rows = (tmp_path / "b" / "mobility_map.csv").read_text().splitlines()
    rolling = dict(zip(hdr, rows[2].split(",")))
    assert (
        rolling["region"] == "rolling" and rolling["inching"] in ("0", "1") and rolling["inching_cheaper"] in ("0", "1")
    )


def test_grade_axis_bisection_equals_every_cell(scenario_path):
    """With a grade axis the inching runs are bisected over the grades (monotone in the grade): the
    regions equal those of simulating every cell, on a grid that has all three regions."""
    sc = load_scenario(scenario_path("traverse_patch"))
    kw = dict(wheel_speed_mps=1.8, grades=[0.0, 8.0, 16.0, 24.0], inch_duration_s=4.0, jobs=2)
    fast = mobility_map(sc, [0.4, 0.7], [0.0], **kw)
    full = mobility_map(sc, [0.4, 0.7], [0.0], every_cell=True, **kw)

    def region(m):
        return {(r["xt"], r["grade_deg"]): r["region"] for r in m["rows"]}

    assert region(fast) == region(full)
    assert set(region(full).values()) == {"rolling", "inching only", "immobile"}
    simulated = [r for r in fast["rows"] if r["inching_speed_mps"] is not None]
    assert len(simulated) < sum(not r["rolling"] for r in fast["rows"])  # the bisection saved runs
    assert all(
        r["inching_note"].startswith("not simulated")
        for r in fast["rows"]
        if r["inching"] is not None and r["inching_speed_mps"] is None
    )


def test_rolling_cells_on_a_grade_use_the_graded_steady_state(scenario_path):
    sc = load_scenario(scenario_path("traverse_patch"))
    m = mobility_map(sc, [0.8], [0.0], wheel_speed_mps=1.8, grades=[10.0, 20.0], inching=False)
    limit = m["rolling_max_grade_deg"][0.0][0.8]
    assert [r["rolling"] for r in m["rows"]] == [10.0 < limit, 20.0 < limit] == [True, False]
    g = m["gradeability"][0.0]
    assert g["rolling_grid_deg"] == [10.0]
    assert g["rolling_J_per_m_climbed"][0] == pytest.approx(
        m["rows"][0]["rolling_energy_per_metre_J_per_m"] / math.sin(math.radians(10.0))
    )


def test_cli_mobility_map_grade_axis(scenario_path, tmp_path):
    r = CliRunner().invoke(
        main,
        [
            "mobility-map",
            str(scenario_path("traverse_patch")),
            "--xt",
            "0.7,0.9",
            "--grade",
            "0:20:3",
            "--no-inching",
            "--out",
            str(tmp_path / "m"),
        ],
    )
    assert r.exit_code == 0, r.output
    header = (tmp_path / "m" / "mobility_map.csv").read_text().splitlines()[0].split(",")
    assert header[:4] == ["xt", "tow_N", "grade_deg", "region"]
    assert (tmp_path / "m" / "gradeability.png").stat().st_size > 10000
    bad = CliRunner().invoke(
        main,
        [
            "mobility-map",
            str(scenario_path("traverse_patch")),
            "--grade",
            "0:60:3",
            "--no-inching",
            "--out",
            str(tmp_path / "b"),
        ],
    )
    assert bad.exit_code == 2 and "--grade" in bad.output and "40" in bad.output


def test_several_gaits_one_curve_each(scenario_path):
    """Two gaits on a 2 x 2 grid: each gait's cells are its own runs; a cell inches when any gait
    moves the chain, reporting that gait; a bad gait is a one-line error before any run."""
    from snoworm.config.schema import ScenarioError
    from snoworm.studies.mobility import parse_gait

    sc = load_scenario(scenario_path("traverse_patch"))
    gaits = ["six_segment", parse_gait("[[0],[1],[2],[3],[4],[5]]")]
    m = mobility_map(sc, [0.4], [0.0], wheel_speed_mps=1.8, grades=[0.0, 8.0], inch_duration_s=4.0, gaits=gaits)
    assert m["gait_labels"] == ["six_segment", "[[0],[1],[2],[3],[4],[5]]"]
    for r in m["rows"]:
        moved = [lab for lab, c in r["inching_by_gait"].items() if c["inching"]]
        assert r["inching"] == bool(moved) and (r["inching_gait"] in moved if moved else r["inching_gait"] == "")
    curves = m["gradeability"][0.0]["inching"]
    assert set(curves) == set(m["gait_labels"])
    with pytest.raises(ScenarioError, match="--gait"):
        parse_gait("[[0], 1]")
    with pytest.raises(ScenarioError, match="gait"):
        mobility_map(sc, [0.4], [0.0], wheel_speed_mps=1.8, inch_duration_s=1.0, gaits=["no_such_gait"])


def test_a_map_over_the_sweep_bound_is_refused_before_any_work(scenario_path, tmp_path, monkeypatch):
    """Issue 30: the cell count (X_t x grades x tows) was not bounded; 100 000 X_t values ran ~40 min.
    Over the sweep's bound, exit 2 naming the options and the bound, with no cell computed and no folder."""
    from snoworm.config.schema import ScenarioError
    from snoworm.studies.sweep.spec import MAX_CASES

    def no_work(*args, **kwargs):
        raise AssertionError("a cell was computed")

    monkeypatch.setattr(mobility, "_rolling_rows", no_work)
    monkeypatch.setattr(mobility, "fill_inching", no_work)
    out = tmp_path / "map"
    args = ["mobility-map", str(scenario_path("traverse_patch")), "--out", str(out), "--no-plot"]
    r = CliRunner().invoke(main, args + ["--xt", f"0.2:1.0:{MAX_CASES // 2 + 1}", "--tow", "0,100"])
    assert r.exit_code == 2, r.output
    for words in ("--xt", "--grade", "--tow", f"{MAX_CASES + 2} cells", str(MAX_CASES)):
        assert words in r.output
    assert not out.exists()
    r = CliRunner().invoke(main, args + ["--xt", "0.2:1.0:400", "--grade", "0:10:300"])  # 120 000 cells
    assert r.exit_code == 2 and "120000 cells (400 X_t x 300 grades x 1 tows)" in r.output
    with pytest.raises(ScenarioError, match=f"over the {MAX_CASES} allowed"):
        mobility_map(load_scenario(scenario_path("traverse_patch")), [0.5] * 1001, [0.0] * 100, wheel_speed_mps=1.8)
    assert str(MAX_CASES) in CliRunner().invoke(main, ["mobility-map", "--help"]).output


# --------------------------------------------------------------------------------- inching cells
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

    def fake_run(raw):
        grade = raw["terrain"].get("grade_deg", 0.0)
        ran.append(grade)
        ok = grade <= 10.0
        return {
            "inching": ok,
            "inching_speed_mps": 0.1 if ok else 0.0,
            "inching_energy_per_metre_J_per_m": 50.0 if ok else None,
            "inching_note": "",
        }

    monkeypatch.setattr(mobility, "_inch_run", fake_run)
    sc = load_scenario(SCENARIOS / "inchworm6.yaml")
    grades = [0.0, 5.0, 10.0, 15.0, 20.0]
    rows = [{"xt": 0.5, "tow_N": 0.0, "grade_deg": g, "rolling": False} for g in grades]
    seen = []
    inch_cells(InchingRuns(sc, grades, False, 2.0), rows, progress=lambda d, t: seen.append((d, t)))
    assert len(ran) == 3 and seen[-1] == (3, 3)
    assert [r["inching"] for r in rows] == [True, True, True, False, False]
    inferred = [r for r in rows if r["inching_note"].startswith("not simulated")]
    assert len(inferred) == 2 and all(r["inching_speed_mps"] is None for r in inferred)
    # every_cell: every grade is run
    ran.clear()
    rows = [{"xt": 0.5, "tow_N": 0.0, "grade_deg": g, "rolling": g == 0.0} for g in grades]
    inch_cells(InchingRuns(sc, grades, True, 2.0), rows)
    assert sorted(ran) == grades and all(r["inching_note"] == "" for r in rows)


def test_an_inching_cell_moves_unless_its_verdict_is_immobilised():
    """The map's inching cells use the run's verdict (snoworm.results.verdict): on level X_t 0.6 the
    gait moves; on 24 deg it slides back, and the cell says where, when and why, as `snoworm run`
    would for the same run (its window the run's 8 s at most: the criteria's 5 s)."""
    from snoworm import simulate

    sc = load_scenario(SCENARIOS / "traverse_patch.yaml")
    for grade, moves in ((0.0, True), (24.0, False)):
        raw = inching_scenario(sc, 0.6, 0.0, 8.0, grade)
        cell = mobility._inch_run(raw)
        res = simulate(scenario_from_dict(raw))
        v = res.verdict()
        assert cell["inching"] is moves and (v.status != "immobilised") is moves
        assert cell["inching_note"] == ("" if moves else v.reason)
        centre = res.segments["x_m"].mean(axis=1)
        assert bool(centre[-1] - centre[0] > 0) is moves  # by hand: the gait advances, or slides back


def test_a_gait_that_hangs_after_its_first_phase_does_not_inch():
    """With a 100 N tow on X_t 0.3 the six-segment gait moves the chain 0.23 m in its first phase
    (by 3 s) and then hangs: a mean speed over the 8 s run (0.029 m/s, over the 0.02 m/s the map used to
    require) called the cell "inching only"; its run's verdict calls it immobilised."""
    from snoworm import simulate

    sc = load_scenario(SCENARIOS / "traverse_patch.yaml")
    raw = inching_scenario(sc, 0.3, 100.0, 8.0)
    res = simulate(scenario_from_dict(raw))
    t, centre = res.t, res.segments["x_m"].mean(axis=1)
    assert (centre[-1] - centre[0]) / (t[-1] - t[0]) > 0.02  # the old rule: moves
    assert abs(centre[-1] - np.interp(4.0, t, centre)) < 0.005  # by hand: nothing in the last 4 s
    cell = mobility._inch_run(raw)
    assert cell["inching"] is False and cell["inching_note"] == res.verdict().reason
    # a goal the scenario carries does not apply to a cell (uniform snow has no end): still immobile
    with_goal = load_scenario(SCENARIOS / "traverse_patch.yaml", ["simulation.goal_m=0.1"])
    assert res.segments["x_m"][-1, 0] > 0.1  # the leader passes it before the gait hangs
    assert mobility._inch_run(inching_scenario(with_goal, 0.3, 100.0, 8.0))["inching"] is False
