"""Slip-sinkage (``terrain.model.sinkage: slip``, docs/model.md section 2, "Slip-sinkage") against
hand computations: the law's fixed point, the steady states below its onset, and a wheel that digs
itself in above it (issue 32: "climbing" at high slip, where a real wheel sinks).
"""

import numpy as np
import pytest

from snoworm import load_scenario, simulate, steady, terrain


def scenario(xt, **model):
    over = [("terrain.model.sinkage", "slip"), ("terrain.xt", xt), ("simulation.duration_s", 60.0)]
    return load_scenario("frostyboy_case5", over + [(f"terrain.model.{k}", v) for k, v in model.items()])


def hand_fixed_point(wheel_mps, V, i, p):
    """z at which dz/dt = 0, by hand: a (1 - z / z_max) = z b with a the digging, b the relaxation rate."""
    a = p.sinkage_rate * abs(wheel_mps - V) * max(abs(i) - p.sinkage_onset_slip, 0.0)
    b = abs(V) / p.sinkage_relax_length_m
    return a / (b + a / p.sinkage_max_m)


def test_the_law_by_hand():
    p = scenario(0.65).terrain.model.params()
    # below the onset a rolling wheel keeps no sinkage and leaves a rut behind at |V| / L_relax
    assert terrain.sinkage_rate(1.8, 1.5, 0.2, 0.0, p) == 0.0
    assert terrain.sinkage_rate(1.8, 1.5, 0.2, 0.05, p) == pytest.approx(-0.05 * 1.5 / p.sinkage_relax_length_m)
    # a wheel spinning in place (V = 0) digs until z_max, and never beyond it
    assert terrain.sinkage_rate(1.8, 0.0, 1.0, p.sinkage_max_m, p) == 0.0
    rate0 = p.sinkage_rate * 1.8 * (1.0 - p.sinkage_onset_slip)
    assert terrain.sinkage_rate(1.8, 0.0, 1.0, 0.0, p) == pytest.approx(rate0, rel=1e-14)
    for wheel, V, i in [(1.8, 1.0, 0.444), (1.6, 0.2, 0.875), (1.0, 0.5, 0.5)]:
        z = hand_fixed_point(wheel, V, i, p)
        assert terrain.sinkage_rate(wheel, V, i, z, p) == pytest.approx(0.0, abs=1e-15)
    assert terrain.sinkage_resistance_factor(p.sinkage_ref_m, p) == 2.0


def test_below_the_onset_the_steady_state_is_unchanged():
    """Table 2 case 5 (X_t 0.65, 30 % slip, below the 35 % onset): the run with slip-sinkage ends at
    snoworm.steady's slip and speed without any sinkage."""
    sc = scenario(0.65)
    r = simulate(sc)
    ss = steady.steady_state(0.65, sc.vehicle.segment, sc.terrain.model.params(), wheel_speed_mps=1.58)
    assert r.segments["slip"][-1, 0] == pytest.approx(ss.slip, abs=1e-4)
    assert r.segments["v_mps"][-1, 0] == pytest.approx(ss.ground_speed_mps, rel=1e-4)
    assert abs(r.segments["sinkage_m"][-1, 0]) < 1e-6


def test_above_the_onset_a_wheel_digs_itself_in():
    """On X_t 0.62 the start from rest passes the onset, the resistance grows with the sinkage
    and the segment stops dug in: the final sinkage is the law's fixed point at the final wheel and
    ground speeds, and the resistance is Eq. 3 raised by 1 + z / z_ref (both by hand).  Without
    the law the same segment rolls on."""
    sc = scenario(0.62)
    p = sc.terrain.model.params()
    r = simulate(sc)
    seg = r.segments
    V, wheel, i, z = (seg[k][-1, 0] for k in ("v_mps", "wheel_speed_mps", "slip", "sinkage_m"))
    assert V < 0.01 and i > 0.99
    assert z == pytest.approx(hand_fixed_point(wheel, V, i, p), rel=1e-3)
    F_n = sc.vehicle.segment.mass_kg * sc.vehicle.segment.gravity_mps2 / 4
    hand_F_tr = 4 * p.b_trF * F_n * np.tanh(V / p.sign_eps_mps) / 0.62**p.A * (1 + z / p.sinkage_ref_m)
    assert seg["resistance_N"][-1, 0] == pytest.approx(hand_F_tr, rel=1e-3)
    free = simulate(sc.with_({"terrain.model.sinkage": "off"}))
    assert free.segments["v_mps"][-1, 0] > 0.5 and np.all(free.segments["sinkage_m"] == 0.0)


def test_the_verdict_calls_a_dug_in_segment_immobilised_when_its_sinkage_passes_the_limit():
    """The verdict's default sinkage limit with the law on is 0.9 x ``sinkage_max_m`` (the law
    approaches the maximum only asymptotically); the dug-in segment of the test above passes it,
    and the verdict's time is the first output time at which the sinkage reached it (or an earlier
    slip stall).  With the law off the limit is not judged."""
    from snoworm.results.verdict import SINKAGE_LIMIT_FRACTION, criteria_of

    sc = scenario(0.62)
    limit = SINKAGE_LIMIT_FRACTION * sc.terrain.model.sinkage_max_m
    assert criteria_of(sc).sinkage_m == pytest.approx(limit)
    assert criteria_of(sc.with_({"terrain.model.sinkage": "off"})).sinkage_m is None
    r = simulate(sc)
    v = r.verdict()
    z = r.segments["sinkage_m"][:, 0]
    first_sunk = r.t[np.flatnonzero(z >= limit)[0]]
    assert v.status == "immobilised"
    assert v.t_s <= first_sunk + 1e-12
    if v.cause == "sinkage":
        assert v.t_s == pytest.approx(first_sunk)
