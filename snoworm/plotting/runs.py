"""Figures of one run (a :class:`~snoworm.results.result.Result`): forces, speeds, positions, the
steady-state force diagram.  Each function draws on new or given axes and returns the Figure."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.patches import Patch, Rectangle
from matplotlib.ticker import MaxNLocator

from .phases import PHASE_COLOURS, gait_spans, shade_phases
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
    """Links (left) and segments (right), one small panel each, shared axes."""
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
            a_l.text(0.01, 0.95, f"link {j} ({j}-{j + 1})", transform=a_l.transAxes, va="top", fontsize=small_pt())
        else:
            a_l.set_visible(False)
        a_s.plot(t, net[:, j], color="#D55E00", lw=1.0)
        a_s.text(0.01, 0.95, seg_label(j), transform=a_s.transAxes, va="top", fontsize=small_pt())
        for a in (a_l, a_s):
            a.grid(alpha=0.3)
            a.axhline(0.0, color="0.6", lw=0.5)
    shade_phases(list(axes.flat), gait_spans(result), legend_ax=None)
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
    :data:`MULTIPLES_MAX` links: two colour charts.
    Gait phases are shaded.  ``ax``: two axes (links, segments) of your own (lines); ``fig``: a
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
            a1.plot(t, F[:, j], label=f"link {j} ({j}-{j + 1})", **series_style(j, t.size))
        if result.scenario.tow.force_N:
            _tow_line(a1, result.scenario.tow.force_N, F)
        a1.set_ylabel("connector force [N]\n(tension +)")
        for k in range(net.shape[1]):
            a2.plot(t, net[:, k], label=seg_label(k), **series_style(k, t.size))
        a2.set_ylabel("net wheel force [N]\n(forward +)")
        for a in (a1, a2):
            a.grid(alpha=0.3)
            if a.get_legend_handles_labels()[0]:
                legend_outside(a)
        shade_phases([a1, a2], gait_spans(result), legend_ax=None)
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
        a.plot(t, sp[:, k], label=seg_label(k), **series_style(k, t.size))
    a.set_ylabel("wheel-speed\nset-point [m/s]")
    a.grid(alpha=0.3)
    legend_outside(a)


def _legend_with_phase(a, grp, spans):
    """The panel's legend, with a patch keying the shading of the gait phase in which ``grp`` moves."""
    handles = a.get_legend_handles_labels()[0]
    key = ", ".join(str(k) for k in grp)
    phases = sorted({k for *_, k, moving in spans if moving == key})
    if phases:
        handles.append(Patch(color=PHASE_COLOURS[phases[0] % len(PHASE_COLOURS)], label="their phase"))
    legend_outside(a, handles=handles)


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
            a.plot(t, v[:, k], label=seg_label(k), lw=1.4, **series_style(k, t.size))
        a.axhline(0.0, color="0.5", lw=0.6)
        a.set_ylabel("speed [m/s]")
        a.grid(alpha=0.3)
    spans = gait_spans(result)
    shade_phases(list(axes[:, 0]), spans)
    for a, grp in zip(axes[:, 0], groups):
        _legend_with_phase(a, grp, spans)
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
    one panel with every segment (distinct colour, line style and marker each).  The last panel
    shows the set-points: as a chart (a row per segment, a colour per value) when they switch
    between a few values (a gait), else as lines.  Gait phases are shaded.  Returns the Figure.
    """
    own = ax is None and fig is None
    groups = moving_groups(result) or [tuple(range(result.n_segments))]
    n = len(groups)
    chart = _switching_setpoints(result)
    last = max(1.0, 0.25 * result.n_segments) if chart else 1.6
    fig, axes = new_figure(
        ax, fig, n + 1, 1, figsize=(9, 1.9 * n + 2.6), sharex=True, gridspec_kw={"height_ratios": [2.2] * n + [last]}
    )
    t, v = result.t, result.segments["v_mps"]
    for a, grp in zip(axes[:n, 0], groups):
        for k in grp:
            a.plot(t, v[:, k], label=seg_label(k), lw=1.3, **series_style(k, t.size))
        a.set_ylabel("ground speed\n[m/s]")
        a.grid(alpha=0.3)
    spans = gait_spans(result)
    shade_phases(list(axes[:n, 0]), spans)
    for a, grp in zip(axes[:n, 0], groups):
        _legend_with_phase(a, grp, spans)
    if chart:
        _setpoint_chart(axes[n, 0], fig, result)
    else:
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
        a1.plot(t, x[:, k], label=seg_label(k), **series_style(k, t.size))
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
        f"{result.scenario.name}: position-time diagram" + ("" if varies else f" (uniform terrain, X_t = {X[0]:g})"),
        own,
    )
    return fig


#: ``Result.plot(kind)``: kind -> function drawing it.
@figure_function
def plot_route(result, *, ax=None, fig=None):
    """The run along the route (docs/model.md section 7): each segment's ground speed against its
    position, over the elevation z(s) and the terrain coefficient X_t(s) of the stretch driven
    (shared distance axis).  Drawn for every run on a grade.  Returns the Figure."""
    own = ax is None and fig is None
    x, v = result.segments["x_m"], result.segments["v_mps"]
    fig, axes = new_figure(ax, fig, 3, 1, figsize=(9, 7.5), sharex=True, gridspec_kw={"height_ratios": [2.2, 1.4, 1.0]})
    a0, a1, a2 = axes[:, 0]
    for k in range(x.shape[1]):
        a0.plot(x[:, k], v[:, k], label=seg_label(k), lw=1.2, **series_style(k, x.shape[0]))
    a0.set_ylabel("ground speed\n[m/s]")
    legend_outside(a0)
    xs = np.linspace(x.min() - 1.0, x.max() + 1.0, 600)
    elev = result.scenario.terrain.elevation_profile()
    z = np.zeros_like(xs) if elev is None else np.asarray(elev.elevation(xs), float)
    a1.fill_between(xs, z.min() - 0.05 * (np.ptp(z) + 1.0), z, color="#d9d9d9")
    a1.plot(xs, z, color="0.25")
    a1.set_ylabel("elevation\n[m]")
    a2.plot(xs, np.asarray(result.scenario.terrain.compile()(xs), float), color="#8c510a")
    a2.set_ylabel("X_t")
    a2.set_xlabel("distance along the route [m]")
    for a in (a0, a1, a2):
        a.grid(alpha=0.3)
    title(fig, axes, f"{result.scenario.name}: speeds along the route, elevation and X_t", own)
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
    names += ["route"] if result.scenario.terrain.elevation_profile() is not None else []
    return [write_figure(out / f"{name}.{fmt}", PLOT_KINDS[name], result, fmt=fmt, size=size) for name in names]
