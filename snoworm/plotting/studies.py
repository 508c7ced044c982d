"""Figures of the studies: field data against the model (paper Table 2), terrain curves (paper
Figure 3), sweeps (metrics, heat maps) and the mobility map.  Drawn from the tables and dicts
the studies return; each function draws on new or given axes and returns the Figure."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from .style import (
    COLOURS,
    LINESTYLES,
    MARKERS,
    blank_figure,
    figure_function,
    legend_outside,
    new_figure,
    quantity_label,
    small_pt,
    target_width,
    title,
    wrap_title,
)

__all__ = [
    "plot_table2",
    "plot_terrain_curves",
    "plot_sweep",
    "plot_sweep_heatmap",
    "plot_mobility_map",
    "plot_gradeability",
    "compared_grades",
]


@figure_function
def plot_table2(rows, *, ax=None, fig=None):
    """Measured against modelled slip and torque per field case (paper Table 2); two panels."""
    lab = [str(r["case"]) for r in rows]
    x = np.arange(len(rows))
    narrow = ax is None and target_width() < 5.0  # a column: the two panels one above the other
    fig, axes = new_figure(ax, fig, *((2, 1) if narrow else (1, 2)), figsize=(3.5, 5.0) if narrow else (10, 4.2))
    a1, a2 = axes.flat
    w = 0.38
    kw_m, kw_s = dict(color=COLOURS[0]), dict(color=COLOURS[1], hatch="//", edgecolor="white")
    a1.bar(x - w / 2, [100 * r["slip_measured"] for r in rows], w, label="measured", **kw_m)
    a1.bar(x + w / 2, [100 * r["slip_model"] for r in rows], w, label="model", **kw_s)
    a1.set_ylabel("steady slip [%]")
    a2.bar(x - w / 2, [r["torque_measured_Nm"] for r in rows], w, label="measured", **kw_m)
    a2.bar(x + w / 2, [r["torque_model_Nm"] for r in rows], w, label="model", **kw_s)
    a2.set_ylabel("motor torque per wheel [N m]")
    for a in (a1, a2):
        a.set_xticks(x, [f"{c}\nX_t={r['xt']:g}" for c, r in zip(lab, rows)])
        a.set_xlabel("case")
        a.grid(alpha=0.3, axis="y")
        a.legend()
    fig.suptitle(
        wrap_title(
            "FrostyBoy field cases (paper Table 2): measured vs steady-state model",
            fig.get_figwidth(),
            "figure.titlesize",
        )
    )
    return fig


@figure_function
def plot_terrain_curves(curves, title=None, *, ax=None, fig=None):
    """Tractive, resistive and net force per wheel against slip at each X_t (paper Figure 3).

    ``title``: the figure's title (default: the normal load and direction)."""
    wide = target_width() >= 5.0
    if ax is None and fig is None and not wide:  # a column: the legend above in two columns, 3 entries per X_t
        fig = blank_figure((3.5, 3.8), 1.6 + 0.15 * 3 * len(curves.xt))
    fig, axes = new_figure(ax, fig, 1, 1, figsize=(9, 5) if wide else (3.5, 3.8))
    a = axes[0, 0]
    for m, x in enumerate(curves.xt):
        col = COLOURS[m % len(COLOURS)]
        s = 100 * curves.slip
        a.plot(s, curves.traction_N[m], color=col, ls="--", lw=1, label=f"traction, X_t={x:g}")
        a.plot(s, -curves.resistance_N[m], color=col, ls=":", lw=1, label=f"\u2212resistance, X_t={x:g}")
        a.plot(s, curves.net_N[m], color=col, lw=2, label=f"net, X_t={x:g}")
        zc = curves.zero_crossing_slip[m]
        if np.isfinite(zc):
            a.plot([100 * zc], [0.0], "o", color=col, ms=7, mfc="none")
            a.annotate(
                f"{100 * zc:.2f} %",
                (100 * zc, 0.0),
                textcoords="offset points",
                xytext=(6, -14),
                color=col,
                fontsize=small_pt(),
            )
    a.axhline(0.0, color="0.4", lw=0.8)
    a.set_xlabel("slip [%]")
    a.set_ylabel("longitudinal force per wheel [N]")
    a.set_title(
        wrap_title(
            title or f"Terrain forces per wheel (F_n = {curves.normal_load_N:.1f} N), forward motion",
            fig.get_figwidth(),
        )
    )
    a.grid(alpha=0.3)
    wide = fig.get_figwidth() >= 5.0  # wide: one column beside; narrow: two columns above
    legend_outside(a, ncol=(1 if len(curves.xt) < 4 else 2) if wide else 2)
    return fig


@figure_function
def plot_sweep(x, metrics, xlabel, immobilised=None, ok=None, tick_labels=None, *, ax=None, fig=None):
    """Metrics of a one-axis sweep against the swept value (``sweep.png``), one panel per metric.

    Parameters
    ----------
    x : list of float
        Swept values (or positions 0..n-1 with ``tick_labels`` for non-numeric values).
    metrics : dict of str -> list
        Metric name -> one value per case (None for failed cases); one panel each.
    xlabel : str
        The swept key (shown in words with its unit, see :func:`quantity_label`).
    immobilised : list of bool, optional
        Cases flagged immobilised, marked with crosses.
    ok : list of bool, optional
        False for failed cases, marked by grey lines at their value.
    tick_labels : list of str, optional
        Labels of categorical values.
    ax : sequence of Axes, optional
        One axes per metric; ``fig``: a figure to draw in.

    Returns
    -------
    matplotlib.figure.Figure
    """
    x = np.asarray(x, float)
    order = np.argsort(x, kind="stable")
    n = len(metrics)
    fig, axs = new_figure(ax, fig, n, 1, figsize=(7.5, 2.1 * n + 0.6), sharex=True)
    for a, (name, vals) in zip(axs[:, 0], metrics.items()):
        y = np.array([np.nan if v is None else float(v) for v in vals])
        a.plot(x[order], y[order], "o-", ms=4, color=COLOURS[0])
        pos = y[np.isfinite(y)]
        if pos.size and pos.min() > 0 and pos.max() > 100 * pos.min():
            a.set_yscale("log")  # e.g. energy per metre of a nearly immobilised vehicle
        if immobilised is not None:
            m = np.array([bool(v) for v in immobilised])
            if m.any():
                a.plot(x[m], y[m], "x", color=COLOURS[3], ms=8, mew=2, label="immobilised")
                a.legend(loc="best")
        if ok is not None:
            for xv, good in zip(x, ok):
                if not good:
                    a.axvline(xv, color="0.6", ls=":", lw=1)
        a.set_ylabel(quantity_label(name))
        a.grid(alpha=0.3)
    axs[-1, 0].set_xlabel(quantity_label(xlabel))
    if tick_labels is not None:
        axs[-1, 0].set_xticks(x, tick_labels)
    axs[0, 0].set_title(
        wrap_title(
            f"sweep over the {quantity_label(xlabel)}"
            + (" (dotted lines: failed cases)" if ok is not None and not all(ok) else ""),
            fig.get_figwidth(),
        )
    )
    return fig


@figure_function
def plot_sweep_heatmap(
    x_labels, y_labels, values, xlabel, ylabel, label, *, immobilised=None, failed=None, ax=None, fig=None
):
    """Heat map of one metric over a two-axis sweep (``heatmap.png``).

    Parameters
    ----------
    x_labels, y_labels : list of str
        Values of the first (columns) and second (rows) swept key.
    values : ndarray (len(y_labels), len(x_labels))
        The metric; NaN where the case failed.
    xlabel, ylabel : str
        The swept keys (shown in words with units); ``label``: the colour-bar label.
    immobilised, failed : ndarray of bool, optional
        Cells annotated "immob." / "failed".

    Returns
    -------
    matplotlib.figure.Figure
    """
    v = np.asarray(values, float)
    ny, nx = v.shape
    fig, axes = new_figure(ax, fig, 1, 1, figsize=(max(5.0, 0.75 * nx + 2.5), max(3.5, 0.55 * ny + 1.8)))
    a = axes[0, 0]
    im = a.imshow(np.ma.masked_invalid(v), origin="lower", aspect="auto", cmap="viridis")
    fig.colorbar(im, ax=a, label=label)
    finite = v[np.isfinite(v)]
    mid = 0.5 * (finite.min() + finite.max()) if finite.size else 0.0
    for j in range(ny):
        for k in range(nx):
            if failed is not None and failed[j, k]:
                txt, col = "failed", COLOURS[3]
            elif np.isfinite(v[j, k]):
                txt = f"{v[j, k]:.2f}" + ("\nimmob." if immobilised is not None and immobilised[j, k] else "")
                col = "white" if v[j, k] < mid else "black"
            else:
                continue
            a.text(k, j, txt, ha="center", va="center", fontsize=small_pt(), color=col)
    a.set_xticks(range(nx), x_labels, rotation=45 if nx > 8 else 0)
    a.set_yticks(range(ny), y_labels)
    a.set_xlabel(quantity_label(xlabel))
    a.set_ylabel(quantity_label(ylabel))
    a.set_title(wrap_title(f"{label} over {quantity_label(xlabel)} and {quantity_label(ylabel)}", fig.get_figwidth()))
    return fig


def _cell_edges(v):
    """Cell boundaries of grid values ``v`` that stay within [min, max] of the grid (half cells at
    its ends); a single value gets a cell of unit width around it."""
    v = np.asarray(v, float)
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    return np.concatenate([[v[0]], (v[:-1] + v[1:]) / 2, [v[-1]]])


@figure_function
def plot_mobility_map(mmap, *, ax=None, fig=None):
    """Mobility map: regions (rolling, inching only, immobile) over X_t and tow, and energy per metre.

    Left: one cell per grid point coloured by region (cells end at the grid's first and last
    values), with the steady rolling limit X_t(tow)
    (:func:`snoworm.steady.immobilisation_limit_xt`) drawn as a line; cells where inching costs
    less electrical energy per metre than rolling are marked with a star.  Right: electrical
    energy per metre of each mode against X_t, one colour per tow.  ``ax``: two axes.  With several
    grades: the regions over X_t and grade instead, one panel per tow (:func:`_plot_grade_map`).
    """
    if len(mmap.get("grades", (0.0,))) > 1:
        return _plot_grade_map(mmap, ax=ax, fig=fig)
    REGIONS = tuple(mmap["regions"])
    xts, tows = np.asarray(mmap["xts"], float), np.asarray(mmap["tows"], float)
    code = {r: j for j, r in enumerate(REGIONS)}
    Z = np.zeros((tows.size, xts.size))
    for r in mmap["rows"]:
        Z[list(tows).index(r["tow_N"]), list(xts).index(r["xt"])] = code[r["region"]]
    colours = ["#d9d9d9", COLOURS[1], COLOURS[5]]
    narrow = ax is None and target_width() < 5.0  # a column: the two panels one above the other
    fig, axes = new_figure(ax, fig, *((2, 1) if narrow else (1, 2)), figsize=(3.5, 5.6) if narrow else (13, 4.8))
    a1, a2 = axes.flat
    xe, ye = _cell_edges(xts), _cell_edges(tows)
    a1.pcolormesh(
        xe,
        ye,
        Z,
        cmap=ListedColormap(colours[: len(REGIONS)]),
        vmin=-0.5,
        vmax=len(REGIONS) - 0.5,
        edgecolors="white",
        lw=0.5,
    )
    a1.set_xlim(xe[0], xe[-1])
    a1.set_ylim(ye[0], ye[-1])
    lim = [(f, mmap["rolling_limit_xt"][f]) for f in mmap["tows"] if mmap["rolling_limit_xt"][f] is not None]
    if lim:
        a1.plot([x for _, x in lim], [f for f, _ in lim], "k--", lw=1.2, marker="o", ms=3, label="steady rolling limit")
    for r in mmap["rows"]:
        if r["inching_cheaper"]:
            a1.plot(r["xt"], r["tow_N"], "*", color=COLOURS[0], ms=9, clip_on=False)
    handles = [Patch(color=c, label=lab) for c, lab in zip(colours, REGIONS)]
    handles += a1.get_legend_handles_labels()[0]
    if any(r["inching_cheaper"] for r in mmap["rows"]):
        handles.append(Line2D([], [], ls="", marker="*", color=COLOURS[0], label="inching cheaper per metre"))
    a1.set_xlabel("terrain coefficient X_t")
    a1.set_ylabel("tow force [N]")
    if tows.size == 1:
        a1.set_yticks([tows[0]])
    below = ax is None and not narrow  # our own page-wide figure: one legend under both panels
    panel_in = fig.get_figwidth() * (1.0 if narrow else 0.45)
    a1.set_title(wrap_title(f"{mmap['scenario']}: which modes move the vehicle", panel_in))
    _energy_panel(a2, mmap, panel_in, legend=not below)
    if below:
        handles += a2.get_legend_handles_labels()[0]
        fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 4), frameon=False)
    else:
        legend_outside(a1, handles=handles)
    return fig


def _energy_panel(a2, mmap, panel_width, legend=True):
    """The mobility map's right panel: electrical energy per metre against X_t, rolling and inching, a
    colour per tow (with its own legend unless ``legend`` is false)."""
    for j, f in enumerate(mmap["tows"]):
        rs = sorted((r for r in mmap["rows"] if r["tow_N"] == f), key=lambda r: r["xt"])
        xr = [r["xt"] for r in rs if r["rolling"]]
        er = [r["rolling_energy_per_metre_J_per_m"] for r in rs if r["rolling"]]
        xi = [r["xt"] for r in rs if r.get("inching")]
        ei = [r["inching_energy_per_metre_J_per_m"] for r in rs if r.get("inching")]
        c = COLOURS[j % len(COLOURS)]
        a2.plot(xr, er, ls="-", marker=MARKERS[j % len(MARKERS)], color=c, ms=4, label=f"rolling, tow {f:g} N")
        if xi:
            a2.plot(
                xi,
                ei,
                ls=LINESTYLES[1],
                marker=MARKERS[j % len(MARKERS)],
                mfc="none",
                color=c,
                ms=5,
                label=f"inching, tow {f:g} N",
            )
    a2.set_yscale("log")
    a2.set_xlabel("terrain coefficient X_t")
    a2.set_ylabel("electrical energy per metre [J/m]")
    a2.grid(alpha=0.3, which="both")
    if legend and a2.get_legend_handles_labels()[0]:
        legend_outside(a2)
    a2.set_title(wrap_title(f"energy per metre (rolling at {mmap['wheel_speed_mps']:g} m/s wheel speed)", panel_width))


_REGION_COLOURS = ["#d9d9d9", COLOURS[1], COLOURS[5]]


def _plot_grade_map(mmap, *, ax=None, fig=None):
    """Regions (rolling, inching only, immobile) over X_t and grade, one panel per tow (side by side;
    one above the other in a column), with the steady maximum grade of a rolling chain
    (:func:`snoworm.steady.max_grade_deg`) as a line."""
    REGIONS = tuple(mmap["regions"])
    xts, grades = np.asarray(mmap["xts"], float), np.asarray(mmap["grades"], float)
    code = {r: j for j, r in enumerate(REGIONS)}
    tows = list(mmap["tows"])
    narrow = ax is None and target_width() < 5.0  # a column: the panels one above the other
    shape = (len(tows), 1) if narrow else (1, len(tows))
    fig, axes = new_figure(
        ax, fig, *shape, figsize=(3.5, 2.6 * len(tows) + 1.2) if narrow else (5.5 * len(tows) + 2, 4.8)
    )
    xe, ye = _cell_edges(xts), _cell_edges(grades)
    for a, f in zip(axes.flat, tows):
        Z = np.zeros((grades.size, xts.size))
        for r in mmap["rows"]:
            if r["tow_N"] == f:
                Z[list(grades).index(r["grade_deg"]), list(xts).index(r["xt"])] = code[r["region"]]
        a.pcolormesh(
            xe,
            ye,
            Z,
            cmap=ListedColormap(_REGION_COLOURS[: len(REGIONS)]),
            vmin=-0.5,
            vmax=len(REGIONS) - 0.5,
            edgecolors="white",
            lw=0.5,
        )
        mg = mmap["rolling_max_grade_deg"][f]
        pts = [(x, mg[x]) for x in mmap["xts"] if mg[x] is not None]
        if pts:
            a.plot(*zip(*pts), "k--", lw=1.2, marker="o", ms=3, label="steady rolling limit")
        a.set_xlim(xe[0], xe[-1])
        a.set_ylim(ye[0], ye[-1])
        a.set_xlabel("terrain coefficient X_t")
        a.set_ylabel("grade [deg]")
        a.set_title(f"{mmap['scenario']}, tow {f:g} N")
    handles = [Patch(color=c, label=lab) for c, lab in zip(_REGION_COLOURS, REGIONS)]
    handles += axes.flat[-1].get_legend_handles_labels()[0]
    legend_outside(axes.flat[0] if narrow else axes.flat[-1], handles=handles)
    return fig


def _gait_cells(mmap, lab):
    """A gait's (``"rolling"`` or an inchworm gait label) view of a map row: (moved, speed, energy per
    metre travelled); moved is None where the gait was not simulated."""

    def cell(r):
        if lab == "rolling":
            return r["rolling"], r.get("rolling_speed_mps"), r.get("rolling_energy_per_metre_J_per_m")
        c = r.get("inching_by_gait", {}).get(lab, r)
        return c.get("inching"), c.get("inching_speed_mps"), c.get("inching_energy_per_metre_J_per_m")

    return cell


def compared_grades(mmap, tow_N, gaits):
    """Per X_t of the map: the grade [deg] at which the gaits are compared, the steepest grid grade
    every gait that moved at this X_t climbed (the least of their steepest grades; None where
    nothing moved), and ``{gait: (speed, energy per metre travelled)}`` there (gaits not simulated
    or not moving at that grade left out)."""
    cells = {(r["xt"], r["grade_deg"]): r for r in mmap["rows"] if r["tow_N"] == tow_N}
    out = []
    for x in mmap["xts"]:
        rows = sorted((r for (xx, _), r in cells.items() if xx == x), key=lambda r: r["grade_deg"])
        tops = [max((r["grade_deg"] for r in rows if _gait_cells(mmap, g)(r)[0]), default=None) for g in gaits]
        tops = [t for t in tops if t is not None]
        if not tops:
            out.append((None, {}))
            continue
        g_star = min(tops)
        vals = {}
        for g in gaits:
            moved, speed, energy = _gait_cells(mmap, g)(cells[(x, g_star)])
            if moved:
                vals[g] = (speed, energy)
        out.append((g_star, vals))
    return out


def _gradeability_keys(gaits, tows):
    """The gradeability figure's legend entries: a colour and marker per gait, the compared grade's
    mark, a line style per tow (several tows)."""
    handles = [
        Line2D(
            [],
            [],
            color=COLOURS[k % len(COLOURS)],
            marker=MARKERS[0],
            mfc="none" if k else None,
            label=("rolling (top: steady limit)" if k == 0 else f"{lab} (top: grid)"),
        )
        for k, lab in enumerate(gaits)
    ]
    handles.append(Line2D([], [], ls="", marker="_", ms=11, mew=1.6, color="0.35", label="compared grade (grid)"))
    if len(tows) > 1:
        handles += [
            Line2D(
                [],
                [],
                color="0.2",
                ls=LINESTYLES[j % len(LINESTYLES)],
                marker=MARKERS[j % len(MARKERS)],
                label=f"tow {f:g} N",
            )
            for j, f in enumerate(tows)
        ]
    return handles


@figure_function
def plot_gradeability(mmap, *, ax=None, fig=None):
    """Gradeability: the steepest grade climbed against X_t, and the speed and electrical energy per
    metre travelled of every gait *at one grade* per X_t (``mmap["gradeability"]``,
    :func:`snoworm.studies.gradeability.gradeability`).

    Top: the steepest grade climbed, one curve per gait (rolling: its steady limit; each inchworm
    gait: the steepest grid grade it climbed), and the grade the lower panels compare the gaits at
    (:func:`compared_grades`: the steepest grid grade every gait that moves there climbed, so rolling
    and inching are never compared at different grades).  Middle and bottom: speed and electrical
    energy per metre travelled there (defined on level ground too, unlike the energy per metre
    climbed), for rolling and for every gait simulated there (inching is simulated only where the
    chain does not roll unless ``--every-cell``), as markers (the compared grade may change from
    one X_t to the next).  A colour per gait (rolling filled, inching open markers), a marker and
    line style per tow; one legend under the panels.  ``ax``: three axes.  Returns the Figure.
    """
    own = ax is None and fig is None
    fig, axes = new_figure(ax, fig, 3, 1, figsize=(7.5, 8.0), sharex=True, gridspec_kw={"height_ratios": [1.4, 1, 1]})
    a1, a2, a3 = axes[:, 0]
    gaits = ["rolling", *(mmap.get("gait_labels") or ["inching"])]
    tows = list(mmap["tows"])
    for j, f in enumerate(tows):
        g = mmap["gradeability"][f]
        ls = LINESTYLES[j % len(LINESTYLES)]
        tops = [g["rolling_max_grade_deg"]] + [g["inching"][lab]["grid_deg"] for lab in gaits[1:]]
        compared = compared_grades(mmap, f, gaits)
        for k, (lab, top) in enumerate(zip(gaits, tops)):
            kw = dict(ls=ls, marker=MARKERS[j % len(MARKERS)], color=COLOURS[k % len(COLOURS)], ms=5)
            if k:
                kw["mfc"] = "none"
            pts = [(x, v) for x, v in zip(g["xt"], top) if v is not None]
            if pts:
                a1.plot(*zip(*pts), **kw)
            at = [(x, vals[lab]) for x, (_, vals) in zip(mmap["xts"], compared) if lab in vals]
            if at:
                # markers only: the compared grade may differ from one X_t to the next
                a2.plot([x for x, _ in at], [v[0] for _, v in at], **{**kw, "ls": ""})
                en = [(x, v[1]) for x, v in at if v[1] is not None and v[1] > 0]
                if en:
                    a3.plot(*zip(*en), **{**kw, "ls": ""})
        cg = [(x, gs) for x, (gs, _) in zip(mmap["xts"], compared) if gs is not None]
        if cg:
            a1.plot(*zip(*cg), ls="", marker="_", ms=11, mew=1.6, color="0.35", zorder=1)
    grades = mmap["grades"]
    # the grid's range, up to a steady rolling limit above it (X_t 1.0 rolls to 28 deg on a 25 deg grid);
    # limits below the grid (cannot start on level snow) are the printed sentences' to tell
    a1.set_ylim(min(grades) - 1, np.nanmax([max(grades), a1.dataLim.y1]) + 1)
    a1.set_ylabel("steepest grade\nclimbed [deg]")
    a2.set_ylabel("speed\n[m/s]")
    a3.set_ylabel("energy per\nmetre [J/m]")
    a3.set_xlabel("terrain coefficient X_t")
    if a3.get_lines():
        a3.set_yscale("log")
    for a in (a1, a2, a3):
        a.grid(alpha=0.3, which="both")
    handles = _gradeability_keys(gaits, tows)
    text = (
        f"{mmap['scenario']}: gradeability on a grid of {min(grades):g} to {max(grades):g} deg; speed and "
        "energy of each gait at one grade per X_t"
    )
    if own:
        fig.legend(handles=handles, loc="outside lower center", ncol=2, frameon=False)
        title(fig, axes, text, own)
    else:
        legend_outside(a1, handles=handles)
        a1.set_title(wrap_title(text, a1.get_position().width * fig.get_figwidth()))
    return fig
