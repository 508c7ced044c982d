"""Figures of one run (snoworm.plotting.runs): panels, styles, legends, own axes, file formats, and the
force diagram of a force-control run."""

import dataclasses

import numpy as np
import pytest
from matplotlib.figure import Figure

from snoworm import load_scenario, simulate
from snoworm.plotting import runs
from tests.conftest import SCENARIOS


@pytest.fixture(scope="module")
def inch():
    return simulate(load_scenario(SCENARIOS / "inchworm6.yaml", ["simulation.duration_s=4"]))


@pytest.fixture(scope="module")
def uniform():
    return simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml", ["simulation.duration_s=2"]))


def _labels(ax):
    return [ln.get_label() for ln in ax.get_lines() if not ln.get_label().startswith("_")]


def test_inchworm_speeds_one_panel_per_moving_group(inch):
    fig = runs.plot_speeds(inch)
    groups = runs.moving_groups(inch)
    assert groups == [(0, 3), (1, 4), (2, 5)]  # the six_segment gait's phases (paper Fig 5)
    panels = [a for a in fig.axes if a.get_ylabel().startswith("ground speed")]
    assert [_labels(a) for a in panels] == [
        ["leader 0", "follower 3"],
        ["follower 1", "follower 4"],
        ["follower 2", "follower 5"],
    ]
    for a in panels:  # the two traces of a pair overlap: they differ in colour, line style and marker
        l1, l2 = a.get_lines()[:2]
        assert l1.get_color() != l2.get_color() and l1.get_marker() != l2.get_marker()
    chart = [a for a in fig.axes if a.get_ylabel().startswith("segment")]
    assert len(chart) == 1 and len(chart[0].get_yticklabels()) == 6  # set-points as a chart, a row each


def test_uniform_speeds_one_panel(uniform):
    fig = runs.plot_speeds(uniform)
    panels = [a for a in fig.axes if a.get_ylabel().startswith("ground speed")]
    assert len(panels) == 1 and len(_labels(panels[0])) == 6
    assert runs.moving_groups(uniform) is None
    # set-points that do not switch between a few values are lines, not a chart
    assert [a.get_ylabel() for a in fig.axes][-1] == "wheel-speed\nset-point [m/s]"
    assert len(fig.axes[-1].get_lines()) == 6


@pytest.fixture(scope="module")
def three():
    return simulate(load_scenario(SCENARIOS / "pi3_equal.yaml", ["simulation.duration_s=2"]))


def test_legends_outside_the_data(three):
    fig = runs.plot_forces(three)
    fig.draw_without_rendering()
    for a in fig.axes:
        leg = a.get_legend()
        assert leg is not None
        assert leg.get_window_extent().x0 >= a.get_window_extent().x1 - 1e-6


def test_many_links_get_small_multiples_and_shaded_phases(inch):
    """Six segments of an inchworm gait: a panel per link and per segment (shared axes), and the
    gait phases as shaded spans (not a line per phase change)."""
    fig = runs.plot_forces(inch)
    visible = [a for a in fig.axes if a.get_visible()]
    assert len(visible) == 5 + 6
    texts = sorted(t.get_text() for a in visible for t in a.texts)
    assert texts == sorted(
        [f"link {j} ({j}-{j + 1})" for j in range(5)] + ["leader 0"] + [f"follower {k}" for k in range(1, 6)]
    )
    assert all(len(a.get_lines()) <= 2 for a in visible)  # the series and the zero line
    spans = runs.gait_spans(inch)
    assert len(spans) >= 3 and {k for *_, k, _ in spans} == {0, 1, 2}
    assert all(t1 > t0 for t0, t1, *_ in spans)
    pos = runs.plot_positions(inch)
    assert not [
        ln for ln in pos.axes[0].get_lines() if ln.get_label().startswith("_child") and np.ptp(ln.get_xdata()) == 0
    ]  # no vertical line per phase


def test_tow_far_off_scale_is_a_note_not_a_line(three):
    F = three.links["force_N"]
    for tow, line in ((1e5, False), (float(F.max()), True)):
        a = Figure().subplots()
        a.plot(three.t, F)
        runs._tow_line(a, tow, F)
        assert bool([ln for ln in a.get_lines() if ln.get_label() == "tow"]) is line
        assert any("off scale" in t.get_text() for t in a.texts) is not line
        assert a.get_ylim()[1] < F.max() + 0.5 * np.ptp(F) + 1  # the link traces keep the scale


def test_supervisor_gets_one_speed_panel_per_moving_group():
    sup = simulate(load_scenario(SCENARIOS / "traverse_patch.yaml", ["simulation.duration_s=2"]))
    assert runs.moving_groups(sup) == [(0, 3), (1, 4), (2, 5)]


def test_positions_side_panel_only_when_terrain_varies(uniform):
    assert len(runs.plot_positions(uniform).axes) == 1
    patch = load_scenario(
        SCENARIOS / "tow6_uniform.yaml",
        ["simulation.duration_s=1", ("terrain.patches", [{"start_m": -4.0, "end_m": -2.0, "xt": 0.5, "ramp_m": 0.5}])],
    )
    fig = runs.plot_positions(simulate(patch))
    assert len(fig.axes) == 2 and fig.axes[0].get_xlabel() == "X_t"


def test_draws_on_the_users_axes(uniform):
    user = Figure()
    axes = user.subplots(2, 1)
    assert runs.plot_forces(uniform, ax=axes) is user
    assert len(axes[0].get_lines()) >= 5 and len(axes[1].get_lines()) == 6
    one = Figure().subplots()
    assert runs.plot_positions(uniform, ax=one) is one.figure and len(one.get_lines()) >= 6
    with pytest.raises(ValueError, match="panel"):
        runs.plot_forces(uniform, ax=one)


@pytest.mark.parametrize("fmt, magic", [("svg", b"<?xml"), ("pdf", b"%PDF-")])
def test_plot_result_in_other_formats(uniform, tmp_path, fmt, magic):
    paths = runs.plot_result(uniform, tmp_path, fmt)
    assert [p.name for p in paths] == [f"forces.{fmt}", f"speeds.{fmt}", f"positions.{fmt}"]
    assert all(p.read_bytes()[:5] == magic for p in paths)


def test_route_figure_shows_speeds_over_elevation_and_xt(tmp_path):
    """A run on a grade gets the route figure: speeds against distance over z(s) and X_t(s)."""
    res = simulate(load_scenario("ramp_drift", ["simulation.duration_s=4"]))
    fig = runs.plot_route(res)
    speed_ax, elev_ax, xt_ax = fig.axes[:3]
    assert len(_labels(speed_ax)) == res.n_segments
    xs = elev_ax.get_lines()[0].get_xdata()
    z = elev_ax.get_lines()[0].get_ydata()
    np.testing.assert_allclose(z, res.scenario.terrain.elevation_profile().elevation(xs))
    np.testing.assert_allclose(xt_ax.get_lines()[0].get_ydata(), res.scenario.terrain.compile()(xs))
    names = sorted(p.name for p in runs.plot_result(res, tmp_path))
    assert "route.png" in names
    level = simulate(load_scenario("tow6_uniform", ["simulation.duration_s=1"]))
    assert "route.png" not in [p.name for p in runs.plot_result(level, tmp_path / "level")]


# ---------------------------------------------------------------------------------- force diagram
def test_one_box_per_segment_with_its_wheel_force(uniform):
    fig = runs.plot_force_diagram(uniform)
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert sum(t.startswith(("leader 0", "follower")) for t in texts) == uniform.n_segments
    assert sum("wheels" in t for t in texts) == uniform.n_segments


def test_force_diagram_never_prints_minus_zero(uniform):
    links = dict(uniform.links, force_N=np.full_like(uniform.links["force_N"], -1e-3))
    segments = dict(uniform.segments, net_force_N=np.full_like(uniform.segments["net_force_N"], -0.02))
    res = dataclasses.replace(uniform, links=links, segments=segments)
    fig = runs.plot_force_diagram(res)
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert any("0.0 N" in t for t in texts)
    assert not [t for t in texts if "-0.0" in t or "\u22120.0" in t]
