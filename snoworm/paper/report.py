"""The report's items in order, running them (:func:`evaluate`) and writing the report (:func:`run_paper`)."""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

from .._version import __version__
from ..driver import SolverError
from ..fileio import atomic_write_text, output_folder, relocate
from ..schema import ScenarioError
from .claims import Context, Section, make_claim
from .fig3_table2 import item_fig3, item_table2
from .fig5 import item_fig5
from .fig6_11 import item_fig6, item_fig7, item_fig8, item_fig9, item_fig11
from .readings import item_readings
from .render import render_html, render_markdown

__all__ = ["ITEMS", "PaperReport", "evaluate", "run_paper"]


#: The report's items in order: key -> item function.
ITEMS = {"fig3": item_fig3, "table2": item_table2, "fig5": item_fig5, "fig6": item_fig6, "fig7": item_fig7,
         "fig8": item_fig8, "fig9": item_fig9, "fig11": item_fig11, "readings": item_readings}


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
    return Section(key, (fn.__doc__ or key).splitlines()[0], "", claims=[make_claim(
        f"{key}.ran", key, "the item's simulations ran", {"error": f"{type(exc).__name__}: {exc}"},
        "no solver or input error", False)])


def evaluate(items=None, quick=False, model=None, scenario_overrides=None, out_dir=None, progress=None) -> list:
    """Run report items and return their :class:`Section` objects.

    Parameters
    ----------
    items : sequence of str, optional
        Keys of :data:`ITEMS` (default: all, in order).
    quick, model, scenario_overrides, out_dir
        See :class:`Context`.  ``out_dir=None`` draws no figures.
    progress : callable, optional
        Called with one line of text per item when it finishes.

    A solver failure or invalid scenario in one item becomes a failing claim ``<key>.ran``
    carrying the error message; the other items still run.
    """
    ctx = Context(quick, model, scenario_overrides, out_dir)
    keys = list(ITEMS) if items is None else list(items)
    unknown = [k for k in keys if k not in ITEMS]
    if unknown:
        raise ScenarioError(f"unknown report item(s) {unknown}; known: {', '.join(ITEMS)}.")
    out = []
    for n, key in enumerate(keys, 1):
        t0 = time.perf_counter()
        try:
            sec = ITEMS[key](ctx)
        except (SolverError, ScenarioError) as exc:
            sec = _error_section(key, exc)
        sec.wall_time_s = time.perf_counter() - t0
        out.append(sec)
        if progress is not None:
            bad = [c.id for c in sec.claims if not c.holds]
            progress(f"[{n}/{len(keys)}] {sec.title}: {len(sec.claims) - len(bad)}/{len(sec.claims)} claims hold"
                     + (f" (failed: {', '.join(bad)})" if bad else "") + f" [{sec.wall_time_s:.1f} s]")
    return out


def run_paper(out_dir, quick=False, progress=None, overwrite=False) -> PaperReport:
    """Run every item, write the figures, ``report.md``, ``report.html`` and ``claims.json`` into ``out_dir``.

    All or nothing (:func:`snoworm.fileio.output_folder`): the figures and the report go to a
    temporary sibling folder that replaces ``out_dir`` when everything is written.

    Returns
    -------
    PaperReport
    """
    with output_folder(out_dir, overwrite) as out:
        rep = _run_into(out, quick, progress)
    rep.paths = relocate(rep.paths, out, out_dir)
    for sec in rep.sections:
        sec.figures = relocate(sec.figures, out, out_dir)
    return rep


def _run_into(out: Path, quick, progress) -> PaperReport:
    t0 = time.perf_counter()
    sections = evaluate(None, quick, out_dir=out, progress=progress)
    rep = PaperReport(sections, bool(quick), time.perf_counter() - t0)
    figs = [p for s in sections for p in s.figures]
    rep.paths = figs + [
        atomic_write_text(out / "report.md", render_markdown(rep)),
        atomic_write_text(out / "report.html", render_html(rep)),
        atomic_write_text(out / "claims.json", json.dumps(
            {"snoworm_version": __version__, "quick": rep.quick, "all_hold": rep.all_hold,
             "claims": [c.to_dict() for c in rep.claims],
             "variants": {s.key: [{"label": v.label, "overrides": v.overrides,
                                   "claims": [c.to_dict() for c in v.claims]} for v in s.variants]
                          for s in sections if s.variants}}, indent=2) + "\n"),
    ]
    return rep

