"""The interval solve (snoworm.simulation.interval): one IntervalSolver per run owns the counters,
the options of each method and the VODE stepper; tolerances per field; the output grid."""

import numpy as np
import pytest

from snoworm import load_scenario
from snoworm.simulation.driver import assemble, chain_model
from snoworm.simulation.interval import IntervalSolver, output_grid
from snoworm.simulation.vode import VodeStepper


def test_atol_per_field_scales_only_the_named_fields(scenario_path):
    from snoworm.simulation.interval import ATOL, atol_per_field, solver_options

    sc = load_scenario(scenario_path("inchworm6"), [("simulation.atol_scale_fields", {"omega_rear": 7.0})])
    sim = sc.simulation
    got = atol_per_field(sim)
    scale = sim.atol_scale * np.array([sim.atol_scale_fields.get(k, 1.0) for k in ATOL])
    # the same products (in another order of multiplication: to rounding)
    np.testing.assert_allclose(list(got.values()), np.array(list(ATOL.values())) * scale, rtol=1e-15)
    assert got["omega_rear"] == pytest.approx(ATOL["omega_rear"] * sim.atol_scale * 7.0, rel=1e-15)
    assert got["omega_front"] == ATOL["omega_front"] * sim.atol_scale  # no factor: unchanged
    m = chain_model(sc)
    atol = solver_options(m, sim)["atol"]
    assert atol[m.layout.flat_index(3, "omega_rear")] == got["omega_rear"]
    assert atol[m.layout.flat_index(3, "s_m")] == got["s_m"]


def test_output_grid_is_the_multiples_of_dt_inside_and_the_ends():
    assert output_grid(0.0, 0.2, 0.05, True) == pytest.approx([0.0, 0.05, 0.1, 0.15, 0.2], abs=1e-15)
    assert output_grid(0.0, 0.2, 0.05, False) == pytest.approx([0.05, 0.1, 0.15, 0.2], abs=1e-15)
    g = output_grid(0.123, 0.31, 0.05, False)
    assert g[-1] == 0.31 and g[:-1] == [k * 0.05 for k in (3, 4, 5, 6)]
    assert output_grid(0.1, 0.1 + 1e-12, 0.05, False) == [0.1 + 1e-12]  # no multiple strictly inside
    assert isinstance(output_grid(0.0, 1.0, 0.1, True), list)  # walked by index, no arrays


@pytest.mark.parametrize("method", ["LSODA", "VODE"])
def test_one_solver_per_run_accumulates_its_work_and_finds_events(scenario_path, method):
    sc = load_scenario(scenario_path("tow6_uniform"), [("simulation.method", method)])
    case = assemble(sc)
    y = case.mode.initial_state()
    ctl = case.mode.interval(1.0, y).controls
    solver = IntervalSolver(case.model, sc.simulation, "test")
    ts, ys, t1, y1, which = solver.solve(ctl, 0.0, 0.5, y, (), output_grid(0.0, 0.5, 0.05, True))
    assert which is None and t1 == 0.5 and ts[-1] == 0.5 and ys.shape == (len(ts), y.size)
    first = dict(solver.stats)
    assert first["intervals"] == 1 and first["nfev"] > 0
    assert solver.options(method) is solver.options(method)  # built once per run

    def moved(t, yy):  # the leader reaches 2 m: a terminal event
        return yy[case.model.layout.flat_index(0, "x_m")] - 2.0

    moved.direction = 1
    ts, ys, t2, y2, which = solver.solve(ctl, t1, 5.0, y1, [moved], output_grid(t1, 5.0, 0.05, False))
    assert which == 0 and 0.5 < t2 < 5.0 and ts[-1] == t2
    assert y2[case.model.layout.flat_index(0, "x_m")] == pytest.approx(2.0, abs=1e-6)
    assert solver.stats["intervals"] == 2 and solver.stats["nfev"] > first["nfev"]


def test_carrying_vodes_history_skips_the_restart_where_the_last_interval_ended(scenario_path, monkeypatch):
    sc = load_scenario(scenario_path("tow6_uniform"), [("simulation.method", "VODE")])
    case = assemble(sc)
    y = case.mode.initial_state()
    ctl = case.mode.interval(1.0, y).controls
    restarts = []
    real = VodeStepper.restart
    monkeypatch.setattr(VodeStepper, "restart", lambda self, t, yy: restarts.append(t) or real(self, t, yy))
    for carry, expected in ((True, [0.0]), (False, [0.0, 0.1, 0.2])):
        restarts.clear()
        solver = IntervalSolver(case.model, sc.simulation, "test", carry_history=carry)
        t, yy = 0.0, y
        for _ in range(3):
            _, _, t, yy, _ = solver.solve(ctl, t, t + 0.1, yy, (), [t + 0.1])
        assert restarts == pytest.approx(expected)
