"""Figures of a sweep's table: metrics against the swept value (one varying key, or a zip) or a
heat map of one metric (two keys on a grid).  Used by :meth:`SweepTable.plot` and by
:func:`~snoworm.studies.sweep.run.run_sweep` for ``sweep.<fmt>`` / ``heatmap.<fmt>``."""

from __future__ import annotations

import numpy as np

from ...infra.csvwriter import FULL, canonical_json, format_cell

__all__ = ["plot_table", "write_plot", "SWEEP_METRICS"]

#: The metrics drawn against a one-axis (or zip) sweep, a panel each.
SWEEP_METRICS = ("mean_speed_mps", "mean_slip", "max_link_force_N", "energy_per_m_J")


def _distinct(values) -> list:
    """Distinct values in order of first appearance (the rows are in case-id order, so a grid's
    values come back in the order of the sweep's definition)."""
    seen, out = set(), []
    for v in values:
        key = canonical_json(v)
        if key not in seen:
            seen.add(key)
            out.append(v)
    return out


def _positions(values):
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return [float(v) for v in values], None
    return list(range(len(values))), [format_cell(v, FULL) for v in values]


def _layout(table):
    """("line", key) for one varying key or a zip; ("heatmap", (key_x, key_y)) for a two-key grid."""
    varying = [k for k in table.keys if len(_distinct(table.column(k))) > 1] or list(table.keys[:1])
    counts = [len(_distinct(table.column(k))) for k in varying]
    grid = len(varying) == 2 and counts[0] * counts[1] == len(table.rows)
    if grid:
        return "heatmap", tuple(varying)
    if len(varying) > 2 and int(np.prod(counts)) == len(table.rows):
        raise ValueError(
            f"a sweep over {len(varying)} keys on a grid has no standard figure; "
            "pick two keys with table.to_pandas() and plotting.plot_sweep_heatmap"
        )
    return "line", varying[0]


def plot_table(table, metric=None, *, size=None, ax=None, fig=None):
    """The standard figure of a sweep: ``metric`` (default: the four of :data:`SWEEP_METRICS`)
    against the swept value for one varying key or a zip (immobilised cases crossed, failed ones
    dotted), or a heat map of ``metric`` (default ``mean_speed_mps``) over a two-key grid.
    ``size``, ``ax``, ``fig``: as for every plotting function.  Returns the Figure."""
    from ... import plotting  # lazy: matplotlib costs ~0.5 s to import; sweeps without plots never pay it

    kind, keys = _layout(table)
    ok = [r["status"] == "ok" for r in table.rows]
    if kind == "line":
        x, labels = _positions(table.column(keys))
        names = [metric] if isinstance(metric, str) else list(metric or SWEEP_METRICS)
        return plotting.plot_sweep(
            x,
            {m: table.column(m) for m in names},
            keys,
            immobilised=table.column("immobilised"),
            ok=ok,
            tick_labels=labels,
            size=size,
            ax=ax,
            fig=fig,
        )
    metric = metric or "mean_speed_mps"
    kx, ky = keys
    xs, ys = _distinct(table.column(kx)), _distinct(table.column(ky))
    xi = {canonical_json(v): j for j, v in enumerate(xs)}
    yi = {canonical_json(v): j for j, v in enumerate(ys)}
    grid = np.full((len(ys), len(xs)), np.nan)
    imm = np.zeros(grid.shape, bool)
    fail = np.zeros(grid.shape, bool)
    for r in table.rows:
        j, k = yi[canonical_json(r[ky])], xi[canonical_json(r[kx])]
        if r["status"] == "ok":
            grid[j, k] = np.nan if r.get(metric) is None else r[metric]
            imm[j, k] = bool(r["immobilised"])
        else:
            fail[j, k] = True
    return plotting.plot_sweep_heatmap(
        [format_cell(v, FULL) for v in xs],
        [format_cell(v, FULL) for v in ys],
        grid,
        kx,
        ky,
        plotting.quantity_label(metric),
        immobilised=imm,
        failed=fail,
        size=size,
        ax=ax,
        fig=fig,
    )


def write_plot(table, out, plot_format="png", size=None):
    """Write the sweep's standard figure (headless) as ``sweep.<fmt>`` (line) or
    ``heatmap.<fmt>`` (grid of two keys) in ``out``; nothing for a grid of more keys.
    Returns the path or None."""
    from ... import plotting  # lazy: matplotlib costs ~0.5 s to import; sweeps without plots never pay it

    try:
        kind, _ = _layout(table)
    except ValueError:
        return None
    name = "sweep" if kind == "line" else "heatmap"
    return plotting.write_figure(
        out / f"{name}.{plot_format}", lambda size=None: plot_table(table, size=size), fmt=plot_format, size=size
    )
