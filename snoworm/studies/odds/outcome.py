"""One draw of an odds study: its scenario (a strategy, the drawn values, the X_t field), its run and
its outcome (go, where it stopped, time, speed made good, energy per metre).

Strategies (``--strategy``) map to scenario modes the way the mobility map compares gaits
(:mod:`snoworm.studies.mobility`): ``rolling`` drives every segment at the scenario's rolling
wheel-speed set-point (a ``uniform`` mode; :meth:`ModeConfig.rolling_speed`, or ``rolling_speed``),
``inching`` runs the inchworm gait of the scenario's mode (``inchworm`` settings of an ``inchworm``
or ``supervisor`` mode, :func:`snoworm.studies.mobility.inching_mode_raw`), ``supervisor`` the
scenario's ``supervisor`` mode (its thresholds are the user's), and ``scenario`` the mode as written.

The end of the route (:func:`goal_of`): ``goal_m`` if given, else the scenario's
``simulation.goal_m`` (where a snoworm has it), else the last point of a route file or an
elevation table; without one, "go" means "not immobilised by the end of the run".
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from ...config.scenario import apply_overrides, scenario_from_dict
from ...config.schema import ScenarioError, quote
from ...results.verdict import verdict
from ...simulation.driver import simulate
from ...terrain import TerrainProfile, gaussian_field
from ..mobility import inching_mode_raw
from ..sweep.metrics import failure_row
from .inputs import XT_FIELD_FLOOR

__all__ = [
    "STRATEGIES",
    "OUTCOME_COLUMNS",
    "OddsTask",
    "strategy_raw",
    "goal_of",
    "field_span",
    "draw_scenario",
    "field_profile",
    "outcome",
    "run_draw",
]

#: Strategies of ``--strategy`` (module docstring).
STRATEGIES = ("scenario", "rolling", "inching", "supervisor")

#: Outcome columns of ``samples.csv`` (after draw, strategy and the drawn inputs).
OUTCOME_COLUMNS = {
    "status": "ok, or why the draw has no outcome (solver_failure, invalid, error, controller_failure)",
    "go": "1 if the leader reached the end of the route (or, without one, was not immobilised), else 0",
    "verdict": "reached_end, moving (ran out of time) or immobilised",
    "stop_m": "where the leader stopped (immobilised) or was at the end of the run [m]; empty if it got through",
    "stop_xt": "mean X_t under the chain's axles where it stopped (the draw's field)",
    "stop_grade_deg": "mean grade under the chain's segments where it stopped [deg]",
    "time_s": "time from the start until the leader reached the end [s]; empty if it did not",
    "speed_made_good_mps": "distance made good / time: to the end if it got through, else over the whole run [m/s]",
    "energy_per_m_J": "electrical energy per metre made good, up to the end (or over the run) [J/m]",
    "error": "the message of a draw without outcome",
}


def strategy_raw(raw: dict, sc, strategy: str, rolling_speed: float | None = None) -> dict:
    """The scenario mapping ``raw`` (validated as ``sc``) with the mode of ``strategy`` (module docstring)."""
    raw = dict(raw)
    mode = sc.mode
    start = np.max(np.atleast_1d(getattr(mode, "start_time_s", 0.0))).item()  # uniform: one per segment
    if strategy == "scenario":
        return raw
    if strategy == "rolling":
        v = rolling_speed if rolling_speed is not None else mode.rolling_speed()
        if v is None:
            raise ScenarioError(
                f"--strategy rolling: mode {mode.type!r} does not roll at one speed (a 'uniform' or 'supervisor' "
                "mode does); give the rolling wheel speed with --rolling-speed."
            )
        raw["mode"] = {"type": "uniform", "speed_mps": float(v), "start_time_s": start}
        return raw
    if strategy == "inching":
        m = inching_mode_raw(sc)  # ScenarioError naming the mode if it does not inch
        m["start_time_s"] = start
        raw["mode"] = m
        return raw
    if strategy == "supervisor":
        if mode.type != "supervisor":
            raise ScenarioError(
                f"--strategy supervisor: the scenario's mode is {mode.type!r}; the supervisor's switching thresholds "
                "are the scenario's, so give a scenario whose mode is 'supervisor' (see traverse_patch)."
            )
        return raw
    raise ScenarioError(f"--strategy: unknown strategy {quote(strategy)}; expected one of {', '.join(STRATEGIES)}.")


def goal_of(sc, goal_m: float | None = None) -> float | None:
    """The leader's distance that counts as the end of the route (module docstring), or None."""
    if goal_m is not None:
        return float(goal_m)
    g = getattr(sc.simulation, "goal_m", None)  # simulation.goal_m, where the scenario section has it
    if g is not None:
        return float(g)
    t = sc.terrain
    if t.route is not None:
        return float(t.route_data().distance_m[-1])
    if t.elevation is not None:
        return float(t.elevation[-1][0])
    return None


def _chain_length_m(sc) -> float:
    return float(sc.vehicle.links.rest_spacing_m) * (sc.vehicle.segments - 1)


def field_span(sc, goal_m: float | None, corr_m: float) -> tuple:
    """``(start_m, length_m)`` of the X_t field: from behind the last segment to the end of the route
    (without one, as far as the wheels' no-load speed can go in the run), two correlation lengths beyond."""
    start = -_chain_length_m(sc) - 2 * corr_m
    if goal_m is not None:
        end = goal_m
    else:
        seg = sc.vehicle.segment_params()[0]
        end = sc.simulation.duration_s * seg.no_load_speed_radps * seg.wheel_radius_m
    return start, end + 2 * corr_m - start


def field_profile(sc, field, seed: int, goal_m) -> TerrainProfile:
    """X_t along the route of one draw: ``sc``'s X_t plus the field of ``seed`` (docs/odds.md), clipped
    to [:data:`~snoworm.studies.odds.inputs.XT_FIELD_FLOOR`, 1], on the field's grid (:func:`field_span`)."""
    start, length = field_span(sc, goal_m, field.corr_m)
    pos, g = gaussian_field(field.corr_m, seed, length, start)
    base = np.asarray(sc.terrain.compile()(pos), float)
    return TerrainProfile(tuple(pos.tolist()), tuple(np.clip(base + field.sd * g, XT_FIELD_FLOOR, 1.0).tolist()))


def _with_field(raw: dict, sc, field, seed: int, goal_m):
    """``raw`` with the X_t field of ``seed`` added to ``sc``'s X_t (a profile table), the route's
    elevation kept as an elevation table."""
    prof = field_profile(sc, field, seed, goal_m)
    pos, xt = prof.positions_m, prof.values
    terrain = dict(raw["terrain"])
    if terrain.get("route") is not None:
        r = sc.terrain.route_data()
        terrain.pop("route")
        terrain["elevation"] = [[float(d), float(z)] for d, z in zip(r.distance_m, r.elevation_m)]
    for k in ("xt", "patches", "random", "profile"):
        terrain.pop(k, None)
    terrain["profile"] = [[float(p), float(x)] for p, x in zip(pos, xt)]
    return {**raw, "terrain": terrain}


def draw_scenario(raw, values: dict, field=None, seed: int = 0, goal_m=None, source="scenario", base_dir=None):
    """The validated scenario of one draw: ``raw`` with the drawn ``values`` (dotted path -> value)
    and, with ``field`` (:class:`~snoworm.studies.odds.inputs.XtField`), the X_t field of ``seed``."""
    raw = apply_overrides(raw, [(k, float(v)) for k, v in values.items()]) if values else raw
    sc = scenario_from_dict(raw, source, base_dir=base_dir)
    if field is None:
        return sc
    return scenario_from_dict(_with_field(raw, sc, field, seed, goal_m), source, base_dir=base_dir)


def _leader_crossing(t, x, goal):
    """First time the leader's position ``x`` reaches ``goal`` (linear between samples), or None."""
    hit = np.nonzero(x >= goal)[0]
    if hit.size == 0:
        return None
    j = int(hit[0])
    if j == 0:
        return float(t[0])
    return float(t[j - 1] + (goal - x[j - 1]) / (x[j] - x[j - 1]) * (t[j] - t[j - 1]))


def _stop_verdict(result, goal_m=None) -> dict:
    """Where, when and why the chain stopped: ``{"status", "x_m", "t_s", "reason"}``, from the run's
    verdict (:func:`snoworm.results.verdict.verdict`, the test of runs, sweeps and the mobility map);
    "reached the end" is decided here, from ``goal_m`` (:func:`goal_of`).
    """
    t = np.asarray(result.t, float)
    lead = result.segments["x_m"][:, 0]
    if goal_m is not None:
        tg = _leader_crossing(t, lead, goal_m)
        if tg is not None:
            return {"status": "reached_end", "x_m": float(goal_m), "t_s": tg, "reason": "reached the end of the route"}
    v = verdict(result)
    status = "moving" if v.status == "reached_end" else v.status  # the end is goal_m's, decided above
    x = float(v.x_m) if v.status == "immobilised" else float(lead[-1])
    return {"status": status, "x_m": x, "t_s": float(v.t_s), "reason": v.reason}


def _site(result) -> tuple:
    """(X_t, grade [deg]) where the chain stopped: the means over its axles and segments at the end of the
    run (the chain's X_t, as the steady screen's; the leader's own X_t may not be what held it)."""
    sc = result.scenario
    x = result.segments["x_m"][-1]
    half = sc.vehicle.segment_params()[0].wheelbase_m / 2
    prof = sc.terrain.compile()
    xt = float(np.mean((prof(x + half) + prof(x - half)) / 2))
    el = sc.terrain.elevation_profile()
    if el is None:
        return xt, 0.0
    s = np.clip(np.asarray(el.sin_grade(x, half), float), -1.0, 1.0)
    return xt, float(np.mean(np.degrees(np.arcsin(s))))


def outcome(result, goal_m=None) -> dict:
    """The outcome columns (:data:`OUTCOME_COLUMNS`) of one finished run."""
    v = _stop_verdict(result, goal_m)
    t = np.asarray(result.t, float)
    lead = result.segments["x_m"][:, 0]
    x0 = float(lead[0])
    along = result.energy_along()
    reached = v["status"] == "reached_end"
    go = reached if goal_m is not None else v["status"] != "immobilised"
    out = {"status": "ok", "go": int(go), "verdict": v["status"], "error": ""}
    if reached:
        tg = v["t_s"]
        made = float(goal_m) - x0
        e = float(np.interp(tg, along["t_s"], along["total_electrical_J"]))
        out.update(stop_m=None, stop_xt=None, stop_grade_deg=None, time_s=tg - float(t[0]))
        out.update(
            speed_made_good_mps=made / max(tg - float(t[0]), 1e-12), energy_per_m_J=e / made if made > 0 else None
        )
        return out
    made = float(lead[-1]) - x0
    dur = float(t[-1] - t[0])
    e = float(along["total_electrical_J"][-1])
    xt, grade = _site(result)
    out.update(stop_m=v["x_m"], stop_xt=xt, stop_grade_deg=grade, time_s=None)
    out.update(speed_made_good_mps=made / dur if dur > 0 else 0.0, energy_per_m_J=e / made if made > 1e-6 else None)
    return out


@dataclass(frozen=True)
class OddsTask:
    """One draw of one strategy, as an executor hands it to :func:`run_draw` (small: pickles to a worker).

    ``raw``: the strategy's scenario mapping (fixed ``--set`` values applied); ``values``: the drawn
    values (dotted path -> float); ``field``/``seed``: the X_t field and its seed (or None)."""

    index: int
    raw: dict
    values: dict
    field: object = None
    seed: int = 0
    goal_m: float | None = None
    source: str = "scenario"
    base_dir: str | None = None
    allow_code: tuple = ()

    def scenario(self):
        return draw_scenario(self.raw, self.values, self.field, self.seed, self.goal_m, self.source, self.base_dir)


def run_draw(task: OddsTask) -> dict:
    """Run one draw (the function executors call; top-level so it pickles): ``index`` and the outcome
    columns; never raises for a failing draw (its ``status`` and ``error`` say why)."""
    wall0 = time.perf_counter()
    out = {"index": task.index, "status": "ok", "error": ""}
    try:
        res = simulate(task.scenario(), allow_code=task.allow_code)
        out.update(outcome(res, task.goal_m))
    except Exception as exc:  # noqa: BLE001 - a draw must never stop the study
        out.update(failure_row(exc))
    out["wall_time_s"] = time.perf_counter() - wall0
    return out


def with_index(task: OddsTask, index: int) -> OddsTask:
    return dataclasses.replace(task, index=index)
