"""The float kernel (snoworm.model.floatkernel) against the NumPy kernel it is generated from.

Both evaluate the same law code: the float kernel is traced from ``ChainModel.evaluate``.  They
differ only by rounding (the float kernel uses :mod:`math` where NumPy uses its own elementwise
functions), so they are compared to 1e-10 relative: each derivative against the largest
magnitude of the same field over the chain and the states compared (a wheel's acceleration
that cancels to ~1e-7 rad/s^2 at a steady state, from torques of tens of newton-metres, is
compared at the scale of wheel accelerations, not at its own).
"""

import functools
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from snoworm import load_scenario, simulate
from snoworm.dynamics import ChainModel, Controls
from snoworm.model import floatkernel
from snoworm.model.floatkernel import MAX_SEGMENTS, FloatKernel
from snoworm.simulation.driver import chain_model
from tests.conftest import SCENARIOS, TERRAIN_LAWS, busy_controls, model_for, random_state

SHIPPED = sorted(p.stem for p in SCENARIOS.glob("*.yaml"))
REL = 1e-10


def numpy_rhs(m, y, ctl):
    return m.evaluate(m.unpack(y), ctl)[0].reshape(-1)


def scaled_difference(m, a, b):
    """max |a - b| / (largest |b| of the same field over the chain and the states), over every derivative.

    ``a``, ``b``: one flat derivative each, or a list of them (states compared together)."""
    A = np.stack([m.unpack(x) for x in (a if isinstance(a, list) else [a])])
    B = np.stack([m.unpack(x) for x in (b if isinstance(b, list) else [b])])
    scale = np.maximum(np.max(np.abs(B), axis=(0, 1), keepdims=True), 1e-300)
    return float(np.max(np.abs(A - B) / scale))


@functools.cache
def recorded(name):
    """The controls a shipped scenario's run used (each distinct object once) and states met on the way."""
    sc = load_scenario(SCENARIOS / f"{name}.yaml")
    seen, states, calls = {}, [], [0]
    call = FloatKernel.__call__

    def spy(self, y, ctl):
        seen.setdefault(id(ctl), ctl)
        calls[0] += 1
        if calls[0] % 23 == 1 and len(states) < 400:
            states.append(np.array(y))
        return call(self, y, ctl)

    FloatKernel.__call__ = spy
    try:
        simulate(sc)
    finally:
        FloatKernel.__call__ = call
    return sc, list(seen.values()), states


def states_along_track(m, rng, k):
    """``k`` random states; with an X_t profile the chain is moved along the whole table."""
    prof = m.profile
    out = []
    for _ in range(k):
        y = random_state(m, rng)
        Y = m.unpack(y)
        elev = m.elevation
        table = prof.positions_m if not prof.is_constant else (elev.positions_m if elev is not None else ())
        if len(table):
            Y[:, m.layout.x] += rng.uniform(table[0] - 5.0, min(table[-1], table[0] + 1e3) + 5.0)
        out.append(y)
    return out


@pytest.mark.parametrize("name", SHIPPED)
def test_float_kernel_equals_the_numpy_kernel_on_every_shipped_scenario(name):
    sc, controls, states = recorded(name)
    m = chain_model(sc)
    assert m.float_kernel is not None and controls and states
    rng = np.random.default_rng(11)
    fk = FloatKernel(m)
    got, want = [], []
    for j, ctl in enumerate(controls[:: max(1, len(controls) // 25)]):
        ys = [states[(7 * j + i) % len(states)] for i in range(3)] + states_along_track(m, rng, 3)
        got += [fk(y, ctl) for y in ys]
        want += [numpy_rhs(m, y, ctl) for y in ys]
    worst = scaled_difference(m, got, want)
    assert worst <= REL, f"{name}: float kernel {worst:.2e} from the NumPy kernel"
    assert fk._by_key  # run on generated code (made here or shared)


GRADES = [
    [],
    [("terrain.grade_deg", 8.0)],
    [
        ("terrain.elevation", [[-20.0, 0.0], [0.0, 0.0], [10.0, 1.5], [12.0, 1.6], [30.0, 0.5]]),
        ("terrain.patches", [{"start_m": 2.0, "end_m": 9.0, "xt": 0.4, "ramp_m": 0.5}]),
    ],
]


@pytest.mark.parametrize("standstill", list(TERRAIN_LAWS))
@pytest.mark.parametrize("grade", GRADES, ids=["level", "constant grade", "elevation table and patch"])
def test_every_branch_of_the_kernel_on_busy_controls(grade, standstill):
    """Force loops, free joints in force and length command, direct torques, motors off, on level
    ground, a constant grade and an elevation table (gravity and normal loads, docs/model.md
    section 7) with an X_t patch, with either law of the slip near rest and with or without
    slip-sinkage (state fields of their own, docs/model.md section 2): both paths agree."""
    rng = np.random.default_rng(5)
    law = TERRAIN_LAWS[standstill]
    for overrides in ([("vehicle.links.type", "prismatic")] + grade + law, grade + law):
        m = model_for(SCENARIOS / "tow6_uniform.yaml", overrides, force_loop=True)
        assert (m.layout.j is not None) == ("shear" in standstill)
        assert (m.layout.z is not None) == ("sinkage" in standstill)
        for k in range(20):
            ctl = busy_controls(m, rng)
            n = m.n
            if k % 2:
                ctl = ctl.with_(
                    joint_length_mode=rng.integers(0, 2, n - 1).astype(float),
                    joint_sref_m=rng.uniform(0.0, 0.3, n - 1),
                    joint_ka=np.full(n - 1, 800.0),
                    joint_anchor=np.arange(1, n),
                )
            if k % 3 == 0:
                ctl = ctl.with_(
                    torque_active=rng.integers(0, 2, n).astype(float),
                    torque_cmd_Nm=rng.uniform(-30, 30, n),
                    motor_on=rng.integers(0, 2, n).astype(float),
                )
            y = states_along_track(m, rng, 1)[0]
            assert scaled_difference(m, m.float_kernel(y, ctl), numpy_rhs(m, y, ctl)) <= REL


def test_one_generated_function_per_structure_of_controls():
    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    rng = np.random.default_rng(2)
    y = random_state(m, rng)
    for _ in range(5):  # new set-points, same structure: no new code
        ctl = Controls.rolling(m.n, np.ones(m.n), rng.uniform(0, 2, m.n))
        assert scaled_difference(m, m.float_kernel(y, ctl), numpy_rhs(m, y, ctl)) <= REL
    assert len(m.float_kernel._by_key) == 1
    # motors off (a settle before the start): the same code, which always applies the on/off mask
    off = Controls.rolling(m.n, np.r_[0.0, np.ones(m.n - 1)], np.ones(m.n))
    assert scaled_difference(m, m.float_kernel(y, off), numpy_rhs(m, y, off)) <= REL
    assert len(m.float_kernel._by_key) == 1
    # a structural change (a motor on direct torque): new code
    direct = replace(off, torque_active=np.r_[1.0, np.zeros(m.n - 1)], torque_cmd_Nm=np.r_[3.0, np.zeros(m.n - 1)])
    assert scaled_difference(m, m.float_kernel(y, direct), numpy_rhs(m, y, direct)) <= REL
    assert len(m.float_kernel._by_key) == 2


def test_models_differing_in_parameters_share_the_generated_code():
    """A sweep's cases (other X_t, tow, masses) run the same generated code with their own parameters."""
    rng = np.random.default_rng(8)
    ms = [
        model_for(
            SCENARIOS / "inchworm6.yaml", [("terrain.xt", xt), ("tow.force_N", f), ("vehicle.segment.mass_kg", mk)]
        )
        for xt, f, mk in ((0.25, 0.0, 60.0), (0.31, 90.0, 75.0))
    ]
    ctl = busy_controls(ms[0], rng)
    y = random_state(ms[0], rng)
    fs = [m.float_kernel.function(ctl)[0] for m in ms]
    assert fs[0] is not fs[1] and fs[0].__code__ is fs[1].__code__  # one code, two parameter sets
    assert ms[0].float_kernel.generated + ms[1].float_kernel.generated <= 1
    for m in ms:
        assert scaled_difference(m, m.float_kernel(y, ctl), numpy_rhs(m, y, ctl)) <= REL
    assert scaled_difference(ms[0], ms[0].float_kernel(y, ctl), ms[1].float_kernel(y, ctl)) > 1e-3


def test_a_changed_law_reaches_both_paths(monkeypatch):
    """Change a law function and a law constant: the NumPy kernel and the float kernel both move, together."""
    from snoworm import feedback, terrain

    m0 = model_for(SCENARIOS / "inchworm6.yaml")
    rng = np.random.default_rng(4)
    y = random_state(m0, rng)
    ctl = busy_controls(m0, rng)
    smooth = terrain.smooth_sign
    monkeypatch.setattr(terrain, "smooth_sign", lambda u, scale: smooth(u, 3.0 * scale))
    monkeypatch.setattr(feedback, "K_LENGTH", 7.0)
    ctl = ctl.with_(joint_length_mode=np.ones(m0.n - 1), joint_sref_m=np.full(m0.n - 1, 0.05))
    m = ChainModel(m0.seg, m0.links, m0.tp, m0.profile, m0.tow_force_N)
    new_np, new_float = numpy_rhs(m, y, ctl), m.float_kernel(y, ctl)
    monkeypatch.undo()
    m_old = ChainModel(m0.seg, m0.links, m0.tp, m0.profile, m0.tow_force_N)
    old_np, old_float = numpy_rhs(m_old, y, ctl), m_old.float_kernel(y, ctl)
    assert scaled_difference(m, new_float, new_np) <= REL
    assert scaled_difference(m, old_float, old_np) <= REL
    assert scaled_difference(m, new_np, old_np) > 1e-3  # the change moved the NumPy kernel ...
    assert scaled_difference(m, new_float, old_float) > 1e-3  # ... and the float kernel
    s = m.layout.s
    assert not np.allclose(m.unpack(new_float)[:-1, s], m.unpack(old_float)[:-1, s])  # K_LENGTH: the joints


def test_long_chains_and_stacks_keep_the_numpy_kernel():
    m = model_for(SCENARIOS / "tow6_uniform.yaml", [("vehicle.segments", MAX_SEGMENTS + 1)])
    assert m.float_kernel is None
    short = model_for(SCENARIOS / "tow6_uniform.yaml")
    assert ChainModel.stack([short, short]).float_kernel is None


def test_a_branch_on_a_state_cannot_be_traced():
    """The trace refuses kernel code it cannot turn into float code (instead of freezing one branch)."""
    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    ctl = Controls.rolling(m.n, np.ones(m.n), np.ones(m.n))
    orig = m.evaluate

    def branching(Y, c, outputs=False, cd=None):
        if np.any(Y[..., 0] > 0):
            pass
        return orig(Y, c, outputs, cd)

    m.evaluate = branching
    with pytest.raises(TypeError):
        floatkernel.generate(m, ctl)


def test_a_model_with_generated_code_pickles_for_worker_processes():
    """Sweeps and the paper send models to worker processes: the generated closures stay behind
    and the copy generates (or reuses) its own."""
    import pickle

    m = model_for(SCENARIOS / "inchworm6.yaml")
    rng = np.random.default_rng(6)
    ctl, y = busy_controls(m, rng), random_state(m, rng)
    before = m.float_kernel(y, ctl)
    m2 = pickle.loads(pickle.dumps(m))
    assert m2.float_kernel.model is m2 and not m2.float_kernel._by_key
    np.testing.assert_array_equal(m2.float_kernel(y, ctl), before)  # the same code on the same numbers


# ------------------------------------------------------------------ the cache key holds every value the code holds
_GROUNDS = st.sampled_from(["level", "grade", "table", "patches"])


@st.composite
def same_structure_pair(draw):
    """Two models of one structure (segment count, ground kind, table lengths, links, force loop)
    that differ in values: X_t (constant or patches), grade or elevations, tow, mass, wheel radius."""
    force_loop, prismatic = draw(st.booleans()), draw(st.booleans())
    n = draw(st.integers(2, 8))
    ground = draw(_GROUNDS)
    patch_xt = draw(st.booleans())

    f = st.floats
    ranges = {
        "terrain.xt": f(0.2, 1.0),
        "tow.force_N": f(0.0, 300.0),
        "vehicle.segment.mass_kg": f(40.0, 90.0),
        "vehicle.segment.wheel_radius_m": f(0.15, 0.3),
        "grade": f(-15.0, 15.0).filter(lambda g: abs(g) > 0.1),
        "elevation_m": f(-60.0, 60.0),
        "patch_grade": f(-12.0, 12.0),
        "patch_xt": f(0.2, 1.0),
    }
    # each value is either the same in both models or drawn for each: a value left out of the key
    # shows only when the models agree on everything the key holds and differ in that value
    shared = {k: draw(s) for k, s in ranges.items()}
    varies = draw(st.sets(st.sampled_from(sorted(ranges)), min_size=1))

    def one():
        v = {k: draw(ranges[k]) if k in varies else shared[k] for k in ranges}
        ov = [
            (k, v[k])
            for k in ("terrain.xt", "tow.force_N", "vehicle.segment.mass_kg", "vehicle.segment.wheel_radius_m")
        ]
        ov.append(("vehicle.segments", n))
        if prismatic:
            ov.append(("vehicle.links.type", "prismatic"))
        if ground == "grade":
            ov.append(("terrain.grade_deg", v["grade"]))
        elif ground == "table":
            ov.append(("terrain.elevation", [[-100.0, 0.0], [3.0, 0.0], [600.0, v["elevation_m"]]]))
        elif ground == "patches":
            ov.append(("terrain.grade_deg", 0.0))
            ov.append(("terrain.grade_patches", [{"start_m": 1.0, "end_m": 20.0, "grade_deg": v["patch_grade"]}]))
        if patch_xt:
            ov.append(("terrain.patches", [{"start_m": 2.0, "end_m": 9.0, "xt": v["patch_xt"], "ramp_m": 0.5}]))
        return ov

    return force_loop, one(), one()


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(same_structure_pair(), st.integers(0, 2**32 - 1))
def test_generated_code_holds_no_value_outside_its_key(pair, seed):
    """The class of defect behind a sweep over X_t on an elevation table returning its first case
    for every case: a model's value traced into generated code as a literal while the code is
    shared by every model with the same key.  For two models of one structure: the same key
    implies the same source text (no model's value in it), and the second model, run on the code
    the first one generated, equals its own NumPy kernel."""
    force_loop, ov_a, ov_b = pair
    ms = [model_for(SCENARIOS / "tow6_uniform.yaml", ov, force_loop=force_loop) for ov in (ov_a, ov_b)]
    rng = np.random.default_rng(seed)
    ctl = busy_controls(ms[0], rng)
    sigs = [floatkernel.model_parameters(m)[1] for m in ms]
    if sigs[0] == sigs[1]:
        assert floatkernel.generate(ms[0], ctl) == floatkernel.generate(ms[1], ctl)
    for m in ms:  # in this order: the second runs on the code the first one generated (when shared)
        for y in states_along_track(m, rng, 3):
            assert scaled_difference(m, m.float_kernel(y, ctl), numpy_rhs(m, y, ctl)) <= REL


def test_the_x_t_of_a_route_with_an_elevation_table_is_a_parameter():
    """The reported case: constant X_t on an elevation table, three X_t, one process (on 8ca4e02
    the three models shared code holding the first X_t as a literal)."""
    elev = ("terrain.elevation", [[-100.0, 0.0], [3.0, 0.0], [600.0, 52.03]])
    ms = [model_for(SCENARIOS / "tow6_uniform.yaml", [("terrain.xt", xt), elev]) for xt in (0.7, 0.8, 1.0)]
    assert len({floatkernel.model_parameters(m)[1] for m in ms}) == 1  # one key: one generated code ...
    ctl = Controls.rolling(ms[0].n, np.ones(ms[0].n), np.full(ms[0].n, 1.5))
    y = random_state(ms[0], np.random.default_rng(3))  # moving: X_t acts on traction and resistance
    outs = [m.float_kernel(y, ctl) for m in ms]
    for m, out in zip(ms, outs):  # ... that reads each model's own X_t
        assert scaled_difference(m, out, numpy_rhs(m, y, ctl)) <= REL
    assert sum(m.float_kernel.generated for m in ms) <= 1


def test_the_process_wide_cache_of_generated_code_is_bounded(monkeypatch):
    monkeypatch.setattr(floatkernel, "SHARED_MAX", 2)
    monkeypatch.setattr(floatkernel, "_SHARED", type(floatkernel._SHARED)())
    for n in (2, 3, 4, 5):
        m = model_for(SCENARIOS / "tow6_uniform.yaml", [("vehicle.segments", n)])
        m.float_kernel(m.initial_state(), Controls.rolling(n, np.ones(n), np.ones(n)))
    assert len(floatkernel._SHARED) == 2


def test_an_attribute_the_walk_cannot_classify_is_refused():
    """A model attribute that is neither a parameter nor keyed would be traced as a literal: refused."""
    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    m.mystery = object()
    with pytest.raises(TypeError, match="mystery"):
        floatkernel.model_parameters(m)
