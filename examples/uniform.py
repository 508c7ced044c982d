"""Uniform mode: every segment at the same wheel-speed set-point, towing a load (paper Figs 6-7).

Run: ``python examples/uniform.py [OUT_DIR]`` (default: a new temporary folder).
"""

import sys
import tempfile
from importlib.resources import files
from pathlib import Path

import snoworm
from snoworm import plotting

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="snoworm-uniform-"))
sc = snoworm.load_scenario(files("snoworm") / "scenarios" / "tow6_uniform.yaml")
sc = sc.with_({"simulation.duration_s": 6.0, "tow.force_N": 200.0})
res = snoworm.simulate(sc)

# the links carry the tow: the last link's tension approaches the tow force
final = res.links["force_N"][-1]
print(
    f"{sc.name}: mean speed {res.summary()['mean_speed_mps']:.3f} m/s; final link forces [N]:",
    ", ".join(f"{f:.1f}" for f in final),
)
paths = res.write(out / "run", plot=False)
paths.append(plotting.save(res.plot("forces"), out / "forces.png"))
print(f"wrote {len(paths)} files to {out}")
