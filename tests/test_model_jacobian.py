"""Jacobian structure and banded finite differences (snoworm.model.jacobian, docs/model.md section 6)."""

import numpy as np
import pytest

from snoworm.dynamics import Controls
from tests.conftest import TERRAIN_LAWS, busy_controls, model_for, random_state

#: the terrain laws of docs/model.md section 2 with state of their own (shear displacement, sinkage)
STANDSTILL = pytest.mark.parametrize("standstill", list(TERRAIN_LAWS))


@STANDSTILL
@pytest.mark.parametrize(
    "links,force_loop,n",
    [("fixed", False, 6), ("prismatic", False, 6), ("prismatic", True, 5), ("fixed", True, 3), ("fixed", False, 1)],
)
def test_jac_sparsity_covers_finite_difference_jacobian(scenario_path, links, force_loop, n, standstill):
    """An incomplete jac_sparsity stalls BDF/Radau (docs/performance.md): check it covers every non-zero."""
    rng = np.random.default_rng(n)
    m = model_for(
        scenario_path("tow6_uniform"),
        [
            ("vehicle.links.type", links),
            ("vehicle.segments", n),
            ("terrain.profile", [[-5, 0.4], [5, 1.0]]),
            *TERRAIN_LAWS[standstill],
        ],
        force_loop=force_loop,
    )
    assert (m.layout.j is not None) == ("shear" in standstill)
    assert (m.layout.z is not None) == ("sinkage" in standstill)
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


@STANDSTILL
@pytest.mark.parametrize(
    "links,force_loop,n", [("fixed", False, 6), ("prismatic", False, 6), ("prismatic", True, 5), ("fixed", False, 1)]
)
def test_jacobian_banded_matches_column_by_column_differences(scenario_path, links, force_loop, n, standstill):
    """The one-call grouped finite difference equals perturbing one column at a time (same steps)."""
    rng = np.random.default_rng(10 + n)
    m = model_for(
        scenario_path("tow6_uniform"),
        [
            ("vehicle.links.type", links),
            ("vehicle.segments", n),
            ("terrain.profile", [[-5, 0.4], [5, 1.0]]),
            *TERRAIN_LAWS[standstill],
        ],
        force_loop=force_loop,
    )
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
            np.testing.assert_allclose(
                packed[ub + rows - j, j], col[rows], rtol=1e-9, atol=1e-9 * (1 + np.abs(col).max())
            )
            outside = np.setdiff1d(np.arange(m.n_states), rows)
            assert np.all(col[outside] == 0.0), "a non-zero outside the band"
