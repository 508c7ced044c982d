"""Controller mode: your own discrete-time controller, from a scenario and step by step (docs/controllers.md).

Runs the Fig 8 link-force PI of ``examples/controllers/fig8_pi.py`` twice: as ``mode: {type:
controller}`` through :func:`snoworm.simulate`, and by hand with :class:`snoworm.Simulator`
calling the same class every period.  Both give the same link force.

Run: ``python examples/controller.py [OUT_DIR]`` (default: a new temporary folder).
"""

import sys
import tempfile
from pathlib import Path

import snoworm
from snoworm import plotting

here = Path(__file__).resolve().parent
out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="snoworm-controller-"))
sc = snoworm.load_scenario(here / "controllers" / "fig8_pi.yaml").with_({"simulation.duration_s": 8.0})

# 1. the controller named in the scenario, run by simulate()
res = snoworm.simulate(sc)
print(f"{sc.name}: link force at {res.t[-1]:.0f} s: {res.links['force_N'][-1, 0]:.3f} N (scenario run)")

# 2. the same controller class, called by hand every period with the Simulator
sys.path.insert(0, str(here / "controllers"))
from fig8_pi import LinkForcePI  # noqa: E402  (the example controller's own file)

ctrl = LinkForcePI(sc.mode.params, sc)
sim = snoworm.Simulator(sc)
obs = sim.reset()
while obs.t_s < sc.simulation.duration_s - 1e-9:
    obs = sim.step(ctrl(obs), sc.mode.period_s)
print(f"{sc.name}: link force at {obs.t_s:.0f} s: {obs.link_force_N[0]:.3f} N (Simulator)")
plotting.save(sim.result().plot("forces"), out / "forces.png")
print(f"wrote forces.png to {out}")
