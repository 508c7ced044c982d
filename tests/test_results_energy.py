"""Energy of a run (snoworm.results.energy): energy balance and energy metrics.

The balance: motor work + joint work - dissipation - tow work = change of kinetic + spring energy.
"""

import pytest

from snoworm import load_scenario, simulate
from snoworm.results.energy import energy_balance, energy_metrics


def test_energy_balance(scenario_path):
    """Motor work - dissipation - tow work = change of kinetic + spring energy (within 0.5 % of motor work)."""
    sc = load_scenario(
        scenario_path("tow6_staggered"),
        ["simulation.output_dt_s=0.002", "simulation.rtol=1e-7", "simulation.duration_s=10"],
    )
    res = simulate(sc)
    b = energy_balance(res)  # fixed links: throughput = |motor work| (no joint power)
    assert b["joint_J"] == 0.0
    assert b["throughput_J"] > 1e4
    assert abs(b["residual_J"]) < 5e-3 * b["throughput_J"]


def test_energy_balance_rolling(stuck):
    """Rolling into the patch and spinning there: residual below 0.5 % of the motor work.

    Tolerance: the wheel kinetic energy uses the mean of the two axles' speeds (they differ while
    a segment straddles the patch edge) and the trapezoidal rule on 10 ms output samples.
    """
    b = energy_balance(stuck)
    assert b["motor_J"] > 5e4
    assert abs(b["residual_J"]) < 5e-3 * b["throughput_J"]


def test_energy_balance_inching(scenario_path):
    """Inching on X_t = 0.25 (paper Fig 5): motor + joint work = dissipation + stored, within 0.5 %."""
    sc = load_scenario(scenario_path("inchworm6"), ["simulation.duration_s=5", "simulation.output_dt_s=0.005"])
    res = simulate(sc)
    b = energy_balance(res)
    assert b["joint_J"] > 300 and b["motor_J"] > 300  # both sources matter
    assert abs(b["residual_J"]) < 5e-3 * b["throughput_J"]
    e = energy_metrics(res)
    assert e["joint_electrical_total_J"] == pytest.approx(sum(e["joint_mechanical_J"]) / 0.7, rel=1e-12)


def test_energy_along_ends_at_the_metrics_totals(scenario_path):
    """The cumulative energy (trapezoids summed step by step) ends at energy_metrics' totals (the
    same trapezoids summed by numpy: equal to rounding, 1e-9 relative), never decreases, starts at 0."""
    import numpy as np

    from snoworm.results.energy import energy_along

    res = simulate(load_scenario(scenario_path("inchworm2"), ["simulation.duration_s=4"]))
    e, m = energy_along(res), energy_metrics(res)
    assert e["total_electrical_J"][0] == 0.0 and np.all(np.diff(e["total_electrical_J"]) >= 0)
    assert e["motor_electrical_J"][-1] == pytest.approx(m["motor_electrical_total_J"], rel=1e-9)
    assert e["joint_electrical_J"][-1] == pytest.approx(m["joint_electrical_total_J"], rel=1e-9)
    assert m["joint_electrical_total_J"] > 0  # inching: the joints do work
    assert e["distance_m"][-1] == pytest.approx(m["distance_m"], rel=1e-12)
