"""Plots of results and study tables.  The only module that imports matplotlib (Agg backend, files only).

Figures are drawn from data alone (a :class:`~snoworm.results.Result`, or the tables and dicts
the studies return): this module imports neither the driver nor the studies.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from .fileio import atomic_path  # noqa: E402

__all__ = ["plot_result", "save", "plot_mobility_map"]


def save(fig, path) -> Path:
    """Save a figure atomically and close it."""
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format=path.suffix.lstrip(".") or "png")
    plt.close(fig)
    return path


def _seg_label(k):
    return "leader 0" if k == 0 else f"follower {k}"


def plot_forces(result, path):
    """Connector (link) forces and net wheel force per segment against time (paper Figs 6-9)."""
    t = result.t
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    F = result.links["force_N"]
    for j in range(F.shape[1]):
        a1.plot(t, F[:, j], label=f"link {j} ({j}-{j + 1})")
    if result.scenario.tow.force_N:
        a1.axhline(result.scenario.tow.force_N, color="0.5", ls=":", lw=1, label="tow")
    a1.set_ylabel("connector force [N]\n(tension +)")
    a1.legend(fontsize=8, ncol=2, loc="best")
    a1.grid(alpha=0.3)
    net = result.segments["net_force_N"]
    for k in range(net.shape[1]):
        a2.plot(t, net[:, k], label=_seg_label(k))
    a2.set_ylabel("net wheel force [N]\n(forward +)")
    a2.set_xlabel("time [s]")
    a2.legend(fontsize=8, ncol=3, loc="best")
    a2.grid(alpha=0.3)
    a1.set_title(f"{result.scenario.name}: connector and net forces")
    fig.tight_layout()
    return save(fig, path)


def plot_speeds(result, path):
    """Ground speed and wheel-speed set-point per segment against time (paper Figs 5, 8, 9, 11)."""
    t = result.t
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for k in range(result.n_segments):
        a1.plot(t, result.segments["v_mps"][:, k], label=_seg_label(k))
        a2.plot(t, result.segments["speed_setpoint_mps"][:, k], label=_seg_label(k))
    a1.set_ylabel("ground speed [m/s]")
    a2.set_ylabel("wheel-speed set-point [m/s]")
    a2.set_xlabel("time [s]")
    for a in (a1, a2):
        a.grid(alpha=0.3)
        a.legend(fontsize=8, ncol=3, loc="best")
    a1.set_title(f"{result.scenario.name}: speeds")
    fig.tight_layout()
    return save(fig, path)


def plot_positions(result, path):
    """Position-time diagram of every segment, over the terrain coefficient (paper Fig 4)."""
    t = result.t
    x = result.segments["x_m"]
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(10, 5), gridspec_kw={"width_ratios": [1, 4]}, sharey=True)
    xs = np.linspace(x.min() - 1.0, x.max() + 1.0, 400)
    a0.plot(result.scenario.terrain.compile()(xs), xs, color="tab:brown")
    a0.set_xlabel("X_t")
    a0.set_ylabel("position [m]")
    a0.grid(alpha=0.3)
    for k in range(x.shape[1]):
        a1.plot(t, x[:, k], label=_seg_label(k))
    for ev in result.events:
        a1.axvline(ev["t_s"], color="0.85", lw=0.6, zorder=0)
    # mode switches (supervisor mode): a marked line at the switch, the leader's position there
    sw_style = {"switch_to_inching": ("tab:red", "v", "to inching"), "switch_to_rolling": ("tab:green", "^", "to rolling")}
    for ev in result.events:
        if ev.get("kind") in sw_style:
            c, mk, lab = sw_style[ev["kind"]]
            a1.axvline(ev["t_s"], color=c, lw=1.0, ls="--", zorder=1)
            a1.plot([ev["t_s"]], [ev["x_m"]], mk, color=c, ms=9, zorder=3)
            a1.annotate(lab, (ev["t_s"], ev["x_m"]), textcoords="offset points", xytext=(4, 6), fontsize=8, color=c)
    a1.set_xlabel("time [s]")
    a1.legend(fontsize=8, ncol=3, loc="best")
    a1.grid(alpha=0.3)
    a1.set_title(f"{result.scenario.name}: position-time diagram")
    fig.tight_layout()
    return save(fig, path)


def plot_result(result, out_dir) -> list:
    """Every standard plot of a run: ``forces.png``, ``speeds.png``, ``positions.png``."""
    out = Path(out_dir)
    paths = [plot_forces(result, out / "forces.png"), plot_speeds(result, out / "speeds.png"),
             plot_positions(result, out / "positions.png")]
    for name in getattr(result.scenario.mode, "extra_plots", ()):  # mode-specific plots, e.g. force_diagram
        paths.append(globals()[f"plot_{name}"](result, out / f"{name}.png"))
    return paths


# ------------------------------------------------------------------ ground truth (groundtruth.py)

def plot_table2(rows, path):
    """Measured against modelled slip and torque per field case (paper Table 2)."""
    lab = [str(r["case"]) for r in rows]
    x = np.arange(len(rows))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4.2))
    w = 0.38
    a1.bar(x - w / 2, [100 * r["slip_measured"] for r in rows], w, label="measured")
    a1.bar(x + w / 2, [100 * r["slip_model"] for r in rows], w, label="model")
    a1.set_ylabel("steady slip [%]")
    a2.bar(x - w / 2, [r["torque_measured_Nm"] for r in rows], w, label="measured")
    a2.bar(x + w / 2, [r["torque_model_Nm"] for r in rows], w, label="model")
    a2.set_ylabel("motor torque per wheel [N m]")
    for a in (a1, a2):
        a.set_xticks(x, [f"{c}\nX_t={r['xt']:g}" for c, r in zip(lab, rows)])
        a.set_xlabel("case")
        a.grid(alpha=0.3, axis="y")
        a.legend(fontsize=8)
    fig.suptitle("FrostyBoy field cases (paper Table 2): measured vs steady-state model")
    fig.tight_layout()
    return save(fig, path)


def plot_terrain_curves(curves, path):
    """Tractive, resistive and net force per wheel against slip at each X_t (paper Figure 3)."""
    fig, ax = plt.subplots(figsize=(8, 5))
    for m, x in enumerate(curves.xt):
        col = f"C{m % 10}"
        s = 100 * curves.slip
        ax.plot(s, curves.traction_N[m], color=col, ls="--", lw=1, label=f"traction, X_t={x:g}")
        ax.plot(s, -curves.resistance_N[m], color=col, ls=":", lw=1, label=f"-resistance, X_t={x:g}")
        ax.plot(s, curves.net_N[m], color=col, lw=2, label=f"net, X_t={x:g}")
        zc = curves.zero_crossing_slip[m]
        if np.isfinite(zc):
            ax.plot([100 * zc], [0.0], "o", color=col, ms=7, mfc="none")
            ax.annotate(f"{100 * zc:.2f} %", (100 * zc, 0.0), textcoords="offset points", xytext=(6, -14),
                        color=col, fontsize=8)
    ax.axhline(0.0, color="0.4", lw=0.8)
    ax.set_xlabel("slip [%]")
    ax.set_ylabel("longitudinal force per wheel [N]")
    ax.set_title(f"Terrain forces per wheel (F_n = {curves.normal_load_N:.1f} N), forward motion")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2, loc="best")
    fig.tight_layout()
    return save(fig, path)


def plot_force_diagram(result, path, window_s=1.0):
    """Steady-state force diagram of the chain (paper Fig 10): the forces acting on each segment.

    Each segment is a box (the leader on the right, travel to the right).  Below it, the net
    wheel force (traction - resistance); above it, the force of the link ahead (``T_{k-1}``,
    pulling forward when in tension) and of the link behind (``-T_k``) or the tow.  Values are
    means over the last ``window_s`` seconds of the run; arrows point the way the force acts on
    the segment and their length is proportional to it.
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
    fig, ax = plt.subplots(figsize=(2.6 * n + 1.5, 4.2))
    pos = lambda k: (n - 1 - k) * 2.0              # leader on the right
    for k in range(n):
        x0 = pos(k)
        ax.add_patch(plt.Rectangle((x0 - 0.45, -0.3), 0.9, 0.6, fc="0.9", ec="0.2"))
        ax.text(x0, 0.0, f"{_seg_label(k)}\nset-point {sp[k]:.3f} m/s", ha="center", va="center", fontsize=8)
        rows = [(-0.75, W[k], "tab:green", f"wheels {W[k]:+.1f} N"),
                (0.6, ahead[k], "tab:blue", f"link ahead {ahead[k]:+.1f} N" if k else None),
                (0.95, behind[k], "tab:red" if k < n - 1 else "tab:purple",
                 f"link behind {behind[k]:+.1f} N" if k < n - 1 else f"tow {behind[k]:+.1f} N")]
        for yy, F, c, lab in rows:
            if lab is None:
                continue
            if abs(F) > 1e-9 * fmax:
                ax.annotate("", xy=(x0 + F * scale / 2, yy), xytext=(x0 - F * scale / 2, yy),
                            arrowprops=dict(arrowstyle="-|>", color=c, lw=2))
            else:
                ax.plot([x0], [yy], "o", color=c, ms=4)
            ax.text(x0, yy + 0.12, lab, ha="center", va="bottom", fontsize=7.5, color=c)
        ax.text(x0, -1.1, f"net connector {ahead[k] + behind[k]:+.1f} N", ha="center", va="top", fontsize=7.5)
    for j in range(n - 1):
        ax.text((pos(j) + pos(j + 1)) / 2, 0.0, f"T{j}\n{T[j]:+.1f} N", ha="center", va="center", fontsize=8,
                color="0.3")
    ax.annotate("travel", xy=(pos(0) + 0.9, -1.55), xytext=(pos(0) + 0.2, -1.55),
                arrowprops=dict(arrowstyle="-|>", color="0.4"), va="center", fontsize=8, color="0.4")
    ax.set_xlim(-1.1, pos(0) + 1.1)
    ax.set_ylim(-1.75, 1.35)
    ax.axis("off")
    ax.set_title(f"{result.scenario.name}: steady-state forces on each segment "
                 f"(mean of the last {window_s:g} s; tension positive)", fontsize=9)
    fig.tight_layout()
    return save(fig, path)


# ---------------------------------------------------------------------------------- sweeps
_SWEEP_LABELS = {"mean_speed_mps": "mean speed [m/s]", "mean_slip": "mean slip (2nd half)",
                 "max_link_force_N": "max |link force| [N]", "energy_per_m_J": "energy per metre [J/m]"}


def plot_sweep(x, metrics, xlabel, path, immobilised=None, ok=None, tick_labels=None):
    """Metrics of a one-axis sweep against the swept value (``sweep.png``).

    Parameters
    ----------
    x : list of float
        Swept values (or positions 0..n-1 with ``tick_labels`` for non-numeric values).
    metrics : dict of str -> list
        Metric name -> one value per case (None for failed cases); one panel each.
    xlabel : str
        The swept key.
    path : str or Path
        Output PNG, written atomically.
    immobilised : list of bool, optional
        Cases flagged immobilised, marked with red crosses.
    ok : list of bool, optional
        False for failed cases, marked by grey lines at their value.
    tick_labels : list of str, optional
        Labels of categorical values.
    """
    x = np.asarray(x, float)
    order = np.argsort(x, kind="stable")
    n = len(metrics)
    fig, axs = plt.subplots(n, 1, figsize=(7, 2.1 * n + 0.6), sharex=True, squeeze=False)
    for a, (name, vals) in zip(axs[:, 0], metrics.items()):
        y = np.array([np.nan if v is None else float(v) for v in vals])
        a.plot(x[order], y[order], "o-", ms=4)
        pos = y[np.isfinite(y)]
        if pos.size and pos.min() > 0 and pos.max() > 100 * pos.min():
            a.set_yscale("log")     # e.g. energy per metre of a nearly immobilised vehicle
        if immobilised is not None:
            m = np.array([bool(v) for v in immobilised])
            if m.any():
                a.plot(x[m], y[m], "x", color="tab:red", ms=8, label="immobilised")
                a.legend(fontsize=8, loc="best")
        if ok is not None:
            for xv, good in zip(x, ok):
                if not good:
                    a.axvline(xv, color="0.6", ls=":", lw=1)
        a.set_ylabel(_SWEEP_LABELS.get(name, name), fontsize=9)
        a.grid(alpha=0.3)
    axs[-1, 0].set_xlabel(xlabel)
    if tick_labels is not None:
        axs[-1, 0].set_xticks(x, tick_labels)
    axs[0, 0].set_title(f"sweep over {xlabel}" + (" (dotted lines: failed cases)" if ok is not None and not all(ok) else ""))
    fig.tight_layout()
    return save(fig, path)


def plot_sweep_heatmap(x_labels, y_labels, values, xlabel, ylabel, label, path, immobilised=None, failed=None):
    """Heat map of one metric over a two-axis sweep (``heatmap.png``).

    Parameters
    ----------
    x_labels, y_labels : list of str
        Values of the first (columns) and second (rows) swept key.
    values : ndarray (len(y_labels), len(x_labels))
        The metric; NaN where the case failed.
    xlabel, ylabel, label : str
        Axis names and the colour-bar label.
    path : str or Path
        Output PNG, written atomically.
    immobilised, failed : ndarray of bool, optional
        Cells annotated "immob." / "failed".
    """
    v = np.asarray(values, float)
    ny, nx = v.shape
    fig, a = plt.subplots(figsize=(max(5.0, 0.75 * nx + 2.5), max(3.5, 0.55 * ny + 1.8)))
    im = a.imshow(np.ma.masked_invalid(v), origin="lower", aspect="auto", cmap="viridis")
    fig.colorbar(im, ax=a, label=label)
    finite = v[np.isfinite(v)]
    mid = 0.5 * (finite.min() + finite.max()) if finite.size else 0.0
    for j in range(ny):
        for k in range(nx):
            if failed is not None and failed[j, k]:
                txt, col = "failed", "tab:red"
            elif np.isfinite(v[j, k]):
                txt = f"{v[j, k]:.2f}" + ("\nimmob." if immobilised is not None and immobilised[j, k] else "")
                col = "white" if v[j, k] < mid else "black"
            else:
                continue
            a.text(k, j, txt, ha="center", va="center", fontsize=7, color=col)
    a.set_xticks(range(nx), x_labels, rotation=45 if nx > 8 else 0)
    a.set_yticks(range(ny), y_labels)
    a.set_xlabel(xlabel)
    a.set_ylabel(ylabel)
    a.set_title(f"{label} over {xlabel} x {ylabel}")
    fig.tight_layout()
    return save(fig, path)


# ------------------------------------------------------------------ mobility map (mobility.py)

def plot_mobility_map(mmap, path):
    """Mobility map: regions (rolling, inching only, immobile) over X_t and tow, and energy per metre.

    Left: one cell per grid point coloured by region, with the steady rolling limit X_t(tow)
    (:func:`snoworm.steady.immobilisation_limit_xt`) drawn as a line; cells where inching costs
    less electrical energy per metre than rolling are marked with a star.  Right: electrical
    energy per metre of each mode against X_t, one colour per tow.
    """
    REGIONS = tuple(mmap["regions"])
    xts, tows = np.asarray(mmap["xts"]), np.asarray(mmap["tows"])
    code = {r: j for j, r in enumerate(REGIONS)}
    Z = np.zeros((tows.size, xts.size))
    for r in mmap["rows"]:
        Z[list(tows).index(r["tow_N"]), list(xts).index(r["xt"])] = code[r["region"]]
    colours = ["#d9d9d9", "#fdae61", "#66bd63"]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8))
    edges = lambda v: (np.concatenate([[v[0] - 0.5], (v[:-1] + v[1:]) / 2, [v[-1] + 0.5]]) if v.size == 1 else
                       np.concatenate([[1.5 * v[0] - 0.5 * v[1]], (v[:-1] + v[1:]) / 2, [1.5 * v[-1] - 0.5 * v[-2]]]))
    a1.pcolormesh(edges(xts), edges(tows) if tows.size > 1 else np.array([tows[0] - 50, tows[0] + 50]), Z,
                  cmap=ListedColormap(colours), vmin=-0.5, vmax=len(REGIONS) - 0.5, edgecolors="white", lw=0.5)
    lim = [(f, mmap["rolling_limit_xt"][f]) for f in tows if mmap["rolling_limit_xt"][f] is not None]
    if lim:
        a1.plot([x for _, x in lim], [f for f, _ in lim], "k--", lw=1.2, marker="o", ms=3,
                label="steady rolling limit")
    for r in mmap["rows"]:
        if r["inching_cheaper"]:
            a1.plot(r["xt"], r["tow_N"], "*", color="tab:blue", ms=9)
    handles = [Patch(color=c, label=lab) for c, lab in zip(colours, REGIONS)]
    handles += a1.get_legend_handles_labels()[0]
    if any(r["inching_cheaper"] for r in mmap["rows"]):
        handles.append(plt.Line2D([], [], ls="", marker="*", color="tab:blue", label="inching cheaper per metre"))
    a1.legend(handles=handles, fontsize=8, loc="upper left")
    a1.set_xlabel("terrain coefficient X_t")
    a1.set_ylabel("tow force [N]")
    a1.set_title(f"{mmap['scenario']}: which modes move the vehicle", fontsize=10)
    for j, f in enumerate(tows):
        rs = sorted((r for r in mmap["rows"] if r["tow_N"] == f), key=lambda r: r["xt"])
        xr = [r["xt"] for r in rs if r["rolling"]]
        er = [r["rolling_energy_per_metre_J_per_m"] for r in rs if r["rolling"]]
        xi = [r["xt"] for r in rs if r.get("inching")]
        ei = [r["inching_energy_per_metre_J_per_m"] for r in rs if r.get("inching")]
        a2.plot(xr, er, "-o", color=f"C{j}", ms=3, label=f"rolling, tow {f:g} N")
        if xi:
            a2.plot(xi, ei, "--s", color=f"C{j}", ms=3, label=f"inching, tow {f:g} N")
    a2.set_yscale("log")
    a2.set_xlabel("terrain coefficient X_t")
    a2.set_ylabel("electrical energy per metre [J/m]")
    a2.grid(alpha=0.3, which="both")
    a2.legend(fontsize=7, ncol=2)
    a2.set_title(f"energy per metre (rolling at {mmap['wheel_speed_mps']:g} m/s wheel speed)", fontsize=10)
    fig.tight_layout()
    return save(fig, path)


# ------------------------------------------------------------------ paper reproduction (snoworm/paper/)

def plot_inchworm_pairs(result, path, pairs=((0, 3), (1, 4), (2, 5))):
    """Ground speed of the segments that move together, one panel per pair (paper Fig 5).

    Each panel overlays the speed traces of a pair of segments that share their place in the
    gait; gait phase changes are drawn as faint vertical lines.
    """
    t = result.t
    v = result.segments["v_mps"]
    fig, axes = plt.subplots(len(pairs), 1, figsize=(8, 2.2 * len(pairs) + 0.8), sharex=True, squeeze=False)
    for ax, (a, b) in zip(axes[:, 0], pairs):
        ax.plot(t, v[:, a], lw=1.6, label=_seg_label(a))
        ax.plot(t, v[:, b], lw=1.2, ls="--", label=_seg_label(b))
        for ev in result.events:
            if ev.get("kind") == "phase_change":
                ax.axvline(ev["t_s"], color="0.85", lw=0.6, zorder=0)
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_ylabel("speed [m/s]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    axes[-1, 0].set_xlabel("time [s]")
    axes[0, 0].set_title(f"{result.scenario.name}: ground speed of segments moving together "
                         f"(X_t = {result.segments['xt'][0].mean():.2f})")
    fig.tight_layout()
    return save(fig, path)
