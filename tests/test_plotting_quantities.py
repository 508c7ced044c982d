"""Slip, motor torque and power, energy along the run (snoworm.plotting.quantities)."""

import numpy as np
import pytest
from matplotlib.figure import Figure

from snoworm import load_scenario, simulate
from snoworm.plotting import FIGURE_SIZES, headless
from tests.conftest import SCENARIOS
from tests.figure_checks import problems


@pytest.fixture(scope="module")
def three():
    return simulate(load_scenario(SCENARIOS / "pi3_equal.yaml", ["simulation.duration_s=2"]))


@pytest.fixture(scope="module")
def inch():
    return simulate(load_scenario(SCENARIOS / "inchworm6.yaml", ["simulation.duration_s=4"]))


def test_slip_lines_with_a_dimensionless_unit(three):
    fig = three.plot("slip")
    a = fig.axes[0]
    assert a.get_ylabel() == "slip [-]"
    lines = [ln for ln in a.get_lines() if not ln.get_label().startswith("_")]
    assert len(lines) == 3
    np.testing.assert_array_equal(lines[1].get_ydata(), three.segments["slip"][:, 1])


def test_a_gait_is_drawn_as_charts(inch):
    fig = inch.plot("motor")
    meshes = [
        c
        for a in fig.axes
        if a.get_ylabel().startswith("segment")
        for c in a.collections
        if c.__class__.__name__ == "QuadMesh"
    ]
    assert len(meshes) == 2  # torque and power, a row per segment
    np.testing.assert_array_equal(np.asarray(meshes[0].get_array()).reshape(6, -1), inch.segments["motor_torque_Nm"].T)


def test_energy_curves_end_at_the_summary(inch):
    fig = inch.plot("energy")
    a_dist, a_time = fig.axes[:2]
    total = {ln.get_label(): ln.get_ydata()[-1] for ln in a_time.get_lines()}
    e = inch.energy()
    assert total["total"] == pytest.approx(e["total_J"] / 1e3, rel=1e-9)
    assert total["joints"] == pytest.approx(sum(e["joint_electrical_J"]) / 1e3, rel=1e-9)
    assert a_dist.get_xlabel() == "distance [m]"


@pytest.mark.parametrize("kind", ["slip", "motor", "energy"])
def test_readable_at_column_width(three, inch, kind):
    with headless():
        for res in (three, inch):
            fig = res.plot(kind, size="column")
            assert problems(fig, FIGURE_SIZES["column"]) == []


def test_on_the_users_axes(three):
    user = Figure()
    axes = user.subplots(2, 1)
    assert three.plot("motor", ax=axes) is user
    assert len(axes[0].get_lines()) == 3
