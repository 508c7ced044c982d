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
