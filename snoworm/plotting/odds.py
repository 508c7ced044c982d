"""Figures of an odds study (``snoworm odds``, docs/odds.md): P(go) per strategy with its interval,
where the draws stop along the route over its elevation (the route's risk map), the estimate and its
interval against the number of draws, and the Sobol indices.  Drawn from the plain dicts and arrays
:func:`snoworm.odds` hands over (no solver, no study imported here)."""

from __future__ import annotations

import numpy as np

from .style import COLOURS, figure_function, headless, new_figure, save, wrap_title

__all__ = [
    "plot_odds",
    "plot_odds_stops",
    "plot_odds_convergence",
    "plot_odds_sobol",
    "write_odds_figures",
    "ODDS_FIGURES",
]

#: File stems of the figures ``snoworm odds`` writes.
ODDS_FIGURES = ("odds", "stops", "convergence", "sobol")


@figure_function
def plot_odds(summary, *, ax=None, fig=None):
    """P(go) per strategy (bars) with its Wilson 95 % interval (error bars), from ``odds.json``."""
    fig, axes = new_figure(ax, fig, figsize=(5, 3.5))
    a = axes[0, 0]
    names = list(summary["strategies"])
    p = np.array(
        [np.nan if summary["strategies"][s]["p_go"] is None else summary["strategies"][s]["p_go"] for s in names]
    )
    ci = np.array([summary["strategies"][s]["p_go_ci"] for s in names], float).reshape(-1, 2)
    x = np.arange(len(names))
    a.bar(x, 100 * p, 0.6, color=[COLOURS[k % len(COLOURS)] for k in range(len(names))])
    a.errorbar(
        x, 100 * p, yerr=100 * np.abs(np.vstack([p - ci[:, 0], ci[:, 1] - p])), fmt="none", ecolor="black", capsize=4
    )
    n = [summary["strategies"][s]["n"] for s in names]
    a.set_xticks(x, [f"{s}\n(n = {k:,})" for s, k in zip(names, n)])
    a.set_ylim(0, 100)
    a.set_ylabel("P(gets through) [%]")
    a.grid(alpha=0.3, axis="y")
    a.set_title(
        wrap_title(f"{summary['scenario']}: odds of getting through (95 % Wilson interval)", fig.get_figwidth())
    )
    return fig


@figure_function
def plot_odds_stops(rows, route, strategies, *, ax=None, fig=None):
    """Where the draws stop along the route: the elevation and nominal X_t (top), a histogram of the stop
    positions per strategy (bottom).  ``route``: ``{"x_m", "elevation_m", "xt", "goal_m"}``."""
    fig, axes = new_figure(ax, fig, 2, 1, figsize=(7, 5), sharex=True)
    a1, a2 = axes[:, 0]
    x = np.asarray(route["x_m"], float)
    a1.plot(x, route["elevation_m"], color="black", label="elevation")
    a1.set_ylabel("elevation [m]")
    b = a1.twinx()
    b.plot(x, route["xt"], color=COLOURS[2], linestyle="--", label="X_t (nominal)")
    b.set_ylabel("X_t (nominal)")
    b.set_ylim(0, 1.05)
    if route.get("goal_m") is not None:
        for a in (a1, a2):
            a.axvline(route["goal_m"], color="grey", linestyle=":")
    edges = np.linspace(x[0], x[-1], 41)
    for k, s in enumerate(strategies):
        stops = [
            r["stop_m"]
            for r in rows
            if r["strategy"] == s and r.get("verdict") == "immobilised" and r["stop_m"] is not None
        ]
        n = sum(1 for r in rows if r["strategy"] == s and r["status"] == "ok")
        if n:
            h, _ = np.histogram(stops, edges)
            a2.stairs(
                100 * h / n,
                edges,
                color=COLOURS[k % len(COLOURS)],
                label=f"{s} ({len(stops)} of {n} stop)",
                linewidth=1.5,
            )
    a2.set_xlabel("distance along the route (leader) [m]")
    a2.set_ylabel("draws stopping here [%]")
    a2.grid(alpha=0.3)
    a2.legend()
    a1.set_title(wrap_title("Where the draws stop along the route", fig.get_figwidth()))
    return fig


@figure_function
def plot_odds_convergence(curves, *, ax=None, fig=None):
    """The estimate of P(go) and its Wilson interval against the number of draws, per strategy.
    ``curves``: ``{strategy: {"n", "p", "low", "high"}}`` (arrays)."""
    fig, axes = new_figure(ax, fig, figsize=(6, 4))
    a = axes[0, 0]
    for k, (s, c) in enumerate(curves.items()):
        col = COLOURS[k % len(COLOURS)]
        n = np.asarray(c["n"])
        a.plot(n, 100 * np.asarray(c["p"]), color=col, label=s)
        a.fill_between(n, 100 * np.asarray(c["low"]), 100 * np.asarray(c["high"]), color=col, alpha=0.2, linewidth=0)
    a.set_xscale("log")
    a.set_ylim(0, 100)
    a.set_xlabel("number of draws")
    a.set_ylabel("P(gets through) [%]")
    a.grid(alpha=0.3, which="both")
    a.legend()
    a.set_title(wrap_title("Estimate and 95 % interval against the number of draws", fig.get_figwidth()))
    return fig


@figure_function
def plot_odds_sobol(sobol, *, ax=None, fig=None):
    """First-order and total Sobol indices per uncertain input (bars with bootstrap intervals), a panel per
    strategy and output.  ``sobol``: ``{strategy: {output: {input: {first, total, first_ci, total_ci}}}}``."""
    panels = [
        (s, o, d) for s, per in sobol.items() if isinstance(per, dict) for o, d in per.items() if isinstance(d, dict)
    ]
    panels = [p for p in panels if p[2] and all(isinstance(v, dict) for v in p[2].values())]
    fig, axes = new_figure(ax, fig, max(1, len(panels)), 1, figsize=(6, 2.6 * max(1, len(panels))))
    for a, (s, o, d) in zip(axes[:, 0], panels):
        names = list(d)
        x = np.arange(len(names))
        for j, (kind, off) in enumerate((("first", -0.2), ("total", 0.2))):
            v = np.array([d[n][kind] for n in names])
            ci = np.array([d[n][f"{kind}_ci"] for n in names], float)
            err = np.abs(np.vstack([v - ci[:, 0], ci[:, 1] - v]))
            a.bar(x + off, v, 0.4, color=COLOURS[j], label=f"{kind}-order" if kind == "first" else "total")
            a.errorbar(x + off, v, yerr=err, fmt="none", ecolor="black", capsize=3)
        a.set_xticks(x, names)
        a.set_ylabel("Sobol index")
        a.set_title(f"{s}: {'getting through' if o == 'go' else 'speed made good'}")
        a.grid(alpha=0.3, axis="y")
        a.legend()
    return fig


def write_odds_figures(rows, summary, route, curves, out, plot_format="png", size=None) -> list:
    """Write the figures of :data:`ODDS_FIGURES` (``sobol`` only with Sobol indices) to ``out``; returns the paths."""
    strategies = list(summary["strategies"])
    jobs = [("odds", plot_odds, (summary,)), ("stops", plot_odds_stops, (rows, route, strategies))]
    jobs.append(("convergence", plot_odds_convergence, (curves,)))
    if summary.get("sobol"):
        jobs.append(("sobol", plot_odds_sobol, (summary["sobol"],)))
    paths = []
    for stem, draw, args in jobs:
        with headless():
            fig = draw(*args, size=size)
        paths.append(save(fig, out / f"{stem}.{plot_format}", plot_format))
    return paths
