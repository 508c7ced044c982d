"""Reproduce the paper's quantitative content in one command (``snoworm paper``).

Every item of the paper with numbers behind it -- Figure 3, Table 2, Figure 5, Figures 6 to 11 --
is recomputed from the shipped scenarios and the steady-state model, and each statement of the
paper about it is turned into a :class:`Claim` by a *check function*: the claim's ``holds`` is
derived from the computed numbers and a stated tolerance, never written down.  Where the model
chose a reading of the paper (docs/model.md section 2: the peak exponent ``d`` of Eq. 2, the
resistance-torque law fitted to Table 2, the wheel torque-balance convention), the same checks
are re-run under the alternative and the report shows which claims then change.

Data flow::

    Context (quick?, terrain-model overrides, per-scenario overrides, output dir)
      -> item functions (one per figure/table: run scenarios, check claims, draw figures)
      -> Section objects (claims, tables, figures, variants)
      -> report.md, report.html (figures embedded as base64 PNG), claims.json

Two kinds of claim (``Claim.source``): ``"paper"`` -- stated in the paper (quoted with its
section); ``"model"`` -- a number of the reference model (docs/model.md) the paper does not print,
e.g. Fig 6's 4.80 % slip or the d = 1 failure slips.  Both count for ``--strict``; the claims
re-evaluated under an alternative reading (``Section.variants``) do not -- they are expected to
change.

Modules, each importing only those above it in this list (and lower layers of snoworm):

- :mod:`.claims` -- Claim, Variant, Section, make_claim, find_claim, the Context that runs and caches scenarios;
- :mod:`.fig3_table2`, :mod:`.fig5`, :mod:`.fig6_11` -- one check/item pair per figure or table;
- :mod:`.readings` -- the alternative readings of the paper, re-using the Fig 3 and Table 2 checks;
- :mod:`.render` -- report.md and report.html;
- :mod:`.report` -- the ITEMS registry, evaluate (serial, or the items in parallel on the shared
  process pool, :mod:`snoworm.infra.pool`), run_paper, PaperReport.
"""

from __future__ import annotations

from .claims import (
    QUICK_INCHWORM_DURATION_S,
    SCENARIO_DIR,
    STEADY_WINDOW_S,
    Claim,
    Context,
    Section,
    Variant,
    find_claim,
    make_claim,
    start_time_s,
    steady_mean,
)
from .fig3_table2 import TABLE2_CASES, check_fig3, check_table2, item_fig3, item_table2, table2_model
from .fig5 import (
    FIG5_LATE_EVERY_MAX,
    FIG5_LATE_FRACTION_MAX,
    FIG5_MOVE_MIN_M,
    FIG5_NONPAIR_RMS_MIN,
    FIG5_PAIR_RMS_MAX,
    FIG5_PAIRS,
    FIG5_PEAK_EARLY_FRACTION,
    FIG5_XT_HIGH,
    SLIDING_FRACTION,
    backward_sliding_timing,
    check_fig5,
    fig5_runs,
    item_fig5,
    pair_overlap,
)
from .fig6_11 import (
    FC_TOL_N,
    FIG6_TOL_N,
    PAPER_TOW_N,
    check_fig6,
    check_fig7,
    check_fig8,
    check_fig9,
    check_fig11,
    item_fig6,
    item_fig7,
    item_fig8,
    item_fig9,
    item_fig11,
)
from .readings import item_readings
from .render import render_html, render_markdown
from .report import ITEMS, PaperReport, default_jobs, evaluate, run_paper

__all__ = [
    "Claim",
    "Variant",
    "Section",
    "Context",
    "PaperReport",
    "ITEMS",
    "default_jobs",
    "QUICK_INCHWORM_DURATION_S",
    "SCENARIO_DIR",
    "STEADY_WINDOW_S",
    "evaluate",
    "run_paper",
    "render_markdown",
    "render_html",
    "find_claim",
    "make_claim",
    "start_time_s",
    "steady_mean",
    "TABLE2_CASES",
    "table2_model",
    "check_fig3",
    "check_table2",
    "check_fig5",
    "check_fig6",
    "check_fig7",
    "check_fig8",
    "check_fig9",
    "check_fig11",
    "fig5_runs",
    "item_fig3",
    "item_table2",
    "item_fig5",
    "item_fig6",
    "item_fig7",
    "item_fig8",
    "item_fig9",
    "item_fig11",
    "item_readings",
    "pair_overlap",
    "backward_sliding_timing",
    "FIG5_PAIRS",
    "FIG5_PAIR_RMS_MAX",
    "FIG5_NONPAIR_RMS_MIN",
    "FIG5_MOVE_MIN_M",
    "FIG5_PEAK_EARLY_FRACTION",
    "FIG5_LATE_FRACTION_MAX",
    "FIG5_LATE_EVERY_MAX",
    "FIG5_XT_HIGH",
    "SLIDING_FRACTION",
    "PAPER_TOW_N",
    "FIG6_TOL_N",
    "FC_TOL_N",
]
