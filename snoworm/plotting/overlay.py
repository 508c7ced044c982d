"""Several runs on one figure: :func:`compare` (``snoworm.plotting.compare([res_a, res_b], kind)``).

Each run is reduced to one curve per quantity (the chain's mean speed, the leader's position,
the largest link force, ...), so runs with different numbers of segments compare too.
"""

from __future__ import annotations

import numpy as np

from .style import figure_function, legend_outside, new_figure, series_style, title

__all__ = ["compare", "COMPARE_KINDS"]


def _mean_speed(r):
    return r.t, r.segments["v_mps"].mean(1)


def _position(r):
    return r.t, r.segments["x_m"][:, 0] - r.segments["x_m"][0, 0]


def _max_link(r):
    F = r.links["force_N"]
    return r.t, (np.abs(F).max(1) if F.shape[1] else np.zeros_like(r.t))


def _slip(r):
    return r.t, r.segments["slip"].mean(1)


def _power(r):
    return r.t, r.segments["motor_electrical_power_W"].sum(1)


def _energy(r):
    e = r.energy_along()
    return e["distance_m"], e["total_electrical_J"] / 1e3


#: kind -> (curve of a run: (x, y), x label, y label).
COMPARE_KINDS = {
    "speeds": (_mean_speed, "time [s]", "mean ground speed [m/s]"),
    "positions": (_position, "time [s]", "leader advance [m]"),
    "forces": (_max_link, "time [s]", "largest |link force| [N]"),
    "slip": (_slip, "time [s]", "mean slip [-]"),
    "motor": (_power, "time [s]", "electrical power [W]"),
    "energy": (_energy, "distance [m]", "electrical energy [kJ]"),
}


@figure_function
def compare(results, kind="speeds", labels=None, *, ax=None, fig=None):
    """Overlay several runs on one panel.

    Parameters
    ----------
    results : sequence of Result
        The runs (any number of segments each).
    kind : str
        ``speeds`` (mean ground speed of the chain), ``positions`` (the leader's advance),
        ``forces`` (largest absolute link force), ``slip`` (mean slip), ``motor`` (electrical
        power of all motors) or ``energy`` (electrical energy against distance).
    labels : sequence of str, optional
        One per run (default: the scenario names, numbered when they repeat).
    ax, fig, size
        Your own axes or figure; the print size (``"column"``, ``"page"``, ``"WxH"``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if kind not in COMPARE_KINDS:
        raise ValueError(f"unknown comparison kind {kind!r}; kinds: {', '.join(COMPARE_KINDS)}")
    results = list(results)
    if not results:
        raise ValueError("compare needs at least one result")
    names = [r.scenario.name for r in results]
    if labels is None:
        labels = [f"{n} ({i})" if names.count(n) > 1 else n for i, n in enumerate(names)]
    if len(labels) != len(results):
        raise ValueError(f"labels: {len(labels)} given for {len(results)} results; give one per result")
    own = ax is None and fig is None
    fig, axes = new_figure(ax, fig, 1, 1, figsize=(9, 4))
    a = axes[0, 0]
    curve, xl, yl = COMPARE_KINDS[kind]
    for k, (r, lab) in enumerate(zip(results, labels)):
        x, y = curve(r)
        a.plot(x, y, label=str(lab), **series_style(k, len(x), len(results)))
    a.set_xlabel(xl)
    a.set_ylabel(yl)
    a.grid(alpha=0.3)
    legend_outside(a)
    title(fig, axes, f"{yl.split(' [')[0]} of {len(results)} runs", own)
    return fig
