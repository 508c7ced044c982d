"""Paper Fig 8 as a discrete controller: the leader's wheel speed drives the link force behind it to 0 N.

The rear segment drives at ``speed_mps`` from ``start_time_s``; the leader runs the built-in
force-control mode's PI loop (snoworm.feedback.link_force_pi) as a sampled controller::

    e = F_ref - F_link            (the link behind the leader: more tension -> drive faster)
    v_sp = clip(v_nom + kp e + q, 0, v_max)
    q += ki e dt                  (only while v_sp is not clipped: anti-windup)
"""

import numpy as np


class LinkForcePI:
    def __init__(self, params, scenario):
        self.v_nom = float(params["speed_mps"])
        self.t_start = float(params["start_time_s"])
        self.ref = float(params.get("link_force_N", 0.0))
        self.kp = float(params["kp_mps_per_N"])
        self.ki = float(params["ki_mps_per_Ns"])
        self.v_max = float(params.get("max_speed_mps", 2 * self.v_nom))
        self.dt = float(scenario.mode.period_s)
        self.q = 0.0

    def __call__(self, obs):
        if obs.t_s < self.t_start - 1e-9:
            return {}
        e = self.ref - obs.link_force_N[0]
        raw = self.v_nom + self.kp * e + self.q
        v_sp = float(np.clip(raw, 0.0, self.v_max))
        if v_sp == raw:
            self.q += self.ki * e * self.dt
        return {"wheel_speed_mps": [v_sp, self.v_nom]}
