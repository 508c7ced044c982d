"""Figures of a sweep's table (snoworm.studies.sweep.figures, SweepTable.plot)."""

import numpy as np
import pytest

from snoworm.plotting import FIGURE_SIZES, headless
from snoworm.studies.sweep.figures import plot_table
from snoworm.studies.sweep.summary import SweepTable
from tests.figure_checks import problems


def _table(keys, values, zip_=False):
    rows = []
    for i, vals in enumerate(values):
        r = {
            "case_id": f"c{i:03d}",
            "case_key": "",
            "status": "ok" if i != 1 else "failed",
            "error": "",
            "mean_speed_mps": 0.1 * i if i != 1 else None,
            "mean_slip": 0.01 * i,
            "max_link_force_N": 10.0 * i,
            "energy_per_m_J": 100.0 + i,
            "immobilised": i == 2,
        }
        r.update(dict(zip(keys, vals)))
        rows.append(r)
    cols = [
        "case_id",
        "case_key",
        *keys,
        "status",
        "error",
        "mean_speed_mps",
        "mean_slip",
        "max_link_force_N",
        "energy_per_m_J",
        "immobilised",
    ]
    return SweepTable(cols, rows, keys)


def test_one_key_gives_metric_panels():
    t = _table(["tow.force_N"], [[0.0], [100.0], [200.0], [300.0]])
    with headless():
        fig = t.plot(size="column")
    assert [a.get_ylabel() for a in fig.axes][:2] == ["mean speed [m/s]", "mean slip (2nd half)"]
    assert fig.axes[-1].get_xlabel() == "tow force [N]"
    assert problems(fig, FIGURE_SIZES["column"]) == []
    one = plot_table(t, "mean_slip")
    assert len(one.axes) == 1


def test_two_keys_on_a_grid_give_a_heat_map_in_the_sweeps_order():
    vals = [[x, f] for f in (0.0, 50.0) for x in (1.0, 0.6)]
    t = _table(["terrain.xt", "tow.force_N"], vals)
    fig = t.plot()
    a = fig.axes[0]
    assert [lab.get_text() for lab in a.get_xticklabels()] == ["1.0", "0.6"]
    assert sorted(txt.get_text() for txt in a.texts) == sorted(["0.00", "failed", "0.20\nimmob.", "0.30"])
    assert problems(fig) == []


def test_two_keys_zipped_give_lines():
    t = _table(["terrain.xt", "tow.force_N"], [[0.6, 0.0], [0.8, 50.0], [1.0, 100.0]])
    fig = t.plot("mean_speed_mps")
    assert len(fig.axes) == 1 and fig.axes[0].get_xlabel() == "terrain coefficient X_t"
    y = fig.axes[0].get_lines()[0].get_ydata()
    assert np.isnan(y[1]) and y[2] == pytest.approx(0.2)
