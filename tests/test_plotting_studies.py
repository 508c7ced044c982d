"""Figures of the studies (snoworm.plotting.studies): sweeps, heat maps, mobility map, Table 2."""

import numpy as np
from matplotlib.figure import Figure

from snoworm.plotting import studies
from snoworm.studies.groundtruth import run_groundtruth, run_terrain_curves
from snoworm.studies.mobility import REGIONS


def _mmap():
    xts, tows = [0.2, 0.6, 1.0], [0.0, 50.0, 100.0]
    rows = []
    for f in tows:
        for x in xts:
            rolling = x > 0.5 + f / 500
            rows.append(
                {
                    "xt": x,
                    "tow_N": f,
                    "rolling": rolling,
                    "inching": not rolling and x > 0.3,
                    "region": "rolling" if rolling else ("inching only" if x > 0.3 else "immobile"),
                    "rolling_energy_per_metre_J_per_m": 100.0 / x,
                    "inching_energy_per_metre_J_per_m": 300.0,
                    "inching_cheaper": False,
                }
            )
    return {
        "regions": REGIONS,
        "xts": xts,
        "tows": tows,
        "rows": rows,
        "scenario": "test",
        "rolling_limit_xt": {f: 0.5 + f / 500 for f in tows},
        "wheel_speed_mps": 0.5,
    }


def test_mobility_map_cells_stay_within_the_grid():
    fig = studies.plot_mobility_map(_mmap())
    a1 = fig.axes[0]
    assert a1.get_xlim() == (0.2, 1.0) and a1.get_ylim() == (0.0, 100.0)  # not to -25 N or X_t 0
    mesh = a1.collections[0]  # rows: tows; at tow 50 N: immobile, inching only, rolling
    coords = mesh.get_coordinates()
    assert coords[..., 1].min() == 0.0 and coords[..., 1].max() == 100.0
    assert coords[..., 0].min() == 0.2 and coords[..., 0].max() == 1.0
    assert mesh.get_array().reshape(3, 3)[1].tolist() == [
        REGIONS.index("immobile"),
        REGIONS.index("inching only"),
        REGIONS.index("rolling"),
    ]


def test_sweep_axes_in_words_with_units():
    fig = studies.plot_sweep(
        [0.0, 100.0, 200.0],
        {"mean_speed_mps": [0.5, 0.4, None], "energy_per_m_J": [1, 2, 3]},
        "tow.force_N",
        immobilised=[False, False, True],
        ok=[True, True, False],
    )
    assert fig.axes[-1].get_xlabel() == "tow force [N]"
    assert [a.get_ylabel() for a in fig.axes] == ["mean speed [m/s]", "energy per metre [J/m]"]
    assert "tow.force_N" not in fig.axes[0].get_title()


def test_heatmap_on_the_users_axes():
    ax = Figure().subplots()
    v = np.array([[0.1, 0.2], [np.nan, 0.4]])
    fig = studies.plot_sweep_heatmap(
        ["0.5", "1"], ["0", "100"], v, "terrain.xt", "tow.force_N", "mean speed [m/s]", failed=np.isnan(v), ax=ax
    )
    assert fig is ax.figure
    assert ax.get_xlabel() == "terrain coefficient X_t" and ax.get_ylabel() == "tow force [N]"
    assert sorted(t.get_text() for t in ax.texts) == ["0.10", "0.20", "0.40", "failed"]


def test_groundtruth_figures_in_the_chosen_format(tmp_path):
    _, _, paths = run_groundtruth(tmp_path / "gt", plot_format="svg")  # each run owns its folder
    _, _, paths2 = run_terrain_curves([1.0, 0.5], tmp_path / "tc", n_points=51, plot_format="pdf")
    names = ["table2.csv", "table2.svg", "frostyboy_2020.csv", "terrain_curves.csv", "terrain_curves.pdf"]
    assert [p.name for p in paths + paths2] == names  # the field data compared, copied (issue 30)
    assert b"<svg" in paths[1].read_bytes() and paths2[1].read_bytes()[:5] == b"%PDF-"


def test_study_figures_readable_at_column_width():
    """Mobility map, sweep, heat map, Table 2 and Figure 3 at 3.5 in: text >= 7 pt, nothing
    overlapping (a title above a legend above the axes becomes the legend's title), all inside."""
    from snoworm.plotting import FIGURE_SIZES, headless
    from snoworm.studies.groundtruth import terrain_curves, vehicle_model
    from tests.figure_checks import problems

    v = np.array([[0.1, 0.2, 0.3], [np.nan, 0.4, 0.5]])
    rows = [
        {
            "case": k,
            "xt": 0.5 + 0.1 * k,
            "slip_measured": 0.1,
            "slip_model": 0.12,
            "torque_measured_Nm": 20.0,
            "torque_model_Nm": 21.0,
        }
        for k in range(1, 6)
    ]
    with headless():
        figs = {
            "mobility": studies.plot_mobility_map(_mmap(), size="column"),
            "sweep": studies.plot_sweep(
                [0.0, 100.0, 200.0],
                {"mean_speed_mps": [0.5, 0.4, None], "energy_per_m_J": [1, 2, 3]},
                "tow.force_N",
                immobilised=[False, False, True],
                ok=[True, True, False],
                size="column",
            ),
            "heatmap": studies.plot_sweep_heatmap(
                ["0.5", "0.75", "1"],
                ["0", "100"],
                v,
                "terrain.xt",
                "tow.force_N",
                "mean speed [m/s]",
                failed=np.isnan(v),
                size="column",
            ),
            "table2": studies.plot_table2(rows, size="column"),
            "terrain curves": studies.plot_terrain_curves(
                terrain_curves([1.0, 0.5], *vehicle_model("frostyboy", None), 101), size="column"
            ),
        }
    assert " ".join(figs["mobility"].axes[0].get_legend().get_title().get_text().split()).endswith(
        "which modes move the vehicle"
    )
    for name, fig in figs.items():
        assert problems(fig, FIGURE_SIZES["column"]) == [], name


def _grade_map():
    """X_t 0.3: only inching moves (0 and 5 deg); 0.6: rolling up to 5 deg, inching simulated only at
    10 deg (failed); 0.9 (every cell simulated): rolling on level ground only, inching up to 10 deg."""
    moves = {  # (xt, grade) -> (rolling, inching: None = not simulated)
        (0.3, 0): (False, True),
        (0.3, 5): (False, True),
        (0.3, 10): (False, False),
        (0.6, 0): (True, None),
        (0.6, 5): (True, None),
        (0.6, 10): (False, False),
        (0.9, 0): (True, True),
        (0.9, 5): (False, True),
        (0.9, 10): (False, True),
    }
    rows = []
    for (x, g), (roll, inch) in moves.items():
        rows.append(
            {
                "xt": x,
                "tow_N": 0.0,
                "grade_deg": g,
                "rolling": roll,
                "rolling_speed_mps": 1.0 * x - 0.01 * g if roll else 0.0,
                "rolling_energy_per_metre_J_per_m": 1000.0 + 10 * g if roll else None,
                "inching": inch,
                "inching_speed_mps": None if inch is None else (0.1 - 0.001 * g if inch else 0.0),
                "inching_energy_per_metre_J_per_m": 5000.0 + 100 * g if inch else None,
            }
        )
    from snoworm.studies.gradeability import gradeability

    m = {"rows": rows, "xts": [0.3, 0.6, 0.9], "tows": [0.0], "grades": [0, 5, 10], "scenario": "test"}
    m["rolling_max_grade_deg"] = {0.0: {0.3: -5.0, 0.6: 6.0, 0.9: 2.0}}
    m["gradeability"] = {0.0: gradeability(m, 0.0)}
    return m


def test_gradeability_compares_the_gaits_at_one_grade_per_xt():
    """Issue 34: the energy panel compared rolling at its steepest grade with inching at its own.
    Now both are read at the steepest grid grade every moving gait climbed (by hand from the map
    above: 5, 5 and 0 deg), and level inching-only cells (energy per metre climbed undefined) show."""
    m = _grade_map()
    got = studies.compared_grades(m, 0.0, ["rolling", "inching"])
    assert [g for g, _ in got] == [5, 5, 0]
    assert got[0][1] == {"inching": (0.1 - 0.005, 5500.0)}
    assert got[1][1] == {"rolling": (0.6 - 0.05, 1050.0)}
    assert got[2][1] == {"rolling": (0.9, 1000.0), "inching": (0.1, 5000.0)}
    fig = studies.plot_gradeability(m)
    speed_panel = fig.axes[1]
    drawn = sorted((float(x), float(y)) for ln in speed_panel.get_lines() for x, y in zip(*ln.get_data()))
    want = sorted([(0.3, 0.095), (0.6, 0.55), (0.9, 0.9), (0.9, 0.1)])
    assert np.allclose(drawn, want, rtol=0, atol=1e-12)  # float rounding of the hand values only
