"""Mobility map: which modes move a vehicle over terrain coefficient X_t and towed load.

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
    terrain with the tow; it *moves* the vehicle when the chain's mean position advances at
    ``inch_min_speed_mps`` or more.  Speed and energy per metre are those of the run (from
    rest, so they include the start-up of the first phase).  Eqs. 4-6 alone would say whether
    each phase can start but not how fast the gait goes nor what it costs, hence simulation.
    A solver failure marks the cell as not inching (the message is kept in the CSV).

Which cells are simulated
    By default only the cells where the chain does *not* roll: a rolling cell's region is
    "rolling" whatever inching does, so its run cannot change the map's regions (this needs no
    assumption; ``tests/test_studies_mobility.py`` checks it against the full computation on the
    9 x 3 traverse_patch grid).  Those cells leave the inching columns and ``inching_cheaper``
    empty (None).  ``every_cell=True`` (``--every-cell``) simulates every cell, which is needed
    to compare inching's and rolling's energy per metre where both move.

Runtime: rolling cells are ~10 ms; each inching cell costs about 0.1 s of wall time per
simulated second (0.25-0.9 s for an 8 s run of six segments, longer at higher X_t), run in
``jobs`` worker processes, highest X_t first so that the longest runs do not finish last.
"""
from __future__ import annotations

import time
import numpy as np

from .. import steady
from ..simulation.driver import SolverError, simulate
from ..results.energy import energy_metrics
from ..infra.folders import check_output_folder, output_folder, relocate
from ..infra.pool import ProcessExecutor
from ..config.scenario import SimulationConfig, TerrainConfig, TowConfig, load_scenario, scenario_from_dict
from ..modes import InchwormMode, SupervisorConfig
from ..config.schema import ScenarioError, check_field, dump, quote
from .sweep.spec import RANGE, parse_spec
from ..infra.csvwriter import CellFormat, csv_text, write_csv

__all__ = ["parse_grid", "parse_list", "rolling_cell", "inching_scenario", "mobility_map", "map_csv",
           "rolling_speed_of", "REGIONS"]

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
        raise ScenarioError(f"mode.type: the mobility map takes the rolling wheel speed from the scenario's mode, "
                            f"and mode {sc.mode.type!r} does not roll at one speed (a 'supervisor' or 'uniform' "
                            "mode does). Pass --rolling-speed.")
    return float(v)


def _inching_mode_raw(sc) -> dict:
    raw = sc.mode.inching_settings()
    if raw is None:
        raise ScenarioError(f"mode.type: the mobility map takes the inching gait from the scenario's mode, and mode "
                            f"{sc.mode.type!r} does not inch (a 'supervisor' or 'inchworm' mode does). "
                            "Use --no-inching for rolling only.")
    raw = dump(raw)
    raw.update({"type": InchwormMode.name, "start_time_s": 0.0})
    return raw


def rolling_cell(sc, xt: float, tow_N: float, wheel_speed_mps: float) -> dict:
    """Steady rolling of the scenario's vehicle on uniform X_t with a tow (one map cell).

    Returns ``rolling`` (bool), ``rolling_speed_mps``, ``rolling_slip``,
    ``rolling_energy_per_metre_J_per_m`` (electrical) and ``rolling_max_drawbar_N`` (per segment).
    Uses the first segment's parameters for every segment (a uniform chain).
    """
    seg = sc.vehicle.segment_params()[0]
    tp = sc.terrain.model.params()
    n = sc.vehicle.segments
    share = tow_N / n
    dmax = steady.max_drawbar_N(xt, seg, tp, wheel_speed_mps)
    out = {"rolling": False, "rolling_speed_mps": 0.0, "rolling_slip": None,
           "rolling_energy_per_metre_J_per_m": None, "rolling_max_drawbar_N": dmax}
    if share >= dmax:
        return out
    try:
        ss = steady.steady_state(xt, seg, tp, drawbar_N=share, wheel_speed_mps=wheel_speed_mps)
    except steady.Immobilised:
        return out
    if ss.ground_speed_mps <= 0:
        return out
    n_w, _, R = steady.segment_geometry(seg)
    p_el = n * n_w * max(ss.torque_Nm * wheel_speed_mps / R, 0.0) / seg.drivetrain_efficiency
    out.update(rolling=True, rolling_speed_mps=ss.ground_speed_mps, rolling_slip=ss.slip,
               rolling_energy_per_metre_J_per_m=p_el / ss.ground_speed_mps)
    return out


def inching_scenario(sc, xt: float, tow_N: float, duration_s: float) -> dict:
    """Raw scenario mapping of a short inchworm run on uniform X_t with a tow (one map cell)."""
    raw = sc.to_dict()
    raw["name"] = f"{sc.name}_inch_xt{xt:g}_tow{tow_N:g}"
    raw["terrain"] = {"xt": float(xt), "model": raw["terrain"]["model"]}
    raw["tow"] = {"force_N": float(tow_N)}
    raw["mode"] = _inching_mode_raw(sc)
    raw["simulation"]["duration_s"] = float(duration_s)
    return raw


def _inch_run(args):
    raw, min_speed = args
    try:
        res = simulate(scenario_from_dict(raw))
    except SolverError as exc:
        return {"inching": False, "inching_speed_mps": 0.0, "inching_energy_per_metre_J_per_m": None,
                "inching_note": f"solver failure: {exc}"[:200]}
    e = energy_metrics(res)
    dur = float(res.t[-1] - res.t[0])
    speed = e["distance_m"] / dur
    ok = speed >= min_speed
    return {"inching": bool(ok), "inching_speed_mps": speed,
            "inching_energy_per_metre_J_per_m": e["energy_per_metre_J_per_m"] if ok else None,
            "inching_note": ""}


def _indexed_inch_run(item):
    j, task = item
    return j, _inch_run(task)


def _inch_all(tasks, jobs, progress, cost=None):
    """The inching runs' outcomes, in the order of ``tasks`` (``jobs`` processes).

    ``cost`` (one number per task, optional): the pool starts the costliest tasks first, so that
    no long run starts last while the other workers idle; the outcomes do not depend on the order.
    """
    outs = [None] * len(tasks)
    if jobs > 1:
        order = range(len(tasks)) if cost is None else sorted(range(len(tasks)), key=lambda j: -cost[j])
        with ProcessExecutor(jobs) as pool:
            done = pool.map_unordered(_indexed_inch_run, ((j, tasks[j]) for j in order))
            for n, (j, o) in enumerate(done, 1):
                outs[j] = o
                if progress is not None:
                    progress(n, len(tasks))
        return outs
    for j, tk in enumerate(tasks):
        outs[j] = _inch_run(tk)
        if progress is not None:
            progress(j + 1, len(tasks))
    return outs


def mobility_map(sc, xts, tows, *, wheel_speed_mps: float, inching: bool = True, inch_duration_s: float = 8.0,
                 inch_min_speed_mps: float = 0.02, jobs: int = 1, every_cell: bool = False, progress=None) -> dict:
    """Mobility map of a scenario's vehicle over ``xts`` x ``tows``.

    Parameters
    ----------
    sc : Scenario
        Gives the vehicle, terrain model, inching gait (supervisor ``inching`` or inchworm mode).
    xts, tows : sequence of float
        Terrain coefficients and tow forces [N] of the grid.
    wheel_speed_mps : float
        Rolling wheel-speed set-point [m/s].
    inching : bool
        Simulate inching (else rolling only, steady state).
    inch_duration_s : float
        Simulated time of each inching run [s].
    inch_min_speed_mps : float
        Mean chain speed above which inching counts as moving [m/s].
    jobs : int
        Worker processes for the inching runs.
    every_cell : bool
        Simulate inching in every cell; by default only where the chain does not roll (the
        regions are the same; rolling cells then have no inching speed, energy nor
        ``inching_cheaper``, all None).
    progress : callable, optional
        ``progress(done, total)`` after each inching cell (e.g. a :class:`snoworm.infra.progress.Progress`).

    Returns
    -------
    dict
        ``rows`` (one dict per cell), ``rolling_limit_xt`` (per tow, the steady immobilisation
        limit, None if above 1), ``wall_time_s``, and the settings.
    """
    wall0 = time.perf_counter()
    xts = [check_field(TerrainConfig, "xt", x, "--xt") for x in xts]
    tows = [check_field(TowConfig, "force_N", f, "--tow") for f in tows]
    wheel_speed_mps = check_field(SupervisorConfig, "rolling_speed_mps", wheel_speed_mps, "--rolling-speed")
    if inching:
        check_field(SimulationConfig, "duration_s", inch_duration_s, "--inch-duration")
    rows = []
    for f in tows:
        for x in xts:
            rows.append({"xt": x, "tow_N": f, **rolling_cell(sc, x, f, wheel_speed_mps)})
    if inching:
        _add_inching(sc, rows, inch_duration_s, inch_min_speed_mps, jobs, every_cell, progress)
    _classify(rows, inching)
    limits = _rolling_limits(sc, tows, wheel_speed_mps)
    return {"rows": rows, "xts": xts, "tows": tows, "regions": REGIONS, "rolling_limit_xt": limits, "inching": inching,
            "every_cell": bool(every_cell), "inch_duration_s": inch_duration_s, "wheel_speed_mps": wheel_speed_mps,
            "wall_time_s": time.perf_counter() - wall0, "scenario": sc.name}


def _add_inching(sc, rows, inch_duration_s, inch_min_speed_mps, jobs, every_cell, progress):
    """Simulate inching in the cells that do not roll (every cell if ``every_cell``), in ``jobs``
    processes, and add its results to the rows (None where it was not simulated)."""
    todo = [r for r in rows if every_cell or not r["rolling"]]
    tasks = [(inching_scenario(sc, r["xt"], r["tow_N"], inch_duration_s), inch_min_speed_mps) for r in todo]
    for r, o in zip(todo, _inch_all(tasks, jobs, progress, cost=[r["xt"] for r in todo])):
        r.update(o)
    for r in rows:
        if "inching" not in r:
            r.update(inching=None, inching_speed_mps=None, inching_energy_per_metre_J_per_m=None,
                     inching_note="")


def _classify(rows, inching):
    """Each cell's region (rolling, inching only, immobile) and whether inching costs less energy per metre."""
    for r in rows:
        inch_ok = bool(r.get("inching", False))
        r["region"] = "rolling" if r["rolling"] else ("inching only" if inch_ok else "immobile")
        er, ei = r["rolling_energy_per_metre_J_per_m"], r.get("inching_energy_per_metre_J_per_m")
        r["inching_cheaper"] = (None if inching and r.get("inching") is None
                                else bool(er is not None and ei is not None and ei < er))


def _rolling_limits(sc, tows, wheel_speed_mps) -> dict:
    """Per tow force, the X_t below which the chain cannot roll steadily (None if above 1)."""
    seg = sc.vehicle.segment_params()[0]
    tp = sc.terrain.model.params()
    limits = {}
    for f in tows:
        try:
            limits[f] = steady.immobilisation_limit_xt(seg, tp, drawbar_N=f / sc.vehicle.segments,
                                                       wheel_speed_mps=wheel_speed_mps)
        except ValueError:
            limits[f] = None
    return limits


#: Columns of ``mobility_map.csv``.
MAP_COLUMNS = ("xt", "tow_N", "region", "rolling", "rolling_speed_mps", "rolling_slip",
               "rolling_energy_per_metre_J_per_m", "rolling_max_drawbar_N", "inching", "inching_speed_mps",
               "inching_energy_per_metre_J_per_m", "inching_cheaper", "inching_note")


#: Cells of ``mobility_map.csv``: 6 significant digits, booleans 1/0, commas in notes as ``;``.
MAP_FORMAT = CellFormat(comma=";")


def map_csv(result: dict) -> str:
    """The map's rows as CSV text (empty fields for values that do not apply)."""
    return csv_text(MAP_COLUMNS, result["rows"], MAP_FORMAT)


def run_mobility_map(scenario_path, xt_spec, tow_spec, out_dir, sets=(), *, rolling_speed_mps=None,
                     inching=True, inch_duration_s=8.0, jobs=1, every_cell=False, plot=True, plot_format="png", overwrite=False,
                     progress=None):
    """Load a scenario, compute its map, write ``mobility_map.csv`` (and the plot, a ``plot_format`` file:
    png, pdf or svg); return (map, text, paths).

    The output folder is checked before the map is computed and written all or nothing
    (:func:`snoworm.infra.folders.output_folder`).
    """
    sc = load_scenario(scenario_path, sets)
    v = rolling_speed_of(sc) if rolling_speed_mps is None else float(rolling_speed_mps)
    xts, tows = parse_grid(xt_spec, "--xt"), parse_list(tow_spec, "--tow")
    check_output_folder(out_dir, overwrite)
    res = mobility_map(sc, xts, tows, wheel_speed_mps=v, inching=inching, inch_duration_s=inch_duration_s,
                       jobs=jobs, every_cell=every_cell, progress=progress)
    with output_folder(out_dir, overwrite) as out:
        paths = [write_csv(out / "mobility_map.csv", MAP_COLUMNS, res["rows"], MAP_FORMAT)]
        if plot:
            from .. import plotting   # lazy: matplotlib costs ~0.5 s to import; --no-plot never pays it
            paths.append(plotting.save(plotting.plot_mobility_map(res), out / "mobility_map.png", plot_format))
    paths = relocate(paths, out, out_dir)
    lines = [f"{sc.name}: mobility map, {len(res['xts'])} X_t x {len(res['tows'])} tow values, "
             f"{res['wall_time_s']:.1f} s"]
    for f in res["tows"]:
        lim = res["rolling_limit_xt"][f]
        roll = [r["xt"] for r in res["rows"] if r["tow_N"] == f and r["rolling"]]
        inch = [r["xt"] for r in res["rows"] if r["tow_N"] == f and r["region"] == "inching only"]
        cheap = [r["xt"] for r in res["rows"] if r["tow_N"] == f and r["inching_cheaper"]]
        lines.append(f"tow {f:g} N: steady rolling limit X_t = {lim:.3f}" if lim is not None
                     else f"tow {f:g} N: no rolling for X_t <= 1")
        lines.append(f"  rolling from X_t = {min(roll):g}" if roll else "  rolling nowhere on the grid")
        lines.append(f"  inching only at X_t = {', '.join(f'{x:g}' for x in inch)}" if inch else "  no inching-only cells")
        failed = [r["xt"] for r in res["rows"] if r["tow_N"] == f and r.get("inching_note")]
        if failed:
            lines.append(f"  inching run failed (solver) at X_t = {', '.join(f'{x:g}' for x in failed)}; see inching_note")
        if cheap:
            lines.append(f"  inching cheaper per metre than rolling at X_t = {', '.join(f'{x:g}' for x in cheap)}")
    if inching and not every_cell and any(r["rolling"] for r in res["rows"]):
        lines.append("inching not simulated where the chain rolls (--every-cell compares its energy with rolling's)")
    return res, "\n".join(lines), paths
