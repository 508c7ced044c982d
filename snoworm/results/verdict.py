"""The verdict of a run: did the chain reach the end of its route, is it still moving, or is it
immobilised, and where, when and why (docs/model.md section 8, "Immobilisation verdict").

One function, :func:`verdict`, judges a finished :class:`~snoworm.results.result.Result` from its
output series alone; ``snoworm run``'s last line, ``summary.json`` (``status``,
``immobilised_at_m``, ``status_reason``), the sweeps' columns, the mobility map's simulated cells
and the odds all call it, so they apply the same test.

Immobilised
    From the first output time ``t`` after which, over the window ``[t, t + window_s]``
    (reported from the first time in that window at which the wheels are driven: a chain whose
    motors start at 0.5 s is immobilised at 0.5 s),

    * the wheels are driven: the chain's *driven travel* ``C``, the integral over the window of the
      mean over the segments of ``max(v_sp, R_w w, 0)`` (wheel-speed set-point or wheel speed,
      whichever is larger: a stalled motor and a spinning wheel both count; the set-point of a
      motor that is off, giving no torque, does not), is at least ``speed_mps * window``;
    * the chain is stalled: its centre (the mean position of the segments) advances
      ``P < speed_mps * window``;
    * the wheels slip: ``P < (1 - slip) C``, the chain covers less than ``1 - slip`` of its wheels'
      travel.

    and it never gets out: no later window sees the chain advance ``speed_mps * window`` (a
    stall the chain gets out of, as when a paper Fig 7 chain waits for its rear motors to start,
    or a supervisor inches out of a patch, is not an immobilisation).

    The chain's centre is used for progress, not a segment: an inching gait stops its anchor
    segments by design and advances the chain's centre phase by phase, and its anchors' set-points
    (0) do not count as driven.  A chain parked with its wheels at rest is not driven, so never
    immobilised.  The third condition matters for slow commands only: a chain commanded at less
    than ``speed_mps / (1 - slip)`` (0.5 m/s by default) may follow its command slower than
    ``speed_mps``; it is stalled only if it covers less than ``1 - slip`` of its wheels' travel.
    With a sinkage
    series (``sinkage_m`` in ``Result.segments``) the chain is also immobilised from the first
    output time at which the mean sinkage of its segments reaches ``sinkage_m`` (dug in).

Reached the end
    The leader (segment 0) passes the goal: ``simulation.goal_m``; without it the last point of
    ``terrain.route`` or ``terrain.elevation``; a scenario with neither has no end.  The time is
    interpolated linearly between the output samples.

Moving
    Neither happened before the run's end.

Whichever of "immobilised" and "reached the end" happens first is the verdict.  The run is not
stopped by either (the integration runs to ``simulation.duration_s``): the verdict is a judgement
of the results, computed after the run, so every series, figure and summary quantity keeps its
meaning, a mode that recovers from a stall (the supervisor's inching) is judged on what it did,
and the verdict can be recomputed with other criteria without running again.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

__all__ = ["Verdict", "Criteria", "STATUSES", "criteria_of", "goal_of", "verdict", "IMMOBILISED_SPEED_MPS"]

#: The verdict's statuses.
STATUSES = ("moving", "reached_end", "immobilised")

#: Floor of the default stall speed [m/s]; the default is ``max(this, IMMOBILISED_SIGN_FACTOR * sign_eps_mps)``.
IMMOBILISED_SPEED_MPS = 0.05
#: The default stall speed is at least this multiple of ``terrain.model.sign_eps_mps``: below it
#: ``tanh(V / sign_eps_mps) > tanh(5) = 0.9999``, the resistance is saturated and what is left is the
#: smooth sign's creep (0.006 m/s at X_t 0.5, 0.032 m/s at the rolling limit 0.586 for FrostyBoy).
IMMOBILISED_SIGN_FACTOR = 5.0
#: The default dug-in sinkage as a fraction of the law's maximum: the law approaches its maximum
#: only asymptotically (its growth falls with 1 - z / z_max), so the limit itself is never reached;
#: at 90 % the hub is nearly in the snow.
SINKAGE_LIMIT_FRACTION = 0.9


@dataclass(frozen=True)
class Criteria:
    """The immobilisation criteria, resolved to numbers (:func:`criteria_of`).

    Attributes
    ----------
    speed_mps : float
        Progress per second below which the chain is stalled [m/s].
    window_s : float
        Time over which the chain must stay stalled [s].
    slip : float
        The chain covers less than ``1 - slip`` of its wheels' travel over the window.
    sinkage_m : float or None
        Mean sinkage at which the chain is dug in [m] (None: not judged).
    goal_m : float or None
        The leader's position at which the run has reached the end of its route [m] (None: no end).
    """

    speed_mps: float
    window_s: float
    slip: float
    sinkage_m: float | None = None
    goal_m: float | None = None


@dataclass(frozen=True)
class Verdict:
    """Where a run ended up.

    Attributes
    ----------
    status : str
        ``"moving"`` (ran the whole duration, not immobilised, no end reached), ``"reached_end"``
        (the leader passed the goal) or ``"immobilised"``.
    t_s : float
        When: the start of the first stalled window, or the first time in it at which the wheels
        are driven (immobilised; or the time the sinkage limit was reached), the time the leader passed the goal (reached_end), the run's last
        output time (moving) [s].
    x_m : float
        Where: the leader's (segment 0's) position at ``t_s`` [m].
    reason : str
        The one line ``snoworm run`` prints: ``"immobilised at x = 91.6 m, t = 48.2 s (X_t 0.35,
        grade 6.1 deg, slip 0.97)"``, ``"reached the end of the route (x = 220.0 m) at t = 130.4 s"``
        or ``"moving at the end (t = 60.0 s, x = 45.1 m, mean speed 0.76 m/s)"``.
    xt : float or None
        Immobilised: the terrain coefficient X_t under the chain at ``t_s`` (mean over the segments).
    grade_deg : float or None
        Immobilised: the grade under the chain at ``t_s`` (mean over the segments) [deg].
    slip : float or None
        Immobilised: the chain's slip over the stalled window, ``1 - P / C`` (the quantity the
        criterion judges: 1 when the chain does not advance at all, above 1 when it slides back);
        dug in: the wheels' slip (Eq. 1) then, mean over the segments.
    cause : str or None
        Immobilised: ``"slip"`` (stalled with the wheels driven) or ``"sinkage"`` (dug in).
    sinkage_m : float or None
        Immobilised, with a sinkage series: the chain's mean sinkage at ``t_s`` [m].
    criteria : Criteria or None
        The criteria judged by.
    """

    status: str
    t_s: float
    x_m: float
    reason: str
    xt: float | None = None
    grade_deg: float | None = None
    slip: float | None = None
    cause: str | None = None
    sinkage_m: float | None = None
    criteria: Criteria | None = None

    @property
    def immobilised_at_m(self) -> float | None:
        """``x_m`` if immobilised, else None (``summary.json``'s ``immobilised_at_m``)."""
        return self.x_m if self.status == "immobilised" else None

    def to_dict(self) -> dict:
        """Plain data (JSON-safe): every attribute, ``criteria`` as a mapping."""
        d = dataclasses.asdict(self)
        return d


def goal_of(scenario) -> float | None:
    """The leader's position at which ``scenario``'s run has reached the end [m], or None.

    ``simulation.goal_m`` if given; else the last distance of ``terrain.route`` (the route file)
    or of ``terrain.elevation`` (the table); else None: a scenario without a route has no end.
    """
    goal = getattr(scenario.simulation, "goal_m", None)
    if goal is not None:
        return float(goal)
    terrain = scenario.terrain
    if terrain.route is not None:
        return float(terrain.route_data().distance_m[-1])
    if terrain.elevation is not None:
        return float(terrain.elevation[-1][0])
    return None


def criteria_of(scenario, **changes) -> Criteria:
    """The criteria of ``scenario`` (``simulation.immobilised`` and the goal, :func:`goal_of`),
    resolved to numbers, with ``changes`` (fields of :class:`Criteria`) applied.

    ``speed_mps`` unset: ``max(IMMOBILISED_SPEED_MPS, IMMOBILISED_SIGN_FACTOR * sign_eps_mps)``.
    ``sinkage_m`` unset: :data:`SINKAGE_LIMIT_FRACTION` of the terrain model's ``sinkage_max_m`` if its
    sinkage law is on, else None.  An unknown
    name in ``changes`` raises ValueError naming the known ones.
    """
    cfg = scenario.simulation.immobilised
    model = scenario.terrain.model
    speed = cfg.speed_mps
    if speed is None:
        speed = max(IMMOBILISED_SPEED_MPS, IMMOBILISED_SIGN_FACTOR * model.sign_eps_mps)
    sinkage = cfg.sinkage_m
    if sinkage is None and model.sinkage != "off":
        sinkage = SINKAGE_LIMIT_FRACTION * model.sinkage_max_m
    crit = Criteria(
        speed_mps=float(speed),
        window_s=float(cfg.window_s),
        slip=float(cfg.slip),
        sinkage_m=None if sinkage is None else float(sinkage),
        goal_m=goal_of(scenario),
    )
    unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(Criteria)})
    if unknown:
        raise ValueError(
            f"verdict criteria: unknown {', '.join(map(repr, unknown))}; give some of "
            f"{', '.join(f.name for f in dataclasses.fields(Criteria))}"
        )
    return dataclasses.replace(crit, **changes) if changes else crit


def _stalled_windows(t, centre, driven, travel, crit):
    """``(first stalled window's start index or None, its end index)`` (module docstring);
    ``travel``: the driven travel from the start (the cumulative trapezoid of ``driven``)."""
    n = t.size
    if n < 2 or t[-1] - t[0] < crit.window_s * (1 - 1e-9):
        return None, None
    end = np.searchsorted(t, t + crit.window_s * (1 - 1e-9))  # first sample a full window later
    ok = end < n
    i = np.nonzero(ok)[0]
    j = end[ok]
    span = t[j] - t[i]
    progress = centre[j] - centre[i]
    driven_travel = travel[j] - travel[i]
    moves = progress >= crit.speed_mps * span
    stuck = (driven_travel >= crit.speed_mps * span) & ~moves & (progress < (1.0 - crit.slip) * driven_travel)
    if moves.any():  # a stall the chain got out of (a later window advances) is not an immobilisation
        stuck &= i > i[moves][-1]
    hit = np.flatnonzero(stuck)
    if hit.size == 0:
        return None, None
    first, last = int(i[hit[0]]), int(j[hit[0]])
    first += int(np.argmax(driven[first : last + 1] > 0))  # from when the wheels are driven (motors started)
    return first, last


def _sunk(segments, crit):
    """The first output index at which the chain's mean sinkage reaches ``crit.sinkage_m``, or None."""
    z = segments.get("sinkage_m")
    if z is None or crit.sinkage_m is None:
        return None
    hit = np.flatnonzero(np.mean(np.asarray(z, float), axis=1) >= crit.sinkage_m)
    return int(hit[0]) if hit.size else None


def _goal_time(t, leader, goal):
    """The time the leader first reaches ``goal`` (linear between samples), or None."""
    if goal is None:
        return None
    hit = np.flatnonzero(leader >= goal)
    if hit.size == 0:
        return None
    k = int(hit[0])
    if k == 0:
        return float(t[0])
    x0, x1 = leader[k - 1], leader[k]
    return float(t[k - 1] + (t[k] - t[k - 1]) * (goal - x0) / (x1 - x0))


def verdict(result, criteria=None) -> Verdict:
    """Judge a finished run: moving, reached the end of its route, or immobilised (module docstring).

    Parameters
    ----------
    result : Result
        A finished run (its ``t`` and ``segments``: ``x_m``, ``wheel_speed_mps``,
        ``speed_setpoint_mps``, ``slip``, ``xt``, ``grade_deg``, and ``sinkage_m`` if present).
    criteria : Criteria or mapping, optional
        The criteria; a mapping changes those of the scenario (:func:`criteria_of`); None: the
        scenario's (``simulation.immobilised``, ``simulation.goal_m``).

    Returns
    -------
    Verdict
        ``status``, ``t_s``, ``x_m`` (the leader's position), ``reason`` (one line), and for an
        immobilised chain ``xt``, ``grade_deg``, ``slip`` and ``cause``.
    """
    if criteria is None:
        crit = criteria_of(result.scenario)
    elif isinstance(criteria, Criteria):
        crit = criteria
    else:
        crit = criteria_of(result.scenario, **dict(criteria))
    t = np.asarray(result.t, float)
    seg = result.segments
    x = np.asarray(seg["x_m"], float)
    leader = x[:, 0]
    centre = x.mean(axis=1)
    motors_on = np.asarray(seg["motor_torque_Nm"]) != 0.0  # a motor switched off gives exactly no torque
    commanded = np.where(motors_on, seg["speed_setpoint_mps"], 0.0)
    driven = np.maximum(np.maximum(commanded, seg["wheel_speed_mps"]), 0.0).mean(axis=1)
    travel = np.concatenate(([0.0], np.cumsum(0.5 * (driven[1:] + driven[:-1]) * np.diff(t))))
    i_stall, j_stall = _stalled_windows(t, centre, driven, travel, crit)
    i_sunk = _sunk(seg, crit)
    t_goal = _goal_time(t, leader, crit.goal_m)
    candidates = []
    if i_stall is not None:
        candidates.append((float(t[i_stall]), "slip", i_stall))
    if i_sunk is not None:
        candidates.append((float(t[i_sunk]), "sinkage", i_sunk))
    stop = min(candidates, key=lambda c: c[0]) if candidates else None
    if t_goal is not None and (stop is None or t_goal <= stop[0]):
        return Verdict(
            "reached_end",
            t_goal,
            float(crit.goal_m),
            f"reached the end of the route (x = {crit.goal_m:.1f} m) at t = {t_goal:.1f} s",
            criteria=crit,
        )
    if stop is not None:
        t_s, cause, i = stop
        if cause == "slip":  # the chain's slip over the stalled window: 1 - progress / driven travel
            slip = 1.0 - float(centre[j_stall] - centre[i]) / float(travel[j_stall] - travel[i])
        else:  # dug in: the wheels' slip (Eq. 1) then, mean over the segments
            slip = float(np.mean(seg["slip"][i]))
        xt = float(np.mean(seg["xt"][i]))
        grade = float(np.mean(seg["grade_deg"][i]))
        z = seg.get("sinkage_m")
        sink = None if z is None else float(np.mean(z[i]))
        why = f"X_t {xt:.2f}, grade {grade:.1f} deg, slip {slip:.2f}"
        if cause == "sinkage":
            why += f", sinkage {sink:.3f} m"
        return Verdict(
            "immobilised",
            t_s,
            float(leader[i]),
            f"immobilised at x = {leader[i]:.1f} m, t = {t_s:.1f} s ({why})",
            xt=xt,
            grade_deg=grade,
            slip=slip,
            cause=cause,
            sinkage_m=sink,
            criteria=crit,
        )
    dur = float(t[-1] - t[0]) if t.size > 1 else 0.0
    speed = float(np.mean(x[-1] - x[0])) / dur if dur > 0 else 0.0
    return Verdict(
        "moving",
        float(t[-1]),
        float(leader[-1]),
        f"moving at the end (t = {t[-1]:.1f} s, x = {leader[-1]:.1f} m, mean speed {speed:.2f} m/s)",
        criteria=crit,
    )
