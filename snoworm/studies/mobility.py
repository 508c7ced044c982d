"""Mobility map: which modes move a vehicle over terrain coefficient X_t, grade and towed load.

Beyond the paper: the paper shows rolling (section 5.2) and inching (section 5.1) on chosen
terrain; this map sweeps X_t and the tow for one vehicle.

Rolling (steady state, milliseconds per cell)
    The chain rolls when each segment's share of the tow, ``F_tow / N``, is below its largest
    steady drawbar on uniform terrain, :func:`snoworm.steady.max_drawbar_N` (docs/model.md
    section 2; without tow this is X_t > 0.586 for FrostyBoy).  Speed and torque follow from
    :func:`snoworm.steady.steady_state` at the rolling wheel-speed set-point; the electrical
    energy per metre is ``N n_wheels max(T_m w, 0) / (eta V)`` (definitions in
    :mod:`snoworm.results.energy`).
Inching (short simulations, seconds per cell)
    The inchworm mode (paper section 5.1) is simulated for ``inch_duration_s`` on uniform
    terrain with the tow; it *moves* the vehicle unless the run's verdict is immobilised
    (:func:`snoworm.results.verdict.verdict`, the test of ``snoworm run``, sweeps and the odds,
    with the scenario's ``simulation.immobilised`` criteria and a window of at most the run's
    duration): judged on the chain's centre against its wheels' driven travel, so a gait that
    stops its anchors by design moves, and one that makes less than a tenth of its wheels' travel
    and less than ``speed_mps`` (0.05 m/s) for a window does not; the verdict's sentence is the
    cell's ``inching_note``.  Speed and energy per metre are those of the run (from
    rest, so they include the start-up of the first phase).  Eqs. 4-6 alone would say whether
    each phase can start but not how fast the gait goes nor what it costs, hence simulation.
    A solver failure marks the cell as not inching (the message is kept in the CSV).  The runs
    are this module's inching cells (section "Inching cells").

Which cells are simulated
    By default only the cells where the chain does *not* roll: a rolling cell's region is
    "rolling" whatever inching does, so its run cannot change the map's regions (this needs no
    assumption; ``tests/test_studies_mobility.py`` checks it against the full computation on the
    9 x 3 traverse_patch grid).  Those cells leave the inching columns and ``inching_cheaper``
    empty (None).  ``every_cell=True`` (``--every-cell``) simulates every cell, which is needed
    to compare inching's and rolling's energy per metre where both move.

Grades (``grades``, docs/model.md section 7)
    Every cell can sit on a constant grade: rolling then uses the steady state on the grade
    (:func:`snoworm.steady.max_drawbar_N` with ``grade_deg``), inching a run on the grade.  With
    several grades, the inching runs of one X_t and tow are bisected over the grades where the chain
    does not roll: gravity along the track only adds a backward force on every segment, so a gait
    that fails on a grade is taken to fail on every steeper one and one that climbs a grade to
    climb every gentler one (an assumption of monotonicity, checked against ``every_cell=True`` in
    ``tests/test_studies_mobility.py``).  Cells decided that way say so in ``inching_note`` and have no
    inching speed nor energy.  ``every_cell=True`` simulates every cell.

Runtime: rolling cells are ~10 ms; each inching cell costs about 0.1 s of wall time per
simulated second (0.25-0.9 s for an 8 s run of six segments, longer at higher X_t), run in
``jobs`` worker processes, highest X_t first so that the longest runs do not finish last.

Inching cells
-------------
Each cell that the map simulates is an inchworm run (paper section 5.1) of ``duration_s`` on
uniform X_t and grade with the tow (:func:`inching_scenario`); it *moves* the vehicle unless the
run's verdict (:func:`snoworm.results.verdict.verdict`, its window at most ``duration_s``) is
immobilised.  The runs go to a process pool,
costliest (highest X_t) first.  Over several grades the runs of one X_t and tow are bisected:
a gait that fails on a grade is taken to fail on every steeper one (see above); the cells decided
that way say so in ``inching_note``.  Several gaits are mapped one after the other
(:func:`inch_gaits`).
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass

import numpy as np

from .. import steady
from ..config.scenario import SimulationConfig, TerrainConfig, TowConfig, load_scenario, scenario_from_dict
from ..config.schema import ScenarioError, check_field, dump, quote
from ..infra.csvwriter import CellFormat, csv_text, write_csv
from ..infra.folders import check_output_folder, output_folder, relocate
from ..infra.pool import ProcessExecutor
from ..modes import InchwormMode, SupervisorConfig
from ..results.energy import energy_metrics
from ..results.verdict import verdict
from ..simulation.driver import SolverError, simulate
from .gradeability import GRADEABILITY_COLUMNS, SLIP_CAP, SlipCap, grade_text, gradeability, gradeability_rows
from .sweep.spec import MAX_CASES, RANGE, parse_spec

__all__ = [
    "parse_grid",
    "parse_list",
    "parse_gait",
    "rolling_cell",
    "mobility_map",
    "map_csv",
    "rolling_speed_of",
    "gradeability",
    "REGIONS",
    "check_cell_count",
    "InchingRuns",
    "INCH_KEYS",
    "inching_mode_raw",
    "inching_scenario",
    "inch_cells",
    "inch_gaits",
    "fill_inching",
    "gait_label",
]

#: Region labels of the map, in plotting order.
REGIONS = ("immobile", "inching only", "rolling")


def _numbers(text: str, name: str, expected: str) -> np.ndarray:
    """The values of ``text`` (:func:`snoworm.studies.sweep.spec.parse_spec`), which must all be numbers."""
    opt = f"{name} {quote(text, 60)}"
    values = parse_spec(name, text, option=opt)
    if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in values):
        raise ScenarioError(f"{opt}: expected {expected}.")
    return np.array(values, dtype=float)


def parse_grid(text: str, name: str = "--xt") -> np.ndarray:
    """``"start:stop:count"`` (inclusive, ``count`` values) or a comma list -> array of floats.

    The grammar of ``snoworm sweep --set`` (:func:`snoworm.studies.sweep.spec.parse_spec`); messages
    name the option ``name``.
    """
    return _numbers(text, name, "START:STOP:COUNT (e.g. 0.2:1.0:9) or a comma-separated list of numbers")


def parse_gait(text: str):
    """``--gait``: a gait name (``six_segment``) or its phases as a list (``[[0],[1],[2]]``)."""
    t = text.strip()
    if not t.startswith("["):
        return t
    try:
        phases = json.loads(t)
    except ValueError:
        phases = None
    if not (
        isinstance(phases, list)
        and phases
        and all(isinstance(p, list) and p for p in phases)
        and all(isinstance(k, int) and not isinstance(k, bool) for p in phases for k in p)
    ):
        raise ScenarioError(
            f"--gait {quote(text, 60)}: expected a gait name or a list of phases, each a list of "
            "segment indices, e.g. [[0],[1],[2]]."
        )
    return phases


def parse_list(text: str, name: str = "--tow") -> np.ndarray:
    """``"0,100,200"`` -> array of floats (a list only, no range)."""
    expected = "a comma-separated list of numbers, e.g. 0,100,200"
    if RANGE.match(text.strip()):
        raise ScenarioError(f"{name} {quote(text, 60)}: expected {expected}.")
    return _numbers(text, name, expected)


def rolling_speed_of(sc) -> float:
    """The rolling wheel-speed set-point of a scenario's mode (:meth:`ModeConfig.rolling_speed`) [m/s]."""
    v = sc.mode.rolling_speed()
    if v is None:
        raise ScenarioError(
            f"mode.type: the mobility map takes the rolling wheel speed from the scenario's mode, "
            f"and mode {sc.mode.type!r} does not roll at one speed (a 'supervisor' or 'uniform' "
            "mode does). Pass --rolling-speed."
        )
    return float(v)


def rolling_cell(sc, xt: float, tow_N: float, wheel_speed_mps: float, grade_deg: float = 0.0) -> dict:
    """Steady rolling of the scenario's vehicle on uniform X_t and grade with a tow (one map cell).

    Returns ``rolling`` (bool), ``rolling_speed_mps``, ``rolling_slip``,
    ``rolling_energy_per_metre_J_per_m`` (electrical) and ``rolling_max_drawbar_N`` (per segment).
    Uses the first segment's parameters for every segment (a uniform chain); the scenario's sled, if it
    tows one, adds its steady pull on the grade to ``tow_N`` (:func:`snoworm.steady.tow_drawbar_N`).
    """
    seg = sc.vehicle.segment_params()[0]
    tp = sc.terrain.model.params()
    n = sc.vehicle.segments
    share = steady.tow_drawbar_N(tow_N, seg, grade_deg, sc.tow.mass_kg, sc.tow.sled_friction) / n
    dmax = steady.max_drawbar_N(xt, seg, tp, wheel_speed_mps, grade_deg=grade_deg)
    out = {
        "rolling": False,
        "rolling_speed_mps": 0.0,
        "rolling_slip": None,
        "rolling_energy_per_metre_J_per_m": None,
        "rolling_max_drawbar_N": dmax,
    }
    if share >= dmax:
        return out
    try:
        ss = steady.steady_state(xt, seg, tp, drawbar_N=share, wheel_speed_mps=wheel_speed_mps, grade_deg=grade_deg)
    except steady.Immobilised:
        return out
    if ss.ground_speed_mps <= 0:
        return out
    n_w, _, R = steady.segment_geometry(seg)
    p_el = n * n_w * max(ss.torque_Nm * wheel_speed_mps / R, 0.0) / seg.drivetrain_efficiency
    out.update(
        rolling=True,
        rolling_speed_mps=ss.ground_speed_mps,
        rolling_slip=ss.slip,
        rolling_energy_per_metre_J_per_m=p_el / ss.ground_speed_mps,
    )
    return out


def _classify(rows, inching):
    """Each cell's region (rolling, inching only, immobile) and whether inching costs less energy per metre."""
    for r in rows:
        inch_ok = bool(r.get("inching", False))
        r["region"] = "rolling" if r["rolling"] else ("inching only" if inch_ok else "immobile")
        er, ei = r["rolling_energy_per_metre_J_per_m"], r.get("inching_energy_per_metre_J_per_m")
        r["inching_cheaper"] = (
            None if inching and r.get("inching") is None else bool(er is not None and ei is not None and ei < er)
        )


def check_cell_count(n_xt: int, n_grade: int, n_tow: int) -> int:
    """The map's cell count ``n_xt * n_grade * n_tow``; ScenarioError if over ``MAX_CASES``.

    :data:`~snoworm.studies.sweep.spec.MAX_CASES` is the bound of one sweep (each cell is a steady state and possibly an inching run, and a row of
    ``mobility_map.csv``), checked before any cell is computed.
    """
    n = n_xt * n_grade * n_tow
    if n > MAX_CASES:
        raise ScenarioError(
            f"--xt x --grade x --tow: the map has {n} cells ({n_xt} X_t x {n_grade} grades x {n_tow} tows), "
            f"over the {MAX_CASES} allowed in one map (as in one sweep); use fewer values or split the map "
            "into several maps."
        )
    return n


def _checked_grid(xts, tows, grades) -> dict:
    """``xts``, ``tows`` and ``grades`` as lists of floats, each value checked against the domain of
    the scenario field it stands for (``--xt``, ``--tow``, ``--grade``)."""
    return {
        "xts": [check_field(TerrainConfig, "xt", x, "--xt") for x in xts],
        "tows": [check_field(TowConfig, "force_N", f, "--tow") for f in tows],
        "grades": [check_field(TerrainConfig, "grade_deg", g, "--grade") for g in grades],
    }


def _rolling_rows(sc, grid, wheel_speed_mps) -> list:
    """One row per cell of the grid (tows, then grades, then X_t) with its steady rolling columns."""
    return [
        {"xt": x, "tow_N": f, "grade_deg": g, **rolling_cell(sc, x, f, wheel_speed_mps, g)}
        for f in grid["tows"]
        for g in grid["grades"]
        for x in grid["xts"]
    ]


def _steady_limits(sc, xts, tows, wheel_speed_mps, slip_cap=SLIP_CAP) -> dict:
    """``rolling_limit_xt``: per tow, the level rolling limit X_t (None above 1); per tow and X_t, the
    steepest rolling grade once moving (``rolling_max_grade_deg``), from rest
    (``rolling_from_rest_grade_deg``) and with the steady slip at most ``slip_cap``
    (``rolling_slip_capped_grade_deg``; docs/model.md section 7)."""
    seg = sc.vehicle.segment_params()[0]
    tp = sc.terrain.model.params()
    n, sled = sc.vehicle.segments, {"sled_mass_kg": sc.tow.mass_kg, "sled_friction": sc.tow.sled_friction}
    limits, max_grade, rest, capped = {}, {}, {}, {}
    for f in tows:
        try:
            limits[f] = steady.immobilisation_limit_xt(
                seg, tp, drawbar_N=steady.tow_drawbar_N(f, seg, 0.0, **sled) / n, wheel_speed_mps=wheel_speed_mps
            )
        except ValueError:
            limits[f] = None
        max_grade[f] = {x: steady.max_grade_deg(x, seg, tp, wheel_speed_mps, f / n, segments=n, **sled) for x in xts}
        rest[f] = {x: steady.max_grade_from_rest_deg(x, seg, tp, f / n, segments=n, **sled) for x in xts}
        capped[f] = {
            x: steady.max_grade_below_slip_deg(x, seg, tp, wheel_speed_mps, slip_cap, f / n, segments=n, **sled)
            for x in xts
        }
    return {
        "rolling_limit_xt": limits,
        "rolling_max_grade_deg": max_grade,
        "rolling_from_rest_grade_deg": rest,
        "rolling_slip_capped_grade_deg": capped,
        "slip_cap": slip_cap,
    }


# ------------------------------------------------------- the inching cells: short inchworm runs
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
    pool : ProcessExecutor or None
        Where the runs go (None: this process).
    """

    sc: object
    grades: list
    every_cell: bool
    duration_s: float
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
    raw["tow"] = {**raw["tow"], "force_N": float(tow_N)}  # the scenario's sled, if any, with the cell's force
    raw["mode"] = inching_mode_raw(sc)
    if gait is not None:
        raw["mode"]["gait"] = gait
    raw["simulation"]["duration_s"] = float(duration_s)
    return raw


def _inch_run(raw):
    """One inching cell: its run's speed, energy per metre, and whether it moves (its verdict)."""
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
    # a cell is uniform snow without an end: a goal_m the scenario may carry does not apply
    v = verdict(res, {"window_s": min(res.scenario.simulation.immobilised.window_s, dur), "goal_m": None})
    ok = v.status != "immobilised"
    return {
        "inching": bool(ok),
        "inching_speed_mps": speed,
        "inching_energy_per_metre_J_per_m": e["energy_per_metre_J_per_m"] if ok else None,
        "inching_note": "" if ok else v.reason,
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
            inching_scenario(runs.sc, c[j]["xt"], c[j]["tow_N"], runs.duration_s, c[j]["grade_deg"], gait)
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


def mobility_map(
    sc,
    xts,
    tows,
    *,
    wheel_speed_mps: float,
    grades=(0.0,),
    inching: bool = True,
    inch_duration_s: float = 8.0,
    jobs: int = 1,
    every_cell: bool = False,
    progress=None,
    gaits=None,
    slip_cap: float = SLIP_CAP,
) -> dict:
    """Mobility map of a scenario's vehicle over ``xts`` x ``grades`` x ``tows``.

    At most :data:`~snoworm.studies.sweep.spec.MAX_CASES` cells (:func:`check_cell_count`: a
    ScenarioError before any cell is computed).

    Parameters
    ----------
    sc : Scenario
        Gives the vehicle, terrain model, inching gait (supervisor ``inching`` or inchworm mode).
    xts, tows : sequence of float
        Terrain coefficients and tow forces [N] of the grid.
    wheel_speed_mps : float
        Rolling wheel-speed set-point [m/s].
    grades : sequence of float
        Constant grades [deg] of the grid, positive uphill (docs/model.md section 7).
    inching : bool
        Simulate inching (else rolling only, steady state).
    inch_duration_s : float
        Simulated time of each inching run [s]; a cell inches unless its run's verdict is
        immobilised (:func:`snoworm.results.verdict.verdict`, the scenario's criteria, a window of
        at most ``inch_duration_s``).
    jobs : int
        Worker processes for the inching runs.
    every_cell : bool
        Simulate inching in every cell; by default only where the chain does not roll, bisected
        over the grades (the regions are the same; rolling cells then have no inching speed,
        energy nor ``inching_cheaper``, all None).
    progress : callable, optional
        ``progress(done, total)`` after each inching cell (e.g. a :class:`snoworm.infra.progress.Progress`).
    gaits : sequence, optional
        Inchworm gaits to map (names or lists of phases); None: the scenario's.  With several, a cell
        is "inching only" when any gait moves the chain; its inching columns are those of the moving
        gait with the least energy per metre (``inching_gait``), and ``inching_by_gait`` holds each
        gait's.
    slip_cap : float
        Slip cap of the slip-capped rolling limit, in (0, 1] (:func:`snoworm.steady.max_grade_below_slip_deg`).

    Returns
    -------
    dict
        ``rows`` (one dict per cell), ``rolling_limit_xt`` (per tow, the steady immobilisation
        limit on level ground, None if above 1), ``rolling_max_grade_deg`` (per tow and X_t,
        :func:`snoworm.steady.max_grade_deg`), ``gradeability`` (per tow, :func:`gradeability`),
        ``wall_time_s``, and the settings.
    """
    wall0 = time.perf_counter()
    check_cell_count(len(xts), len(grades), len(tows))
    grid = _checked_grid(xts, tows, grades)
    v = check_field(SupervisorConfig, "rolling_speed_mps", wheel_speed_mps, "--rolling-speed")
    cap = check_field(SlipCap, "slip_cap", slip_cap, "--slip-cap")
    if inching:
        check_field(SimulationConfig, "duration_s", inch_duration_s, "--inch-duration")
    rows = _rolling_rows(sc, grid, v)
    labels = [None] if not gaits else list(gaits)
    if inching:  # the inching runs (fill_inching)
        runs = InchingRuns(sc, grid["grades"], every_cell, inch_duration_s)
        fill_inching(runs, rows, labels, jobs=jobs, progress=progress)
    _classify(rows, inching)
    res = {"rows": rows, **grid, "regions": REGIONS, **_steady_limits(sc, grid["xts"], grid["tows"], v, cap)}
    res["gait_labels"] = [gait_label(g) for g in labels] if len(labels) > 1 else None
    res.update(inching=inching, every_cell=bool(every_cell), inch_duration_s=inch_duration_s)
    res.update(wheel_speed_mps=v, scenario=sc.name)
    res["gradeability"] = {f: gradeability(res, f) for f in grid["tows"]}
    res["wall_time_s"] = time.perf_counter() - wall0
    return res


#: Columns of ``mobility_map.csv``.
MAP_COLUMNS = (
    "xt",
    "tow_N",
    "grade_deg",
    "region",
    "rolling",
    "rolling_speed_mps",
    "rolling_slip",
    "rolling_energy_per_metre_J_per_m",
    "rolling_max_drawbar_N",
    "inching",
    "inching_speed_mps",
    "inching_energy_per_metre_J_per_m",
    "inching_cheaper",
    "inching_note",
)


#: Cells of ``mobility_map.csv``: 6 significant digits, booleans 1/0, commas in notes as ``;``.
MAP_FORMAT = CellFormat(comma=";")
#: Cells of ``gradeability.csv``: 6 significant digits; the sentences keep their commas (quoted).
GRADE_FORMAT = CellFormat()


def map_csv(result: dict) -> str:
    """The map's rows as CSV text (empty fields for values that do not apply)."""
    return csv_text(MAP_COLUMNS, result["rows"], MAP_FORMAT)


def run_mobility_map(
    scenario_path,
    xt_spec,
    tow_spec,
    out_dir,
    sets=(),
    *,
    rolling_speed_mps=None,
    inching=True,
    inch_duration_s=8.0,
    jobs=1,
    every_cell=False,
    plot=True,
    plot_format="png",
    overwrite=False,
    progress=None,
    grade_spec="0",
    gaits=None,
    figure_size=None,
    command=None,
    slip_cap=SLIP_CAP,
):
    """Load a scenario, compute its map, write ``mobility_map.csv`` (and the plot, a ``plot_format`` file:
    png, pdf or svg, at print ``figure_size``: column, page or WxH; with several grades also
    ``gradeability``); return (map, text, paths).

    The output folder is checked before the map is computed and written all or nothing
    (:func:`snoworm.infra.folders.output_folder`; ``command``: the command line its manifest
    records, default this process's).
    """
    sc = load_scenario(scenario_path, sets)
    v = rolling_speed_of(sc) if rolling_speed_mps is None else float(rolling_speed_mps)
    xts, tows = parse_grid(xt_spec, "--xt"), parse_list(tow_spec, "--tow")
    grades = parse_grid(grade_spec, "--grade")
    check_cell_count(len(xts), len(grades), len(tows))
    check_output_folder(out_dir, overwrite)
    res = mobility_map(
        sc,
        xts,
        tows,
        wheel_speed_mps=v,
        grades=grades,
        inching=inching,
        inch_duration_s=inch_duration_s,
        jobs=jobs,
        every_cell=every_cell,
        progress=progress,
        gaits=[parse_gait(g) for g in gaits] if gaits else None,
        slip_cap=slip_cap,
    )
    columns = MAP_COLUMNS + (("inching_gait",) if res["gait_labels"] else ())
    with output_folder(out_dir, overwrite, command) as out:
        paths = [write_csv(out / "mobility_map.csv", columns, res["rows"], MAP_FORMAT)]
        if len(res["grades"]) > 1:  # the gradeability in numbers and sentences (docs/model.md section 7)
            paths.append(
                write_csv(out / "gradeability.csv", GRADEABILITY_COLUMNS, gradeability_rows(res), GRADE_FORMAT)
            )
        if plot:
            from .. import plotting  # lazy: matplotlib costs ~0.5 s to import; --no-plot never pays it

            paths.append(
                plotting.write_figure(
                    out / "mobility_map.png", plotting.plot_mobility_map, res, fmt=plot_format, size=figure_size
                )
            )
            if len(res["grades"]) > 1:
                paths.append(
                    plotting.write_figure(
                        out / "gradeability.png", plotting.plot_gradeability, res, fmt=plot_format, size=figure_size
                    )
                )
    paths = relocate(paths, out, out_dir)
    text = grade_text(sc.name, res, inching, every_cell) if len(res["grades"]) > 1 else _map_text(sc, res)
    return res, text, paths


def _map_text(sc, res) -> str:
    """The report of a map on one grade: per tow, where the chain rolls, inches, fails."""
    lines = [
        f"{sc.name}: mobility map, {len(res['xts'])} X_t x {len(res['tows'])} tow values, {res['wall_time_s']:.1f} s"
    ]
    for f in res["tows"]:
        lim = res["rolling_limit_xt"][f]
        roll = [r["xt"] for r in res["rows"] if r["tow_N"] == f and r["rolling"]]
        inch = [r["xt"] for r in res["rows"] if r["tow_N"] == f and r["region"] == "inching only"]
        cheap = [r["xt"] for r in res["rows"] if r["tow_N"] == f and r["inching_cheaper"]]
        lines.append(
            f"tow {f:g} N: steady rolling limit X_t = {lim:.3f}"
            if lim is not None
            else f"tow {f:g} N: no rolling for X_t <= 1"
        )
        lines.append(f"  rolling from X_t = {min(roll):g}" if roll else "  rolling nowhere on the grid")
        lines.append(
            f"  inching only at X_t = {', '.join(f'{x:g}' for x in inch)}" if inch else "  no inching-only cells"
        )
        failed = [r["xt"] for r in res["rows"] if r["tow_N"] == f and r.get("inching_note", "").startswith("solver")]
        if failed:
            lines.append(
                f"  inching run failed (solver) at X_t = {', '.join(f'{x:g}' for x in failed)}; see inching_note"
            )
        if cheap:
            lines.append(f"  inching cheaper per metre than rolling at X_t = {', '.join(f'{x:g}' for x in cheap)}")
    if res["inching"] and not res["every_cell"] and any(r["rolling"] for r in res["rows"]):
        lines.append("inching not simulated where the chain rolls (--every-cell compares its energy with rolling's)")
    return "\n".join(lines)
