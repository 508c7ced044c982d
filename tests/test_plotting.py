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
    assert sorted(x.name for x in (tmp_path / "plots").iterdir()) == sorted(expected)  # no temporary files left


def test_library_never_changes_the_backend(tmp_path):
    """A user's backend survives importing snoworm, writing a run with plots (headless: pyplot is
    not even imported) and Result.plot (a figure of pyplot's manager, so it can be shown)."""
    import subprocess
    import sys

    code = f"""
import sys, matplotlib
matplotlib.use("svg")
import snoworm
from snoworm import plotting
res = snoworm.simulate(snoworm.load_scenario({str(SCENARIOS / "tow6_uniform.yaml")!r}, ["simulation.duration_s=1"]))
res.write({str(tmp_path / "run")!r})
assert "matplotlib.pyplot" not in sys.modules            # files only: no pyplot, no window
fig = res.plot("forces")
import matplotlib.pyplot as plt
assert plt.fignum_exists(fig.number), "a figure drawn without ax/fig is pyplot's (plt.show() shows it)"
assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
with plotting.headless():
    bare = res.plot("speeds")
assert not hasattr(bare, "number") or not plt.fignum_exists(bare.number)
assert len(plt.get_fignums()) == 1
print("ok")
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
    assert (tmp_path / "run" / "speeds.png").exists()


def test_script_shows_the_figures_with_plt_show(tmp_path):
    """In a script, plt.show() shows what Result.plot drew: with the headless Agg backend, the
    figure manager holds it (show itself is a no-op there) and saving it from pyplot works."""
    import subprocess
    import sys

    code = f"""
import matplotlib
matplotlib.use("agg")
import matplotlib.pyplot as plt
import snoworm
res = snoworm.simulate(snoworm.load_scenario({str(SCENARIOS / "pi2_zero.yaml")!r}, ["simulation.duration_s=1"]))
fig = res.plot("positions", size="column")
assert plt.gcf() is fig
plt.savefig({str(tmp_path / "gcf.png")!r})
plt.show()
print("ok")
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "gcf.png").read_bytes()[:8] == PNG_MAGIC
