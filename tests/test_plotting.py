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


def test_library_never_changes_the_backend_nor_uses_pyplot(tmp_path):
    """A notebook user's backend survives importing snoworm, writing a run with plots and Result.plot."""
    import subprocess
    import sys
    code = f"""
import sys, matplotlib
matplotlib.use("svg")
import snoworm
from snoworm import plotting
res = snoworm.simulate(snoworm.load_scenario({str(SCENARIOS / 'tow6_uniform.yaml')!r}, ["simulation.duration_s=1"]))
res.write({str(tmp_path / 'run')!r})
fig = res.plot("forces")
assert type(fig).__name__ == "Figure", type(fig)
assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
assert "matplotlib.pyplot" not in sys.modules
print("ok")
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
    assert (tmp_path / "run" / "speeds.png").exists()
