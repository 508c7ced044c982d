"""Results of a simulation: time series per segment and per link, summary, files on disk.

Every output quantity is recomputed from the solved states after the solve, in one vectorised
pass of the same force kernel the right-hand side uses (:meth:`ChainModel.evaluate`).
"""
from __future__ import annotations

import io
import math
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._version import __version__
from .energy import energy_metrics
from .fileio import atomic_write_text
from .scenario import dump_scenario

__all__ = ["Result", "SEGMENT_COLUMNS", "LINK_COLUMNS"]

#: Columns of ``segments.csv`` (after ``t_s, segment``): name -> description.
SEGMENT_COLUMNS = {
    "x_m": "position of the segment's reference point [m]",
    "v_mps": "ground speed [m/s]",
    "wheel_speed_mps": "wheel circumferential speed R_w*omega, mean of the axles [m/s]",
    "slip": "slip (Eq. 1, regularised), mean of the axles",
    "traction_N": "tractive force F_t summed over the segment's wheels [N]",
    "resistance_N": "terrain resistance force F_tr summed over the segment's wheels [N]",
    "net_force_N": "traction - resistance, summed over the wheels [N]",
    "motor_torque_Nm": "motor torque per wheel at the wheel, mean of the axles [N m]",
    "speed_setpoint_mps": "wheel-speed set-point R_w*omega_ref [m/s]",
    "connector_net_N": "net force of the links (and tow) on the segment, forward positive [N]",
    "xt": "terrain coefficient X_t under the segment, mean of the axles",
    "motor_power_W": "mechanical motor power at the wheels, summed over the wheels [W]",
    "terrain_dissipation_W": "power dissipated at the wheel-terrain contacts of the segment [W]",
    "motor_electrical_power_W": "electrical power drawn by the segment's motors: motoring power / drivetrain "
                                "efficiency, braking not recovered [W]",
}

#: Columns of ``links.csv`` (after ``t_s, link``).
LINK_COLUMNS = {
    "force_N": "link force, tension positive [N]",
    "length_m": "centre-to-centre distance of the two segments [m]",
    "extension_m": "prismatic joint extension (0 for a fixed link) [m]",
    "joint_power_W": "mechanical power delivered by the prismatic joint actuator [W]",
    "spring_force_N": "force of the link spring (in series with the damper and the actuator), tension positive [N]",
    "damper_power_W": "power dissipated in the link damper [W]",
}


@dataclass
class Result:
    """A finished simulation.

    Attributes
    ----------
    scenario : Scenario
        The resolved scenario.
    t : ndarray (n_t,)
        Output times [s].
    segments : dict of str -> ndarray (n_t, N)
        Per-segment series, exactly the keys of :data:`SEGMENT_COLUMNS`.
    links : dict of str -> ndarray (n_t, N-1)
        Per-link series, exactly the keys of :data:`LINK_COLUMNS`.
    phases : list of dict
        Integration intervals (start, end, label).
    events : list of dict
        Mode events (gait phase changes, switches), with time and cause.
    stats : dict
        Solver statistics (nfev, njev, nlu, intervals, wall_time_s).
    mode_summary : dict
        Mode-specific metrics.
    """

    scenario: object
    t: np.ndarray
    segments: dict
    links: dict
    phases: list
    events: list
    stats: dict
    mode_summary: dict = field(default_factory=dict)

    @classmethod
    def from_pieces(cls, sc, model, mode, pieces, phases, stats):
        seg_parts, link_parts, ts = [], [], []
        eta = model.seg.drivetrain_efficiency
        L = model.layout
        for t, ys, ctl in pieces:
            Y = model.unpack(ys)
            dY, out = model.evaluate(Y, ctl, outputs=True)
            R = model.seg.wheel_radius_m
            nw = model.seg.wheels_per_axle
            w = out["omega"]
            Tm = out["motor_torque_Nm"]
            Ft = out["traction_axle_N"].sum(-1)
            Ftr = out["resistance_axle_N"].sum(-1)
            seg = {
                "x_m": Y[..., L.x], "v_mps": Y[..., L.v],
                "wheel_speed_mps": (w * R[:, None]).mean(-1), "slip": out["slip"].mean(-1),
                "traction_N": Ft, "resistance_N": Ftr, "net_force_N": Ft - Ftr,
                "motor_torque_Nm": Tm.mean(-1), "speed_setpoint_mps": np.array(out["speed_sp_mps"], float),
                "connector_net_N": out["link_net_N"], "xt": out["X"].mean(-1),
                "motor_power_W": (Tm * w).sum(-1) * nw,
                "terrain_dissipation_W": out["terrain_dissipation_W"],
                "motor_electrical_power_W": (np.maximum(Tm * w, 0.0)).sum(-1) * nw / eta,
            }
            x = seg["x_m"]
            lk = {"force_N": out["link_force_N"], "length_m": x[..., :-1] - x[..., 1:],
                  "spring_force_N": out["link_spring_N"], "damper_power_W": out["link_damper_W"]}
            if model.has_joints:
                s = Y[..., :-1, L.s]
                ds = dY[..., :-1, L.s]
                lk["extension_m"] = s
                # the actuator is in series with the link's spring-damper: it carries the link force
                lk["joint_power_W"] = -out["link_force_N"] * ds
            else:
                lk["extension_m"] = np.zeros_like(lk["length_m"])
                lk["joint_power_W"] = np.zeros_like(lk["length_m"])
            seg_parts.append(seg)
            link_parts.append(lk)
            ts.append(t)
        t = np.concatenate(ts)
        segments = {k: np.concatenate([p[k] for p in seg_parts]) for k in seg_parts[0]}
        links = {k: np.concatenate([p[k] for p in link_parts]) for k in link_parts[0]}
        segments = {k: segments[k] for k in SEGMENT_COLUMNS}     # the documented columns, in order
        links = {k: links[k] for k in LINK_COLUMNS}
        res = cls(sc, t, segments, links, phases, list(mode.log), stats)
        res.mode_summary = mode.summary(res)
        return res

    # ------------------------------------------------------------------ metrics
    @property
    def n_segments(self) -> int:
        return self.segments["x_m"].shape[1]

    def energy(self, metrics: dict | None = None) -> dict:
        """Energy used [J]: motors (mechanical and electrical, with the drivetrain loss) and joints.

        Electrical energy counts only motoring power (``T w > 0``) divided by the drivetrain
        efficiency; braking and holding power are not recovered.  Joint energy counts the
        positive mechanical work of the prismatic actuators, and its electrical energy that work
        divided by ``vehicle.links.joint_efficiency``.  ``total_J`` is the electrical total
        (definitions in :mod:`snoworm.energy`).  ``metrics``: an already computed
        :func:`snoworm.energy.energy_metrics` of this result, to select from.
        """
        e = energy_metrics(self) if metrics is None else metrics
        return {"motor_electrical_J": e["motor_electrical_J"], "motor_mechanical_J": e["motor_mechanical_J"],
                "joint_work_J": e["joint_mechanical_J"], "joint_electrical_J": e["joint_electrical_J"],
                "total_J": e["total_electrical_J"]}

    def summary(self) -> dict:
        """The metrics written to ``summary.json``."""
        x = self.segments["x_m"]
        dist = float(np.mean(x[-1] - x[0]))
        dur = float(self.t[-1] - self.t[0]) if self.t.size > 1 else 0.0
        metrics = energy_metrics(self)
        e = self.energy(metrics)
        s = {
            "scenario": self.scenario.name,
            "snoworm_version": __version__,
            "segments": self.n_segments,
            "duration_s": dur,
            "distance_m": dist,
            "mean_speed_mps": dist / dur if dur > 0 else 0.0,
            "final_link_forces_N": self.links["force_N"][-1].tolist(),
            "final_net_forces_N": self.segments["net_force_N"][-1].tolist(),
            "final_slip": self.segments["slip"][-1].tolist(),
            "final_speed_mps": self.segments["v_mps"][-1].tolist(),
            "max_abs_link_force_N": float(np.max(np.abs(self.links["force_N"]))) if self.links["force_N"].size else 0.0,
            "energy": e,
            "energy_per_metre_J_per_m": e["total_J"] / dist if dist > 1e-9 else None,
            "energy_metrics": metrics,
            "solver": dict(self.stats),
            "events": self.events,
        }
        s.update(self.mode_summary)
        return s

    # ------------------------------------------------------------------ tables
    def segments_csv(self) -> str:
        n_t, n = self.segments["x_m"].shape
        cols = ["t_s", "segment"] + list(SEGMENT_COLUMNS)
        data = np.column_stack([np.repeat(self.t, n), np.tile(np.arange(n), n_t)]
                               + [self.segments[c].reshape(-1) for c in SEGMENT_COLUMNS])
        return _csv(cols, data, int_cols=(1,), t_decimals=time_decimals(self.scenario.simulation.output_dt_s))

    def links_csv(self) -> str:
        n_t, n = self.links["force_N"].shape
        cols = ["t_s", "link"] + list(LINK_COLUMNS)
        data = np.column_stack([np.repeat(self.t, n), np.tile(np.arange(n), n_t)]
                               + [self.links[c].reshape(-1) for c in LINK_COLUMNS])
        return _csv(cols, data, int_cols=(1,), t_decimals=time_decimals(self.scenario.simulation.output_dt_s))

    def write(self, out_dir, plot: bool = True) -> list:
        """Write ``segments.csv``, ``links.csv``, ``summary.json``, ``scenario.yaml`` (and plots).

        Each file is written atomically (temporary file, then rename).  Returns the paths.
        """
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = [
            atomic_write_text(out / "segments.csv", self.segments_csv()),
            atomic_write_text(out / "links.csv", self.links_csv()),
            atomic_write_text(out / "summary.json", json.dumps(self.summary(), indent=2) + "\n"),
            atomic_write_text(out / "scenario.yaml", dump_scenario(self.scenario)),
        ]
        if plot:
            from . import plotting   # lazy: matplotlib costs ~0.5 s to import; runs without plots never pay it
            paths += plotting.plot_result(self, out)
        return paths


def time_decimals(output_dt_s: float) -> int:
    """Decimals of ``t_s`` in the CSVs: 4, or enough that times ``output_dt_s`` apart print apart
    (one digit below the sampling interval's leading digit; at most 12)."""
    return int(min(12, max(4, 1 - math.floor(math.log10(output_dt_s)))))


def _csv(cols, data, int_cols=(), t_decimals=4):
    buf = io.StringIO()
    buf.write(",".join(cols) + "\n")
    fmt = ["%.6g"] * data.shape[1]
    fmt[0] = f"%.{t_decimals}f"
    for c in int_cols:
        fmt[c] = "%d"
    np.savetxt(buf, data, fmt=fmt, delimiter=",")
    return buf.getvalue()
