"""Issue 34: every figure of every command, at the default, column and page sizes, is readable:
nothing clipped (every text inside the figure), no two text boxes overlapping, text >= 7 pt, no
legend inside the axes covering data while a corner is free (tests/figure_checks.py).

The figures are caught as the commands save them (``Figure.savefig`` wrapped), so what is checked
is what the commands write.  Runs are short (a few simulated seconds); ``snoworm run``'s figures
are drawn by ``Result.write`` (what the command calls after simulating) from one run per scenario
at each size.
"""

import os
import re
from pathlib import Path

import pytest
from click.testing import CliRunner
from matplotlib.figure import Figure

from snoworm import load_scenario, simulate
from snoworm.cli import main
from snoworm.plotting import FIGURE_SIZES
from tests.figure_checks import legends_covering_data, problems

#: The print sizes checked; the default size is the page width (checked below), so "page" covers it.
SIZES = {"column": "column", "page": "page"}


@pytest.fixture
def caught(monkeypatch):
    """name of each figure saved -> its readability problems."""
    found = {}
    save = Figure.savefig

    def checked(fig, fname, *args, **kwargs):
        path = Path(fname if isinstance(fname, (str, os.PathLike)) else fname.name)  # saved as .NAME.png.XXXX.tmp.png
        folder, base = path.parent.name, path.name
        name = re.match(r"\.?(.+?\.(?:png|pdf|svg))", base).group(1)
        found[name if name not in found else f"{folder}/{name}"] = problems(fig) + legends_covering_data(fig)
        return save(fig, fname, *args, **{**kwargs, "dpi": 20})  # a valid file, written fast

    monkeypatch.setattr(Figure, "savefig", checked)
    return found


def _size_args(size):
    return [] if SIZES[size] is None else ["--figure-size", SIZES[size]]


def _check(found, expected, size):
    assert set(expected) <= set(found), sorted(found)
    bad = {name: p for name, p in found.items() if p}
    assert bad == {}, size


#: scenario -> (overrides for a short run, figures expected)
RUNS = {
    "climb": (["simulation.duration_s=6"], ["forces", "speeds", "positions", "route"]),
    "traverse_patch": (["simulation.duration_s=24"], ["forces", "speeds", "positions", "route"]),
    "tow6_uniform": (["simulation.duration_s=4"], ["forces", "speeds", "positions"]),
    "pi3_equal": (["simulation.duration_s=4"], ["forces", "speeds", "positions", "force_diagram"]),
    "ramp_drift": (["simulation.duration_s=8"], ["forces", "speeds", "positions", "route"]),
    "inchworm2": (["simulation.duration_s=6"], ["forces", "speeds", "positions"]),
}


@pytest.fixture(scope="module")
def run_results():
    return {n: simulate(load_scenario(n, sets)) for n, (sets, _) in RUNS.items()}


@pytest.mark.parametrize("size", SIZES)
@pytest.mark.parametrize("name", RUNS)
def test_run_figures_are_readable(run_results, caught, tmp_path, name, size):
    run_results[name].write(tmp_path / "o", plot=True, figure_size=SIZES[size])
    _check(caught, [f"{k}.png" for k in RUNS[name][1]], size)


@pytest.mark.parametrize("size", SIZES)
def test_study_command_figures_are_readable(caught, tmp_path, size):
    runner = CliRunner()
    commands = {
        "sweep 1-D": ["sweep", "tow6_uniform", "--set", "tow.force_N=0,300", "--set", "simulation.duration_s=2"],
        "sweep 2-D": [
            "sweep",
            "tow6_uniform",
            "--set",
            "tow.force_N=0,300",
            "--set",
            "terrain.xt=0.5,0.9",
            "--set",
            "simulation.duration_s=2",
        ],
        "mobility-map": ["mobility-map", "tow6_uniform", "--xt", "0.3,0.6,0.9", "--tow", "0,200", "--no-inching"],
        "gradeability": [
            "mobility-map",
            "traverse_patch",
            "--xt",
            "0.3,0.6,0.9",
            "--tow",
            "0,200",
            "--grade",
            "0,5,10",
            "--inch-duration",
            "3",
        ],
        "groundtruth": ["groundtruth"],
        "terrain-curves": ["terrain-curves", "--xt", "1.0", "--xt", "0.5", "--xt", "0.25"],
    }
    for k, (label, args) in enumerate(commands.items()):
        r = runner.invoke(main, [*args, "--out", str(tmp_path / f"o{k}"), *_size_args(size)])
        assert r.exit_code == 0, (label, r.output)
    expected = ["sweep.png", "heatmap.png", "mobility_map.png", "gradeability.png", "table2.png"]
    _check(caught, expected, size)


@pytest.mark.parametrize("size", [pytest.param(s, marks=pytest.mark.slow) if s != "column" else s for s in SIZES])
def test_paper_figures_are_readable(caught, tmp_path, size):
    r = CliRunner().invoke(main, ["paper", "--quick", "-j", "1", "--out", str(tmp_path / "p"), *_size_args(size)])
    assert r.exit_code == 0, r.output
    _check(caught, ["fig5_speeds.png", "fig10_force_diagram.png", "table2.png", "fig3_terrain_curves.png"], size)


def test_the_default_size_is_the_page_width(run_results):
    from snoworm.plotting import headless

    with headless():
        fig = run_results["tow6_uniform"].plot("speeds")
    assert fig.get_figwidth() == FIGURE_SIZES["page"]


def test_the_legend_check_can_fail():
    """A legend in the upper right over a line there, while the lower left is empty, is found."""
    fig = Figure(figsize=(FIGURE_SIZES["column"], 2.5), layout="constrained")
    a = fig.subplots()
    a.plot([0, 1, 2, 3], [0, 0.1, 0.9, 1.0], label="rising trace")
    a.legend(loc="upper right")
    assert legends_covering_data(fig) == ["axes0.legend covers data while a corner of the axes is free"]
    a.legend(loc="lower right")
    assert legends_covering_data(fig) == []
