"""The one stepper of one chain or many (snoworm.simulation.stepper, issue 31 seam 2)."""

import ast
from pathlib import Path

import numpy as np
import pytest

import snoworm
from snoworm import load_scenario
from snoworm.dynamics import Controls
from snoworm.simulation.guard import SolverError
from snoworm.simulation.interval import IntervalSolver, output_grid
from snoworm.simulation.stepper import PERIODS, WHOLE_RUNS, ChainStepper, stack_size

PKG = Path(snoworm.__file__).parent


def _tow6(**ov):
    sc = load_scenario("tow6_uniform", [("simulation.method", "VODE"), *ov.items()])
    from snoworm.simulation.driver import assemble

    case = assemble(sc)
    return sc, case.model, case.mode.initial_state()


def test_one_member_steps_as_the_interval_solver_does():
    """B = 1 is the Simulator's and the single environment's stepper: the same numbers as the
    driver's interval solve of the same period (same solver, same options)."""
    sc, m, y0 = _tow6()
    ctl = Controls.rolling(m.n, np.ones(m.n), np.full(m.n, 1.5))
    t_eval = output_grid(0.0, 0.5, sc.simulation.output_dt_s, include_start=True)
    st = ChainStepper(m, sc.simulation, 1)
    ys, y_end, failed, errors = st.solve(ctl, 0.0, 0.5, y0[None, :], t_eval)
    ref = IntervalSolver(m, sc.simulation, "step", asked_steps=True)
    ts, yr, t_next, yr_end, _ = ref.solve(ctl, 0.0, 0.5, y0, (), t_eval, "step")
    assert not failed.any() and errors == {}
    np.testing.assert_array_equal(ys[:, 0, :], yr)
    np.testing.assert_array_equal(y_end[0], yr_end)
    assert st.stats["nfev"] == ref.stats["nfev"]


def test_members_go_in_bounded_stacks_and_each_steps_as_alone_within_tolerance():
    sc, m, y0 = _tow6()
    B = stack_size(m) + 3
    st = ChainStepper(m, sc.simulation, B)
    sizes = [s.stop - s.start for s, _ in st.stacks]
    assert sum(sizes) == B and max(sizes) - min(sizes) <= 1 and max(sizes) <= stack_size(m)
    speeds = np.linspace(0.5, 2.0, B)
    ctl = Controls.stack([Controls.rolling(m.n, np.ones(m.n), np.full(m.n, v)) for v in speeds])
    t_eval = output_grid(0.0, 0.5, sc.simulation.output_dt_s, include_start=True)
    ys, _, failed, _ = st.solve(ctl, 0.0, 0.5, np.tile(y0, (B, 1)), t_eval)
    assert not failed.any()
    for b in (0, B - 1):
        alone, _, _, _ = ChainStepper(m, sc.simulation, 1).solve(
            Controls.rolling(m.n, np.ones(m.n), np.full(m.n, speeds[b])), 0.0, 0.5, y0[None, :], t_eval
        )
        v, v_alone = m.unpack(ys[-1, b])[:, m.layout.v], m.unpack(alone[-1, 0])[:, m.layout.v]
        np.testing.assert_allclose(v, v_alone, rtol=0, atol=1e-3)  # VODE at rtol 1e-5 on a 1.5 m/s scale


def test_a_member_that_leaves_the_physics_fails_alone_and_the_others_go_on():
    sc, m, y0 = _tow6()
    B = 3
    st = ChainStepper(m, sc.simulation, B)
    y = np.tile(y0, (B, 1))
    y[1, m.layout.flat_index(0, "v_mps")] = np.nan  # member 1 starts out of the physics
    ctl = Controls.stack([Controls.rolling(m.n, np.ones(m.n), np.full(m.n, 1.5))] * B)
    t_eval = output_grid(0.0, 0.2, sc.simulation.output_dt_s, include_start=True)
    ys, y_end, failed, errors = st.solve(ctl, 0.0, 0.2, y, t_eval)
    assert failed.tolist() == [False, True, False] and set(errors) == {1}
    assert np.all(np.isfinite(ys[:, [0, 2]])) and np.array_equal(y_end[1], y[1], equal_nan=True)
    assert st.stats["member_solves"] == B and st.stats["solver_failures"] == 1


def test_the_environments_and_the_simulator_have_no_stepper_of_their_own():
    """The vector environment, the single one (through the Simulator) and the Simulator step with
    ChainStepper: none of them builds an interval solve or checks states itself."""
    for rel in ("env/vector.py", "env/single.py", "env/core.py", "simulation/stepwise.py"):
        tree = ast.parse((PKG / rel).read_text())
        names = {a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names}
        assert not names & {"IntervalSolver", "SPEED_SANITY_FACTOR", "ChainModel"}, rel


def test_member_chains_stack_as_given_and_a_failed_stack_is_the_callers_under_whole_runs():
    """of_members: B different chains of one structure (a batched sweep's cases) in one stack under
    WHOLE_RUNS, each member within the batched path's accuracy of its chain alone (LSODA's max
    norm: 1e-3 m/s on a 1.5 m/s scale); a failed stack raises (the caller reruns the members), where
    PERIODS solves the bad member alone and the others go on."""
    cases = [_tow6(**{"tow.force_N": f, "simulation.method": "LSODA"}) for f in (0.0, 150.0, 300.0)]
    sc, models, y0 = cases[0][0], [m for _, m, _ in cases], np.stack([y for _, _, y in cases])
    st = ChainStepper.of_members(models, sc.simulation, "batch", policy=WHOLE_RUNS, asked_steps=False)
    assert [(s.start, s.stop, m.n_batch) for s, m in st.stacks] == [(0, 3, 3)]
    np.testing.assert_array_equal(st.stacks[0][1].tow_force_N, [0.0, 150.0, 300.0])
    n = models[0].n
    ctl = Controls.rolling(n, np.ones(n), np.full(n, 1.5))
    t_eval = output_grid(0.0, 0.5, sc.simulation.output_dt_s, include_start=True)
    ys, _, failed, errors = st.solve(Controls.stack([ctl] * 3), 0.0, 0.5, y0, t_eval)
    assert not failed.any() and errors == {} and "member_solves" not in st.stats
    for b, m in enumerate(models):
        alone = IntervalSolver(m, sc.simulation, "alone").solve(ctl, 0.0, 0.5, y0[b], (), t_eval)[1]
        v, v_alone = m.unpack(ys[-1, b])[:, m.layout.v], m.unpack(alone[-1])[:, m.layout.v]
        np.testing.assert_allclose(v, v_alone, rtol=0, atol=1e-3)
    y_bad = y0.copy()
    y_bad[1, models[1].layout.flat_index(0, "v_mps")] = np.nan
    stack = Controls.stack([ctl] * 3)
    with pytest.raises(SolverError):
        ChainStepper.of_members(models, sc.simulation, "batch", policy=WHOLE_RUNS).solve(
            stack, 0.0, 0.2, y_bad, t_eval[:5]
        )
    per = ChainStepper.of_members(models, sc.simulation, "env", policy=PERIODS)
    _, _, failed, errors = per.solve(stack, 0.0, 0.2, y_bad, output_grid(0.0, 0.2, sc.simulation.output_dt_s, True))
    assert failed.tolist() == [False, True, False] and set(errors) == {1}
