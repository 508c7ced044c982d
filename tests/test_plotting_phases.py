"""Gait phases as shaded spans (snoworm.plotting.phases)."""

from types import SimpleNamespace

import numpy as np
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure

from snoworm.plotting.phases import PHASE_COLOURS, gait_spans, shade_phases


def _res(phases=(), events=(), t_end=10.0):
    return SimpleNamespace(phases=list(phases), events=list(events), t=np.linspace(0, t_end, 11))


def test_spans_from_the_intervals_merge_one_phase():
    res = _res(
        [
            {"t_start_s": 0.0, "t_end_s": 0.5, "label": "before start"},
            {"t_start_s": 0.5, "t_end_s": 1.6, "label": "phase 0 (moving [0, 3])"},
            {"t_start_s": 1.6, "t_end_s": 1.7, "label": "phase 0 (moving [3])"},
            {"t_start_s": 1.7, "t_end_s": 3.0, "label": "inching: phase 1 (moving [1, 4])"},
            {"t_start_s": 3.0, "t_end_s": 4.0, "label": "rolling"},
        ]
    )
    assert gait_spans(res) == [(0.5, 1.7, 0, "0, 3"), (1.7, 3.0, 1, "1, 4")]


def test_spans_from_events_when_the_intervals_are_gone():
    ev = [
        {"t_s": 2.0, "kind": "phase_change", "detail": "phase 1 starts (moving [1, 4]) after joint 2 ..."},
        {"t_s": 2.0, "kind": "joint_limit", "detail": "joint 0 fully extended"},
        {"t_s": 5.0, "kind": "phase_change", "detail": "phase 2 starts (moving [2, 5]) after ..."},
        {"t_s": 7.0, "kind": "switch_to_rolling", "detail": ""},
    ]
    assert gait_spans(_res(events=ev)) == [(2.0, 5.0, 1, "1, 4"), (5.0, 7.0, 2, "2, 5")]
    assert gait_spans(_res()) == []


def test_shading_one_colour_per_phase():
    a = Figure().subplots()
    handles = shade_phases([a], [(0, 1, 0, "0, 3"), (1, 2, 1, "1, 4"), (2, 3, 0, "0, 3")], legend_ax=a)
    assert len(a.patches) == 3
    assert [h.get_label() for h in handles] == ["moving 0, 3", "moving 1, 4"]
    assert a.patches[0].get_facecolor() == a.patches[2].get_facecolor() != a.patches[1].get_facecolor()
    assert len(PHASE_COLOURS) >= 3


def _cycles(n, t0=11.0, period=2.4):
    """``n`` gait cycles of three phases from ``t0`` (as traverse_patch's 31 cycles in 74 s)."""
    out = []
    for c in range(n):
        for k in range(3):
            a = t0 + c * period + k * period / 3
            out.append((a, a + period / 3, k, f"{k}, {k + 3}"))
    return out


def test_phases_too_short_to_read_become_one_band_with_the_cycle_count():
    """Issue 34: traverse_patch's 31 gait cycles (93 phases of 0.8 s on a 100 s axis) shaded as a
    striped band.  On a page-wide panel a 0.8 s phase is 0.8 / 100 * ~6 in = 0.05 in, below
    MIN_SPAN_IN: the gait is one grey band keyed "gait (31 cycles)"."""
    from snoworm.plotting.phases import GAIT_COLOUR, MIN_SPAN_IN, gait_blocks, readable

    spans = _cycles(31)
    fig = Figure(figsize=(7.16, 3))
    a = fig.subplots()
    a.plot([0, 100], [0, 1])
    width_in = a.get_position().width * 7.16
    assert 0.8 / 100 * width_in < MIN_SPAN_IN and not readable([a], spans)  # every phase 0.8 s: the median
    assert gait_blocks(spans) == [(11.0, spans[-1][1], 31)]
    keys = shade_phases([a], spans, legend_ax=a)
    assert [k.get_label() for k in keys] == ["gait (31 cycles)"]
    assert len(a.patches) == 1 and to_rgb(a.patches[0].get_facecolor()) == to_rgb(GAIT_COLOUR)


def test_phases_wide_enough_are_shaded_one_by_one():
    from snoworm.plotting.phases import readable

    spans = _cycles(2, t0=1.0, period=3.0)  # 1 s phases on a 10 s axis: 0.1 of the width
    fig = Figure(figsize=(3.5, 2.5))
    a = fig.subplots()
    a.plot([0, 10], [0, 1])
    assert readable([a], spans)
    keys = shade_phases([a], spans, legend_ax=a)
    assert len(a.patches) == 6 and [k.get_label() for k in keys] == ["moving 0, 3", "moving 1, 4", "moving 2, 5"]
