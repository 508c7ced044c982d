"""The steady screen of an odds study (``--fidelity steady``): each route element at its steady state,
stitched along the route (docs/odds.md, section "Steady fidelity").

Rolling
    At every leader position ``x`` (a step of ``min(0.5 m, corr / 8)``, the X_t field's grid) the chain rolls when its
    steady drawbar surplus is not negative, the supervisor's resume rule
    (:func:`snoworm.modes.supervisor.chain_drawbar_surplus_N`, docs/model.md section 2)::

        sum_k [D(X_t(front axle k), theta_k) + D(X_t(rear axle k), theta_k)] / 2 - F_tow >= 0

    with ``D(X, theta)`` the largest steady drawbar of one segment (:func:`snoworm.steady.max_drawbar_N`)
    at the rolling wheel speed, ``theta_k`` the chord grade under segment ``k`` (docs/model.md section 7)
    and the segments at their rest spacing behind the leader.  The first position where it is negative
    is where the chain stops.  ``D`` is tabulated once per study on a grid of X_t (step 0.02) and grade
    (step 1.5 deg over the route's grades) and interpolated linearly (speed and energy: X_t step 0.08).  The speed and the electrical
    energy per metre at ``x`` are those of one segment's steady state
    (:func:`snoworm.steady.steady_state`, drawbar ``F_tow / N``) at the chain's mean X_t and grade,
    tabulated the same way (where that mean segment cannot carry its share, at the nearest X_t above
    where it can).  Time = the motors' start time + sum of ``dx / V``.
Inching
    A per-cycle table: the inchworm gait of the scenario's mode (:func:`snoworm.studies.mobility.inching_scenario`)
    simulated for :data:`INCH_TABLE_S` seconds on uniform X_t and grade with the tow, on the grid
    :data:`INCH_XT` x the route's grades (at most :data:`MAX_INCH_GRADES`); its mean speed (advance per
    cycle / cycle time, from the distance over the run after the motors start) and electrical energy
    per metre.  Computed once (in the study's executor), kept in memory and in the output folder
    (``inching_table.json``), keyed by everything it read.  The chain inches at ``x`` when the table's
    speed at the chain's mean X_t and grade is at least the sweeps' immobilised threshold.
Supervisor
    Rolls where rolling works, inches elsewhere (detection delays and switches cost nothing here).

What the screen leaves out (transient effects): start-up, the time a supervisor needs to detect
immobilisation, a chain's momentum carrying it over a short bad patch, segments not at rest spacing.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass

import numpy as np

from ... import steady
from ..._version import __version__
from ...config.scenario import scenario_from_dict
from ...config.schema import ScenarioError
from ...infra.csvwriter import canonical_json
from ...infra.folders import atomic_write_text
from ...results.energy import energy_metrics
from ...simulation.driver import SolverError, simulate
from ..mobility import inching_scenario
from ..sweep.metrics import IMMOBILISED_SIGN_FACTOR, IMMOBILISED_SPEED_MPS
from .outcome import draw_scenario, field_profile

__all__ = ["screen_draws", "RollingTable", "rolling_table", "InchingTable", "inching_table", "INCH_XT", "INCH_TABLE_S"]

#: X_t grid of the tables (rolling drawbar; the speed/energy tables use every fourth point).
XT_GRID = np.round(np.arange(0.05, 1.0 + 1e-9, 0.02), 4)
#: Step of the leader's positions along the route [m] (at most the field's grid, correlation length / 8).
STEP_M = 0.5
#: Grade step of the tables [deg].
GRADE_STEP_DEG = 1.5
#: X_t of the inching table.
INCH_XT = (0.2, 0.4, 0.6, 0.8, 1.0)
#: Most grades of the inching table (the route's range, evenly).
MAX_INCH_GRADES = 3
#: Simulated time of each inching-table run, after the motors start [s].
INCH_TABLE_S = 8.0

_MEMO: dict = {}
#: Most tables kept in memory (a study drawing the tow or a coefficient makes one per draw).
MEMO_MAX = 256


def _grades(lo, hi, step=GRADE_STEP_DEG, most=None):
    if hi - lo < 1e-9:
        return np.array([lo])
    n = max(2, int(math.ceil((hi - lo) / step)) + 1)
    if most is not None:
        n = min(n, most)
    return np.linspace(lo, hi, n)


def _cell(grid, v):
    """Index of the cell of the evenly spaced ``grid`` holding ``v`` (clamped) and the fraction across it."""
    h = (grid[-1] - grid[0]) / (len(grid) - 1)
    t = (np.clip(v, grid[0], grid[-1]) - grid[0]) / h
    i = np.minimum(t.astype(np.intp), len(grid) - 2)
    return i, t - i


def _interp2(table, xs, gs, X, G):
    """Bilinear interpolation of ``table`` (len(xs), len(gs)) on evenly spaced grids at ``(X, G)`` (clamped)."""
    X = np.asarray(X, float)
    i, tx = _cell(xs, X)
    if len(gs) == 1:
        return table[i, 0] * (1 - tx) + table[i + 1, 0] * tx
    j, tg = _cell(gs, np.asarray(G, float))
    lo = table[i, j] * (1 - tx) + table[i + 1, j] * tx
    hi = table[i, j + 1] * (1 - tx) + table[i + 1, j + 1] * tx
    return lo * (1 - tg) + hi * tg


@dataclass(frozen=True)
class RollingTable:
    """Steady rolling of one segment on (X_t, grade): largest drawbar, speed and energy per metre."""

    xs: np.ndarray
    gs: np.ndarray
    drawbar_N: np.ndarray  # (len(xs), len(gs))
    xs_v: np.ndarray
    speed_mps: np.ndarray  # (len(xs_v), len(gs))
    energy_J_per_m: np.ndarray

    def drawbar(self, X, G):
        return _interp2(self.drawbar_N, self.xs, self.gs, X, G)

    def speed(self, X, G):
        return _interp2(self.speed_mps, self.xs_v, self.gs, X, G)

    def energy(self, X, G):
        return _interp2(self.energy_J_per_m, self.xs_v, self.gs, X, G)


def _fill_up(col):
    """NaNs of a column over X_t replaced by the nearest finite value above (higher X_t)."""
    out = col.copy()
    last = np.nan
    for i in range(len(out) - 1, -1, -1):
        if np.isfinite(out[i]):
            last = out[i]
        else:
            out[i] = last
    return out


def rolling_table(seg, tp, n_segments: int, tow_N: float, wheel_speed_mps: float, grades) -> RollingTable:
    """:class:`RollingTable` of a segment ``seg`` on terrain model ``tp`` (memoised by its inputs)."""
    key = ("rolling", repr(seg), repr(tp), n_segments, float(tow_N), float(wheel_speed_mps), tuple(np.round(grades, 9)))
    if key in _MEMO:
        return _MEMO[key]
    if len(_MEMO) > MEMO_MAX:
        _MEMO.clear()
    gs = np.asarray(grades, float)
    dkey = ("drawbar", *key[1:3], float(wheel_speed_mps), key[-1])  # the drawbar does not depend on the tow
    if dkey not in _MEMO:
        _MEMO[dkey] = np.array(
            [[steady.max_drawbar_N(x, seg, tp, wheel_speed_mps, grade_deg=float(g)) for g in gs] for x in XT_GRID]
        )
    D = _MEMO[dkey]
    xs_v = XT_GRID[::4]
    n_w, _, R = steady.segment_geometry(seg)
    V = np.full((len(xs_v), len(gs)), np.nan)
    E = np.full_like(V, np.nan)
    for a, x in enumerate(xs_v):
        for b, g in enumerate(gs):
            try:
                ss = steady.steady_state(
                    x, seg, tp, drawbar_N=tow_N / n_segments, wheel_speed_mps=wheel_speed_mps, grade_deg=float(g)
                )
            except steady.Immobilised:
                continue
            if ss.ground_speed_mps > 0:
                V[a, b] = ss.ground_speed_mps
                p_el = n_segments * n_w * max(ss.torque_Nm * wheel_speed_mps / R, 0.0) / seg.drivetrain_efficiency
                E[a, b] = p_el / ss.ground_speed_mps
    for b in range(len(gs)):
        V[:, b], E[:, b] = _fill_up(V[:, b]), _fill_up(E[:, b])
    V = np.where(np.isfinite(V), V, 0.0)
    E = np.where(np.isfinite(E), E, np.nan)
    tab = RollingTable(XT_GRID, gs, D, xs_v, V, E)
    _MEMO[key] = tab
    return tab


@dataclass(frozen=True)
class InchingTable:
    """Inching on (X_t, grade): mean speed and electrical energy per metre of the gait."""

    xs: np.ndarray
    gs: np.ndarray
    speed_mps: np.ndarray
    energy_J_per_m: np.ndarray

    def speed(self, X, G):
        return _interp2(self.speed_mps, self.xs, self.gs, X, G)

    def energy(self, X, G):
        return _interp2(self.energy_J_per_m, self.xs, self.gs, X, G)

    def to_dict(self) -> dict:
        return {
            "xt": self.xs.tolist(),
            "grade_deg": self.gs.tolist(),
            "speed_mps": self.speed_mps.tolist(),
            "energy_J_per_m": [[None if not np.isfinite(v) else float(v) for v in r] for r in self.energy_J_per_m],
        }


def _inch_cell(args):
    """One inching-table run (top-level: it pickles to a worker): ``(a, b, speed, energy per metre)``."""
    a, b, raw, start = args
    try:
        res = simulate(scenario_from_dict(raw))
    except SolverError:
        return a, b, 0.0, float("nan")
    t = np.asarray(res.t, float)
    x = res.segments["x_m"]
    j = int(np.searchsorted(t, start))
    dur = float(t[-1] - t[min(j, len(t) - 1)])
    dist = float(np.mean(x[-1] - x[min(j, len(t) - 1)]))
    e = energy_metrics(res)
    speed = dist / dur if dur > 0 else 0.0
    return a, b, speed, (e["total_electrical_J"] / e["distance_m"] if e["distance_m"] > 1e-6 else float("nan"))


def inching_table(sc, grades, executor=None, cache_dir=None) -> InchingTable:
    """:class:`InchingTable` of ``sc``'s vehicle and gait (module docstring); memoised and cached in ``cache_dir``."""
    gs = np.asarray(grades, float)
    start = float(getattr(sc.mode, "start_time_s", 0.0))
    base = sc.to_dict()
    base["terrain"] = {"xt": 1.0, "model": base["terrain"]["model"]}
    key_doc = {
        "scenario": base,
        "xt": list(INCH_XT),
        "grades": gs.tolist(),
        "duration_s": INCH_TABLE_S,
        "version": __version__,
    }
    key = hashlib.sha256(canonical_json(key_doc).encode()).hexdigest()
    if key in _MEMO:
        return _MEMO[key]
    path = cache_dir / "inching_table.json" if cache_dir is not None else None
    if path is not None and path.exists():
        try:
            doc = json.loads(path.read_text("utf-8"))
            if doc.get("key") == key:
                tab = InchingTable(
                    np.array(doc["xt"]),
                    np.array(doc["grade_deg"]),
                    np.array(doc["speed_mps"], float),
                    np.array([[np.nan if v is None else v for v in r] for r in doc["energy_J_per_m"]], float),
                )
                _MEMO[key] = tab
                return tab
        except (OSError, ValueError, KeyError):
            pass
    tasks = []
    for a, x in enumerate(INCH_XT):
        for b, g in enumerate(gs):
            raw = inching_scenario(sc, x, sc.tow.force_N, start + INCH_TABLE_S, float(g))
            raw["mode"]["start_time_s"] = start
            tasks.append((a, b, raw, start))
    S = np.zeros((len(INCH_XT), len(gs)))
    E = np.full_like(S, np.nan)
    runs = executor.map_unordered(_inch_cell, tasks) if executor is not None else map(_inch_cell, tasks)
    for a, b, s, e in runs:
        S[a, b], E[a, b] = s, e
    tab = InchingTable(np.array(INCH_XT), gs, S, E)
    _MEMO[key] = tab
    if path is not None:
        atomic_write_text(path, json.dumps({"key": key, **tab.to_dict()}, indent=1) + "\n")
    return tab


# ------------------------------------------------------------------------------------- along the route
def _kind(sc, strategy):
    if strategy in ("rolling", "inching", "supervisor"):
        return strategy
    kinds = {"uniform": "rolling", "inchworm": "inching", "supervisor": "supervisor"}
    if sc.mode.type not in kinds:
        raise ScenarioError(
            f"--fidelity steady: the steady screen knows rolling, inching and the supervisor; mode {sc.mode.type!r} "
            "is none of them. Use --fidelity transient or --strategy rolling/inching."
        )
    return kinds[sc.mode.type]


def _route_grades(sc, goal_m):
    """Chord grades [deg] under the chain along the route (for the tables' grade range)."""
    el = sc.terrain.elevation_profile()
    if el is None:
        return 0.0, 0.0
    if el.is_constant:
        return el.grade_deg, el.grade_deg
    seg = sc.vehicle.segment_params()[0]
    L = float(sc.vehicle.links.rest_spacing_m) * (sc.vehicle.segments - 1)
    s = np.arange(-L - 1.0, goal_m + 1.0, 0.25)
    g = np.degrees(np.arcsin(np.clip(el.sin_grade(s, seg.wheelbase_m / 2), -1, 1)))
    return float(np.min(g)), float(np.max(g))


@dataclass(frozen=True)
class _Along:
    """What the screen of one draw needs along the route: leader positions, chain mean X_t and grade,
    the rolling surplus (N)."""

    xs: np.ndarray
    xt_mean: np.ndarray
    grade_mean: np.ndarray
    surplus_N: np.ndarray


def _along(sc, prof, goal_m, step, rt: RollingTable | None) -> _Along:
    seg = sc.vehicle.segment_params()[0]
    n = sc.vehicle.segments
    xs = np.arange(0.0, goal_m + step / 2, step)
    centres = xs[None, :] - float(sc.vehicle.links.rest_spacing_m) * np.arange(n)[:, None]
    half = seg.wheelbase_m / 2
    Xf, Xr = prof(centres + half), prof(centres - half)
    el = sc.terrain.elevation_profile()
    G = np.zeros_like(centres) if el is None else np.degrees(np.arcsin(np.clip(el.sin_grade(centres, half), -1, 1)))
    surplus = np.full(xs.shape, np.inf)
    if rt is not None:
        surplus = np.sum((rt.drawbar(Xf, G) + rt.drawbar(Xr, G)) / 2, axis=0) - sc.tow.force_N
    return _Along(xs, np.mean((Xf + Xr) / 2, axis=0), np.mean(G, axis=0), surplus)


def _screen_one(sc, prof, kind, goal_m, step, rt, it, thr):
    a = _along(sc, prof, goal_m, step, rt if kind != "inching" else None)
    rolls = a.surplus_N >= 0 if kind != "inching" else np.zeros(a.xs.shape, bool)
    v = np.zeros(a.xs.shape)
    e = np.full(a.xs.shape, np.nan)
    if kind != "inching":
        v = np.where(rolls, rt.speed(a.xt_mean, a.grade_mean), 0.0)
        e = np.where(rolls, rt.energy(a.xt_mean, a.grade_mean), np.nan)
    if kind != "rolling":
        vi, ei = it.speed(a.xt_mean, a.grade_mean), it.energy(a.xt_mean, a.grade_mean)
        inch = ~rolls & (vi >= thr)
        v, e = np.where(inch, vi, v), np.where(inch, ei, e)
    moving = v >= thr
    start = float(np.max(np.atleast_1d(getattr(sc.mode, "start_time_s", 0.0))))
    blocked = np.nonzero(~moving)[0]
    j = int(blocked[0]) if blocked.size else len(a.xs)
    dx = np.diff(a.xs[: j + 1]) if j > 0 else np.zeros(0)
    t = start + float(np.sum(dx / np.maximum(v[:j][: len(dx)], 1e-9))) if j > 0 else start
    energy = float(np.nansum(e[:j][: len(dx)] * dx)) if j > 0 else 0.0
    if not blocked.size:
        made = float(a.xs[-1])
        return {
            "status": "ok",
            "go": 1,
            "verdict": "reached_end",
            "stop_m": None,
            "stop_xt": None,
            "stop_grade_deg": None,
            "time_s": t,
            "speed_made_good_mps": made / t if t > 0 else 0.0,
            "energy_per_m_J": energy / made if made > 0 else None,
            "error": "",
        }
    made = float(a.xs[j])
    dur = sc.simulation.duration_s
    return {
        "status": "ok",
        "go": 0,
        "verdict": "immobilised",
        "stop_m": made,
        "stop_xt": float(a.xt_mean[j]),
        "stop_grade_deg": float(a.grade_mean[j]),
        "time_s": None,
        "speed_made_good_mps": made / dur,
        "energy_per_m_J": energy / made if made > 1e-6 else None,
        "error": "",
    }


def screen_draws(plan, todo, executor=None, cache_dir=None):
    """Yield ``((draw, strategy), outcome)`` of the steady screen for every ``(draw, strategy)`` of ``todo``."""
    if plan.goal_m is None:
        raise ScenarioError(
            "--fidelity steady: the screen walks the route to its end, and this scenario has none; give --goal-m "
            "(or a route file / elevation table)."
        )
    field = plan.unc.xt_field
    step = min(STEP_M, field.corr_m / 8) if field is not None else STEP_M
    tables = {}
    for s in plan.strategies:
        sc0 = scenario_from_dict(plan.strategy_raws[s], plan.source, base_dir=plan.base_dir)
        kind = _kind(sc0, s)
        lo, hi = _route_grades(sc0, plan.goal_m)
        seg, tp = sc0.vehicle.segment_params()[0], sc0.terrain.model.params()
        rt = it = None
        if kind != "inching":
            rt = rolling_table(
                seg, tp, sc0.vehicle.segments, sc0.tow.force_N, sc0.mode.rolling_speed(), _grades(lo, hi)
            )
        if kind != "rolling":
            it = inching_table(sc0, _grades(lo, hi, most=MAX_INCH_GRADES), executor, cache_dir)
        thr = max(IMMOBILISED_SPEED_MPS, IMMOBILISED_SIGN_FACTOR * sc0.terrain.model.sign_eps_mps)
        tables[s] = (kind, rt, it, thr, sc0)
    for k, s in todo:
        values = {p: float(v[k]) for p, v in plan.values.items()}
        kind, rt, it, thr, sc0 = tables[s]
        # the drawn values validated (a few ms); the field is added here, not validated as a profile table
        sc = (
            draw_scenario(plan.strategy_raws[s], values, None, 0, plan.goal_m, plan.source, plan.base_dir)
            if values
            else sc0
        )
        prof = field_profile(sc, field, int(plan.dsg.field_seeds[k]), plan.goal_m) if field else sc.terrain.compile()
        if values and kind != "inching":  # a drawn coefficient, tow or speed changes the rolling table
            seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
            lo, hi = _route_grades(sc, plan.goal_m)
            rt = rolling_table(seg, tp, sc.vehicle.segments, sc.tow.force_N, sc.mode.rolling_speed(), _grades(lo, hi))
        yield (k, s), _screen_one(sc, prof, kind, plan.goal_m, step, rt, it, thr)
