"""Force control: a PI loop on each link force shares the towing between segments (paper Figs 8-10).

Run: ``python examples/force_control.py [OUT_DIR]`` (default: a new temporary folder).
"""

import sys
import tempfile
from importlib.resources import files
from pathlib import Path

import snoworm
from snoworm import plotting

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="snoworm-force-control-"))
sc = snoworm.load_scenario(files("snoworm") / "scenarios" / "pi3_equal.yaml").with_({"simulation.duration_s": 6.0})
res = snoworm.simulate(sc)

links = res.links_frame()
late = links[links["t_s"] >= res.t[-1] - 1.0].groupby("link")["force_N"].mean()
print(f"{sc.name}: link forces over the last second [N]:", ", ".join(f"{f:.1f}" for f in late))
paths = [
    plotting.save(res.plot("force_diagram"), out / "force_diagram.png"),
    plotting.save(res.plot("speeds"), out / "speeds.png"),
]
print(f"wrote {len(paths)} files to {out}")
