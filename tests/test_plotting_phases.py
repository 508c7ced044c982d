"""Gait phases as shaded spans (snoworm.plotting.phases)."""

from types import SimpleNamespace

import numpy as np
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
