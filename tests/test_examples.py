"""examples/: one script per mode, each run as a user would (``python examples/<mode>.py OUT``)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(
    "name, expect, files",
    [
        ("uniform", "final link forces [N]: ", {"forces.png", "run"}),
        ("force_control", "link forces over the last second [N]: ", {"force_diagram.png", "speeds.png"}),
        ("inchworm", "gait phase changes", {"fig5_groups.png"}),
        ("supervisor", "switch_to_inching", {"positions.png"}),
        ("controller", "(Simulator)", {"forces.png"}),
        ("climb", "Eq. 6 with gravity", {"positions.png"}),
    ],
)
def test_example_runs(tmp_path, name, expect, files):
    r = subprocess.run(
        [sys.executable, str(ROOT / "examples" / f"{name}.py"), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert expect in r.stdout
    assert {p.name for p in tmp_path.iterdir()} == files


def test_one_example_per_mode():
    from snoworm.modes import MODES

    assert {p.stem for p in (ROOT / "examples").glob("*.py")} >= set(MODES)


def test_controller_example_scenario_run_equals_simulator(tmp_path):
    """The controller example's two ways (scenario run, Simulator by hand) print the same force (to 1e-3 N)."""
    r = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "controller.py"), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    forces = [float(line.split(": ")[-1].split(" N")[0]) for line in r.stdout.splitlines() if "link force at" in line]
    assert len(forces) == 2 and abs(forces[0] - forces[1]) <= 1e-3 and abs(forces[0]) < 2.0


def test_climb_example_rolling_stalls_and_inching_climbs(tmp_path):
    """The model's answer on the 10 deg X_t = 0.7 slope: the rolling chain ends spinning (slip ~1,
    under 2 cm/s), the inching chain climbs (over 2 m along the slope in 20 s)."""
    r = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "climb.py"), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    lines = {ln.split(":")[0].strip(): ln for ln in r.stdout.splitlines() if ln.startswith(("rolling", "inching"))}
    dist = {k: float(v.split(":")[1].split(" m along")[0]) for k, v in lines.items()}
    speed = {k: float(v.split("last 2 s: ")[1].split(" m/s")[0]) for k, v in lines.items()}
    assert speed["rolling"] < 0.02 and dist["rolling"] < 0.3
    assert dist["inching"] > 2.0 and speed["inching"] > 0.05
