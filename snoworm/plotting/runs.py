"""Figures of one run (a :class:`~snoworm.results.result.Result`): forces, speeds, positions, the
steady-state force diagram.  Each function draws on new or given axes and returns the Figure."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.patches import Rectangle

from .style import force_text, legend_outside, new_figure, save, series_style

__all__ = ["plot_forces", "plot_speeds", "plot_positions", "plot_force_diagram", "plot_groups", "plot_result",
           "moving_groups", "plot_route", "PLOT_KINDS"]


def _seg_label(k):
    return "leader 0" if k == 0 else f"follower {k}"


def _title(fig, axes, text, own):
    """A title on the figure (our own figure) or on the first panel (the user's axes/figure)."""
    if own:
        fig.suptitle(text, fontsize=10)
    else:
        axes.flat[0].set_title(text, fontsize=9)


def plot_forces(result, *, ax=None, fig=None):
    """Connector (link) forces and net wheel force per segment against time (paper Figs 6-9).

    ``ax``: two axes (links, segments) of your own; ``fig``: a figure to draw in.  Returns the Figure.
    """
    own = ax is None and fig is None
    fig, axes = new_figure(ax, fig, 2, 1, figsize=(9, 6.5), sharex=True)
    a1, a2 = axes[:, 0]
    t = result.t
    F = result.links["force_N"]
    for j in range(F.shape[1]):
        a1.plot(t, F[:, j], label=f"link {j} ({j}-{j + 1})", **series_style(j, t.size))
    if result.scenario.tow.force_N:
        a1.axhline(result.scenario.tow.force_N, color="0.5", ls=":", lw=1, label="tow")
    a1.set_ylabel("connector force [N]\n(tension +)")
    net = result.segments["net_force_N"]
    for k in range(net.shape[1]):
        a2.plot(t, net[:, k], label=_seg_label(k), **series_style(k, t.size))
    a2.set_ylabel("net wheel force [N]\n(forward +)")
    a2.set_xlabel("time [s]")
    for a in (a1, a2):
        a.grid(alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            legend_outside(a)
    _title(fig, axes, f"{result.scenario.name}: connector and net forces", own)
    return fig


def moving_groups(result):
    """The segments that move together, one tuple per phase of an inchworm gait (else None)."""
    phases = getattr(result.scenario.mode, "phases", None)
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
    m = a.pcolormesh(te, np.arange(n + 1) - 0.5, sp.T, cmap="cividis", shading="flat",
                     vmin=lo, vmax=hi if hi > lo else lo + 1e-3, rasterized=True)
    a.set_yticks(range(n), [_seg_label(k) for k in range(n)], fontsize=7)
    a.invert_yaxis()
    a.set_ylabel("segment")
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
        a.plot(t, sp[:, k], label=_seg_label(k), **series_style(k, t.size))
    a.set_ylabel("wheel-speed\nset-point [m/s]")
    a.grid(alpha=0.3)
    legend_outside(a)


def plot_groups(result, groups=None, *, ax=None, fig=None):
    """Ground speed of the segments that move together, one panel per group (paper Fig 5).

    ``groups``: tuples of segment indices (default: the inchworm gait's phases).  Gait phase
    changes are faint vertical lines.  Returns the Figure.
    """
    own = ax is None and fig is None
    groups = list(groups if groups is not None else moving_groups(result) or [tuple(range(result.n_segments))])
    fig, axes = new_figure(ax, fig, len(groups), 1, figsize=(9, 2.0 * len(groups) + 0.8), sharex=True)
    t, v = result.t, result.segments["v_mps"]
    for a, grp in zip(axes[:, 0], groups):
        for k in grp:
            a.plot(t, v[:, k], label=_seg_label(k), lw=1.4, **series_style(k, t.size))
        for ev in result.events:
            if ev.get("kind") == "phase_change":
                a.axvline(ev["t_s"], color="0.85", lw=0.6, zorder=0)
        a.axhline(0.0, color="0.5", lw=0.6)
        a.set_ylabel("speed [m/s]")
        a.grid(alpha=0.3)
        legend_outside(a)
    axes[-1, 0].set_xlabel("time [s]")
    _title(fig, axes, f"{result.scenario.name}: ground speed of segments moving together "
                      f"(X_t = {result.segments['xt'][0].mean():.2f})", own)
    return fig


def plot_speeds(result, *, ax=None, fig=None):
    """Ground speed per segment and the wheel-speed set-points against time (paper Figs 5, 8, 9, 11).

    An inchworm run gets one speed panel per moving group (as the paper's Fig 5), other modes
    one panel with every segment (distinct colour, line style and marker each).  The last panel
    shows the set-points: as a chart (a row per segment, a colour per value) when they switch
    between a few values (a gait), else as lines.  Returns the Figure.
    """
    own = ax is None and fig is None
    groups = moving_groups(result) or [tuple(range(result.n_segments))]
    n = len(groups)
    chart = _switching_setpoints(result)
    last = max(1.0, 0.25 * result.n_segments) if chart else 1.6
    fig, axes = new_figure(ax, fig, n + 1, 1, figsize=(9, 1.9 * n + 2.6), sharex=True,
                           gridspec_kw={"height_ratios": [2.2] * n + [last]})
    t, v = result.t, result.segments["v_mps"]
    for a, grp in zip(axes[:n, 0], groups):
        for k in grp:
            a.plot(t, v[:, k], label=_seg_label(k), lw=1.3, **series_style(k, t.size))
        a.set_ylabel("ground speed\n[m/s]")
        a.grid(alpha=0.3)
        legend_outside(a)
    if chart:
        _setpoint_chart(axes[n, 0], fig, result)
    else:
        _setpoint_lines(axes[n, 0], result)
    axes[-1, 0].set_xlabel("time [s]")
    _title(fig, axes, f"{result.scenario.name}: speeds" + (" (one panel per moving group)" if n > 1 else ""), own)
    return fig


def _terrain_varies(result, xs):
    X = np.asarray(result.scenario.terrain.compile()(xs), float)
    return bool(np.ptp(X) > 1e-12), X


def plot_positions(result, *, ax=None, fig=None):
    """Position-time diagram of every segment (paper Fig 4), beside the terrain coefficient
    X_t(x) when the terrain varies along the way (a narrow side panel).  Returns the Figure."""
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
        a0.set_xlabel("terrain coefficient X_t")
        a0.set_ylabel("position [m]")
        a0.grid(alpha=0.3)
    else:
        fig, axes = new_figure(ax, fig, 1, 1, figsize=(9, 5))
        a1 = axes[0, 0]
        a1.set_ylabel("position [m]")
    for k in range(x.shape[1]):
        a1.plot(t, x[:, k], label=_seg_label(k), **series_style(k, t.size))
    for ev in result.events:
        a1.axvline(ev["t_s"], color="0.85", lw=0.6, zorder=0)
    # mode switches (supervisor mode): a marked line at the switch, the leader's position there
    sw_style = {"switch_to_inching": ("#D55E00", "v", "to inching"), "switch_to_rolling": ("#009E73", "^", "to rolling")}
    for ev in result.events:
        if ev.get("kind") in sw_style:
            c, mk, lab = sw_style[ev["kind"]]
            a1.axvline(ev["t_s"], color=c, lw=1.0, ls="--", zorder=1)
            a1.plot([ev["t_s"]], [ev["x_m"]], mk, color=c, ms=9, zorder=3)
            a1.annotate(lab, (ev["t_s"], ev["x_m"]), textcoords="offset points", xytext=(4, 6), fontsize=8, color=c)
    a1.set_xlabel("time [s]")
    legend_outside(a1)
    a1.grid(alpha=0.3)
    _title(fig, axes, f"{result.scenario.name}: position-time diagram"
                      + ("" if varies else f" (uniform terrain, X_t = {X[0]:g})"), own)
    return fig


def plot_force_diagram(result, window_s=1.0, *, ax=None, fig=None):
    """Steady-state force diagram of the chain (paper Fig 10): the forces acting on each segment.

    Each segment is a box (the leader on the right, travel to the right).  Below it, the net
    wheel force (traction - resistance); above it, the force of the link ahead (``T_{k-1}``,
    pulling forward when in tension) and of the link behind (``-T_k``) or the tow.  Values are
    means over the last ``window_s`` seconds of the run; arrows point the way the force acts on
    the segment and their length is proportional to it.  Returns the Figure.
    """
    t = result.t
    last = t >= t[-1] - window_s
    W = result.segments["net_force_N"][last].mean(0)
    T = result.links["force_N"][last].mean(0) if result.links["force_N"].shape[1] else np.zeros(0)
    sp = result.segments["speed_setpoint_mps"][last].mean(0)
    n = W.size
    tow = float(result.scenario.tow.force_N)
    ahead = np.concatenate([[0.0], T])             # force of the link ahead, forward positive
    behind = -np.concatenate([T, [tow]])           # force of the link behind (or tow), forward positive
    fmax = max(np.max(np.abs(np.concatenate([W, ahead, behind]))), 1.0)
    scale = 0.9 / fmax                             # the longest arrow is 0.9 box spacings
    fig, axes = new_figure(ax, fig, 1, 1, figsize=(2.6 * n + 1.5, 4.2))
    a = axes[0, 0]
    pos = (n - 1 - np.arange(n)) * 2.0            # box centres, leader on the right
    for k in range(n):
        x0 = pos[k]
        a.add_patch(Rectangle((x0 - 0.45, -0.3), 0.9, 0.6, fc="0.9", ec="0.2"))
        a.text(x0, 0.0, f"{_seg_label(k)}\nset-point {sp[k]:.3f} m/s", ha="center", va="center", fontsize=8)
        rows = [(-0.75, W[k], "#009E73", f"wheels {force_text(W[k])}"),
                (0.6, ahead[k], "#0072B2", f"link ahead {force_text(ahead[k])}" if k else None),
                (0.95, behind[k], "#D55E00" if k < n - 1 else "#CC79A7",
                 f"link behind {force_text(behind[k])}" if k < n - 1 else f"tow {force_text(behind[k])}")]
        for yy, F, c, lab in rows:
            if lab is None:
                continue
            if abs(F) > 1e-9 * fmax:
                a.annotate("", xy=(x0 + F * scale / 2, yy), xytext=(x0 - F * scale / 2, yy),
                           arrowprops=dict(arrowstyle="-|>", color=c, lw=2))
            else:
                a.plot([x0], [yy], "o", color=c, ms=4)
            a.text(x0, yy + 0.12, lab, ha="center", va="bottom", fontsize=7.5, color=c)
        a.text(x0, -1.1, f"net connector {force_text(ahead[k] + behind[k])}", ha="center", va="top", fontsize=7.5)
    for j in range(n - 1):
        a.text((pos[j] + pos[j + 1]) / 2, 0.0, f"T{j}\n{force_text(T[j])}", ha="center", va="center", fontsize=8,
               color="0.3")
    a.annotate("travel", xy=(pos[0] + 0.9, -1.55), xytext=(pos[0] + 0.2, -1.55),
               arrowprops=dict(arrowstyle="-|>", color="0.4"), va="center", fontsize=8, color="0.4")
    a.set_xlim(-1.1, pos[0] + 1.1)
    a.set_ylim(-1.75, 1.35)
    a.axis("off")
    a.set_title(f"{result.scenario.name}: steady-state forces on each segment "
                f"(mean of the last {window_s:g} s; tension positive)", fontsize=9)
    return fig


#: ``Result.plot(kind)``: kind -> function drawing it.
def plot_route(result, *, ax=None, fig=None):
    """The run along the route (docs/model.md section 7): each segment's ground speed against its
    position, over the elevation z(s) and the terrain coefficient X_t(s) of the stretch driven
    (shared distance axis).  Drawn for every run on a grade.  Returns the Figure."""
    own = ax is None and fig is None
    x, v = result.segments["x_m"], result.segments["v_mps"]
    fig, axes = new_figure(ax, fig, 3, 1, figsize=(9, 7.5), sharex=True, gridspec_kw={"height_ratios": [2.2, 1.4, 1.0]})
    a0, a1, a2 = axes[:, 0]
    for k in range(x.shape[1]):
        a0.plot(x[:, k], v[:, k], label=_seg_label(k), lw=1.2, **series_style(k, x.shape[0]))
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
    _title(fig, axes, f"{result.scenario.name}: speeds along the route, elevation and X_t", own)
    return fig


PLOT_KINDS = {"forces": plot_forces, "speeds": plot_speeds, "positions": plot_positions,
              "force_diagram": plot_force_diagram, "groups": plot_groups, "route": plot_route}


def plot_result(result, out_dir, fmt: str = "png") -> list:
    """Every standard plot of a run, saved in ``out_dir``: ``forces``, ``speeds``, ``positions``
    (and the mode's extra plots, e.g. ``force_diagram``; ``route`` on a grade), as ``fmt`` files (png, pdf, svg).

    Returns the paths written.
    """
    out = Path(out_dir)
    names = ["forces", "speeds", "positions"] + list(getattr(result.scenario.mode, "extra_plots", ()))
    names += ["route"] if result.scenario.terrain.elevation_profile() is not None else []
    return [save(PLOT_KINDS[name](result), out / f"{name}.{fmt}", fmt) for name in names]
