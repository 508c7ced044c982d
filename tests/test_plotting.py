"""Plots (snoworm.plotting): the standard figures of a run are written as PNG files."""
import pytest

from snoworm import load_scenario, simulate
from snoworm.plotting import plot_result
from tests.conftest import SCENARIOS

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("name, extra", [("tow6_uniform", []), ("pi3_equal", ["force_diagram.png"])])
def test_plot_result_writes_pngs(tmp_path, name, extra):
    res = simulate(load_scenario(SCENARIOS / f"{name}.yaml", ["simulation.duration_s=2"]))
    paths = plot_result(res, tmp_path / "plots")
    expected = ["forces.png", "speeds.png", "positions.png", *extra]
    assert [p.name for p in paths] == expected
    for p in paths:
        assert p.parent == tmp_path / "plots"
        data = p.read_bytes()
        assert data[:8] == PNG_MAGIC and len(data) > 10_000, p.name
    assert sorted(x.name for x in (tmp_path / "plots").iterdir()) == sorted(expected)   # no temporary files left
