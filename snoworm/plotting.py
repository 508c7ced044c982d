"""Plots of results.  The only module that imports matplotlib (Agg backend, files only)."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .fileio import atomic_path  # noqa: E402

__all__ = ["plot_result", "save"]


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
    from .simulate import terrain_profile
    a0.plot(terrain_profile(result.scenario)(xs), xs, color="tab:brown")
    a0.set_xlabel("X_t")
    a0.set_ylabel("position [m]")
    a0.grid(alpha=0.3)
    for k in range(x.shape[1]):
        a1.plot(t, x[:, k], label=_seg_label(k))
    for ev in result.events:
        a1.axvline(ev["t_s"], color="0.85", lw=0.6, zorder=0)
    a1.set_xlabel("time [s]")
    a1.legend(fontsize=8, ncol=3, loc="best")
    a1.grid(alpha=0.3)
    a1.set_title(f"{result.scenario.name}: position-time diagram")
    fig.tight_layout()
    return save(fig, path)


def plot_result(result, out_dir) -> list:
    """Every standard plot of a run: ``forces.png``, ``speeds.png``, ``positions.png``."""
    out = Path(out_dir)
    return [plot_forces(result, out / "forces.png"), plot_speeds(result, out / "speeds.png"),
            plot_positions(result, out / "positions.png")]


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
