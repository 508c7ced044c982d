"""Calibration of terrain coefficients to field data (snoworm.studies.calibrate, docs/model.md sections 2-3),
and its CLI.

Tolerances are stated next to each comparison.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from hypothesis import given, settings, strategies as st

from snoworm.cli import main
from snoworm.config.scenario import load_scenario
from snoworm.studies import calibrate as cal, field_data as fd, groundtruth as gt

ROOT = Path(__file__).resolve().parents[1]
CASES = ("1", "2", "3", "4", "5")
HEADER = ",".join(fd.FIELD_COLUMNS)  # the field-data CSV header


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


_BASE = fd.read_field_data()


@settings(max_examples=15, deadline=None)
@given(
    tau0=st.floats(0.05, 0.4), tau1=st.floats(0.8, 2.5), b_trF=st.floats(0.13, 0.175), seed=st.integers(0, 2**31 - 1)
)
def test_calibration_recovers_known_coefficients(tau0, tau1, b_trF, seed):
    """Synthetic data from known (tau0, tau1, b_trF) + noise (0.05 N m, 0.05 % slip) are fitted back.

    Tolerance: |fit - true| < 0.004 (tau0), 0.015 (tau1), 0.001 (b_trF), about 5-6 typical standard
    errors (0.00065, 0.0030, 0.00016); 25 trial fits stayed below 0.0015, 0.0057, 0.00042.
    """
    true = dataclasses.replace(_TP, tau0=tau0, tau1=tau1, b_trF=b_trF)
    s, T, imm = cal.model_predictions(_BASE, _SEG, true)
    assert not imm.any()
    rng = np.random.default_rng(seed)
    synth = dataclasses.replace(
        _BASE, torque_Nm=T + rng.normal(0, 0.05, T.size), slip=s + rng.normal(0, 0.0005, s.size)
    )
    res = cal.calibrate(synth, ["tau0", "tau1", "b_trF"], _SEG, _TP)
    assert abs(res.value[0] - tau0) < 0.004
    assert abs(res.value[1] - tau1) < 0.015
    assert abs(res.value[2] - b_trF) < 0.001
    assert not res.immobilised_after


def test_cli_calibrate_model_file_round_trip(tmp_path):
    out = tmp_path / "cal"
    r = CliRunner().invoke(
        main, ["calibrate", str(fd.default_data_path()), "--fit", "tau0", "--fit", "tau1", "--out", str(out)]
    )
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


@pytest.mark.parametrize(
    "text, fit, needle",
    [
        (
            "case,surface,speed_mps,wheel_speed_mps,slip,torque,drawbar_N,xt\n" + _GOOD_ROWS[0] + "\n",
            ["tau0"],
            "missing column(s) 'torque_Nm'",
        ),
        (
            HEADER + "\n" + _GOOD_ROWS[0] + "\n4,sled,1.84,1.93,0.047,32.8,N/A,0.8\n",
            ["tau0"],
            "column 'drawbar_N': expected a number",
        ),
        (
            HEADER + "\n" + _GOOD_ROWS[0] + "\n2,lake snow,1.23,1.28,3.9,27,0,0.83\n",
            ["tau0"],
            "slip 3.9 is outside [-1, 1]",
        ),
        (HEADER + "\n" + _GOOD_ROWS[0] + "\n", ["tau0", "tau1", "b_trF"], "3 parameter(s) to fit but only 2 residuals"),
        (HEADER + "\n" + "\n".join(_GOOD_ROWS) + "\n", ["tua0"], "Did you mean 'tau0'"),
        ("# only comments\n", ["tau0"], "no header and no data rows"),
    ],
)
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


def test_progress_counts_model_evaluations_within_the_budget(data, frostyboy):
    seen = []
    res = cal.calibrate(data, ["tau0", "tau1"], *frostyboy, progress=lambda n, budget: seen.append((n, budget)))
    during, end = seen[:-1], seen[-1]
    assert [n for n, _ in during] == list(range(1, len(during) + 1))
    assert {b for _, b in during} == {600}  # 200 * (2 parameters + 1)
    assert len(during) >= res.nfev
    assert end == (len(during), len(during)) and len(during) < 600  # ended early: 100 % of the work done


def test_cli_calibrate_refuses_a_foreign_folder_before_fitting(tmp_path, monkeypatch):
    out = tmp_path / "c"
    out.mkdir()
    (out / "notes.txt").write_text("x")
    monkeypatch.setattr(cal, "calibrate", lambda *a, **k: pytest.fail("fitted before checking --out"))
    r = CliRunner().invoke(main, ["calibrate", str(fd.default_data_path()), "--fit", "tau0", "--out", str(out)])
    assert r.exit_code == 2 and str(out) in r.output and "--overwrite" in r.output


def test_fitted_values_at_a_search_bound_are_noted(data, frostyboy):
    """X_t of a case fitted against its domain's upper end 1 is reported, not passed silently."""
    from dataclasses import replace

    seg, tp = frostyboy
    res = cal.calibrate(data, ["xt"], seg, replace(tp, tau0=0.5))  # more resistance: X_t wants to exceed 1
    assert all(0 < v <= 1 for v in res.xt)
    at_bound = [n for n, v in zip(res.names, res.value) if v >= 1 - 1e-3 * 0.95]
    assert at_bound
    text = cal.format_report(res)
    for n in at_bound:
        assert f"note: {n} = " in text
    assert text.count("sits at a bound of its search range [0.05, 1]") == len(at_bound)
    assert "sits at a bound" not in cal.format_report(cal.calibrate(data, ["xt"], seg, tp))  # the shipped set
