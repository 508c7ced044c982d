"""Chain kernel invariants: momentum of internal forces, Jacobian pattern coverage."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from snoworm.dynamics import Controls
from snoworm.scenario import apply_overrides, read_yaml, scenario_from_dict
from tests.conftest import SCENARIOS


def model_for(path, overrides=(), force_loop=None):
    sc = scenario_from_dict(apply_overrides(read_yaml(path), overrides))
    m = sc.chain_model
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
    return Y.reshape(-1)


def busy_controls(m, rng):
    n = m.n
    c = Controls.rolling(n, np.ones(n), rng.uniform(0, 2, n))
    links = np.arange(n - 1)
    return c.with_(fc_active=np.r_[np.ones(n - 1), 0.0], fc_link=np.r_[links, n - 1], fc_sigma=np.ones(n),
                   fc_ref_N=rng.uniform(-100, 100, n), fc_nominal_mps=np.full(n, 1.8), fc_kp=np.full(n, 0.01),
                   fc_ki=np.full(n, 0.02), fc_vmax_mps=np.full(n, 3.0),
                   joint_active=np.ones(n - 1), joint_dir=rng.choice([-1.0, 1.0], n - 1),
                   joint_ff_N=np.full(n - 1, 200.0), joint_kv=np.full(n - 1, 500.0),
                   joint_vtarget_mps=np.full(n - 1, 0.3), joint_limit_N=np.full(n - 1, 390.0),
                   joint_mover=np.minimum(links + rng.integers(0, 2, n - 1), n - 1))


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000))
def test_internal_link_forces_cancel(seed):
    """Links only move momentum between segments: sum of connector forces = -tow (MODEL.md section 4)."""
    rng = np.random.default_rng(seed)
    m = model_for(SCENARIOS / "tow6_uniform.yaml", [("vehicle.links.type", "prismatic")], force_loop=True)
    Y = m.unpack(random_state(m, rng))
    _, out = m.evaluate(Y, busy_controls(m, rng), outputs=True)
    assert out["link_net_N"].sum() == pytest.approx(-m.tow_force_N, abs=1e-9 * (1 + np.abs(out["link_force_N"]).sum()))


@pytest.mark.parametrize("links,force_loop,n", [("fixed", False, 6), ("prismatic", False, 6),
                                                 ("prismatic", True, 5), ("fixed", True, 3), ("fixed", False, 1)])
def test_jac_sparsity_covers_finite_difference_jacobian(scenario_path, links, force_loop, n):
    """An incomplete jac_sparsity stalls BDF/Radau (PERFORMANCE.md): check it covers every non-zero."""
    rng = np.random.default_rng(n)
    m = model_for(scenario_path("tow6_uniform"), [("vehicle.links.type", links), ("vehicle.segments", n),
                                                  ("terrain.profile", [[-5, 0.4], [5, 1.0]])],
                  force_loop=force_loop)
    P = m.jac_sparsity()
    for _ in range(5):
        y = random_state(m, rng)
        ctl = busy_controls(m, rng) if n > 1 else Controls.rolling(1, [1.0], [1.0])
        f0 = m.rhs(0.0, y, ctl)
        for j in range(m.n_states):
            h = 1e-6 * max(1.0, abs(y[j]))
            yp = y.copy()
            yp[j] += h
            col = (m.rhs(0.0, yp, ctl) - f0) / h
            missing = np.nonzero((np.abs(col) > 1e-8) & ~P[:, j])[0]
            assert missing.size == 0, f"d f[{missing}] / d y[{j}] non-zero but not in the pattern"
    lb, ub = m.bandwidths()
    assert lb < m.layout.n_s * 2 + 2 and ub < m.layout.n_s * 2 + 2


def test_state_layout_named(scenario_path):
    m = model_for(scenario_path("tow6_uniform"))
    assert m.layout.fields[:2] == ("x_m", "v_mps")
    Y = m.unpack(m.initial_state())
    assert np.allclose(np.diff(Y[:, m.layout.index["x_m"]]), -1.5)   # rest spacing, leader in front


@pytest.mark.parametrize("links,force_loop,n", [("fixed", False, 6), ("prismatic", False, 6),
                                                 ("prismatic", True, 5), ("fixed", False, 1)])
def test_jacobian_banded_matches_column_by_column_differences(scenario_path, links, force_loop, n):
    """The one-call grouped finite difference equals perturbing one column at a time (same steps)."""
    rng = np.random.default_rng(10 + n)
    m = model_for(scenario_path("tow6_uniform"), [("vehicle.links.type", links), ("vehicle.segments", n),
                                                  ("terrain.profile", [[-5, 0.4], [5, 1.0]])],
                  force_loop=force_loop)
    lb, ub = m.bandwidths()
    for _ in range(3):
        y = random_state(m, rng)
        ctl = busy_controls(m, rng) if n > 1 else Controls.rolling(1, [1.0], [1.0])
        packed = m.jacobian_banded(0.0, y, ctl)
        f0 = m.rhs(0.0, y, ctl)
        for j in range(m.n_states):
            yp = y.copy()
            yp[j] += 1.2e-4 * max(1e-3, abs(y[j]))
            col = (m.rhs(0.0, yp, ctl) - f0) / (yp[j] - y[j])
            rows = np.arange(max(0, j - ub), min(m.n_states, j + lb + 1))
            np.testing.assert_allclose(packed[ub + rows - j, j], col[rows], rtol=1e-9,
                                       atol=1e-9 * (1 + np.abs(col).max()))
            outside = np.setdiff1d(np.arange(m.n_states), rows)
            assert np.all(col[outside] == 0.0), "a non-zero outside the band"


def test_stacked_model_is_the_members_side_by_side(scenario_path):
    """ChainModel.stack: same derivatives and block-banded Jacobian as each member alone."""
    from snoworm.dynamics import ChainModel
    rng = np.random.default_rng(3)
    ms = [model_for(scenario_path("tow6_uniform"), [("terrain.xt", xt), ("tow.force_N", f)])
          for xt, f in [(0.7, 0.0), (0.9, 200.0), (1.0, 50.0)]]
    big = ChainModel.stack(ms)
    ys = [random_state(m, rng) for m in ms]
    ctls = [Controls.rolling(6, np.ones(6), rng.uniform(0, 2, 6)) for _ in ms]
    ctl = Controls.stack(ctls)
    f = big.rhs(0.0, np.concatenate(ys), ctl).reshape(3, -1)
    J = big.jacobian_banded(0.0, np.concatenate(ys), ctl)
    n = ms[0].n_states
    for b, m in enumerate(ms):
        np.testing.assert_array_equal(f[b], m.rhs(0.0, ys[b], ctls[b]))
        np.testing.assert_allclose(J[:, b * n:(b + 1) * n], m.jacobian_banded(0.0, ys[b], ctls[b]),
                                   rtol=1e-7, atol=1e-6)
    assert big.bandwidths() == ms[0].bandwidths()
