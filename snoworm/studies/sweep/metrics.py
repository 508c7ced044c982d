"""Per-case work of a sweep: run one case (:func:`run_case`) and reduce it to scalar metrics.

The ``verdict``, ``immobilised`` and ``immobilised_at_m`` columns are the run's verdict
(:func:`snoworm.results.verdict.verdict`, the same test as ``snoworm run``'s last line and
``summary.json``'s ``status``): ``immobilised`` when, over ``simulation.immobilised.window_s``
(5 s), the chain's wheels are driven yet its centre advances less than ``speed_mps`` per second
(by default ``max(0.05 m/s, 5 terrain.model.sign_eps_mps)``) and less than ``1 - slip`` (0.1) of
its wheels' travel.  The smooth sign of the terrain resistance (``tanh(V / sign_eps_mps)``) lets a
stuck vehicle creep: with the default ``sign_eps_mps = 0.01 m/s`` a free-rolling FrostyBoy creeps
at 0.006 m/s at X_t = 0.5 and 0.032 m/s at X_t = 0.586, while at X_t = 0.59 it already rolls at
0.2 m/s; below the threshold ``tanh(V / sign_eps_mps) > tanh(5) = 0.9999``: the terrain resistance
is saturated, so the motion is the regularisation's creep, not rolling.
"""

from __future__ import annotations

import dataclasses
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...config.scenario import Scenario, scenario_from_dict
from ...config.schema import ScenarioError
from ...infra.folders import OutputError, os_error_message
from ...infra.locks import lock_token_matches
from ...infra.pool import interrupt_within
from ...modes.controller import ControllerError
from ...results.verdict import IMMOBILISED_SIGN_FACTOR, IMMOBILISED_SPEED_MPS
from ...simulation.driver import SolverError, simulate
from .series import save_series

__all__ = [
    "SweepTask",
    "case_metrics",
    "run_case",
    "failure_row",
    "one_line",
    "save_case_series",
    "IMMOBILISED_SPEED_MPS",
    "IMMOBILISED_SIGN_FACTOR",
    "LATE_FRACTION",
    "SLIP_FRACTION",
    "METRIC_COLUMNS",
    "STATUSES",
    "MAX_ERROR_CHARS",
]

#: Fraction of the run (at its end) over which the immobilised speed is measured.
LATE_FRACTION = 0.25
#: Fraction of the run (at its end) over which slip is averaged.
SLIP_FRACTION = 0.5

#: Case statuses: ``ok``; ``solver_failure`` (SolverError); ``invalid`` (the case's scenario is
#: rejected, ScenarioError); ``error`` (any other exception in the case, a bug: please report it);
#: ``controller_failure`` (the user's controller raised or returned a bad command, ControllerError).
STATUSES = ("ok", "solver_failure", "invalid", "error", "controller_failure")

#: Metric columns of ``summary.csv`` (the final link forces come between ``max_link_force_N``
#: and ``energy_per_m_J``, one column ``final_link_force_<j>_N`` per link).
METRIC_COLUMNS = {
    "n_segments": "number of segments N",
    "distance_m": "distance travelled, mean over the segments [m]",
    "mean_speed_mps": "distance_m / duration [m/s]",
    "late_speed_mps": "mean forward ground speed over the segments and the last 25 % of the run [m/s]",
    "mean_slip": "slip (Eq. 1, signed) averaged over the segments and the second half of the run",
    "max_slip": "largest slip (signed) over the segments and the second half of the run",
    "max_link_force_N": "largest |link force| over the links and the whole run (0 for one segment) [N]",
    "energy_per_m_J": "energy used (electrical motor + joint work) per metre travelled [J/m] (empty if no distance)",
    "immobilised": "the run's verdict is immobilised (snoworm.results.verdict: stalled for window_s with the wheels "
    "driven, or dug in)",
    "verdict": "the run's verdict: moving, reached_end (the leader passed the route's end) or immobilised",
    "immobilised_at_m": "where the chain was immobilised: the leader's position [m] (empty unless immobilised)",
}

#: Longest error message kept in a row (longer ones are cut).
MAX_ERROR_CHARS = 500


def case_metrics(result) -> dict:
    """Scalar metrics of one finished run (the numeric columns of ``summary.csv``).

    Parameters
    ----------
    result : Result
        A finished simulation.

    Returns
    -------
    dict
        ``n_segments``, ``distance_m`` and ``mean_speed_mps`` (as in ``Result.summary()``),
        ``late_speed_mps`` (mean forward ground speed over the segments and the last 25 % of
        the run, from the displacement), ``mean_slip`` and ``max_slip`` (signed slip, mean and
        maximum over the segments and the output samples of the second half of the run),
        ``max_link_force_N`` (largest absolute link force over the whole run, 0 without links),
        ``final_link_forces_N`` (list, tension positive), ``energy_per_m_J`` (total energy of
        ``Result.energy()`` per metre, None if the distance is below 1 micrometre),
        and from the run's verdict (:func:`snoworm.results.verdict.verdict`, see the module
        docstring): ``verdict`` (``moving``, ``reached_end`` or ``immobilised``), ``immobilised``
        (bool) and ``immobilised_at_m`` (the leader's position, None unless immobilised).
    """
    t = np.asarray(result.t, float)
    x = result.segments["x_m"]
    t0, t1 = float(t[0]), float(t[-1])
    dur = t1 - t0
    dist = float(np.mean(x[-1] - x[0]))
    # late window: displacement-based mean speed (independent of output sampling)
    j_late = int(np.searchsorted(t, t1 - LATE_FRACTION * dur - 1e-9))
    j_late = min(j_late, max(len(t) - 2, 0))
    dt_late = t1 - float(t[j_late])
    late = float(np.mean(x[-1] - x[j_late])) / dt_late if dt_late > 0 else 0.0
    half = t >= t1 - SLIP_FRACTION * dur - 1e-9
    slip = result.segments["slip"][half]
    F = result.links["force_N"]
    e = result.energy()
    v = result.verdict()
    return {
        "n_segments": int(x.shape[1]),
        "distance_m": dist,
        "mean_speed_mps": dist / dur if dur > 0 else 0.0,
        "late_speed_mps": late,
        "mean_slip": float(np.mean(slip)),
        "max_slip": float(np.max(slip)),
        "max_link_force_N": float(np.max(np.abs(F))) if F.size else 0.0,
        "final_link_forces_N": [float(f) for f in F[-1]] if F.size else [],
        "energy_per_m_J": float(e["total_J"] / dist) if dist > 1e-6 else None,
        "immobilised": v.status == "immobilised",
        "verdict": v.status,
        "immobilised_at_m": v.immobilised_at_m,
    }


def save_case_series(result, save_dir, lock_token=None) -> dict:
    """Save a case's series (:func:`~snoworm.studies.sweep.series.save_series`); an I/O failure (disk
    full, read-only, a symlink in the way) is returned as ``{"output_error": message}``, never raised
    and never a case status: the sweep stops on it (exit 2) without recording the case, so a
    resume runs it again.  With ``lock_token`` (the sweep's :class:`~snoworm.infra.locks.FolderLease`
    token) nothing is written unless the sweep's folder still holds that lock (it was not removed,
    moved or replaced meanwhile).  Returns ``{}`` on success."""
    folder = Path(save_dir).parent.parent  # <out>/cases/<case_id>[.npz]
    if lock_token is not None and not lock_token_matches(folder, lock_token):
        return {
            "output_error": f"{folder} was removed, moved or replaced while the sweep ran (its lock file is "
            "not this sweep's, or this worker does not see the folder); nothing was written there"
        }
    try:
        save_series(result, save_dir)
    except (OSError, OutputError) as exc:
        msg = os_error_message(exc, save_dir) if isinstance(exc, OSError) else str(exc)
        return {"output_error": one_line(msg)}
    return {}


def one_line(text: object) -> str:
    """``text`` on one line (line breaks become `` | ``), cut to :data:`MAX_ERROR_CHARS`."""
    text = " | ".join(s.strip() for s in str(text).splitlines() if s.strip())
    return text if len(text) <= MAX_ERROR_CHARS else text[: MAX_ERROR_CHARS - 3] + "..."


@dataclass(frozen=True)
class SweepTask:
    """One case of a sweep as an executor hands it to :func:`run_case` (small; pickles to a worker).

    Attributes
    ----------
    index : int
        The case's index in the sweep.
    raw : dict or None
        The scenario mapping with the case's overrides applied, validated where the case runs;
        None if ``scenario`` is given.
    scenario : Scenario or None
        The case's scenario, validated already (by the sweep's plan, or the batched executor's
        grouping).
    source : str
        The scenario's name in messages.
    base_dir : str or None
        The folder relative file paths of ``raw`` are taken from (the scenario file's).
    save_dir : Path or None
        Where to write the case's time series (a folder or a ``.npz`` file, see
        :func:`~snoworm.studies.sweep.series.save_series`); None: not written.
    allow_code : tuple of str
        Resolved paths whose controller code may run besides the scenario's folder
        (``run_sweep(allow_code=...)``).
    lock_token : str or None
        The token of the sweep's folder lock: ``save_dir`` is written only while the folder holds it.
    """

    index: int
    raw: dict | None = None
    scenario: Scenario | None = None
    source: str = "scenario"
    base_dir: str | None = None
    save_dir: str | Path | None = None
    allow_code: tuple = ()
    lock_token: str | None = None

    def validated(self) -> Scenario:
        """The case's scenario (``scenario``, or ``raw`` validated; ScenarioError if invalid)."""
        if self.scenario is not None:
            return self.scenario
        return scenario_from_dict(self.raw, self.source, base_dir=self.base_dir)

    def with_scenario(self, sc: Scenario) -> SweepTask:
        """This task with its scenario validated (so :func:`run_case` does not validate it again)."""
        return dataclasses.replace(self, scenario=sc)


def run_case(task: SweepTask) -> dict:
    """Run one case (the function executors call; top-level so it pickles).

    Parameters
    ----------
    task : SweepTask
        The case.

    Returns
    -------
    dict
        ``index``, ``status``, ``error`` and, for ``ok``, the :func:`case_metrics` and
        ``wall_time_s``; ``output_error`` if its series could not be saved (:func:`save_case_series`).
        Never raises for a failing case; the time series stay in the worker.
    """
    wall0 = time.perf_counter()
    out = {"index": task.index, "status": "ok", "error": ""}
    try:
        res = simulate(task.validated(), allow_code=task.allow_code)
        out.update(case_metrics(res))
        if task.save_dir:
            out.update(save_case_series(res, task.save_dir, task.lock_token))
        del res
    except Exception as exc:  # noqa: BLE001 - a case must never stop the sweep
        out.update(failure_row(exc))
    out["wall_time_s"] = time.perf_counter() - wall0
    return out


def failure_row(exc: Exception) -> dict:
    """``{"status", "error"}`` of a case (or an odds draw) that raised ``exc``: ``invalid`` (a
    ScenarioError), ``solver_failure``, ``controller_failure``, else ``error`` with the exception's
    type and where it was raised.  An interrupt inside it (Ctrl-C/SIGTERM within a C call,
    :func:`~snoworm.infra.pool.interrupt_within`) is raised instead: the study stops, the case is
    not recorded."""
    for kind, status in (
        (ScenarioError, "invalid"),
        (SolverError, "solver_failure"),
        (ControllerError, "controller_failure"),
    ):
        if isinstance(exc, kind):
            return {"status": status, "error": one_line(exc)}
    interrupt = interrupt_within(exc)
    if interrupt is not None:
        raise interrupt from None
    tb = traceback.extract_tb(exc.__traceback__)
    where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
    return {"status": "error", "error": one_line(f"{type(exc).__name__}: {exc}{where}")}
