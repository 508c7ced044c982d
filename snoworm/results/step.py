"""Step-response metrics of a controlled run: rise time, overshoot, settling time, steady-state error.

The definitions are python-control's ``control.step_info`` (python-control 0.10, ``timeresp.py``),
applied to the response measured from the step:

* the step is at the mode's start time ``t_step`` (``mode.start_time_s``, the earliest when it is
  given per segment; 0 without one); time is counted from it and the output from its value there,
  ``y0``, so a response that starts from a non-zero value (a towed chain's link force) is measured
  as python-control measures a response from rest;
* the steady-state value is the response's last value (python-control's ``yfinal`` when the data are
  given: ``InfValue = yout[-1]``), ``dy = y(end) - y0``;
* rise time: from the first time the response reaches 10 % of ``dy`` to the first time it reaches
  90 % (``RiseTimeLimits=(0.1, 0.9)``);
* settling time: the last time the response is outside the band of 2 % of ``|dy|`` around the
  steady-state value, counted from the step (``SettlingTimeThreshold=0.02``);
* overshoot: the peak beyond the steady-state value in per cent of ``|dy|`` (0 if none); undershoot:
  the largest excursion opposite to ``dy`` in per cent of ``|dy|`` (0 if none); peak value and time:
  the largest ``|y - y0|``;
* steady-state error: reference minus the final value, in the response's unit and in per cent of the
  reference step (reference minus ``y0``); python-control has none (its reference is the unit step).

One refinement: times are interpolated linearly between output samples where python-control takes
the first sample at or beyond a threshold, so the metrics do not jump by an output step when the
response moves by a rounding error.  With the steady-state value taken at the run's end, a run too
short to settle reports a settling time close to its end: compare it with ``window_s``.

Which response (:func:`step_responses`): in force control (``force_control`` mode), the force of
each controlled link against its reference (``link_force_refs_N``), the quantity its PI loops
regulate; in the modes with speed set-points (``uniform``, ``controller``), the chain's ground speed
(the mean over the segments) against the mean wheel-speed set-point at the end of the run.  Gaits
(inchworm, supervisor) have no single step: no metrics.
"""

from __future__ import annotations

import numpy as np

__all__ = ["step_info", "step_responses", "STEP_MODES"]

#: Modes whose runs get step-response metrics (``summary.json``'s ``step_response``).
STEP_MODES = ("uniform", "controller", "force_control")


def _first_crossing(t, y, level, sign):
    """The first time ``sign * (y - level) >= 0``, interpolated between samples (NaN if never)."""
    above = sign * (y - level) >= 0
    if not above.any():
        return float("nan")
    i = int(np.argmax(above))
    if i == 0:
        return float(t[0])
    y0, y1 = y[i - 1], y[i]
    frac = (level - y0) / (y1 - y0) if y1 != y0 else 1.0
    return float(t[i - 1] + frac * (t[i] - t[i - 1]))


def _settling_time(t, y, final, band):
    """The last time ``|y - final| >= band``, interpolated to the band's edge (t[0] if never out)."""
    out = np.abs(y - final) >= band
    if not out.any():
        return float(t[0])
    i = int(np.flatnonzero(out)[-1])
    if i + 1 >= t.size:
        return float(t[-1])
    e0, e1 = abs(y[i] - final), abs(y[i + 1] - final)
    frac = (e0 - band) / (e0 - e1) if e0 != e1 else 0.0
    return float(t[i] + frac * (t[i + 1] - t[i]))


def step_info(t, y, reference=None, t_step=0.0, rise_limits=(0.1, 0.9), settling_threshold=0.02) -> dict:
    """Step-response metrics of ``y(t)`` after a step at ``t_step`` (python-control's ``step_info``
    conventions, see the module docstring).

    Parameters
    ----------
    t, y : array_like
        Times [s] (increasing) and the response.
    reference : float, optional
        The reference the response should reach (for the steady-state error).
    t_step : float
        Time of the step [s]; the samples before it are ignored.
    rise_limits, settling_threshold
        As python-control's ``RiseTimeLimits`` and ``SettlingTimeThreshold``.

    Returns
    -------
    dict
        ``initial_value``, ``steady_state_value``, ``rise_time_s``, ``settling_time_s``,
        ``overshoot_pct``, ``undershoot_pct``, ``peak_value``, ``peak_time_s``, ``window_s``, and with
        a reference ``reference``, ``steady_state_error`` and ``steady_state_error_pct``.  Times are
        counted from the step; NaN becomes None (no step: a response that does not move).
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    keep = t >= t_step - 1e-12
    t, y = t[keep] - t_step, y[keep]
    y0, yf = float(y[0]), float(y[-1])
    dy = yf - y0
    out = {
        "initial_value": y0,
        "steady_state_value": yf,
        "rise_time_s": None,
        "settling_time_s": None,
        "overshoot_pct": None,
        "undershoot_pct": None,
        "peak_value": None,
        "peak_time_s": None,
        "window_s": float(t[-1]) if t.size else 0.0,
    }
    if t.size >= 2 and abs(dy) > 1e-12 * max(abs(y0), abs(yf), 1.0):
        s = np.sign(dy)
        r = y - y0  # the response from rest, as python-control measures it
        t_lo = _first_crossing(t, r, rise_limits[0] * dy, s)
        t_hi = _first_crossing(t, r, rise_limits[1] * dy, s)
        over = float(np.max(s * r)) - abs(dy)
        under = float(np.min(s * r))
        k = int(np.argmax(np.abs(r)))
        out.update(
            rise_time_s=t_hi - t_lo,
            settling_time_s=_settling_time(t, r, dy, settling_threshold * abs(dy)),
            overshoot_pct=100.0 * over / abs(dy) if over > 0 else 0.0,
            undershoot_pct=-100.0 * under / abs(dy) if under < 0 else 0.0,
            peak_value=float(y[k]),
            peak_time_s=float(t[k]),
        )
    if reference is not None:
        ref = float(reference)
        out["reference"] = ref
        out["steady_state_error"] = ref - yf
        out["steady_state_error_pct"] = 100.0 * (ref - yf) / abs(ref - y0) if abs(ref - y0) > 1e-12 else None
    return {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in out.items()}


def _t_step(result) -> float:
    start = getattr(result.scenario.mode, "start_time_s", None)
    if start is None:
        return 0.0
    return float(np.min(np.atleast_1d(np.asarray(start, float))))


def step_responses(result) -> list | None:
    """The step-response metrics of a controlled run (:data:`STEP_MODES`), one dict per response:
    :func:`step_info` plus ``response`` (what is measured, with its unit) and ``t_step_s``.  None for
    other modes (a gait has no single step) and for a run that ends before its step.  See the module
    docstring for which responses."""
    mode = getattr(result.scenario.mode, "type", None)
    if mode not in STEP_MODES or result.t.size < 2:
        return None
    t0 = _t_step(result)
    if np.count_nonzero(result.t >= t0 - 1e-12) < 2:  # the run ends before the step: no response
        return None
    if mode == "force_control":
        fc = result.mode_summary.get("force_control", {})
        refs, F = fc.get("link_force_refs_N", []), result.links["force_N"]
        out = []
        for loop in fc.get("loops", []):
            j = int(loop["link"])
            info = step_info(result.t, F[:, j], refs[j], t0)
            out.append({"response": f"link {j} force [N] (segment {loop['segment']}'s loop)", "t_step_s": t0, **info})
        return out
    v = result.segments["v_mps"].mean(1)
    ref = float(result.segments["speed_setpoint_mps"][-1].mean())
    info = step_info(result.t, v, ref, t0)
    return [{"response": "chain ground speed [m/s] (mean of the segments)", "t_step_s": t0, **info}]
