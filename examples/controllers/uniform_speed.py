"""The smallest useful controller: every segment at one wheel speed from a start time on.

Driving scenarios/tow6_uniform.yaml's chain with it (tow6_uniform_controller.yaml) reproduces
the built-in uniform mode (paper Fig 6).
"""


class UniformSpeed:
    def __init__(self, params, scenario):
        self.speed = float(params["speed_mps"])
        self.t_start = float(params["start_time_s"])
        self.n = scenario.vehicle.segments

    def __call__(self, obs):
        if obs.t_s < self.t_start - 1e-9:  # times are sums of periods: allow for rounding
            return {}  # nothing commanded yet: motors off
        return {"wheel_speed_mps": [self.speed] * self.n}
