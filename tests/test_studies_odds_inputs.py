"""Uncertain inputs of the odds study (snoworm/studies/odds/inputs.py): distributions, --vary, the X_t
field, calibrated coefficients, the uncertainty: section; impossible parameters name the field and the fix."""

import json
import math

import numpy as np
import pytest

from snoworm import load_scenario
from snoworm.config.schema import ScenarioError
from snoworm.studies.odds.inputs import (
    XT_FIELD_FLOOR,
    parse_distribution,
    parse_vary,
    parse_xt_field,
    read_calibration,
    uncertainty_from_section,
)


@pytest.mark.parametrize(
    "spec,mean,sd",
    [
        ("normal:0.8:0.05", 0.8, 0.05),
        ("lognormal:150:30", 150.0, 30.0),
        ("uniform:100:250", 175.0, 150 / math.sqrt(12)),
        ("triangular:0:1:2", 1.0, math.sqrt((0 + 1 + 4 - 0 - 0 - 2) / 18)),
    ],
)
def test_distributions_have_the_stated_moments(spec, mean, sd):
    """The frozen distribution's mean and sd are those of the textbook formulas (lognormal: of the value)."""
    d = parse_distribution(spec, "x").frozen()
    assert d.mean() == pytest.approx(mean, rel=1e-12)
    assert d.std() == pytest.approx(sd, rel=1e-12)


def test_truncnormal_stays_in_its_bounds_and_maps_uniforms_by_its_ppf():
    d = parse_distribution("truncnormal:0.8:0.1:0.6:0.9", "x")
    v = d.ppf(np.linspace(0, 1, 101))
    assert v.min() >= 0.6 - 1e-12 and v.max() <= 0.9 + 1e-12
    assert np.all(np.diff(v) >= 0)
    assert np.isfinite(d.ppf(np.array([0.0, 1.0]))).all()  # the ends of [0, 1] give finite values


@pytest.mark.parametrize(
    "item,words",
    [
        ("terrain.xt=normal:0.8:0", ["--vary terrain.xt", "sd must be > 0", "--set"]),
        ("terrain.xt=normal:0.8:-0.1", ["sd must be > 0"]),
        ("terrain.xt=gauss:0.8:0.1", ["unknown distribution", "normal"]),
        ("terrain.xt=normal:0.8", ["takes 2 parameters", "normal:MEAN:SD"]),
        ("terrain.xt=uniform:0.9:0.5", ["high must be greater than low"]),
        ("terrain.xt=triangular:0.5:0.95:0.9", ["mode must lie in"]),
        ("terrain.xt=lognormal:-1:0.1", ["mean must be > 0"]),
        ("terrain.xt=truncnormal:0.5:0.01:0.9:1.0", ["more than 8 sd"]),
        ("terrain.xt=normal:a:0.1", ["must be numbers"]),
        ("terrain.xt", ["expected PATH=DIST:PARAMS"]),
    ],
)
def test_impossible_distributions_are_refused_naming_the_field(item, words):
    with pytest.raises(ScenarioError) as e:
        parse_vary(item)
    for w in words:
        assert w in str(e.value)


def test_a_distribution_mostly_outside_the_field_domain_is_refused():
    sc = load_scenario("climb")
    with pytest.raises(ScenarioError, match=r"terrain.xt=normal:1.05:0.1: only \d+ % .* domain"):
        parse_vary("terrain.xt=normal:1.05:0.1").bounded(sc)
    ok = parse_vary("terrain.xt=normal:0.95:0.1").bounded(sc)
    assert ok.low == XT_FIELD_FLOOR and ok.high == 1.0
    v = ok.values(np.array([[0.999999]]))["terrain.xt"]
    assert v[0] == 1.0  # clipped to the domain
    with pytest.raises(ScenarioError, match="is not a field of the scenario"):
        parse_vary("terrain.xtt=normal:0.8:0.1").bounded(sc)
    with pytest.raises(ScenarioError, match="not a single number"):
        parse_vary("mode.gait=normal:0.8:0.1").bounded(sc)
    t = parse_vary("tow.force_N=uniform:100:250").bounded(sc)  # a field without a lower bound near the draws
    assert t.values(np.array([[0.5]]))["tow.force_N"][0] == pytest.approx(175.0)


def test_xt_field_parsing_and_its_mass_check():
    f = parse_xt_field("sd=0.05,corr=5")
    assert (f.sd, f.corr_m) == (0.05, 5.0)
    assert parse_xt_field({"sd": 0.1, "corr_m": 2}).corr_m == 2.0
    for bad, words in [
        ("sd=0,corr=5", "sd must be > 0"),
        ("sd=0.05", "expected exactly sd and corr"),
        ("sd=0.1,corr=-1", "corr"),
    ]:
        with pytest.raises(ScenarioError, match=words):
            parse_xt_field(bad)
    with pytest.raises(ScenarioError, match="Reduce sd"):
        parse_xt_field("sd=0.5,corr=5").check_mean(0.05, 0.05)
    parse_xt_field("sd=0.05,corr=5").check_mean(0.6, 0.9)


def _calibration(tmp_path, corr, stderr=(0.1, 0.02)):
    doc = {
        "parameters": [
            {"name": "b_tF", "start": 1.0, "value": 0.9, "stderr": stderr[0]},
            {"name": "A", "start": 1.0, "value": 1.2, "stderr": stderr[1]},
            {"name": "xt[1]", "start": 0.7, "value": 0.72, "stderr": 0.03},
        ],
        "correlation": corr,
    }
    (tmp_path / "calibration.json").write_text(json.dumps(doc))
    return tmp_path


def test_calibrated_coefficients_are_drawn_jointly_with_their_covariance(tmp_path):
    """The coefficients' covariance is diag(se) C diag(se) (the fitted X_t of the field cases left out), and
    draws reproduce it within sampling error (4 standard errors of a correlation estimate)."""
    corr = [[1.0, -0.6, 0.1], [-0.6, 1.0, 0.2], [0.1, 0.2, 1.0]]
    cal = read_calibration(_calibration(tmp_path, corr))
    assert cal.names == ("b_tF", "A")
    assert np.allclose(cal.cov, [[0.01, -0.6 * 0.1 * 0.02], [-0.6 * 0.1 * 0.02, 0.0004]])
    n = 20000
    u = np.random.default_rng(1).random((n, 2))
    v = cal.values(u)
    x, y = v["terrain.model.b_tF"], v["terrain.model.A"]
    assert np.mean(x) == pytest.approx(0.9, abs=4 * 0.1 / math.sqrt(n))
    assert np.std(y) == pytest.approx(0.02, rel=4 / math.sqrt(2 * n))
    assert np.corrcoef(x, y)[0, 1] == pytest.approx(-0.6, abs=4 * (1 - 0.36) / math.sqrt(n))


def test_a_calibration_folder_without_covariance_is_refused(tmp_path):
    with pytest.raises(ScenarioError, match="no covariance"):
        read_calibration(_calibration(tmp_path, [[1.0, None, None], [None, 1.0, None], [None, None, 1.0]]))
    with pytest.raises(ScenarioError, match="no standard error"):
        read_calibration(_calibration(tmp_path, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], (None, 0.1)))
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ScenarioError, match="calibrate"):
        read_calibration(empty)


def test_uncertainty_section_is_checked_key_by_key(tmp_path):
    sec = uncertainty_from_section(
        {
            "vary": {"terrain.xt": "normal:0.8:0.05", "tow.force_N": {"dist": "uniform", "low": 0, "high": 50}},
            "xt_field": {"sd": 0.05, "corr_m": 5},
            "calibration": "cal",
        },
        tmp_path,
    )
    assert [s.path for s in sec["vary"]] == ["terrain.xt", "tow.force_N"]
    assert sec["calibration"] == str(tmp_path / "cal")
    with pytest.raises(ScenarioError, match=r"uncertainty.varry: unknown key"):
        uncertainty_from_section({"varry": {}})
    with pytest.raises(
        ScenarioError, match=r"uncertainty.vary.tow.force_N: uniform takes the keys low, high; missing high"
    ):
        uncertainty_from_section({"vary": {"tow.force_N": {"dist": "uniform", "low": 0}}})
