"""Regression references for refactors: every shipped scenario against tests/data/reference_summaries.json.

The file was recorded from main before the restructuring into layers (issue #12), which changed
no number.  A refactor must reproduce it: float results within 1e-9 relative (1e-12 absolute
floor), solver counts and output sizes exactly.  A deliberate numerical change (model, solver
settings, scenario values) must re-record the file and say so, with the reason, in its commit.
"""
import json
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import SCENARIOS, shipped_result

REFERENCE = json.loads((Path(__file__).parent / "data" / "reference_summaries.json").read_text())
SHIPPED = sorted(p.stem for p in SCENARIOS.glob("*.yaml"))
SLOW = {"traverse_patch"}          # ~15 s: marked slow, still run by default
RTOL, ATOL = 1e-9, 1e-12
FLOATS = ("final_link_forces_N", "final_net_forces_N", "final_speed_mps", "distance_m", "total_energy_J", "x_last")
EXACT = ("nfev", "njev", "intervals", "n_t")


def summary_of(res) -> dict:
    s = res.summary()
    return {"final_link_forces_N": s["final_link_forces_N"], "final_net_forces_N": s["final_net_forces_N"],
            "final_speed_mps": s["final_speed_mps"], "distance_m": s["distance_m"],
            "total_energy_J": s["energy"]["total_J"], "x_last": res.segments["x_m"][-1].tolist(),
            "nfev": s["solver"]["nfev"], "njev": s["solver"]["njev"], "intervals": s["solver"]["intervals"],
            "n_t": int(res.t.size)}


def test_every_shipped_scenario_has_a_reference():
    assert sorted(REFERENCE) == SHIPPED
    for name, ref in REFERENCE.items():
        assert set(ref) == set(FLOATS) | set(EXACT), name


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in SHIPPED])
def test_summary_matches_reference(name):
    ref = REFERENCE[name]
    got = summary_of(shipped_result(name))
    for key in EXACT:
        assert got[key] == ref[key], f"{name}: {key} {got[key]} != reference {ref[key]}"
    for key in FLOATS:
        a, b = np.atleast_1d(np.asarray(got[key], float)), np.atleast_1d(np.asarray(ref[key], float))
        assert a.shape == b.shape, f"{name}: {key} shape {a.shape} != reference {b.shape}"
        np.testing.assert_allclose(a, b, rtol=RTOL, atol=ATOL, err_msg=f"{name}: {key}")
