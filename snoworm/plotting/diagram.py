"""The force diagram of a force-control run: each segment as a box with the forces on it,
averaged over the last seconds of the run (``force_diagram.png``)."""

from __future__ import annotations

import numpy as np
from matplotlib.patches import Rectangle

from .style import figure_function, force_text, new_figure, seg_label, small_pt, target_width, wrap_title


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
