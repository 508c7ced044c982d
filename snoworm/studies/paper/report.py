"""The report's items in order, running them (:func:`evaluate`) and writing the report (:func:`run_paper`).

With ``jobs > 1`` the items run in parallel on the shared process pool
(:class:`snoworm.infra.pool.ProcessExecutor`), each in a worker with its own :class:`Context`; the
simulations of the longest item (Figure 5, :data:`PREFETCH`) run as separate tasks and the item
itself then runs in the main process on their results.  Every item computes exactly what it does
serially, so the claims and the report are the same (the items share no state but the cache of
runs, which only saves time).
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..._version import __version__
from ...config.schema import ScenarioError
from ...infra.folders import atomic_write_text, output_folder, relocate
from ...infra.pool import ProcessExecutor
from ...plotting import PLOT_FORMATS
from ...simulation.driver import SolverError
from .claims import Context, Section, make_claim
from .fig3_table2 import item_fig3, item_table2
from .fig5 import fig5_runs, item_fig5
from .fig6_11 import item_fig6, item_fig7, item_fig8, item_fig9, item_fig11
from .readings import item_readings
from .render import render_html, render_markdown

__all__ = ["ITEMS", "PREFETCH", "PaperReport", "default_jobs", "evaluate", "run_paper"]


#: The report's items in order: key -> item function.
ITEMS = {
    "fig3": item_fig3,
    "table2": item_table2,
    "fig5": item_fig5,
    "fig6": item_fig6,
    "fig7": item_fig7,
    "fig8": item_fig8,
    "fig9": item_fig9,
    "fig11": item_fig11,
    "readings": item_readings,
}

#: Items whose simulations run as separate pool tasks before the item (``jobs > 1``): key -> a
#: function of the Context giving ``[(scenario name, extra overrides), ...]``, longest first.
PREFETCH = {"fig5": fig5_runs}

#: Wall time of each item in the serial full report [s] (measured, 2-core machine): the pool
#: starts the longest tasks first.  Only the order depends on it, never a result.
_COST_HINT_S = {
    "fig3": 0.4,
    "table2": 0.6,
    "fig5": 0.5,
    "fig6": 0.6,
    "fig7": 0.6,
    "fig8": 0.9,
    "fig9": 1.3,
    "fig11": 0.9,
    "readings": 1.0,
}

#: Most worker processes ``snoworm paper`` starts by default (there are about a dozen tasks).
MAX_DEFAULT_JOBS = 8


def default_jobs() -> int:
    """Worker processes by default: the usable cores, at most :data:`MAX_DEFAULT_JOBS`."""
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        n = os.cpu_count() or 1
    return max(1, min(n, MAX_DEFAULT_JOBS))


@dataclass
class PaperReport:
    """All sections of a run, with timing and the files written."""

    sections: list
    quick: bool
    wall_time_s: float
    paths: list = field(default_factory=list)

    @property
    def claims(self) -> list:
        return [c for s in self.sections for c in s.claims]

    @property
    def all_hold(self) -> bool:
        return all(c.holds for c in self.claims)


def _error_section(key, exc):
    fn = ITEMS[key]
    return Section(
        key,
        (fn.__doc__ or key).splitlines()[0],
        "",
        claims=[
            make_claim(
                f"{key}.ran",
                key,
                "the item's simulations ran",
                {"error": f"{type(exc).__name__}: {exc}"},
                "no solver or input error",
                False,
            )
        ],
    )


def _run_item(ctx, key) -> Section:
    """Run one item; a solver or input error becomes the failing claim ``<key>.ran``."""
    t0 = time.perf_counter()
    try:
        sec = ITEMS[key](ctx)
    except (SolverError, ScenarioError) as exc:
        sec = _error_section(key, exc)
    sec.wall_time_s = time.perf_counter() - t0
    return sec


def _task(task):
    """Worker side of :func:`evaluate`: ``("item", key)`` -> its Section, ``("run", (name, extra))`` ->
    the Result or None if it failed (the item then runs it again and reports the error)."""
    kind, what, ctx_args = task
    ctx = Context(*ctx_args)
    if kind == "item":
        return kind, what, _run_item(ctx, what), 0.0
    t0 = time.perf_counter()
    try:
        res = ctx.run(*what)
    except (SolverError, ScenarioError):
        res = None
    return kind, what, res, time.perf_counter() - t0


def _evaluate_pooled(ctx, keys, jobs, done):
    """The items' sections by key, computed on ``jobs`` worker processes; ``done(key, sec)`` per item."""
    runs = {k: [(name, list(extra)) for name, extra in PREFETCH[k](ctx)] for k in keys if k in PREFETCH}
    tasks = [("run", r, ctx.args()) for k in runs for r in runs[k]]
    tasks += [
        ("item", k, ctx.args())
        for k in sorted((k for k in keys if k not in runs), key=lambda k: -_COST_HINT_S.get(k, 1.0))
    ]
    waiting = {k: len(v) for k, v in runs.items()}
    spent = dict.fromkeys(runs, 0.0)
    out = {}
    with ProcessExecutor(min(jobs, len(tasks))) as pool:
        for kind, what, value, dt in pool.map_unordered(_task, tasks):
            if kind == "item":
                out[what] = value
                done(what, value)
                continue
            if value is not None:
                ctx.put(*what, value)
            for k in runs:  # an item whose runs are all in runs here, on the cache
                if what in runs[k] and waiting[k] > 0:
                    waiting[k] -= 1
                    spent[k] += dt
                    if waiting[k] == 0:
                        out[k] = _run_item(ctx, k)
                        out[k].wall_time_s += spent[k]
                        done(k, out[k])
    return out


def evaluate(
    items=None,
    quick=False,
    *,
    model=None,
    scenario_overrides=None,
    out_dir=None,
    progress=None,
    jobs=1,
    plot_format="png",
    figure_size=None,
) -> list:
    """Run report items and return their :class:`Section` objects.

    Parameters
    ----------
    items : sequence of str, optional
        Keys of :data:`ITEMS` (default: all, in order).
    quick, model, scenario_overrides, out_dir, plot_format, figure_size
        See :class:`Context`.  ``out_dir=None`` draws no figures.
    progress : callable, optional
        Called with one line of text per item when it finishes (in the order they finish).
    jobs : int
        Worker processes (:class:`snoworm.infra.pool.ProcessExecutor`); 1 runs the items one after
        the other in this process.  The sections and claims do not depend on it.

    A solver failure or invalid scenario in one item becomes a failing claim ``<key>.ran``
    carrying the error message; the other items still run.  The sections come in the order of
    ``items``; ``Section.wall_time_s`` is the item's own time (in parallel, including its
    prefetched runs).
    """
    if plot_format not in PLOT_FORMATS:
        raise ScenarioError(f"plot format {plot_format!r}: expected one of {', '.join(PLOT_FORMATS)}.")
    ctx = Context(quick, model, scenario_overrides, out_dir, plot_format, figure_size)
    keys = list(ITEMS) if items is None else list(items)
    unknown = [k for k in keys if k not in ITEMS]
    if unknown:
        raise ScenarioError(f"unknown report item(s) {unknown}; known: {', '.join(ITEMS)}.")
    finished = []

    def done(key, sec):
        finished.append(key)
        if progress is not None:
            bad = [c.id for c in sec.claims if not c.holds]
            progress(
                f"[{len(finished)}/{len(keys)}] {sec.title}: {len(sec.claims) - len(bad)}/{len(sec.claims)} "
                "claims hold" + (f" (failed: {', '.join(bad)})" if bad else "") + f" [{sec.wall_time_s:.1f} s]"
            )

    if int(jobs) > 1 and len(keys) > 1:
        by_key = _evaluate_pooled(ctx, keys, int(jobs), done)
        return [by_key[k] for k in keys]
    out = []
    for key in keys:
        out.append(_run_item(ctx, key))
        done(key, out[-1])
    return out


def run_paper(
    out_dir,
    quick=False,
    progress=None,
    overwrite=False,
    jobs=1,
    plot_format="png",
    figure_size=None,
    *,
    command: str | None = None,
) -> PaperReport:
    """Run every item, write the figures, ``report.md``, ``report.html`` and ``claims.json`` into ``out_dir``.

    ``jobs`` worker processes run the items (:func:`evaluate`; 1: serial, in this process).
    ``plot_format``: png (default, 200 dpi), pdf or svg figures; report.html shows PNG and SVG
    inline and links PDF figures.  ``figure_size``: their print size (column, page or WxH).

    All or nothing (:func:`snoworm.infra.folders.output_folder`): the figures and the report go to a
    temporary sibling folder that replaces ``out_dir`` when everything is written; ``command`` is
    the command line its manifest records (default: this process's).

    Returns
    -------
    PaperReport
    """
    with output_folder(out_dir, overwrite, command) as out:
        rep = _run_into(out, quick, progress, jobs, plot_format, figure_size)
    rep.paths = relocate(rep.paths, out, out_dir)
    for sec in rep.sections:
        sec.figures = relocate(sec.figures, out, out_dir)
    return rep


def _run_into(out: Path, quick, progress, jobs, plot_format, figure_size=None) -> PaperReport:
    t0 = time.perf_counter()
    sections = evaluate(
        None, quick, out_dir=out, progress=progress, jobs=jobs, plot_format=plot_format, figure_size=figure_size
    )
    rep = PaperReport(sections, bool(quick), time.perf_counter() - t0)
    figs = [p for s in sections for p in s.figures]
    rep.paths = figs + [
        atomic_write_text(out / "report.md", render_markdown(rep)),
        atomic_write_text(out / "report.html", render_html(rep)),
        atomic_write_text(
            out / "claims.json",
            json.dumps(
                {
                    "snoworm_version": __version__,
                    "quick": rep.quick,
                    "all_hold": rep.all_hold,
                    "claims": [c.to_dict() for c in rep.claims],
                    "variants": {
                        s.key: [
                            {"label": v.label, "overrides": v.overrides, "claims": [c.to_dict() for c in v.claims]}
                            for v in s.variants
                        ]
                        for s in sections
                        if s.variants
                    },
                },
                indent=2,
            )
            + "\n",
        ),
    ]
    return rep
