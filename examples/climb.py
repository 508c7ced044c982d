"""Climb: six segments on a 10 deg slope of loose snow (X_t = 0.7): rolling stalls, inching climbs.

Run: ``python examples/climb.py [OUT_DIR]`` (default: a new temporary folder).  The shipped
scenario ``climb`` is the six-segment inchworm gait on the slope; the same chain rolling at
1.8 m/s is the same scenario with a ``uniform`` mode.  The steady state says why rolling stalls
(``snoworm.steady.max_grade_deg``: a rolling chain holds at most 7.9 deg on X_t = 0.7) and the
inchworm phases' Eqs. 4-6 with gravity say why inching climbs (docs/model.md section 7).
A few seconds of computing.
"""

import sys
import tempfile
from importlib.resources import files
from pathlib import Path

import snoworm
from snoworm import plotting, steady
from snoworm.results.energy import energy_metrics

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="snoworm-climb-"))
inch_sc = snoworm.load_scenario(files("snoworm") / "scenarios" / "climb.yaml")
roll_sc = inch_sc.with_(
    {"mode": {"type": "uniform", "speed_mps": 1.8, "start_time_s": 0.5}, "simulation.method": "LSODA"}
)
xt, grade = inch_sc.terrain.xt, inch_sc.terrain.grade_deg
seg, tp = inch_sc.vehicle.segment_params()[0], inch_sc.terrain.model.params()
print(f"slope {grade:g} deg, X_t = {xt:g}: steady rolling limit {steady.max_grade_deg(xt, seg, tp, 1.8):.1f} deg")

for label, sc in (("rolling", roll_sc), ("inching", inch_sc)):
    res = snoworm.simulate(sc)
    e = energy_metrics(res)
    v_end = res.segments["v_mps"][-int(2.0 / sc.simulation.output_dt_s) :].mean()
    per_climbed = e["energy_per_metre_climbed_J_per_m"]
    print(
        f"{label:8s}: {e['distance_m']:5.2f} m along the slope in {sc.simulation.duration_s:g} s "
        f"(last 2 s: {v_end:.3f} m/s, slip {res.segments['slip'][-1].mean():.2f}), climbed "
        f"{e['elevation_gain_m']:.2f} m" + (f", {per_climbed / 1e3:.0f} kJ per metre climbed" if per_climbed else "")
    )
    if label == "inching":
        first = res.mode_summary["phases"][0]["predicted"][0]
        print(
            f"  phase 0, Eq. 6 with gravity: {first['eq6_N']:.0f} N > 0 (progress possible); "
            f"Eq. 5 margin of the anchors {first['eq5_N']:.0f} N"
        )
        print("wrote", plotting.save(res.plot("positions"), out / "positions.png"))
