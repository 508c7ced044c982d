"""Ground truth of the model: paper Table 2 and Figure 3 (MODEL.md sections 2-3), calibration, CLI.

Tolerances are stated next to each comparison.  Numbers quoted from MODEL.md are the default
model (d = 2); the literal reading d = 1 is tested for its documented failure.
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from snoworm import calibrate as cal
from snoworm import groundtruth as gt
from snoworm import steady
from snoworm.cli import main
from snoworm.scenario import load_scenario
from snoworm.schema import ScenarioError
from snoworm import simulate

ROOT = Path(__file__).resolve().parents[1]
CASES = ("1", "2", "3", "4", "5")
# MODEL.md section 3: the default model at the Table 2 wheel speeds
MODEL_TORQUE_NM = (10.0, 27.0, 30.0, 31.9, 45.0)
MODEL_SLIP_PCT = (2.1, 6.3, 7.8, 9.3, 30.4)
HEADER = "case,surface,speed_mps,wheel_speed_mps,slip,torque_Nm,drawbar_N,xt"


@pytest.fixture(scope="module")
def frostyboy():
    return gt.vehicle_model("frostyboy")


@pytest.fixture(scope="module")
def data():
    return gt.read_field_data()


@pytest.fixture(scope="module")
def rows(data, frostyboy):
    return gt.compare_table2(data, *frostyboy)


# ------------------------------------------------------------------------------- field data

def test_shipped_data_is_table2(data):
    assert data.case == CASES
    np.testing.assert_allclose(data.speed_mps, [2.5, 1.23, 1.98, 1.84, 1.11], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.wheel_speed_mps, [2.66, 1.28, 2.05, 1.93, 1.58], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.slip, [0.06, 0.039, 0.034, 0.047, 0.30], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.torque_Nm, [10, 27, 30, 32.8, 45], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.drawbar_N, [0, 0, 0, 28.8, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.xt, [1, 0.83, 0.8, 0.8, 0.65], rtol=0, atol=1e-12)
    # the repository copy (data/) is the package data
    assert (ROOT / "data" / "frostyboy_2020.csv").read_bytes() == gt.default_data_path().read_bytes()


def test_reader_tolerates_comments_blank_lines_extra_columns(tmp_path):
    f = tmp_path / "field.csv"
    f.write_text("# my rover\n\n" + HEADER + ",note\n# a comment between rows\n"
                 'a,"snow, wet",1.0,1.1,0.0909,20,0,0.9,x\n\n  # indented comment\nb,snow,1.0,1.1,0.09,21,5,0.9,y\n')
    d = gt.read_field_data(f)
    assert d.case == ("a", "b")
    assert d.surface[0] == "snow, wet"
    np.testing.assert_allclose(d.drawbar_N, [0.0, 5.0], atol=0)


# ------------------------------------------------------------------------------- Table 2

def test_table2_torques(rows):
    """Table 2 torques: within 1 N m (cases 1, 2, 3, 5) and 1.5 N m (case 4, drawbar)."""
    for r, tol in zip(rows, (1.0, 1.0, 1.0, 1.5, 1.0)):
        assert abs(r["torque_model_Nm"] - r["torque_measured_Nm"]) < tol, r
    np.testing.assert_allclose([r["torque_model_Nm"] for r in rows], MODEL_TORQUE_NM, rtol=0, atol=0.05)


def test_table2_slips_as_model_md(rows):
    """Steady slips 2.1 / 6.3 / 7.8 / 9.3 / 30.4 % (MODEL.md section 3) within 0.2 points."""
    np.testing.assert_allclose([100 * r["slip_model"] for r in rows], MODEL_SLIP_PCT, rtol=0, atol=0.2)
    # the paper: simulated slip above measured for cases 2-4
    assert all(r["slip_model"] > r["slip_measured"] for r in rows[1:4])


# ------------------------------------------------------------------------------- Figure 3

def test_figure3_claims(frostyboy):
    c = gt.terrain_curves([1.0, 0.5], *frostyboy, n_points=2001)
    assert c.normal_load_N == pytest.approx(90 * 9.81 / 4, rel=1e-12)
    # X_t = 1: about 2 % slip gives zero net force (paper Fig 3, section 4); MODEL.md: 2.13 %
    assert 0.015 < c.zero_crossing_slip[0] < 0.03
    assert c.zero_crossing_slip[0] == pytest.approx(0.0213, abs=0.0005)
    # X_t = 0.5: no slip gives a positive net force
    assert np.all(c.net_N[1] < 0)
    assert np.isnan(c.zero_crossing_slip[1])
    assert c.net_N[1].max() == pytest.approx(-24.2, abs=0.1)


def test_literal_reading_d1_fails_as_documented(frostyboy):
    """d = 1 (literal OCR reading): X = 0.5 net force turns positive above ~74 % slip; case 5 slip 16.7 %."""
    seg, tp = frostyboy
    tp1 = dataclasses.replace(tp, peak_exponent_d=1.0)
    c = gt.terrain_curves([1.0, 0.5], seg, tp1, n_points=2001)
    assert c.zero_crossing_slip[0] == pytest.approx(0.0213, abs=0.0005)   # X = 1 unchanged
    assert 0.72 < c.zero_crossing_slip[1] < 0.76
    assert c.net_N[1, -1] > 0
    s5 = steady.steady_state(0.65, seg, tp1, wheel_speed_mps=1.58)
    assert 100 * s5.slip == pytest.approx(16.7, abs=0.2)


# ------------------------------------------------------------------------------- scenarios

@pytest.mark.parametrize("case", range(1, 6))
def test_case_scenario_reaches_steady_state(case, data, frostyboy):
    """Dynamic one-segment run at the measured R_w*omega ends at the steady solver's state."""
    sc = load_scenario(ROOT / "scenarios" / f"frostyboy_case{case}.yaml")
    k = case - 1
    assert sc.terrain.xt == data.xt[k] and sc.tow.force_N == data.drawbar_N[k]
    assert sc.mode.speed_mps == (data.wheel_speed_mps[k],)
    res = simulate(sc)
    ss = steady.steady_state(sc.terrain.xt, frostyboy[0], frostyboy[1], drawbar_N=sc.tow.force_N,
                             wheel_speed_mps=sc.mode.speed_mps[0])
    assert abs(res.segments["slip"][-1, 0] - ss.slip) < 0.002
    assert abs(res.segments["motor_torque_Nm"][-1, 0] - ss.torque_Nm) < 0.2
    assert res.segments["v_mps"][-1, 0] == pytest.approx(ss.ground_speed_mps, abs=0.005)


# ------------------------------------------------------------------------------- calibration

def test_calibration_recovers_torque_law(data, frostyboy):
    """Fitting tau0, tau1 (X_t fixed) on Table 2 recovers tau0 = 0.1710, tau1 = 1.7096 within 2 %."""
    res = cal.calibrate(data, ["tau0", "tau1"], *frostyboy)
    assert res.success
    assert res.names == ("tau0", "tau1")
    assert res.value[0] == pytest.approx(0.1710, rel=0.02)
    assert res.value[1] == pytest.approx(1.7096, rel=0.02)
    assert res.dof == 8 and res.n_residuals == 10
    assert np.all(np.isfinite(res.stderr)) and np.all(res.stderr > 0)
    assert res.cost_after <= res.cost_before


def test_calibration_fits_xt(data, frostyboy):
    """Fitting every case's X_t (with tau0, tau1) lowers the cost; labels name the cases."""
    res = cal.calibrate(data, ["xt", "tau0", "tau1"], *frostyboy)
    assert res.names[:5] == tuple(f"xt[{c}]" for c in CASES)
    assert res.cost_after < 0.75 * res.cost_before
    assert res.dof == 10 - 7


_SEG, _TP = gt.vehicle_model("frostyboy")
_BASE = gt.read_field_data()


@settings(max_examples=15, deadline=None)
@given(tau0=st.floats(0.05, 0.4), tau1=st.floats(0.8, 2.5), b_trF=st.floats(0.13, 0.175),
       seed=st.integers(0, 2**31 - 1))
def test_calibration_recovers_known_coefficients(tau0, tau1, b_trF, seed):
    """Synthetic data from known (tau0, tau1, b_trF) + noise (0.05 N m, 0.05 % slip) are fitted back.

    Tolerance: |fit - true| < 0.004 (tau0), 0.015 (tau1), 0.001 (b_trF), about 5-6 typical standard
    errors (0.00065, 0.0030, 0.00016); 25 trial fits stayed below 0.0015, 0.0057, 0.00042.
    """
    true = dataclasses.replace(_TP, tau0=tau0, tau1=tau1, b_trF=b_trF)
    s, T, imm = cal.model_predictions(_BASE, _SEG, true)
    assert not imm.any()
    rng = np.random.default_rng(seed)
    synth = dataclasses.replace(_BASE, torque_Nm=T + rng.normal(0, 0.05, T.size),
                                slip=s + rng.normal(0, 0.0005, s.size))
    res = cal.calibrate(synth, ["tau0", "tau1", "b_trF"], _SEG, _TP)
    assert abs(res.value[0] - tau0) < 0.004
    assert abs(res.value[1] - tau1) < 0.015
    assert abs(res.value[2] - b_trF) < 0.001
    assert not res.immobilised_after


# ------------------------------------------------------------------------------- CLI

def test_cli_groundtruth(tmp_path):
    out = tmp_path / "gt"
    r = CliRunner().invoke(main, ["groundtruth", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "30.44" in r.output and "31.91" in r.output   # case 5 slip %, case 4 torque
    lines = (out / "table2.csv").read_text().splitlines()
    assert lines[0].split(",")[:8] == ["case", "xt", "drawbar_N", "wheel_speed_mps", "speed_measured_mps",
                                       "speed_model_mps", "speed_residual_mps", "slip_measured"]
    assert len(lines) == 6
    assert (out / "table2.png").stat().st_size > 1000


def test_cli_terrain_curves(tmp_path):
    out = tmp_path / "tc"
    r = CliRunner().invoke(main, ["terrain-curves", "--xt", "1", "--xt", "0.5", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "X_t = 1: net force crosses zero at slip 2.13 %" in r.output
    assert "X_t = 0.5: net force negative for every slip" in r.output
    arr = np.loadtxt(out / "terrain_curves.csv", delimiter=",", skiprows=1)
    assert arr.shape == (2 * 1001, 5)
    np.testing.assert_allclose(arr[:, 4], arr[:, 2] - arr[:, 3], atol=1e-3)
    assert (out / "terrain_curves.png").stat().st_size > 1000


def test_cli_calibrate_model_file_round_trip(tmp_path):
    out = tmp_path / "cal"
    r = CliRunner().invoke(main, ["calibrate", str(gt.default_data_path()), "--fit", "tau0", "--fit", "tau1",
                                  "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "std err" in r.output and "before:" in r.output and "after:" in r.output
    doc = json.loads((out / "calibration.json").read_text())
    fitted = {p["name"]: p for p in doc["parameters"]}
    assert fitted["tau0"]["value"] == pytest.approx(0.1710, rel=0.02)
    assert fitted["tau1"]["stderr"] > 0
    # a scenario references the written model
    scen = yaml.safe_load((ROOT / "scenarios" / "frostyboy_case3.yaml").read_text())
    scen["terrain"]["model_file"] = str(out / "terrain_model.yaml")
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(scen))
    sc = load_scenario(tmp_path / "s.yaml")
    assert sc.terrain.model.tau0 == pytest.approx(fitted["tau0"]["value"], rel=1e-12)
    assert sc.terrain.model.tau1 == pytest.approx(fitted["tau1"]["value"], rel=1e-12)


_GOOD_ROWS = ["1,icy road,2.5,2.66,0.06,10,0,1", "2,lake snow,1.23,1.28,0.039,27,0,0.83"]


@pytest.mark.parametrize("text, fit, needle", [
    ("case,surface,speed_mps,wheel_speed_mps,slip,torque,drawbar_N,xt\n" + _GOOD_ROWS[0] + "\n",
     ["tau0"], "missing column(s) 'torque_Nm'"),
    (HEADER + "\n" + _GOOD_ROWS[0] + "\n4,sled,1.84,1.93,0.047,32.8,N/A,0.8\n", ["tau0"],
     "column 'drawbar_N': expected a number"),
    (HEADER + "\n" + _GOOD_ROWS[0] + "\n2,lake snow,1.23,1.28,3.9,27,0,0.83\n", ["tau0"],
     "slip 3.9 is outside [-1, 1]"),
    (HEADER + "\n" + _GOOD_ROWS[0] + "\n", ["tau0", "tau1", "b_trF"], "3 parameter(s) to fit but only 2 residuals"),
    (HEADER + "\n" + "\n".join(_GOOD_ROWS) + "\n", ["tua0"], "Did you mean 'tau0'"),
    ("# only comments\n", ["tau0"], "no header and no data rows"),
])
def test_cli_calibrate_bad_input(tmp_path, text, fit, needle):
    """Bad field files and --fit names: exit 2, one message naming the problem, nothing written."""
    f = tmp_path / "field.csv"
    f.write_text(text)
    out = tmp_path / "out"
    args = ["calibrate", str(f), "--out", str(out)]
    for n in fit:
        args += ["--fit", n]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2, r.output
    assert needle in r.output
    assert "Traceback" not in r.output
    assert not out.exists()


def test_bad_input_api_raises_scenario_error(tmp_path):
    with pytest.raises(ScenarioError, match="no such file"):
        gt.read_field_data(tmp_path / "missing.csv")
