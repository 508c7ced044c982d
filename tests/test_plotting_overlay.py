"""Several runs on one figure (snoworm.plotting.overlay: snoworm.plotting.compare)."""

import numpy as np
import pytest

from snoworm import load_scenario, simulate
from snoworm.plotting import COMPARE_KINDS, FIGURE_SIZES, compare, headless
from tests.conftest import SCENARIOS
from tests.figure_checks import problems


@pytest.fixture(scope="module")
def runs():
    a = simulate(load_scenario(SCENARIOS / "pi3_equal.yaml", ["simulation.duration_s=2"]))
    b = simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml", ["simulation.duration_s=2"]))
    return a, b


@pytest.mark.parametrize("kind", sorted(COMPARE_KINDS))
def test_one_curve_per_run_readable_at_column_width(runs, kind):
    with headless():
        fig = compare(runs, kind, size="column")
    a = fig.axes[0]
    assert [ln.get_label() for ln in a.get_lines()] == ["pi3_equal", "tow6_uniform"]
    assert problems(fig, FIGURE_SIZES["column"]) == []


def test_values_are_the_runs_own(runs):
    fig = compare(runs, "speeds", labels=["A", "B"])
    la, lb = fig.axes[0].get_lines()
    np.testing.assert_allclose(la.get_ydata(), runs[0].segments["v_mps"].mean(1), rtol=0, atol=0)
    assert lb.get_label() == "B"


def test_bad_arguments_say_what_to_do(runs):
    with pytest.raises(ValueError, match="kinds: speeds"):
        compare(runs, "colour")
    with pytest.raises(ValueError, match="one per result"):
        compare(runs, labels=["only one"])
