"""The inching cells of a mobility map (:mod:`snoworm.studies.mobility`): short inchworm runs.

Each cell that the map simulates is an inchworm run (paper section 5.1) of ``duration_s`` on
uniform X_t and grade with the tow (:func:`inching_scenario`); it *moves* the vehicle when the
chain's mean position advances at ``min_speed_mps`` or more.  The runs go to a process pool,
costliest (highest X_t) first.  Over several grades the runs of one X_t and tow are bisected:
a gait that fails on a grade is taken to fail on every steeper one (the mobility module's
docstring says why and where it is checked); the cells decided that way say so in
``inching_note``.  Several gaits are mapped one after the other (:func:`inch_gaits`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..config.scenario import scenario_from_dict
from ..config.schema import ScenarioError, dump
from ..infra.pool import ProcessExecutor
from ..modes import InchwormMode
from ..results.energy import energy_metrics
from ..simulation.driver import SolverError, simulate

__all__ = [
    "InchingRuns",
    "INCH_KEYS",
    "inching_mode_raw",
    "inching_scenario",
    "inch_cells",
    "inch_gaits",
    "fill_inching",
    "gait_label",
]


@dataclass(frozen=True)
class InchingRuns:
    """What every inching run of one map shares.

    Attributes
    ----------
    sc : Scenario
        The map's scenario (vehicle, terrain model, the gait of its mode).
    grades : list of float
        The map's grades [deg] (several: the runs are bisected over them).
    every_cell : bool
        Simulate every cell, also where the chain rolls, and every grade.
    duration_s : float
        Simulated time of each run [s].
    min_speed_mps : float
        Mean chain speed from which a run counts as moving [m/s].
    pool : ProcessExecutor or None
        Where the runs go (None: this process).
    """

    sc: object
    grades: list
    every_cell: bool
    duration_s: float
    min_speed_mps: float
    pool: ProcessExecutor | None = None


def inching_mode_raw(sc) -> dict:
    """The ``mode:`` mapping of an inchworm run with the gait of the scenario's mode (ScenarioError if it does not inch)."""
    raw = sc.mode.inching_settings()
    if raw is None:
        raise ScenarioError(
            f"mode.type: the mobility map takes the inching gait from the scenario's mode, and mode "
            f"{sc.mode.type!r} does not inch (a 'supervisor' or 'inchworm' mode does). "
            "Use --no-inching for rolling only."
        )
    raw = dump(raw)
    raw.update({"type": InchwormMode.name, "start_time_s": 0.0})
    return raw


def inching_scenario(sc, xt: float, tow_N: float, duration_s: float, grade_deg: float = 0.0, gait=None) -> dict:
    """Raw scenario mapping of a short inchworm run on uniform X_t and grade with a tow (one map cell);
    ``gait`` (a gait name or list of phases) replaces the scenario's gait."""
    raw = sc.to_dict()
    raw["name"] = f"{sc.name}_inch_xt{xt:g}_tow{tow_N:g}" + (f"_grade{grade_deg:g}" if grade_deg else "")
    raw["terrain"] = {"xt": float(xt), "model": raw["terrain"]["model"]}
    if grade_deg:
        raw["terrain"]["grade_deg"] = float(grade_deg)
    raw["tow"] = {"force_N": float(tow_N)}
    raw["mode"] = inching_mode_raw(sc)
    if gait is not None:
        raw["mode"]["gait"] = gait
    raw["simulation"]["duration_s"] = float(duration_s)
    return raw


def _inch_run(args):
    raw, min_speed = args
    try:
        res = simulate(scenario_from_dict(raw))
    except SolverError as exc:
        return {
            "inching": False,
            "inching_speed_mps": 0.0,
            "inching_energy_per_metre_J_per_m": None,
            "inching_note": f"solver failure: {exc}"[:200],
        }
    e = energy_metrics(res)
    dur = float(res.t[-1] - res.t[0])
    speed = e["distance_m"] / dur
    ok = speed >= min_speed
    return {
        "inching": bool(ok),
        "inching_speed_mps": speed,
        "inching_energy_per_metre_J_per_m": e["energy_per_metre_J_per_m"] if ok else None,
        "inching_note": "",
    }


def _indexed_inch_run(item):
    j, task = item
    return j, _inch_run(task)


def _inch_all(tasks, pool, cost=None, report=None):
    """The inching runs' outcomes, in the order of ``tasks`` (in ``pool``, a :class:`ProcessExecutor`, or
    here when None).

    ``cost`` (one number per task, optional): the pool starts the costliest tasks first, so that
    no long run starts last while the other workers idle; the outcomes do not depend on the order.
    ``report()`` is called after each run.
    """
    outs = [None] * len(tasks)
    if pool is not None:
        order = range(len(tasks)) if cost is None else sorted(range(len(tasks)), key=lambda j: -cost[j])
        for j, o in pool.map_unordered(_indexed_inch_run, ((j, tasks[j]) for j in order)):
            outs[j] = o
            if report is not None:
                report()
        return outs
    for j, tk in enumerate(tasks):
        outs[j] = _inch_run(tk)
        if report is not None:
            report()
    return outs


_INFERRED = {
    True: "not simulated: climbs a steeper grade (bisection over the grades)",
    False: "not simulated: fails on a gentler grade (bisection over the grades)",
}


def inch_cells(runs: InchingRuns, rows, progress=None, gait=None):
    """Fill the inching columns of ``rows`` with ``gait`` (None: the scenario's): every cell that
    does not roll (every cell with ``runs.every_cell``), bisected over the grades of each X_t and
    tow (module docstring); ``progress(done, total)`` after each run."""
    every_cell, grades = runs.every_cell, runs.grades
    todo = [r for r in rows if every_cell or not r["rolling"]]
    chains = {}
    for r in todo:
        chains.setdefault((r["xt"], r["tow_N"]), []).append(r)
    chains = [sorted(c, key=lambda r: r["grade_deg"]) for c in chains.values()]
    bounds = [[0, len(c)] for c in chains]  # cells below lo climb, cells from hi on fail
    every = every_cell or len(grades) == 1
    total = len(todo) if every else sum(int(np.ceil(np.log2(len(c) + 1))) for c in chains)
    done = [0]

    def report():
        done[0] += 1
        if progress is not None:
            progress(done[0], max(total, done[0]))

    while True:
        if every:
            picks = [(c, b, j) for c, b in zip(chains, bounds) for j in range(b[0], b[1])]
        else:
            picks = [(c, b, (b[0] + b[1]) // 2) for c, b in zip(chains, bounds) if b[0] < b[1]]
        if not picks:
            break
        tasks = [
            (
                inching_scenario(runs.sc, c[j]["xt"], c[j]["tow_N"], runs.duration_s, c[j]["grade_deg"], gait),
                runs.min_speed_mps,
            )
            for c, _, j in picks
        ]
        for (c, b, j), o in zip(picks, _inch_all(tasks, runs.pool, [c[j]["xt"] for c, _, j in picks], report)):
            c[j].update(o)
            if every:
                b[0] = b[1]
            elif o["inching"]:
                b[0] = j + 1
            else:
                b[1] = j
    for c, (lo, _) in zip(chains, bounds):
        for j, r in enumerate(c):
            if "inching" not in r:
                r.update(
                    inching=j < lo,
                    inching_speed_mps=None,
                    inching_energy_per_metre_J_per_m=None,
                    inching_note=_INFERRED[j < lo],
                )


INCH_KEYS = ("inching", "inching_speed_mps", "inching_energy_per_metre_J_per_m", "inching_note")


def gait_label(gait) -> str:
    """A gait's name, or its phases written as a compact list (``[[0],[1]]``)."""
    if isinstance(gait, str):
        return gait
    return "[" + ",".join("[" + ",".join(str(int(k)) for k in ph) + "]" for ph in gait) + "]"


def inch_gaits(runs: InchingRuns, rows, gaits, progress=None):
    """The inching cells of every gait (:func:`inch_cells` each); one gait fills ``rows`` directly.
    With several, a cell takes the columns of the moving gait with the least energy per metre
    (``inching_gait``) and keeps every gait's in ``inching_by_gait``."""
    if gaits == [None]:
        inch_cells(runs, rows, progress)
        return
    per, base = {}, [0]
    for i, g in enumerate(gaits):
        sub = [{k: r[k] for k in ("xt", "tow_N", "grade_deg", "rolling")} for r in rows]
        prog = None if progress is None else (lambda d, t, i=i: progress(base[0] + d, base[0] + t * (len(gaits) - i)))
        inch_cells(runs, sub, prog, g)
        base[0] += sum(
            1 for c in sub if c.get("inching_speed_mps") is not None or c.get("inching_note", "")[:6] == "solver"
        )
        per[gait_label(g)] = sub
    for j, r in enumerate(rows):
        cells = {lab: {k: sub[j][k] for k in INCH_KEYS} for lab, sub in per.items() if "inching" in sub[j]}
        if not cells:
            continue
        moved = [lab for lab, c in cells.items() if c["inching"]]
        best = (
            min(moved, key=lambda lab, c=cells: c[lab]["inching_energy_per_metre_J_per_m"] or math.inf)
            if moved
            else next(iter(cells))
        )
        r.update(cells[best], inching_gait=best if moved else "", inching_by_gait=cells)


def fill_inching(runs: InchingRuns, rows, gaits, *, jobs=1, progress=None):
    """The inching columns of every row of a map (:func:`inch_gaits` in ``jobs`` processes); a cell
    not simulated gets None.  Every gait is checked first, here (a one-line error), not in a worker."""
    first = rows[0]
    for g in gaits:
        scenario_from_dict(
            inching_scenario(runs.sc, first["xt"], first["tow_N"], runs.duration_s, first["grade_deg"], g)
        )
    if jobs > 1:
        with ProcessExecutor(jobs) as pool:
            inch_gaits(dataclasses.replace(runs, pool=pool), rows, gaits, progress)
    else:
        inch_gaits(runs, rows, gaits, progress)
    for r in rows:
        if "inching" not in r:
            r.update(inching=None, inching_speed_mps=None, inching_energy_per_metre_J_per_m=None, inching_note="")
