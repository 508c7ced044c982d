"""Gait phases of a run as shaded time spans (instead of a line per phase change).

:func:`gait_spans` reads the spans from the run's integration intervals (``Result.phases``:
labels such as ``"phase 1 (moving [1, 4])"``, ``"inching: phase 0 (moving [0, 3])"``) or, for a
run read back from disk (no intervals), from its ``phase_change`` events; :func:`shade_phases`
draws them as light bands, one colour per phase of the gait, or, when the phases are too short to
read at the figure's size, each stretch of gait as one grey band with its number of cycles.
"""

from __future__ import annotations

import re

import numpy as np
from matplotlib.patches import Patch

__all__ = ["gait_spans", "shade_phases", "readable", "gait_blocks", "PHASE_COLOURS", "GAIT_COLOUR"]

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


#: The width of a typical shaded phase that reads at print size [in] (about 4 pt); narrower phases are
#: summarised.
MIN_SPAN_IN = 0.06
#: The fill of a gait whose phases are too short to shade one by one.
GAIT_COLOUR = "#e3e3e3"


def _axes_width_in(a) -> float:
    return a.get_position().width * a.get_figure().get_figwidth()


def readable(axes, spans) -> bool:
    """True when the typical (median) span of ``spans`` is at least :data:`MIN_SPAN_IN` wide on every
    axes of ``axes`` (over the time its data and the spans cover; the median, so that a last phase cut
    short by the end of the run does not decide); False for e.g. the 31 gait cycles of
    ``traverse_patch``'s 100 s, which would shade as a striped band."""
    if not spans:
        return True
    shortest = float(np.median([t1 - t0 for t0, t1, *_ in spans]))
    for a in axes:
        lo = min(float(a.dataLim.x0), spans[0][0]) if a.dataLim.width > 0 else spans[0][0]
        hi = max(float(a.dataLim.x1), spans[-1][1]) if a.dataLim.width > 0 else spans[-1][1]
        if shortest / max(hi - lo, 1e-12) * _axes_width_in(a) < MIN_SPAN_IN:
            return False
    return True


def gait_blocks(spans) -> list:
    """``[(t_start, t_end, cycles), ...]``: the stretches of uninterrupted gait phases, each with the
    number of gait cycles it holds (the spans of its first phase)."""
    blocks = []
    for t0, t1, k, _ in spans:
        if blocks and abs(blocks[-1][1] - t0) < 1e-9:
            b = blocks[-1]
            blocks[-1] = [b[0], t1, b[2], b[3] + (k == b[2])]
        else:
            blocks.append([t0, t1, k, 1])
    return [(b[0], b[1], b[3]) for b in blocks]


def shade_phases(axes, spans, legend_ax=None):
    """Shade each span on every axes of ``axes`` (behind the data, one colour per phase number), or,
    when the phases are too short to read (:func:`readable`), each stretch of gait as one grey band
    (:func:`gait_blocks`).  With ``legend_ax``, returns the legend handles: ``moving 0, 3`` per
    phase, or ``gait, N cycles`` for the grey bands (else an empty list)."""
    if not readable(axes, spans):
        blocks = gait_blocks(spans)
        for t0, t1, _ in blocks:
            for a in axes:
                a.axvspan(t0, t1, color=GAIT_COLOUR, lw=0, zorder=0)
        if legend_ax is None or not blocks:
            return []
        n = sum(c for *_, c in blocks)
        return [Patch(color=GAIT_COLOUR, label=f"gait ({n} cycle{'s' if n != 1 else ''})")]
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
