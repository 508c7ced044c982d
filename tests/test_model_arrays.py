"""The chain's parameter arrays and named state layout (snoworm.model.arrays, docs/model.md section 4)."""

import numpy as np
import pytest

from snoworm.model.arrays import SegmentArrays, StateLayout
from tests.conftest import model_for


def test_layout_fields_follow_the_options():
    assert StateLayout(3, False, False).fields == (
        "x_m",
        "v_mps",
        "omega_front",
        "omega_rear",
        "integral_front_Nm",
        "integral_rear_Nm",
    )
    lay = StateLayout(3, True, True)
    assert lay.fields[-2:] == ("q_mps", "s_m")
    assert (lay.q, lay.s, lay.n_s, lay.size) == (6, 7, 8, 24)
    assert StateLayout(3, False, False).q is None
    assert StateLayout(3, False, False).j is None
    # the shear displacement per axle (terrain.model.standstill: shear) ends the block
    lay = StateLayout(3, True, True, shear=True)
    assert lay.fields[-4:] == ("q_mps", "s_m", "j_front_m", "j_rear_m")
    assert (lay.j, lay.n_s) == (slice(8, 10), 10)
    assert StateLayout(2, False, False, shear=True).j == slice(6, 8)


def test_flat_index_unpack_and_per_state_agree():
    lay = StateLayout(4, False, True, batch_shape=(2,))
    y = np.arange(lay.size, dtype=float)
    Y = lay.unpack(y)
    assert Y.shape == (2, 4, 7)
    # flat_index addresses one chain; the second batch member starts one chain further
    assert Y[0, 2, lay.index["s_m"]] == y[lay.flat_index(2, "s_m")]
    assert Y[1, 2, lay.index["s_m"]] == y[lay.n * lay.n_s + lay.flat_index(2, "s_m")]
    tol = lay.unpack(lay.per_state({f: j for j, f in enumerate(lay.fields)}))
    assert np.array_equal(tol[1, 3], np.arange(lay.n_s))
    assert np.array_equal(lay.get(Y, "v_mps"), Y[..., 1])


def test_segment_arrays_from_list_and_normal_force(scenario_path):
    m = model_for(scenario_path("tow6_uniform"))
    seg = m.seg
    again = SegmentArrays.from_list(
        [type("S", (), {n: getattr(seg, n)[k] for n in SegmentArrays.__dataclass_fields__}) for k in range(m.n)]
    )
    for n in SegmentArrays.__dataclass_fields__:
        assert np.array_equal(getattr(again, n), getattr(seg, n))
    # m g / (2 n_w): half the weight per axle, shared by the axle's wheels
    assert seg.normal_force_N == pytest.approx(seg.mass_kg * seg.gravity_mps2 / (2 * seg.wheels_per_axle), rel=1e-15)


def test_state_layout_named(scenario_path):
    m = model_for(scenario_path("tow6_uniform"))
    assert m.layout.fields[:2] == ("x_m", "v_mps")
    Y = m.unpack(m.initial_state())
    assert np.allclose(np.diff(Y[:, m.layout.index["x_m"]]), -1.5)  # rest spacing, leader in front
