"""Mobility map (snoworm.mobility): which modes move the vehicle over X_t and tow (beyond the paper)."""
import numpy as np
import pytest
from click.testing import CliRunner

from snoworm import steady
from snoworm.cli import main
from snoworm.mobility import mobility_map
from snoworm.scenario import load_scenario


def test_map_rolling_boundary_matches_steady_limit(scenario_path):
    sc = load_scenario(scenario_path("traverse_patch"))
    xts = np.linspace(0.2, 1.0, 33)                     # grid step 0.025
    dx = xts[1] - xts[0]
    m = mobility_map(sc, xts, [0.0, 200.0], wheel_speed_mps=1.8, inching=False)
    for tow, expected in ((0.0, 0.586), (200.0, m["rolling_limit_xt"][200.0])):
        roll = [r["xt"] for r in m["rows"] if r["tow_N"] == tow and r["rolling"]]
        first = min(roll)
        assert first - dx < expected <= first + 1e-12              # boundary within one grid step
        assert all(x >= first for x in roll) and len(roll) == sum(xts >= first - 1e-12)   # one boundary
    # docs/model.md section 2: 0.586 without tow; a 200 N tow (33 N per segment) raises it
    assert m["rolling_limit_xt"][0.0] == pytest.approx(0.586, abs=5e-4)
    seg = sc.vehicle.segment_params()[0]
    assert m["rolling_limit_xt"][200.0] == pytest.approx(
        steady.immobilisation_limit_xt(seg, sc.chain_model.tp, drawbar_N=200.0 / 6, wheel_speed_mps=1.8), abs=1e-9)
    assert m["rolling_limit_xt"][200.0] > m["rolling_limit_xt"][0.0] + 0.01


def test_cli_mobility_map_regions(scenario_path, tmp_path):
    r = CliRunner().invoke(main, ["mobility-map", str(scenario_path("traverse_patch")), "--xt", "0.3,0.9",
                                  "--tow", "0", "--inch-duration", "4", "--out", str(tmp_path)])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "mobility_map.png").stat().st_size > 10000
    lines = (tmp_path / "mobility_map.csv").read_text().splitlines()
    rows = [dict(zip(lines[0].split(","), ln.split(","))) for ln in lines[1:]]
    assert [(float(x["xt"]), x["region"]) for x in rows] == [(0.3, "inching only"), (0.9, "rolling")]
    assert float(rows[0]["inching_speed_mps"]) > 0.02
    assert float(rows[1]["rolling_speed_mps"]) == pytest.approx(1.8 * (1 - 0.039), abs=0.01)   # slip 3.9 %


def test_cli_mobility_map_bad_grid(scenario_path, tmp_path):
    r = CliRunner().invoke(main, ["mobility-map", str(scenario_path("traverse_patch")), "--xt", "0.2:1.0",
                                  "--out", str(tmp_path)])
    assert r.exit_code == 2 and "START:STOP:COUNT" in r.output


def test_progress_counts_the_inching_runs(scenario_path):
    sc = load_scenario(scenario_path("traverse_patch"))
    seen = []
    m = mobility_map(sc, [0.3, 0.9], [0.0], wheel_speed_mps=1.8, inch_duration_s=1.0,
                     progress=lambda n, total: seen.append((n, total)))
    assert seen == [(1, 2), (2, 2)] and len(m["rows"]) == 2


def test_cli_mobility_map_replaces_its_folder_and_refuses_a_foreign_one(scenario_path, tmp_path):
    out = tmp_path / "m"
    args = ["mobility-map", str(scenario_path("traverse_patch")), "--xt", "0.9", "--no-inching", "--out", str(out)]
    assert CliRunner().invoke(main, args).exit_code == 0
    assert CliRunner().invoke(main, args + ["--no-plot"]).exit_code == 0
    assert sorted(p.name for p in out.iterdir()) == [".snoworm-manifest.json", "mobility_map.csv"]
    (out / "mine.txt").write_text("x")
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2 and "--overwrite" in r.output
