"""Figures of one run (a :class:`~snoworm.results.result.Result`): forces, speeds, positions, the
steady-state force diagram.  Each function draws on new or given axes and returns the Figure."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle
from matplotlib.ticker import MaxNLocator

from .phases import GAIT_COLOUR, PHASE_COLOURS, gait_blocks, gait_spans, readable, shade_phases
from .style import (
    blank_figure,
    figure_function,
    force_text,
    legend_outside,
    new_figure,
    seg_label,
    series_style,
    small_pt,
    target_width,
    title,
    wrap_title,
    write_figure,
)

__all__ = [
    "plot_forces",
    "plot_speeds",
    "plot_positions",
    "plot_force_diagram",
    "plot_groups",
    "plot_result",
    "moving_groups",
    "plot_route",
    "PLOT_KINDS",
    "seg_label",
    "title",
    "gait_spans",
]

#: Up to this many links a gait's forces share one panel; more get small multiples (a panel each).
OVERLAY_MAX = 3
#: Beyond this many links small multiples are too small to read: colour charts instead.
MULTIPLES_MAX = 8


def _tow_line(a, tow, F):
    """The tow force as a reference line when it lies near the link forces' range; else a note
    (a far-off line would squash the link traces into a flat band)."""
    lo, hi = (float(F.min()), float(F.max())) if F.size else (0.0, 0.0)
    span = max(hi - lo, 1e-9)
    if lo - 0.3 * span <= tow <= hi + 0.3 * span:
        a.axhline(tow, color="0.5", ls=":", lw=1, label="tow")
    else:
        a.text(
            0.99,
            0.97 if tow > hi else 0.03,
            f"tow {tow:g} N (off scale)",
            transform=a.transAxes,
            ha="right",
            va="top" if tow > hi else "bottom",
            fontsize=small_pt(),
            color="0.35",
        )


def _force_multiples(fig, result, own):
    """Links (left) and segments (right), one small panel each, shared axes; each panel named by its
    y label (not over its trace); the slot under the last link holds the legend of the shading."""
    t, F, net = result.t, result.links["force_N"], result.segments["net_force_N"]
    n = net.shape[1]
    axes = fig.subplots(n, 2, sharex=True, squeeze=False)
    for j in range(1, n):
        axes[j, 0].sharey(axes[0, 0])
        axes[j, 1].sharey(axes[0, 1])
    for j in range(n):
        a_l, a_s = axes[j]
        if j < F.shape[1]:
            a_l.plot(t, F[:, j], color="#0072B2", lw=1.0)
            a_l.set_ylabel(f"link {j}\n({j}-{j + 1})")
        a_s.plot(t, net[:, j], color="#D55E00", lw=1.0)
        a_s.set_ylabel("leader 0" if j == 0 else f"follower\n{j}")
        for a in (a_l, a_s) if j < F.shape[1] else (a_s,):
            a.grid(alpha=0.3)
            a.axhline(0.0, color="0.6", lw=0.5)
    drawn = [a for a in axes.flat if a.get_lines()]
    keys = shade_phases(drawn, gait_spans(result), legend_ax=drawn[0])
    for a in axes[F.shape[1] :, 0]:  # the empty slot(s) under the last link: the shading's key
        a.axis("off")
    if keys and F.shape[1] < n:
        axes[F.shape[1], 0].legend(handles=keys, loc="center", frameon=False, title="shading")
    axes[0, 0].set_title("connector force [N]\n(tension +)")
    axes[0, 1].set_title("net wheel force [N]\n(forward +)")
    axes[-1, 1].set_xlabel("time [s]")
    (axes[-2, 0] if n > 1 else axes[-1, 0]).set_xlabel("time [s]")
    if (n > 1) and F.shape[1] < n:
        axes[-2, 0].xaxis.set_tick_params(labelbottom=True)
    if result.scenario.tow.force_N:
        _tow_line(axes[F.shape[1] - 1, 0] if F.shape[1] else axes[0, 1], result.scenario.tow.force_N, F)
    title(fig, axes, f"{result.scenario.name}: connector and net forces", own)
    return fig


def _force_chart(a, fig, t, F, label, ylabel):
    """Series (n_t, n) as a colour chart, a row per link/segment, a diverging scale around 0."""
    te = np.concatenate([t[:1], (t[1:] + t[:-1]) / 2, t[-1:]]) if t.size > 1 else np.array([t[0], t[0] + 1])
    lim = max(float(np.max(np.abs(F))), 1e-9)
    m = a.pcolormesh(
        te, np.arange(F.shape[1] + 1) - 0.5, F.T, cmap="RdBu_r", vmin=-lim, vmax=lim, shading="flat", rasterized=True
    )
    a.invert_yaxis()
    a.set_ylabel(ylabel)
    fig.colorbar(m, ax=a, label=label, pad=0.01)


@figure_function
def plot_forces(result, *, ax=None, fig=None):
    """Connector (link) forces and net wheel force per segment against time (paper Figs 6-9).

    Two panels (links, segments), a line each, except for a gait (inchworm, supervisor) with more
    than :data:`OVERLAY_MAX` links on a figure of ours: small multiples, a panel per link and per
    segment with shared axes (its square waves would tangle in one panel); beyond
    :data:`MULTIPLES_MAX` links: two colour charts.  Small multiples are named by their y labels,
    and the slot under the last link holds the legend of the shading.
    Gait phases are shaded (keyed in the legend; one grey band when too short to read).  ``ax``: two axes (links, segments) of your own (lines); ``fig``: a
    figure to draw in.  ``size``: print size (:func:`snoworm.plotting.style.parse_size`).
    Returns the Figure.
    """
    own = ax is None and fig is None
    nl = result.links["force_N"].shape[1]
    if ax is None and OVERLAY_MAX < nl <= MULTIPLES_MAX and gait_spans(result):
        fig = fig if fig is not None else blank_figure((9, 1.3 * (nl + 1) + 0.8), nl + 1, row_in=1.0)
        return _force_multiples(fig, result, own)
    fig, axes = new_figure(ax, fig, 2, 1, figsize=(9, 6.5), sharex=True)
    a1, a2 = axes[:, 0]
    t = result.t
    F, net = result.links["force_N"], result.segments["net_force_N"]
    if nl > MULTIPLES_MAX and ax is None:
        _force_chart(a1, fig, t, F, "connector force [N]\n(tension +)", "link")
        _force_chart(a2, fig, t, net, "net wheel force [N]\n(forward +)", "segment")
    else:
        for j in range(nl):
            a1.plot(t, F[:, j], label=f"link {j} ({j}-{j + 1})", **series_style(j, t.size, nl))
        if result.scenario.tow.force_N:
            _tow_line(a1, result.scenario.tow.force_N, F)
        a1.set_ylabel("connector force [N]\n(tension +)")
        for k in range(net.shape[1]):
            a2.plot(t, net[:, k], label=seg_label(k), **series_style(k, t.size, net.shape[1]))
        a2.set_ylabel("net wheel force [N]\n(forward +)")
        keys = shade_phases([a1, a2], gait_spans(result), legend_ax=a1)
        for a, extra in ((a1, keys), (a2, [])):
            a.grid(alpha=0.3)
            handles = a.get_legend_handles_labels()[0] + extra
            if handles:
                legend_outside(a, handles=handles)
    a2.set_xlabel("time [s]")
    title(fig, axes, f"{result.scenario.name}: connector and net forces", own)
    return fig


def moving_groups(result):
    """The segments that move together, one tuple per phase of an inchworm gait (the supervisor's
    inching gait too; else None)."""
    phases = getattr(result.scenario.mode, "phases", None)
    inching = getattr(result.scenario.mode, "inching_config", None)
    if not callable(phases) and callable(inching):
        phases = inching().phases
    if not callable(phases):
        return None
    groups = [tuple(int(k) for k in ph) for ph in phases()]
    rest = tuple(k for k in range(result.n_segments) if not any(k in g for g in groups))
    return groups + ([rest] if rest else [])


def _setpoint_chart(a, fig, result):
    """The wheel-speed set-point of every segment against time as a colour chart (one row each)."""
    t = result.t
    sp = result.segments["speed_setpoint_mps"]
    te = np.concatenate([t[:1], (t[1:] + t[:-1]) / 2, t[-1:]]) if t.size > 1 else np.array([t[0], t[0] + 1])
    n = sp.shape[1]
    lo, hi = float(np.min(sp)), float(np.max(sp))
    m = a.pcolormesh(
        te,
        np.arange(n + 1) - 0.5,
        sp.T,
        cmap="cividis",
        shading="flat",
        vmin=lo,
        vmax=hi if hi > lo else lo + 1e-3,
        rasterized=True,
    )
    a.set_yticks(range(n), [str(k) for k in range(n)])
    a.invert_yaxis()
    a.set_ylabel("segment\n(0 = leader)")
    fig.colorbar(m, ax=a, label="wheel-speed\nset-point [m/s]", pad=0.01)


def _switching_setpoints(result) -> bool:
    """True when the set-points switch between a few values (a gait), better read as a chart;
    False when they vary smoothly or stay put (force control, uniform), better read as lines."""
    sp = np.round(result.segments["speed_setpoint_mps"], 9)
    jumps = (np.diff(sp, axis=0) != 0).sum(0)
    return np.unique(sp).size <= 4 and int(jumps.max(initial=0)) >= 2


def _setpoint_lines(a, result):
    t, sp = result.t, result.segments["speed_setpoint_mps"]
    for k in range(sp.shape[1]):
        a.plot(t, sp[:, k], label=seg_label(k), **series_style(k, t.size, sp.shape[1]))
    a.set_ylabel("wheel-speed\nset-point [m/s]")
    a.grid(alpha=0.3)
    legend_outside(a)


def _legend_with_phase(a, grp, spans, axes=None):
    """The panel's legend, with a patch keying the shading of the gait phase in which ``grp`` moves
    (or the grey band of a gait too fast to shade phase by phase, :func:`.phases.readable` on
    ``axes``)."""
    handles = a.get_legend_handles_labels()[0]
    if spans and not readable(axes or [a], spans):
        n = sum(c for *_, c in gait_blocks(spans))
        handles.append(Patch(color=GAIT_COLOUR, label=f"gait ({n} cycles)"))
    else:
        key = ", ".join(str(k) for k in grp)
        phases = sorted({k for *_, k, moving in spans if moving == key})
        if phases:
            handles.append(Patch(color=PHASE_COLOURS[phases[0] % len(PHASE_COLOURS)], label="their phase"))
    legend_outside(a, handles=handles)


def _shared_setpoint(result):
    """The wheel-speed set-point series when every segment has the same one (uniform mode: drawn as
    a reference line in the speed panel, not as a panel of its own), else None."""
    sp = result.segments["speed_setpoint_mps"]
    if sp.shape[1] and np.all(sp == sp[:, :1]):
        return sp[:, 0]
    return None


def _setpoint_reference(a, t, sp, v):
    """The shared set-point as a dashed line in the speed panel ``a``, or a note where it lies far off
    the speeds' scale (it would squash them into a flat band)."""
    top = max(float(np.max(np.abs(v))), 1e-9)
    if float(np.max(sp)) <= 2.0 * top:
        a.plot(t, sp, color="0.35", ls=(0, (4, 2)), lw=1.0, label="wheel-speed set-point\n(every segment)", zorder=1)
    else:
        a.text(
            0.99,
            0.97,
            f"wheel-speed set-point {float(np.max(sp)):.2f} m/s (off scale)",
            transform=a.transAxes,
            ha="right",
            va="top",
            fontsize=small_pt(),
            color="0.35",
        )


@figure_function
def plot_groups(result, groups=None, *, ax=None, fig=None):
    """Ground speed of the segments that move together, one panel per group (paper Fig 5).

    ``groups``: tuples of segment indices (default: the inchworm gait's phases).  Gait phases are
    shaded (a colour per phase).  Returns the Figure.
    """
    own = ax is None and fig is None
    groups = list(groups if groups is not None else moving_groups(result) or [tuple(range(result.n_segments))])
    fig, axes = new_figure(ax, fig, len(groups), 1, figsize=(9, 2.0 * len(groups) + 0.8), sharex=True)
    t, v = result.t, result.segments["v_mps"]
    for a, grp in zip(axes[:, 0], groups):
        for k in grp:
            a.plot(t, v[:, k], label=seg_label(k), lw=1.4, **series_style(k, t.size, len(grp)))
        a.axhline(0.0, color="0.5", lw=0.6)
        a.set_ylabel("speed [m/s]")
        a.grid(alpha=0.3)
    spans = gait_spans(result)
    shade_phases(list(axes[:, 0]), spans)
    for a, grp in zip(axes[:, 0], groups):
        _legend_with_phase(a, grp, spans, list(axes[:, 0]))
    axes[-1, 0].set_xlabel("time [s]")
    title(
        fig,
        axes,
        f"{result.scenario.name}: ground speed of segments moving together "
        f"(X_t = {result.segments['xt'][0].mean():.2f})",
        own,
    )
    return fig


@figure_function
def plot_speeds(result, *, ax=None, fig=None):
    """Ground speed per segment and the wheel-speed set-points against time (paper Figs 5, 8, 9, 11).

    An inchworm run gets one speed panel per moving group (as the paper's Fig 5), other modes
    one panel with every segment (distinct colour, line style and marker each; the markers of
    coinciding traces in turn).  A set-point every segment shares (uniform mode) is a dashed line in
    the speed panel; otherwise a last panel shows the set-points: as a chart (a row per segment, a
    colour per value) when they switch between a few values (a gait), else as lines.  Gait phases
    are shaded (one grey band when too short to read, :func:`.phases.readable`).  ``ax``: one axes
    per panel.  Returns the Figure.
    """
    own = ax is None and fig is None
    groups = moving_groups(result) or [tuple(range(result.n_segments))]
    n = len(groups)
    shared = _shared_setpoint(result)
    chart = shared is None and _switching_setpoints(result)
    panels = n + (shared is None)
    last = max(1.0, 0.25 * result.n_segments) if chart else 1.6
    fig, axes = new_figure(
        ax,
        fig,
        panels,
        1,
        figsize=(9, 1.9 * n + (2.6 if shared is None else 0.8)),
        sharex=True,
        gridspec_kw={"height_ratios": [2.2] * n + ([last] if shared is None else [])},
    )
    t, v = result.t, result.segments["v_mps"]
    for a, grp in zip(axes[:n, 0], groups):
        for k in grp:
            a.plot(t, v[:, k], label=seg_label(k), lw=1.3, **series_style(k, t.size, len(grp)))
        if shared is not None:
            _setpoint_reference(a, t, shared, v)
        a.set_ylabel("ground speed\n[m/s]")
        a.grid(alpha=0.3)
    spans = gait_spans(result)
    shade_phases(list(axes[:n, 0]), spans)
    for a, grp in zip(axes[:n, 0], groups):
        _legend_with_phase(a, grp, spans, list(axes[:n, 0]))
    if chart:
        _setpoint_chart(axes[n, 0], fig, result)
    elif shared is None:
        _setpoint_lines(axes[n, 0], result)
    axes[-1, 0].set_xlabel("time [s]")
    title(fig, axes, f"{result.scenario.name}: speeds" + (" (one panel per moving group)" if n > 1 else ""), own)
    return fig


def _terrain_varies(result, xs):
    X = np.asarray(result.scenario.terrain.compile()(xs), float)
    return bool(np.ptp(X) > 1e-12), X


@figure_function
def plot_positions(result, *, ax=None, fig=None):
    """Position-time diagram of every segment (paper Fig 4), beside the terrain coefficient
    X_t(x) when the terrain varies along the way (a narrow side panel).  Gait phases are shaded;
    mode switches (supervisor) are marked lines.  Returns the Figure."""
    own = ax is None and fig is None
    t, x = result.t, result.segments["x_m"]
    xs = np.linspace(x.min() - 1.0, x.max() + 1.0, 400)
    varies, X = _terrain_varies(result, xs)
    if ax is not None:
        varies = varies and np.asarray(ax, dtype=object).size == 2
    if varies:
        fig, axes = new_figure(ax, fig, 1, 2, figsize=(10, 5), sharey=True, gridspec_kw={"width_ratios": [1, 4]})
        a0, a1 = axes[0]
        a0.plot(X, xs, color="#8c510a")
        a0.set_xlabel("X_t")
        a0.xaxis.set_major_locator(MaxNLocator(2))
        a0.set_ylabel("position [m]")
        a0.grid(alpha=0.3)
    else:
        fig, axes = new_figure(ax, fig, 1, 1, figsize=(9, 5))
        a1 = axes[0, 0]
        a1.set_ylabel("position [m]")
    for k in range(x.shape[1]):
        a1.plot(t, x[:, k], label=seg_label(k), **series_style(k, t.size, x.shape[1]))
    phase_keys = shade_phases([a1], gait_spans(result), legend_ax=a1)
    # mode switches (supervisor mode): a marked line at the switch, the leader's position there
    sw_style = {
        "switch_to_inching": ("#D55E00", "v", "to inching"),
        "switch_to_rolling": ("#009E73", "^", "to rolling"),
    }
    for ev in result.events:
        if ev.get("kind") in sw_style:
            c, mk, lab = sw_style[ev["kind"]]
            a1.axvline(ev["t_s"], color=c, lw=1.0, ls="--", zorder=1)
            a1.plot([ev["t_s"]], [ev["x_m"]], mk, color=c, ms=6, zorder=3)
            right = ev["t_s"] > 0.6 * t[-1]  # label on the inner side of the line, inside the axes
            a1.annotate(
                lab,
                (ev["t_s"], ev["x_m"]),
                textcoords="offset points",
                xytext=(-4 if right else 4, 6),
                ha="right" if right else "left",
                fontsize=small_pt(),
                color=c,
            )
    a1.set_xlabel("time [s]")
    handles = a1.get_legend_handles_labels()[0] + phase_keys
    if varies and own and fig.get_figwidth() < 5.0:  # narrow, with the side panel: the legend over both
        fig.legend(handles=handles, loc="outside lower center", ncol=3, frameon=False, columnspacing=1.0)
    else:
        legend_outside(a1, handles=handles)
    a1.grid(alpha=0.3)
    title(
        fig,
        axes,
        f"{result.scenario.name}: position-time diagram"
        + ("" if varies else f" (X_t = {X[0]:g} throughout, {_grade_words(result)})"),
        own,
    )
    return fig


def _grade_words(result) -> str:
    """The grade of the run's terrain in words: "level", "10 deg grade" or "grades up to 5.2 deg"."""
    elev = result.scenario.terrain.elevation_profile()
    if elev is None or elev.is_level:
        return "level"
    if elev.is_constant:
        g = float(elev.grade_deg)
        return f"{abs(g):g} deg {'uphill' if g > 0 else 'downhill'} grade"
    return f"grades up to {elev.max_abs_grade_deg():.1f} deg"


def cycle_means(result):
    """The chain's speed averaged over each gait cycle (and sample by sample outside the gait):
    ``(position_m, speed_mps, lowest_mps, highest_mps, t_start_s)`` arrays, the chain's mean position
    at the middle of each window, its mean advance per second over the window, the slowest and
    fastest segment's speed in it (the envelope) and the window's start time.  A gait cycle runs from one start of the gait's first
    phase to the next (:func:`.phases.gait_spans`)."""
    t, x, v = result.t, result.segments["x_m"], result.segments["v_mps"]
    xc = x.mean(1)
    spans = gait_spans(result)
    blocks = gait_blocks(spans)
    first = spans[0][2] if spans else None
    inside = np.zeros(t.size, bool)
    for b0, b1, _ in blocks:
        inside |= (t >= b0 - 1e-9) & (t < b1 - 1e-9)
    cuts = [t0 for t0, _, k, _ in spans if k == first] + [b1 for _, b1, _ in blocks]
    edges = set(np.flatnonzero(~inside).tolist()) | set(np.searchsorted(t, np.array(cuts) - 1e-9).tolist())
    edges = sorted(e for e in edges if e < t.size)
    pos, spd, lo, hi, ts = [], [], [], [], []
    for e0, e1 in zip(edges[:-1], edges[1:]):
        dt = t[e1] - t[e0]
        if dt <= 0:
            continue
        pos.append(0.5 * (xc[e0] + xc[e1]))
        spd.append((xc[e1] - xc[e0]) / dt)
        lo.append(float(v[e0 : e1 + 1].min()))
        hi.append(float(v[e0 : e1 + 1].max()))
        ts.append(float(t[e0]))
    return np.array(pos), np.array(spd), np.array(lo), np.array(hi), np.array(ts)


def _route_speeds(a0, result):
    """The speed panel of the route figure: each segment's speed against its position for a rolling
    run; the chain's cycle-averaged speed (and the segments' envelope) for a run with a gait."""
    x, v = result.segments["x_m"], result.segments["v_mps"]
    if not gait_spans(result):
        for k in range(x.shape[1]):
            a0.plot(x[:, k], v[:, k], label=seg_label(k), lw=1.2, **series_style(k, x.shape[0], x.shape[1]))
        return
    pos, spd, lo, hi, _ = cycle_means(result)
    a0.fill_between(pos, lo, hi, color="#cfe3f3", lw=0, label="segments' range", zorder=0)
    a0.plot(pos, spd, color=COLOURS_ROUTE, lw=1.4, label="chain, cycle mean")


COLOURS_ROUTE = "#0072B2"


def _route_marks(axes, result):
    """Patches of other snow (shaded spans) and the supervisor's mode switches (lines at the
    leader's position) on every panel of the route figure; returns their legend handles."""
    handles = []
    for p in result.scenario.terrain.patches or ():
        for a in axes:
            a.axvspan(p.start_m, p.end_m, color="#8c510a", alpha=0.12, lw=0, zorder=0)
    if result.scenario.terrain.patches:
        handles.append(Patch(color="#8c510a", alpha=0.12, label="patch of other snow"))
    styles = {"switch_to_inching": ("#D55E00", "to inching"), "switch_to_rolling": ("#009E73", "to rolling")}
    seen = set()
    xc = result.segments["x_m"].mean(1)
    for ev in result.events:
        if ev.get("kind") in styles:
            c, lab = styles[ev["kind"]]
            at = float(np.interp(ev["t_s"], result.t, xc))  # the chain's centre, as the speed curve
            for a in axes:
                a.axvline(at, color=c, ls="--", lw=1.0, zorder=1)
            if lab not in seen:
                seen.add(lab)
                handles.append(Line2D([], [], color=c, ls="--", lw=1.0, label=f"switch {lab}"))
    return handles


def route_varies(result) -> bool:
    """True when the run's terrain changes along the way (a grade, a route, patches, an X_t
    profile): the route figure is drawn for it."""
    terrain = result.scenario.terrain
    if terrain.elevation_profile() is not None:
        return True
    x = result.segments["x_m"]
    return _terrain_varies(result, np.linspace(x.min() - 1.0, x.max() + 1.0, 400))[0]


#: ``Result.plot(kind)``: kind -> function drawing it.
@figure_function
def plot_route(result, *, ax=None, fig=None):
    """The run along the route (docs/model.md section 7): speed against position over the elevation
    z(s), the grade [deg] and X_t(s) of the stretch driven (shared distance axis).

    Speed: each segment's against its position for a rolling run; for a run with a gait (inchworm,
    the supervisor's inching) the chain's speed averaged over each gait cycle, with the range of the
    segments' speeds as a light band (the raw speeds of a gait are a comb), against the chain's centre
    (mean position).  The grade and X_t get a
    panel when they change along the stretch, else they are named in the title.  Patches of other
    snow are shaded and mode switches marked (at the chain's centre) on every panel; the elevation
    panel is left out on level ground.  Drawn for every run on a grade or on
    terrain that changes along the way.  ``ax``: as many axes as panels (1 to 4).  Returns the Figure.
    """
    own = ax is None and fig is None
    x = result.segments["x_m"]
    xs = np.linspace(x.min() - 1.0, x.max() + 1.0, 600)
    elev = result.scenario.terrain.elevation_profile()
    z = np.zeros_like(xs) if elev is None else np.asarray(elev.elevation(xs), float)
    grade = np.degrees(np.arcsin(np.clip(np.gradient(z, xs), -1.0, 1.0)))  # z is along the track: dz/ds = sin
    X = np.asarray(result.scenario.terrain.compile()(xs), float)
    show_elev = elev is not None and not elev.is_level
    show_grade, show_xt = bool(np.ptp(grade) > 1e-6), bool(np.ptp(X) > 1e-12)
    heights = [2.2] + [1.2] * show_elev + [1.0] * show_grade + [1.0] * show_xt
    if own:  # room for the legend above the panels on a narrow figure: one row more
        fig = blank_figure((9, 1.5 * sum(heights) + 1.2), len(heights) + 1)
    fig, axes = new_figure(ax, fig, len(heights), 1, sharex=True, gridspec_kw={"height_ratios": heights})
    col = list(axes[:, 0])
    a0 = col[0]
    _route_speeds(a0, result)
    a0.set_ylabel("ground speed\n[m/s]")
    rest = iter(col[1:])
    if show_elev:
        a1 = next(rest)
        a1.fill_between(xs, z.min() - 0.05 * (np.ptp(z) + 1.0), z, color="#d9d9d9")
        a1.plot(xs, z, color="0.25")
        a1.set_ylabel("elevation\n[m]")
    if show_grade:
        a2 = next(rest)
        a2.plot(xs, grade, color="0.25")
        a2.axhline(0.0, color="0.6", lw=0.5)
        a2.set_ylabel("grade\n[deg]")
    if show_xt:
        a3 = next(rest)
        a3.plot(xs, X, color="#8c510a")
        a3.set_ylabel("X_t")
    col[-1].set_xlabel("distance along the route [m]")
    extra = _route_marks(col, result)
    handles = a0.get_legend_handles_labels()[0] + extra
    legend_outside(a0, handles=handles, **({} if fig.get_figwidth() >= 5.0 else {"ncol": 2}))
    for a in col:
        a.grid(alpha=0.3)
    words = [] if show_xt else [f"X_t = {X[0]:g} throughout"]
    words += [] if show_grade else [_grade_words(result)]
    title(
        fig,
        axes,
        f"{result.scenario.name}: speed along the route" + (f" ({', '.join(words)})" if words else ""),
        own,
    )
    return fig


# -------------------------------------------------------- the force diagram (force_diagram.png)
def _diagram_box(a, x0, y0, k, n, W, ahead, behind, sp, fmax):
    """One segment of the force diagram at (x0, y0): the box, its arrows and their values."""
    scale = 0.9 / fmax  # the longest arrow is 0.9 box spacings
    a.add_patch(Rectangle((x0 - 0.45, y0 - 0.3), 0.9, 0.6, fc="0.9", ec="0.2"))
    a.text(x0, y0, f"{seg_label(k)}\n{sp[k]:.3f} m/s", ha="center", va="center", fontsize=small_pt())
    rows = [
        (-0.75, W[k], "#009E73", f"wheels {force_text(W[k])}"),
        (0.6, ahead[k], "#0072B2", f"ahead {force_text(ahead[k])}" if k else None),
        (
            0.95,
            behind[k],
            "#D55E00" if k < n - 1 else "#CC79A7",
            f"behind {force_text(behind[k])}" if k < n - 1 else f"tow {force_text(behind[k])}",
        ),
    ]
    for yy, F, c, lab in rows:
        if lab is None:
            continue
        if abs(F) > 1e-9 * fmax:
            a.annotate(
                "",
                xy=(x0 + F * scale / 2, y0 + yy),
                xytext=(x0 - F * scale / 2, y0 + yy),
                arrowprops=dict(arrowstyle="-|>", color=c, lw=1.5),
            )
        else:
            a.plot([x0], [y0 + yy], "o", color=c, ms=4)
        a.text(x0, y0 + yy + 0.1, lab, ha="center", va="bottom", fontsize=small_pt(), color=c)
    a.text(x0, y0 - 1.05, f"connectors {force_text(ahead[k] + behind[k])}", ha="center", va="top", fontsize=small_pt())


@figure_function
def plot_force_diagram(result, window_s=1.0, *, ax=None, fig=None):
    """Steady-state force diagram of the chain (paper Fig 10): the forces acting on each segment.

    Each segment is a box with its wheel-speed set-point (the leader on the right, travel to the
    right; rows of boxes when the figure is too narrow for one).  Below it, the net wheel force
    (traction − resistance); above it, the force of the link ahead (``T_{k-1}``, pulling forward
    when in tension) and of the link behind (``-T_k``) or the tow; under it, the connectors' net
    force.  Values are means over the last ``window_s`` seconds of the run; arrows point the way
    the force acts on the segment and their length is proportional to it.  Returns the Figure.
    """
    t = result.t
    last = t >= t[-1] - window_s
    W = result.segments["net_force_N"][last].mean(0)
    T = result.links["force_N"][last].mean(0) if result.links["force_N"].shape[1] else np.zeros(0)
    sp = result.segments["speed_setpoint_mps"][last].mean(0)
    n = W.size
    ahead = np.concatenate([[0.0], T])  # force of the link ahead, forward positive
    behind = -np.concatenate([T, [float(result.scenario.tow.force_N)]])  # link behind (or tow), forward +
    fmax = max(np.max(np.abs(np.concatenate([W, ahead, behind]))), 1.0)
    width = target_width()
    if ax is not None:
        a0 = np.atleast_1d(np.asarray(ax, dtype=object)).flat[0]
        width = a0.get_position().width * a0.get_figure().get_figwidth()
    per_row = max(1, min(n, int(width / 1.7)))
    nrow = -(-n // per_row)
    fig, axes = new_figure(ax, fig, 1, 1, figsize=(width, 1.75 * nrow + 0.5))
    a = axes[0, 0]

    def pos(k):
        return ((per_row - 1 - k % per_row) * 2.0, -3.2 * (k // per_row))  # leader on the right

    for k in range(n):
        _diagram_box(a, *pos(k), k, n, W, ahead, behind, sp, fmax)
    for j in range(n - 1):
        if j // per_row == (j + 1) // per_row:
            (x0, y0), (x1, _) = pos(j), pos(j + 1)
            a.text(
                (x0 + x1) / 2,
                y0,
                f"T{j}\n{force_text(T[j])}",
                ha="center",
                va="center",
                fontsize=small_pt(),
                color="0.3",
            )
    a.set_xlim(-1.1, 2.0 * (per_row - 1) + 1.1)
    a.set_ylim(-3.2 * (nrow - 1) - 1.75, 1.5)
    a.axis("off")
    a.set_title(
        wrap_title(
            f"{result.scenario.name}: steady-state forces on each segment (mean of the last "
            f"{window_s:g} s; tension positive; travel \u2192)",
            width,
        )
    )
    return fig


PLOT_KINDS = {
    "forces": plot_forces,
    "speeds": plot_speeds,
    "positions": plot_positions,
    "force_diagram": plot_force_diagram,
    "groups": plot_groups,
    "route": plot_route,
}


def plot_result(result, out_dir, fmt: str = "png", size=None) -> list:
    """Every standard plot of a run, saved in ``out_dir``: ``forces``, ``speeds``, ``positions``
    (and the mode's extra plots, e.g. ``force_diagram``; ``route`` on a grade), as ``fmt`` files
    (png, pdf, svg), at print ``size`` (``column``, ``page`` or ``WxH``; default page width).
    Headless figures (:func:`~snoworm.plotting.style.headless`).

    Returns the paths written.
    """
    out = Path(out_dir)
    names = ["forces", "speeds", "positions"] + list(getattr(result.scenario.mode, "extra_plots", ()))
    names += ["route"] if route_varies(result) else []
    return [write_figure(out / f"{name}.{fmt}", PLOT_KINDS[name], result, fmt=fmt, size=size) for name in names]
