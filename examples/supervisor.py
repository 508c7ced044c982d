"""Supervisor: roll, detect immobilisation in a patch of loose snow, switch to inching.

Run: ``python examples/supervisor.py [OUT_DIR]`` (default: a new temporary folder).  The shipped
scenario (100 s simulated, about a minute of computing) also inches out of the patch and rolls
on; here the patch is moved close to the start and the run stopped after the switch to inching,
so the example takes seconds.
"""

import sys
import tempfile
from importlib.resources import files
from pathlib import Path

import snoworm
from snoworm import plotting

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="snoworm-supervisor-"))
sc = snoworm.load_scenario(files("snoworm") / "scenarios" / "traverse_patch.yaml").with_(
    {"terrain.patches": [{"start_m": 2.0, "end_m": 8.0, "xt": 0.3, "ramp_m": 0.5}], "simulation.duration_s": 12.0}
)
res = snoworm.simulate(sc)

for e in res.events:
    if e.get("kind", "").startswith("switch"):
        print(f"t = {e['t_s']:6.2f} s  {e['kind']:<18} leader at x = {e['x_m']:.2f} m")
print(f"{sc.name}: distance {res.summary()['distance_m']:.2f} m in {sc.simulation.duration_s:g} s")
print("wrote", plotting.save(res.plot("positions"), out / "positions.png"))
