"""Shared test helpers."""

import functools
import os
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import settings

from snoworm import load_scenario, simulate
from snoworm.config.scenario import apply_overrides, read_yaml, scenario_from_dict
from snoworm.dynamics import Controls
from snoworm.simulation.driver import chain_model

# In CI (the CI variable set) every property test draws the same examples on every run, so a
# landing never depends on the luck of the draw; locally the draws stay random and keep finding
# new cases (a failure found there is kept in .hypothesis/ and replayed).
settings.register_profile("ci", derandomize=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"


@functools.cache
def shipped_result(name):
    """A shipped scenario run once per test session at its own settings (shared by the
    reference, tight-reference and solver-budget tests; callers must not modify it)."""
    return simulate(load_scenario(SCENARIOS / f"{name}.yaml"))


@pytest.fixture(autouse=True)
def _close_pyplot_figures():
    """Figures drawn without ax/fig are pyplot's (as in a notebook): release them after each test."""
    yield
    import sys

    if "matplotlib.pyplot" in sys.modules:
        sys.modules["matplotlib.pyplot"].close("all")


@pytest.fixture
def scenario_path():
    """Path of a shipped scenario by name."""
    return lambda name: SCENARIOS / f"{name}.yaml"


# ------------------------------------------------------------------ chain models and states
# (shared by test_dynamics.py and test_model_jacobian.py)


def model_for(path, overrides=(), force_loop=None):
    sc = scenario_from_dict(apply_overrides(read_yaml(path), overrides))
    m = chain_model(sc)
    if force_loop is not None and force_loop != m.force_loop:
        from snoworm.dynamics import ChainModel

        m = ChainModel(m.seg, m.links, m.tp, m.profile, m.tow_force_N, force_loop=force_loop)
    return m


def random_state(m, rng):
    y = m.initial_state()
    Y = m.unpack(y).copy()
    Y[:, m.layout.index["x_m"]] += rng.normal(0, 0.05, m.n)
    Y[:, m.layout.index["v_mps"]] = rng.uniform(-0.5, 2.0, m.n)
    Y[:, 2:4] = rng.uniform(-2, 9, (m.n, 2))
    Y[:, 4:6] = rng.uniform(-50, 50, (m.n, 2))
    if m.force_loop:
        Y[:, m.layout.index["q_mps"]] = rng.uniform(-0.5, 0.5, m.n)
    if m.has_joints:
        Y[:, m.layout.index["s_m"]] = rng.uniform(0.0, 0.3, m.n)
    if m.layout.j is not None:  # shear displacements on both sides of +-K (the clip of j / K)
        K = m.tp.shear_modulus_K_m
        Y[:, m.layout.j] = rng.uniform(-1.5 * K, 1.5 * K, (m.n, 2))
    if m.layout.z is not None:  # slip-sinkage up to its saturation depth
        Y[:, m.layout.z] = rng.uniform(0.0, m.tp.sinkage_max_m, (m.n, 2))
    return Y.reshape(-1)


#: The laws of the slip near rest and of sinkage (docs/model.md section 2) as scenario overrides:
#: the kernel tests run each of them (the shear displacement and the sinkage add state fields).
TERRAIN_LAWS = {
    "regularised": [],
    "shear": [("terrain.model.standstill", "shear")],
    "shear+sinkage": [("terrain.model.standstill", "shear"), ("terrain.model.sinkage", "slip")],
    "sinkage": [("terrain.model.sinkage", "slip")],
}


def busy_controls(m, rng):
    n = m.n
    c = Controls.rolling(n, np.ones(n), rng.uniform(0, 2, n))
    links = np.arange(n - 1)
    return c.with_(
        fc_active=np.r_[np.ones(n - 1), 0.0],
        fc_link=np.r_[links, n - 1],
        fc_sigma=np.ones(n),
        fc_ref_N=rng.uniform(-100, 100, n),
        fc_nominal_mps=np.full(n, 1.8),
        fc_kp=np.full(n, 0.01),
        fc_ki=np.full(n, 0.02),
        fc_vmax_mps=np.full(n, 3.0),
        joint_active=np.ones(n - 1),
        joint_dir=rng.choice([-1.0, 1.0], n - 1),
        joint_ff_N=np.full(n - 1, 200.0),
        joint_kv=np.full(n - 1, 500.0),
        joint_vtarget_mps=np.full(n - 1, 0.3),
        joint_limit_N=np.full(n - 1, 390.0),
        joint_mover=np.minimum(links + rng.integers(0, 2, n - 1), n - 1),
    )


# ------------------------------------------------------ batched runs (test_simulation_driver.py, test_performance.py)


def assert_metrics_close(a, b, rel=1e-3):
    """Summary metrics agree within 0.1 % (with absolute floors for values near zero)."""
    floors = {
        "distance_m": 1e-4,
        "mean_speed_mps": 1e-4,
        "late_speed_mps": 1e-4,
        "mean_slip": 1e-4,
        "max_slip": 1e-4,
        "max_link_force_N": 1e-2,
        "energy_per_m_J": 1e-2,
    }
    for k, floor in floors.items():
        if a[k] is None or b[k] is None:
            assert a[k] is b[k], k
            continue
        assert b[k] == pytest.approx(a[k], rel=rel, abs=floor), k
    fa, fb = np.array(a["final_link_forces_N"]), np.array(b["final_link_forces_N"])
    np.testing.assert_allclose(fb, fa, rtol=rel, atol=1e-2)
    assert a["immobilised"] == b["immobilised"]


# ------------------------------------------------------------------ traverse_patch runs
# (session scope: shared by test_modes_supervisor.py and test_results_energy.py)

UNIFORM = "mode={type: uniform, speed_mps: 1.8, start_time_s: 0.5}"


@pytest.fixture(scope="session")
def traverse():
    """traverse_patch with the supervisor, long enough to leave the patch (~30 s wall time)."""
    sc = load_scenario(SCENARIOS / "traverse_patch.yaml", ["simulation.duration_s=92", "simulation.output_dt_s=0.1"])
    return simulate(sc)


@pytest.fixture(scope="session")
def stuck():
    """The same vehicle and route, rolling only (uniform mode)."""
    sc = load_scenario(
        SCENARIOS / "traverse_patch.yaml", [UNIFORM, "simulation.duration_s=30", "simulation.output_dt_s=0.01"]
    )
    return simulate(sc)


def traverse_raw(**terrain):
    """The traverse_patch scenario as a mapping, its terrain section replaced by ``terrain``."""
    raw = yaml.safe_load((SCENARIOS / "traverse_patch.yaml").read_text())
    raw["terrain"] = terrain
    return raw


@pytest.fixture(scope="session")
def frostyboy():
    """(segment, terrain parameters) of the frostyboy set (ground truth and calibration tests)."""
    from snoworm.studies import groundtruth

    return groundtruth.vehicle_model("frostyboy")


@pytest.fixture(scope="session")
def data():
    """The shipped FrostyBoy field data (paper Table 2)."""
    from snoworm.studies import field_data

    return field_data.read_field_data()
