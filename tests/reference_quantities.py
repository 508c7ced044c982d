"""What the reference tests compare, and on which scale (tests/test_reference_summaries.py,
tests/test_tight_reference.py and benchmarks/record_references.py share it).

Every compared quantity is a physical result of a run: distance, final positions, energy,
time-averaged speeds and forces, the largest link force, and end values.  An error is measured
on the quantity's physical scale::

    scaled_error = max |got - ref| / scale

* kinematics and energy: their own largest magnitude in the reference, with a floor for values
  that are near zero (``FLOORS``: 0.01 m, 0.01 m/s, 1 J, 10 N);
* forces (time averages, last-window averages, end values): the largest force of the same kind
  seen anywhere in the reference run (``max_abs_link_force_N``, ``max_abs_net_force_N``), so a
  force that averages to nearly zero is judged against the forces the vehicle actually carries.

Gait runs (modes that switch gait phases at state events: inchworm, supervisor) end inside a
hand-over, where a link force falls by hundreds of newtons within milliseconds: their end values
are ill-conditioned (a 0.1 ms shift of an event time reached after dozens of events moves them
by newtons), so for them the end values are replaced by averages over the last ``WINDOW`` of the
run, which hold several hand-overs and are well conditioned.  The net forces of gait runs jump
by the full hold force at every hand-over, so only their whole-run average is compared.
"""

from __future__ import annotations

import numpy as np

_trapezoid = getattr(np, "trapezoid", None) or np.trapz  # numpy < 2 names it trapz

#: Modes that switch gait phases at state events (their runs end inside a hand-over).
GAIT_MODES = ("inchworm", "supervisor")
#: The last fraction of the run averaged in place of a gait run's end values.
WINDOW = 0.1
#: Floors of the scales, for quantities that are zero at a steady state or for a still vehicle.
FLOORS = {"m": 0.01, "mps": 0.01, "J": 1.0, "N": 10.0}
#: quantity -> how its scale is taken: a unit (its own largest magnitude, floored) or the key of
#: the run's largest force of that kind.
SCALES = {
    "distance_m": "m",
    "x_last_m": "m",
    "mean_speed_mps": "mps",
    "total_energy_J": "J",
    "max_abs_link_force_N": "N",
    "mean_link_force_N": "max_abs_link_force_N",
    "mean_net_force_N": "max_abs_net_force_N",
    "window_speed_mps": "mps",
    "window_link_force_N": "max_abs_link_force_N",
    "final_speed_mps": "mps",
    "final_link_forces_N": "max_abs_link_force_N",
    "final_net_forces_N": "max_abs_net_force_N",
}
#: Compared only for runs that are not gait runs (see the module docstring).
END_VALUES = ("final_speed_mps", "final_link_forces_N", "final_net_forces_N")
#: Compared only for gait runs, in place of the end values.
WINDOW_VALUES = ("window_speed_mps", "window_link_force_N")
#: Solver and output counts recorded beside the quantities.
COUNTS = ("nfev", "njev", "intervals", "n_t")


def is_gait(scenario) -> bool:
    """Whether a scenario's mode switches gait phases at state events."""
    return scenario.mode.type in GAIT_MODES


def _time_mean(t, y, fraction=1.0):
    """Time average of ``y`` (time x members) over the last ``fraction`` of the run (trapezoids)."""
    if y.size == 0:
        return []
    keep = t >= t[-1] - fraction * (t[-1] - t[0])
    tt, yy = t[keep], y[keep]
    return (_trapezoid(yy, tt, axis=0) / (tt[-1] - tt[0])).tolist()


def quantities(res) -> dict:
    """The compared quantities and counts of a result (see :data:`SCALES`, :data:`COUNTS`)."""
    s = res.summary()
    t, seg, lnk = res.t, res.segments, res.links
    return {
        "distance_m": s["distance_m"],
        "x_last_m": seg["x_m"][-1].tolist(),
        "mean_speed_mps": _time_mean(t, seg["v_mps"]),
        "total_energy_J": s["energy"]["total_J"],
        "max_abs_link_force_N": s["max_abs_link_force_N"],
        "max_abs_net_force_N": float(np.max(np.abs(seg["net_force_N"]))),
        "mean_link_force_N": _time_mean(t, lnk["force_N"]),
        "mean_net_force_N": _time_mean(t, seg["net_force_N"]),
        "window_speed_mps": _time_mean(t, seg["v_mps"], WINDOW),
        "window_link_force_N": _time_mean(t, lnk["force_N"], WINDOW),
        "final_speed_mps": s["final_speed_mps"],
        "final_link_forces_N": s["final_link_forces_N"],
        "final_net_forces_N": s["final_net_forces_N"],
        "nfev": s["solver"]["nfev"],
        "njev": s["solver"]["njev"],
        "intervals": s["solver"]["intervals"],
        "n_t": int(t.size),
    }


def compared(gait: bool) -> tuple:
    """The quantities compared for a gait run or another run."""
    skip = END_VALUES if gait else WINDOW_VALUES
    return tuple(k for k in SCALES if k not in skip)


def scale(ref: dict, key: str) -> float:
    """The physical scale of quantity ``key`` in the reference ``ref``."""
    how = SCALES[key]
    if how in FLOORS:
        values = np.atleast_1d(np.asarray(ref[key], float))
        return max(float(np.max(np.abs(values))) if values.size else 0.0, FLOORS[how])
    return max(float(ref[how]), FLOORS["N"])


def scaled_error(got: dict, ref: dict, key: str) -> float:
    """``max |got - ref| / scale(ref, key)`` over the quantity's values (0 for an empty one)."""
    a, b = np.atleast_1d(np.asarray(got[key], float)), np.atleast_1d(np.asarray(ref[key], float))
    assert a.shape == b.shape, f"{key}: shape {a.shape} != reference {b.shape}"
    if a.size == 0:
        return 0.0
    return float(np.max(np.abs(a - b))) / scale(ref, key)
