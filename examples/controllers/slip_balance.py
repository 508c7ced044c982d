"""Slip-balancing load share for a chain of N segments (beyond the built-in modes).

Each segment starts from its own nominal wheel speed (``speeds_mps``: e.g. unequal wheels or a
miscalibrated drive) and corrects it with a discrete integral loop on its measured slip, so
every segment slips as much as the chain's mean:

    q_k += ki (mean(slip) - slip_k) dt        v_sp,k = v_k + q_k

Equal slip at a common ground speed means equal traction per wheel on uniform snow, so the
towed load is shared evenly without measuring any force.  ``slip_max`` caps the chain's mean
slip: above it every set-point is lowered together.
"""

import numpy as np


class SlipBalance:
    def __init__(self, params, scenario):
        n = scenario.vehicle.segments
        v = np.asarray(params["speeds_mps"], float)
        self.v = v if v.size == n else np.full(n, float(v.reshape(-1)[0]))
        self.ki = float(params["ki_mps"])
        self.slip_max = float(params.get("slip_max", 1.0))
        self.t_start = float(params.get("start_time_s", 0.0))
        self.dt = float(scenario.mode.period_s)
        self.q = np.zeros(n)

    def __call__(self, obs):
        if obs.t_s < self.t_start - 1e-9:
            return {}
        mean = float(np.mean(obs.slip))
        self.q += self.ki * (mean - obs.slip) * self.dt
        self.q -= self.ki * max(0.0, mean - self.slip_max) * self.dt
        return {"wheel_speed_mps": np.maximum(self.v + self.q, 0.0).tolist()}
