"""Controllers used by the tests (importable as ``tests.controller_helpers:Name``)."""

import numpy as np


class Uniform:
    """Every segment at ``speed_mps`` from ``start_time_s`` on (the uniform mode as a controller)."""

    def __init__(self, params, scenario):
        self.speed = float(params["speed_mps"])
        self.t_start = float(params.get("start_time_s", 0.0))
        self.n = scenario.vehicle.segments
        self.seen = []

    def __call__(self, obs):
        self.seen.append(obs.t_s)
        if obs.t_s < self.t_start - 1e-9:
            return {}
        return {"wheel_speed_mps": [self.speed] * self.n}


def schedule(t_s, n):
    """A command schedule exercising every wheel key (used for the controller/Simulator equivalence)."""
    k = int(round(t_s / 0.05))
    if k < 4:
        return {}
    if k % 7 == 0:
        return {"wheel_torque_Nm": list(np.linspace(5.0, 40.0, n))}
    if k % 5 == 0:
        return {"wheel_lock": [j == 0 for j in range(n)]}
    return {"wheel_speed_mps": list(1.0 + 0.1 * np.arange(n) + 0.2 * np.sin(t_s)), "wheel_lock": [False] * n}


class Scheduled:
    def __init__(self, params, scenario):
        self.n = scenario.vehicle.segments

    def __call__(self, obs):
        return schedule(obs.t_s, self.n)
