"""Regression references: every shipped scenario against tests/data/reference_summaries.json.

Built to catch a real change of results and never a change of CPU.  Each quantity of
tests/reference_quantities.py must agree with the recorded one to

    max |got - ref| <= K * rtol * scale

where ``rtol`` is the scenario's own solver tolerance (1e-5 for every shipped scenario),
``scale`` the quantity's physical scale (its largest magnitude, or the run's largest force for
forces; floors 0.01 m, 0.01 m/s, 1 J, 10 N) and ``K`` a factor per kind of run:

* ``K_SMOOTH = 0.1`` for runs without gait hand-overs: a change of 1e-6 of a quantity's scale
  fails the test.  Measured across three numeric paths (native AVX-512; an AVX2 CPU emulated with
  ``OPENBLAS_CORETYPE=Haswell``, an x86-64-v2 CPU with ``OPENBLAS_CORETYPE=Nehalem`` and the
  matching ``NPY_DISABLE_CPU_FEATURES``), these runs differ by at most 1.7e-3 of ``rtol * scale``
  (60x margin): they take the same steps on every CPU.
* ``K_GAIT = 10`` for gait runs (inchworm, supervisor), whose 18-290 state events let the last
  bits of a sum change the step sequence: across the same three paths they differ by up to 2.7
  ``rtol * scale`` (inchworm2 nfev 5 776 / 5 851 / 6 033), so a change of 1e-4 of a quantity's
  scale fails the test (a margin of 3.7 or more over what a CPU change does).  Their end values
  are replaced by last-window averages (see tests/reference_quantities.py).
* Runs whose X_t varies along the track (``KINKED``: a profile table crossed by the axles, whose
  breakpoints are kinks of the right-hand side) also take ``K_GAIT``: ramp_drift (a route file)
  differs by 0.16 ``rtol * scale`` on the x86-64-v2 path (distance, 1.56e-6 of scale; nfev 3653 /
  3680), while the same route with a constant X_t differs by 3e-3.  Raising b_trF or b_tF by
  0.1 % still moves it by 7-9e-4 of scale, 7x the limit (measured once, not a committed test).

It still catches a model change: raising the Eq. 3 resistance coefficient b_trF (or the Eq. 2
coefficient b_tF) of the frostyboy parameter set by 0.1 % fails all 15 scenarios (measured once
by editing snoworm/params.py; not a committed test).

Solver work is held to a band, not equality: nfev and njev within ``WORK_BAND`` of the recorded
counts (the three paths differ by up to 9 %), gait intervals within one, output samples within
two.  A deliberate numerical change (model, solver settings, scenario values) re-records the
file (``python benchmarks/record_references.py summaries``) and says why in its commit.
"""

import json
from pathlib import Path

import pytest

from tests.conftest import SCENARIOS, shipped_result
from tests.reference_quantities import COUNTS, SCALES, compared, is_gait, quantities, scaled_error

REFERENCE = json.loads((Path(__file__).parent / "data" / "reference_summaries.json").read_text())
SHIPPED = sorted(p.stem for p in SCENARIOS.glob("*.yaml"))
SLOW = {"traverse_patch"}  # ~10 s: marked slow, still run by default
K_SMOOTH, K_GAIT = 0.1, 10.0


def kinked(scenario) -> bool:
    """Whether the axles cross breakpoints of an X_t table (the right-hand side has kinks there)."""
    return not scenario.terrain.compile().is_constant


WORK_BAND = (0.8, 1.25)


def test_every_shipped_scenario_has_a_reference():
    assert sorted(REFERENCE) == SHIPPED
    for name, ref in REFERENCE.items():
        assert set(SCALES) | set(COUNTS) <= set(ref), name


def work_outside_band(got: dict, ref: dict) -> dict:
    """The counts of ``got`` outside their band around ``ref``: ``{name: (got, ref)}``."""
    bad = {
        k: (got[k], ref[k]) for k in ("nfev", "njev") if not WORK_BAND[0] * ref[k] <= got[k] <= WORK_BAND[1] * ref[k]
    }
    bad.update({k: (got[k], ref[k]) for k, slack in (("intervals", 1), ("n_t", 2)) if abs(got[k] - ref[k]) > slack})
    return bad


def test_the_checks_can_fail():
    ref = {
        "distance_m": 2.0,
        "max_abs_link_force_N": 400.0,
        "mean_link_force_N": [0.5, -0.5],
        "nfev": 1000,
        "njev": 100,
        "intervals": 50,
        "n_t": 1549,
    }
    assert scaled_error({"distance_m": 2.0 + 2e-5}, ref, "distance_m") == pytest.approx(1e-5)
    assert scaled_error({"mean_link_force_N": [0.5, -0.1]}, ref, "mean_link_force_N") == pytest.approx(1e-3)
    assert work_outside_band(dict(ref), ref) == {}
    assert set(work_outside_band(dict(ref, nfev=1300, intervals=52), ref)) == {"nfev", "intervals"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in SHIPPED])
def test_summary_matches_reference(name):
    ref, res = REFERENCE[name], shipped_result(name)
    got, gait = quantities(res), is_gait(res.scenario)
    tol = (K_GAIT if gait or kinked(res.scenario) else K_SMOOTH) * res.scenario.simulation.rtol
    errors = {k: scaled_error(got, ref, k) for k in compared(gait)}
    bad = {k: f"{e:.2e}" for k, e in errors.items() if e > tol}
    assert not bad, f"{name}: changed by more than {tol:.1e} of their scale: {bad}"
    assert not work_outside_band(got, ref), (
        f"{name}: solver work outside its band (got, reference): {work_outside_band(got, ref)}"
    )
