"""More figures of one run: wheel slip, motor torque and power, energy along the run.

Each draws on new or given axes (``ax=``/``fig=``), at print ``size=``, and returns the Figure;
gait phases are shaded as in :mod:`.runs`.  Six segments or fewer share a panel (colour, line
style and marker each); more are drawn as colour charts, a row per segment.
"""

from __future__ import annotations

import numpy as np

from .phases import gait_spans, shade_phases
from .style import figure_function, legend_outside, new_figure, seg_label, series_style, title

__all__ = ["plot_slip", "plot_motor", "plot_energy", "per_segment"]

#: Above this many segments the per-segment series become colour charts.
LINES_MAX = 6


def per_segment(a, fig, t, Y, ylabel, symmetric=False, chart=False):
    """Per-segment series ``Y`` (n_t, N) on ``a``: a line each (<= :data:`LINES_MAX` and not
    ``chart``), else a colour chart (a row per segment; a gait's square waves read better so)."""
    if Y.shape[1] <= LINES_MAX and not chart:
        for k in range(Y.shape[1]):
            a.plot(t, Y[:, k], label=seg_label(k), **series_style(k, t.size, Y.shape[1]))
        a.set_ylabel(ylabel)
        a.grid(alpha=0.3)
        return False
    te = np.concatenate([t[:1], (t[1:] + t[:-1]) / 2, t[-1:]]) if t.size > 1 else np.array([t[0], t[0] + 1])
    lim = max(float(np.max(np.abs(Y))), 1e-9)
    m = a.pcolormesh(
        te,
        np.arange(Y.shape[1] + 1) - 0.5,
        Y.T,
        cmap="RdBu_r" if symmetric else "viridis",
        vmin=-lim if symmetric else float(np.min(Y)),
        vmax=lim if symmetric else float(np.max(Y)),
        shading="flat",
        rasterized=True,
    )
    a.invert_yaxis()
    a.set_yticks(range(Y.shape[1]), [str(k) for k in range(Y.shape[1])] if Y.shape[1] <= 12 else None)
    a.set_ylabel("segment\n(0 = leader)")
    fig.colorbar(m, ax=a, label=ylabel, pad=0.01)
    return True


@figure_function
def plot_slip(result, *, ax=None, fig=None):
    """Wheel slip of every segment against time (Eq. 1; mean of the axles; 1 = spinning in place,
    −1 = locked while sliding forward).  Returns the Figure."""
    own = ax is None and fig is None
    fig, axes = new_figure(ax, fig, 1, 1, figsize=(9, 4))
    a = axes[0, 0]
    chart = per_segment(
        a, fig, result.t, result.segments["slip"], "slip [-]", symmetric=True, chart=bool(gait_spans(result))
    )
    if not chart:
        a.axhline(0.0, color="0.5", lw=0.6)
        legend_outside(a)
    if not chart:
        shade_phases([a], gait_spans(result))
    a.set_xlabel("time [s]")
    title(fig, axes, f"{result.scenario.name}: wheel slip", own)
    return fig


@figure_function
def plot_motor(result, *, ax=None, fig=None):
    """Motor torque per wheel (mean of the axles) and electrical power drawn per segment
    against time; two panels (``ax``: two axes).  Returns the Figure."""
    own = ax is None and fig is None
    fig, axes = new_figure(ax, fig, 2, 1, figsize=(9, 5.5), sharex=True)
    a1, a2 = axes[:, 0]
    t = result.t
    gait = bool(gait_spans(result))
    c1 = per_segment(
        a1, fig, t, result.segments["motor_torque_Nm"], "motor torque\nper wheel [N m]", symmetric=True, chart=gait
    )
    per_segment(a2, fig, t, result.segments["motor_electrical_power_W"], "electrical power\n[W]", chart=gait)
    if not c1:
        legend_outside(a1)
    if not gait:
        shade_phases([a1, a2], gait_spans(result))
    a2.set_xlabel("time [s]")
    title(fig, axes, f"{result.scenario.name}: motor torque and power", own)
    return fig


@figure_function
def plot_energy(result, *, ax=None, fig=None):
    """Electrical energy along the run: motors, joints and total against the distance travelled
    (left) and against time (right) (:func:`snoworm.results.energy.energy_along`; ``ax``: two axes).
    Returns the Figure."""
    own = ax is None and fig is None
    e = result.energy_along()
    fig, axes = new_figure(ax, fig, 1, 2, figsize=(9, 3.8), sharey=True)
    a1, a2 = axes[0]
    parts = [("total", e["total_electrical_J"]), ("motors", e["motor_electrical_J"])]
    if np.any(e["joint_electrical_J"] > 0):
        parts.append(("joints", e["joint_electrical_J"]))
    for k, (lab, E) in enumerate(parts):
        style = series_style(k, E.size, len(parts))
        a1.plot(e["distance_m"], E / 1e3, label=lab, **style)
        a2.plot(e["t_s"], E / 1e3, label=lab, **style)
    a1.set_xlabel("distance [m]")
    a1.set_ylabel("electrical energy [kJ]")
    a2.set_xlabel("time [s]")
    for a in (a1, a2):
        a.grid(alpha=0.3)
    a2.legend(loc="upper left")
    title(fig, axes, f"{result.scenario.name}: electrical energy along the run", own)
    return fig
