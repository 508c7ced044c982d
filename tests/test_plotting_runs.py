"""Figures of one run (snoworm.plotting.runs): panels, styles, legends, own axes, file formats, and the
force diagram of a force-control run."""

import dataclasses

import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

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
    """Issue 34: a set-point shared by every segment (uniform mode) is a dashed reference line in the
    speed panel, not a flat panel of its own (half the figure)."""
    fig = runs.plot_speeds(uniform)
    assert len(fig.axes) == 1
    panel = fig.axes[0]
    assert panel.get_ylabel().startswith("ground speed")
    assert _labels(panel)[:6] == ["leader 0"] + [f"follower {k}" for k in range(1, 6)]
    (ref,) = [ln for ln in panel.get_lines() if ln.get_label().startswith("wheel-speed set-point")]
    np.testing.assert_array_equal(ref.get_ydata(), uniform.segments["speed_setpoint_mps"][:, 0])
    assert runs.moving_groups(uniform) is None


def test_set_points_that_differ_keep_their_panel():
    res = simulate(load_scenario(SCENARIOS / "pi3_equal.yaml", ["simulation.duration_s=2"]))
    fig = runs.plot_speeds(res)
    assert [a.get_ylabel() for a in fig.axes][-1] == "wheel-speed\nset-point [m/s]"
    assert len(fig.axes[-1].get_lines()) == 3


def test_coinciding_traces_show_their_markers_in_turn(uniform):
    """Issue 34: six coinciding traces piled up their markers.  Now each series has 4 markers
    (about 24 in all) and no two series mark the same sample."""
    fig = runs.plot_speeds(uniform)
    marked = [ln.get_markevery() for ln in fig.axes[0].get_lines()[:6]]
    n = uniform.t.size
    samples = [set(range(m[0], n, m[1])) for m in marked]
    assert all(3 <= len(s) <= 5 for s in samples)
    assert all(not (a & b) for i, a in enumerate(samples) for b in samples[i + 1 :])


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
    """Six segments of an inchworm gait: a panel per link and per segment (shared axes), each named by
    its y label (issue 34: names printed over the traces), the gait phases as shaded spans (not a
    line per phase change), and the empty slot under the last link holding the shading's legend."""
    fig = runs.plot_forces(inch)
    drawn = [a for a in fig.axes if a.get_lines()]
    assert len(drawn) == 5 + 6
    assert not [t for a in fig.axes for t in a.texts]
    names = sorted(" ".join(a.get_ylabel().split()) for a in drawn)
    assert names == sorted(
        [f"link {j} ({j}-{j + 1})" for j in range(5)] + ["leader 0"] + [f"follower {k}" for k in range(1, 6)]
    )
    assert all(len(a.get_lines()) <= 2 for a in drawn)  # the series and the zero line
    spans = runs.gait_spans(inch)
    assert len(spans) >= 3 and {k for *_, k, _ in spans} == {0, 1, 2}
    assert all(t1 > t0 for t0, t1, *_ in spans)
    (slot,) = [a for a in fig.axes if not a.get_lines()]
    assert not slot.axison and [t.get_text() for t in slot.get_legend().get_texts()] == [
        "moving 0, 3",
        "moving 1, 4",
        "moving 2, 5",
    ]
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


def _panel(fig, ylabel):
    (a,) = [a for a in fig.axes if a.get_ylabel().startswith(ylabel)]
    return a


def test_route_figure_shows_speeds_over_elevation_grade_and_xt(tmp_path):
    """A run on a route gets the route figure: speeds against distance over z(s), the grade in
    degrees and X_t(s)."""
    res = simulate(load_scenario("ramp_drift", ["simulation.duration_s=24"]))  # onto the ramp at 30 m
    fig = runs.plot_route(res)
    speed_ax, elev_ax, grade_ax, xt_ax = (_panel(fig, k) for k in ("ground speed", "elevation", "grade", "X_t"))
    assert len(_labels(speed_ax)) == res.n_segments
    xs = elev_ax.get_lines()[0].get_xdata()
    z = elev_ax.get_lines()[0].get_ydata()
    elev = res.scenario.terrain.elevation_profile()
    np.testing.assert_allclose(z, elev.elevation(xs))
    np.testing.assert_allclose(xt_ax.get_lines()[0].get_ydata(), res.scenario.terrain.compile()(xs))
    # the route file's 5 deg ramp (0.8716 m up per 10 m of track), read back in degrees (central
    # differences of a piecewise-linear z: exact away from the table's kinks)
    g = grade_ax.get_lines()[0].get_ydata()
    assert np.max(g) == pytest.approx(np.degrees(np.arcsin(0.08716)), abs=1e-9)
    names = sorted(p.name for p in runs.plot_result(res, tmp_path))
    assert "route.png" in names
    level = simulate(load_scenario("tow6_uniform", ["simulation.duration_s=1"]))
    assert "route.png" not in [p.name for p in runs.plot_result(level, tmp_path / "level")]


def test_route_of_an_inching_climb_is_the_cycle_mean_not_a_comb():
    """Issue 34: the climb's speed against distance was a comb.  Now one point per gait cycle: the
    chain's advance over the cycle divided by its duration, so the points' time-weighted mean is the
    chain's mean speed over the gait (its total advance over the gait's duration); the grade is in
    the title in degrees (a constant grade gets no flat panel), and so is X_t."""
    res = simulate(load_scenario("climb", ["simulation.duration_s=8"]))
    fig = runs.plot_route(res)
    assert [a.get_ylabel() for a in fig.axes] == ["ground speed\n[m/s]", "elevation\n[m]"]
    assert "X_t = 0.7 throughout, 10 deg uphill grade" in " ".join(fig._suptitle.get_text().split())
    pos, spd, lo, hi, t_start = runs.cycle_means(res)
    spans = runs.gait_spans(res)
    starts = [t0 for t0, _, k, _ in spans if k == spans[0][2]]
    (b0, b1, cycles) = runs.gait_blocks(spans)[0]
    assert cycles == len(starts)
    t, xc = res.t, res.segments["x_m"].mean(1)
    inside = (t >= b0 - 1e-9) & (t <= b1 + 1e-9)
    i0, i1 = np.flatnonzero(inside)[[0, -1]]
    # windows inside the gait: one per cycle, from each cycle start to the next (or the gait's end)
    in_gait = [(p, v) for p, v, ts in zip(pos, spd, t_start) if t[i0] <= ts < t[i1]]
    assert len(in_gait) == cycles
    edges = [t[np.searchsorted(t, s - 1e-9)] for s in starts] + [t[i1]]
    durations = np.diff(edges)
    mean = np.sum(np.array([v for _, v in in_gait]) * durations) / durations.sum()
    assert mean == pytest.approx((xc[i1] - xc[i0]) / (t[i1] - t[i0]), rel=1e-12)
    cyc = (t_start >= t[i0]) & (t_start < t[i1])  # the envelope of a cycle (many samples) holds its mean
    assert np.all(lo[cyc] <= spd[cyc]) and np.all(spd[cyc] <= hi[cyc])


def test_positions_title_names_the_terrain_and_grade():
    """Issue 34: the climb example (10 deg, X_t = 0.7) was titled "uniform terrain"."""
    res = simulate(load_scenario("climb", ["simulation.duration_s=1"]))
    text = " ".join(runs.plot_positions(res)._suptitle.get_text().split())
    assert "uniform terrain" not in text and "X_t = 0.7 throughout, 10 deg uphill grade" in text


def test_a_patch_gets_the_route_figure_with_its_extent_and_the_mode_switches():
    """traverse_patch (level, a patch of X_t 0.3): the route figure shades the patch on every panel and
    marks the supervisor's switches at the chain's centre."""
    res = simulate(load_scenario("traverse_patch", ["simulation.duration_s=24"]))
    fig = runs.plot_route(res)
    assert [a.get_ylabel() for a in fig.axes] == ["ground speed\n[m/s]", "X_t"]  # level: no elevation panel
    patch = res.scenario.terrain.patches[0]
    for a in fig.axes:
        spans = [(p.get_x(), p.get_x() + p.get_width()) for p in a.patches if isinstance(p, Rectangle)]
        assert (patch.start_m, patch.end_m) in spans
    switches = [ev for ev in res.events if ev["kind"] == "switch_to_inching"]
    assert switches
    at = float(np.interp(switches[0]["t_s"], res.t, res.segments["x_m"].mean(1)))
    vlines = [ln for ln in fig.axes[0].get_lines() if np.ptp(ln.get_xdata()) == 0]
    assert any(ln.get_xdata()[0] == at for ln in vlines)


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
