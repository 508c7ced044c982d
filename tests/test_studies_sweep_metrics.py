"""snoworm.studies.sweep.metrics: per-case metrics, statuses and failure handling."""

from __future__ import annotations

import numpy as np
import pytest

from snoworm import SolverError, simulate
from snoworm.config.scenario import load_scenario, read_yaml
from snoworm.studies.sweep import SweepTask, case_metrics, run_case, run_sweep
from tests.sweep_helpers import SHORT, TOW6, csv_rows


def test_case_metrics_match_a_direct_run():
    table = run_sweep(TOW6, ["terrain.xt=0.8", "tow.force_N=100", SHORT], plot=False)
    direct = case_metrics(
        simulate(load_scenario(TOW6, [("terrain.xt", 0.8), ("tow.force_N", 100), ("simulation.duration_s", 6)]))
    )
    row = table.rows[0]
    for k in (
        "distance_m",
        "mean_speed_mps",
        "late_speed_mps",
        "mean_slip",
        "max_slip",
        "max_link_force_N",
        "energy_per_m_J",
    ):
        assert row[k] == pytest.approx(direct[k], rel=1e-12), k
    for j, f in enumerate(direct["final_link_forces_N"]):
        assert row[f"final_link_force_{j}_N"] == pytest.approx(f, rel=1e-12)
    # steady state after 6 s: link tensions close to 100 N * (j+1)/6 (force balance)
    assert row["final_link_force_4_N"] == pytest.approx(100 * 5 / 6, rel=0.05)
    assert row["immobilised"] is False and row["n_segments"] == 6


def test_a_failing_case_does_not_stop_the_others(tmp_path, monkeypatch):
    import sys

    simmod = sys.modules["snoworm.studies.sweep.metrics"]  # where run_case looks simulate up
    real = simmod.simulate

    def flaky(sc, allow_code=()):
        if sc.terrain.xt == 0.8:
            raise SolverError("forced failure for the test")
        return real(sc, allow_code=allow_code)

    monkeypatch.setattr(simmod, "simulate", flaky)
    table = run_sweep(TOW6, ["terrain.xt=-1,0.8,0.9", SHORT], out_dir=tmp_path, plot=False)
    st = {r["terrain.xt"]: r for r in table}
    assert st[-1]["status"] == "invalid" and "terrain.xt" in st[-1]["error"]
    assert st[0.8]["status"] == "solver_failure" and "forced failure" in st[0.8]["error"]
    assert st[0.9]["status"] == "ok" and st[0.9]["distance_m"] > 1.0
    assert st[-1]["distance_m"] is None and st[-1]["immobilised"] is None
    assert len(csv_rows(tmp_path / "summary.csv")) == 3


def test_rolling_speed_falls_with_xt_and_immobilised_below_0586():
    xts = [0.5, 0.55, 0.62, 0.7, 0.8, 0.9, 1.0]
    table = run_sweep(
        TOW6,
        [f"terrain.xt={','.join(map(str, xts))}", "tow.force_N=0", "vehicle.segments=1", "simulation.duration_s=10"],
        plot=False,
    )
    assert [r["terrain.xt"] for r in table] == xts
    speed = table["mean_speed_mps"]
    assert all(a < b for a, b in zip(speed, speed[1:]))
    imm = dict(zip(xts, table["immobilised"]))
    assert imm[0.5] and imm[0.55]
    assert not any(imm[x] for x in xts if x >= 0.62)
    # the columns are the run's verdict (the test of snoworm run and summary.json)
    verdicts = dict(zip(xts, table["verdict"]))
    assert all(verdicts[x] == ("immobilised" if imm[x] else "moving") for x in xts)
    at = dict(zip(xts, table["immobilised_at_m"]))
    assert all((at[x] is None) == (not imm[x]) for x in xts)
    direct = simulate(
        load_scenario(TOW6, ["terrain.xt=0.55", "tow.force_N=0", "vehicle.segments=1", "simulation.duration_s=10"])
    )
    assert at[0.55] == pytest.approx(direct.verdict().x_m, rel=1e-12)
    assert at[0.55] == pytest.approx(direct.segments["x_m"][int(np.searchsorted(direct.t, direct.verdict().t_s)), 0])
    late = dict(zip(xts, table["late_speed_mps"]))
    assert late[0.55] < 0.05 and late[0.62] > 0.5
    # free rolling on neve: slip ~2 % (docs/model.md section 2), the wheels near 1.8 m/s
    assert table.rows[-1]["mean_slip"] == pytest.approx(0.0213, abs=0.003)


def test_run_case_reports_each_status_without_raising(monkeypatch):
    raw = read_yaml(TOW6)
    raw["simulation"]["duration_s"] = 1
    ok = run_case(SweepTask(3, raw=raw))
    assert ok["index"] == 3 and ok["status"] == "ok" and ok["error"] == "" and ok["wall_time_s"] > 0
    bad = run_case(SweepTask(4, raw={**raw, "terrain": {"xt": -1}}))
    assert bad["status"] == "invalid" and "terrain.xt" in bad["error"] and "distance_m" not in bad

    def buggy(sc, allow_code=()):
        raise ZeroDivisionError("line one\nline two")

    monkeypatch.setattr("snoworm.studies.sweep.metrics.simulate", buggy)
    err = run_case(SweepTask(5, raw=raw))
    assert err["status"] == "error"
    assert err["error"].startswith("ZeroDivisionError: line one | line two at test_studies_sweep_metrics.py:")


@pytest.mark.parametrize("signal_name", ["KeyboardInterrupt", "Terminated"])
def test_an_interrupt_inside_c_code_stops_the_sweep_instead_of_recording_an_error(monkeypatch, signal_name):
    """Hostile battery (benchmarks/hostile.py): a second Ctrl-C landing in NumPy's C code came back as
    'SystemError: <method 'tolist' ...> returned a result with an exception set', which run_case
    recorded as the case's error (kept by the resume) instead of stopping the sweep."""
    from snoworm.commands.common import Terminated

    kind = {"KeyboardInterrupt": KeyboardInterrupt, "Terminated": Terminated}[signal_name]
    raw = read_yaml(TOW6)

    def interrupted(sc, allow_code=()):
        try:
            raise kind()
        except KeyboardInterrupt as interrupt:
            raise SystemError("<method 'tolist'> returned a result with an exception set") from interrupt

    monkeypatch.setattr("snoworm.studies.sweep.metrics.simulate", interrupted)
    with pytest.raises(kind):
        run_case(SweepTask(0, raw=raw))
