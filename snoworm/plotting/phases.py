"""Gait phases of a run as shaded time spans (instead of a line per phase change).

:func:`gait_spans` reads the spans from the run's integration intervals (``Result.phases``:
labels such as ``"phase 1 (moving [1, 4])"``, ``"inching: phase 0 (moving [0, 3])"``) or, for a
run read back from disk (no intervals), from its ``phase_change`` events; :func:`shade_phases`
draws them as light bands, one colour per phase of the gait.
"""

from __future__ import annotations

import re

from matplotlib.patches import Patch

__all__ = ["gait_spans", "shade_phases", "PHASE_COLOURS"]

#: Light fills of the gait's phases (first, second, third, ...); rolling is left white.
PHASE_COLOURS = ("#cfe3f3", "#fbe3bf", "#cdeadf", "#f2d2e6", "#e0e0e0")
_PHASE = re.compile(r"phase (\d+)(?: starts)?(?: \(moving \[([^\]]*)\]\))?")


def _merge(spans):
    out = []
    for t0, t1, k, moving in spans:
        if out and out[-1][2] == k and abs(out[-1][1] - t0) < 1e-9:
            out[-1] = (out[-1][0], t1, k, out[-1][3] or moving)
        else:
            out.append((t0, t1, k, moving))
    return out


def gait_spans(result) -> list:
    """``[(t_start, t_end, phase_number, moving_text), ...]`` of the gait phases of ``result``
    (consecutive intervals of one phase merged); empty for a run without a gait."""
    spans = []
    for ph in result.phases or ():
        m = _PHASE.search(str(ph.get("label", "")))
        if m:
            spans.append((float(ph["t_start_s"]), float(ph["t_end_s"]), int(m.group(1)), m.group(2) or ""))
    if spans or not result.events:
        return _merge(spans)
    t_end = float(result.t[-1]) if len(result.t) else 0.0
    marks = [
        (float(e["t_s"]), e.get("kind"), str(e.get("detail", "")))
        for e in result.events
        if e.get("kind") in ("phase_change", "switch_to_inching", "switch_to_rolling")
    ]
    for (t0, kind, detail), nxt in zip(marks, marks[1:] + [(t_end, None, "")]):
        m = _PHASE.search(detail)
        if kind == "phase_change" and m:
            spans.append((t0, nxt[0], int(m.group(1)), m.group(2) or ""))
    return _merge(spans)


def shade_phases(axes, spans, legend_ax=None):
    """Shade each span on every axes of ``axes`` (behind the data, one colour per phase number);
    with ``legend_ax``, returns legend handles ``moving 0, 3`` per phase (else an empty list)."""
    seen = {}
    for t0, t1, k, moving in spans:
        seen.setdefault(k, moving)
        for a in axes:
            a.axvspan(t0, t1, color=PHASE_COLOURS[k % len(PHASE_COLOURS)], lw=0, zorder=0)
    if legend_ax is None:
        return []
    return [
        Patch(color=PHASE_COLOURS[k % len(PHASE_COLOURS)], label=f"moving {seen[k]}" if seen[k] else f"phase {k}")
        for k in sorted(seen)
    ]
