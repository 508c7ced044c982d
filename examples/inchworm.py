"""Inchworm gait: prismatic joints move groups of segments while the others anchor (paper Fig 5).

Run: ``python examples/inchworm.py [OUT_DIR]`` (default: a new temporary folder).
"""

import sys
import tempfile
from importlib.resources import files
from pathlib import Path

from matplotlib.figure import Figure

import snoworm
from snoworm import plotting

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="snoworm-inchworm-"))
sc = snoworm.load_scenario(files("snoworm") / "scenarios" / "inchworm6.yaml").with_({"simulation.duration_s": 8.0})
res = snoworm.simulate(sc)

phases = [e for e in res.events if e.get("kind") == "phase_change"]
print(
    f"{sc.name}: {len(phases)} gait phase changes, distance {res.summary()['distance_m']:.2f} m "
    f"on X_t = {sc.terrain.xt:g} (rolling is immobilised below about 0.59)"
)
# the paper's Fig 5: one panel per group of segments moving together, on a figure of our own
fig = Figure(figsize=(8, 6), layout="constrained")
res.plot("groups", fig=fig)
print("wrote", plotting.save(fig, out / "fig5_groups.png"))
