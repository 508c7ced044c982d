"""Figures of an odds study (snoworm/plotting/odds.py): they show the numbers of odds.json."""

import numpy as np
from matplotlib.figure import Figure

from snoworm.plotting import headless
from snoworm.plotting.odds import plot_odds, plot_odds_convergence, plot_odds_sobol, plot_odds_stops, write_odds_figures

from .figure_checks import problems

SUMMARY = {
    "scenario": "climb",
    "strategies": {
        "rolling": {"p_go": 0.41, "p_go_ci": [0.38, 0.44], "n": 1000},
        "inching": {"p_go": 0.97, "p_go_ci": [0.96, 0.98], "n": 1000},
    },
    "sobol": {
        "rolling": {
            "go": {
                "terrain.xt": {"first": 0.8, "total": 0.85, "first_ci": [0.7, 0.9], "total_ci": [0.8, 0.9]},
                "tow.force_N": {"first": 0.1, "total": 0.15, "first_ci": [0.0, 0.2], "total_ci": [0.1, 0.2]},
            }
        }
    },
}
ROWS = [
    {"strategy": "rolling", "status": "ok", "verdict": "immobilised", "stop_m": 65.0, "go": 0},
    {"strategy": "rolling", "status": "ok", "verdict": "immobilised", "stop_m": 72.0, "go": 0},
    {"strategy": "rolling", "status": "ok", "verdict": "reached_end", "stop_m": None, "go": 1},
    {"strategy": "inching", "status": "ok", "verdict": "reached_end", "stop_m": None, "go": 1},
]
ROUTE = {"x_m": np.linspace(0, 100, 50), "elevation_m": np.linspace(0, 17, 50), "xt": np.full(50, 0.8), "goal_m": 100.0}


def test_bars_are_p_go_and_error_bars_the_wilson_interval():
    with headless():
        fig = plot_odds(SUMMARY)
    a = fig.axes[0]
    assert [round(p.get_height(), 9) for p in a.patches] == [41.0, 97.0]
    seg = a.collections[0].get_segments()  # the error bars: from the interval's low to its high end
    assert np.allclose([[s[0][1], s[1][1]] for s in seg], [[38, 44], [96, 98]])
    assert not problems(fig)


def test_stops_histogram_counts_the_immobilised_draws():
    with headless():
        fig = plot_odds_stops(ROWS, ROUTE, ["rolling", "inching"])
    lower = fig.axes[1]
    steps = lower.patches[0]  # rolling's stairs: 2 of 3 draws stop, in two bins
    assert np.isclose(np.sum(steps.get_data().values), 100 * 2 / 3)


def test_convergence_and_sobol_figures(tmp_path):
    curves = {
        "rolling": {
            "n": np.array([1, 10, 100]),
            "p": np.array([0.0, 0.4, 0.41]),
            "low": np.array([0.0, 0.17, 0.32]),
            "high": np.array([0.79, 0.69, 0.51]),
        }
    }
    with headless():
        fig = plot_odds_convergence(curves)
        assert np.allclose(fig.axes[0].lines[0].get_ydata(), [0, 40, 41])
        s = plot_odds_sobol(SUMMARY["sobol"])
    heights = [round(p.get_height(), 9) for p in s.axes[0].patches]
    assert heights == [0.8, 0.1, 0.85, 0.15]
    paths = write_odds_figures(ROWS, SUMMARY, ROUTE, curves, tmp_path)
    assert [p.name for p in paths] == ["odds.png", "stops.png", "convergence.png", "sobol.png"]
    assert all(p.stat().st_size > 1000 for p in paths)
    assert isinstance(fig, Figure)
