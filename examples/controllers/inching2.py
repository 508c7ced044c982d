"""A two-segment inching gait (paper section 5.1) as a discrete controller.

Two phases, switched on the measured joint extension:

* push: the rear segment's wheels are locked (the anchor), the front rolls at ``mover_speed_mps``
  while the joint extends to the end of its stroke;
* pull: the front is locked, the rear rolls while the joint contracts.

A phase ends when the extension is within ``margin_m`` of its end of stroke.
"""


class InchingGait:
    def __init__(self, params, scenario):
        links = scenario.vehicle.links
        self.s_min, self.s_max = float(links.stroke_min_m), float(links.stroke_max_m)
        self.v = float(params["mover_speed_mps"])
        self.margin = float(params.get("margin_m", 0.01))
        self.t_start = float(params.get("start_time_s", 0.0))
        self.phase = "push"
        self.switches = 0

    def __call__(self, obs):
        if obs.t_s < self.t_start - 1e-9:
            return {}
        s = obs.joint_extension_m[0]
        if self.phase == "push" and s >= self.s_max - self.margin:
            self.phase, self.switches = "pull", self.switches + 1
        elif self.phase == "pull" and s <= self.s_min + self.margin:
            self.phase, self.switches = "push", self.switches + 1
        if self.phase == "push":  # rear anchored, front moves, joint extends
            return {"wheel_speed_mps": [self.v, self.v], "wheel_lock": [False, True], "joint_length_m": [self.s_max]}
        return {"wheel_speed_mps": [self.v, self.v], "wheel_lock": [True, False], "joint_length_m": [self.s_min]}
