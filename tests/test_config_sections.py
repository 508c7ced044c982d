"""Scenario sections (snoworm.config.sections): the terrain section compiles to one X_t profile; its validation."""

import re

import numpy as np
import pytest

from snoworm.config.scenario import ScenarioError, scenario_from_dict
from snoworm.simulation.driver import chain_model
from tests.conftest import traverse_raw as _base


def test_patches_compile_to_one_profile():
    sc = scenario_from_dict(
        _base(
            xt=0.9,
            patches=[{"start_m": 8, "end_m": 18, "xt": 0.3, "ramp_m": 0.5}, {"start_m": 30, "end_m": 31, "xt": 0.5}],
        )
    )
    p = sc.terrain.compile()
    X = p(np.array([0.0, 7.5, 7.75, 8.0, 13.0, 18.0, 18.25, 18.5, 25.0, 30.5, 29.998, 40.0]))
    np.testing.assert_allclose(X, [0.9, 0.9, 0.6, 0.3, 0.3, 0.3, 0.6, 0.9, 0.9, 0.5, 0.9, 0.9], atol=1e-3)
    # the chain model evaluates the same table (one evaluation path)
    assert chain_model(sc).profile == p


def test_random_profile_reproducible_and_seeded():
    spec = {"mean": 0.6, "std": 0.15, "correlation_length_m": 5.0, "seed": 7, "length_m": 2000.0, "min_xt": 0.1}
    a = scenario_from_dict(_base(random=spec)).terrain.compile()
    b = scenario_from_dict(_base(random=dict(spec))).terrain.compile()
    c = scenario_from_dict(_base(random={**spec, "seed": 8})).terrain.compile()
    assert a == b  # same seed: identical table
    va, vc = np.array(a.values), np.array(c.values)
    assert va.shape == vc.shape and np.max(np.abs(va - vc)) > 0.1  # another seed: another profile
    assert va.min() >= 0.1  # clipped, X_t > 0
    # 400 correlation lengths: sampling error of the mean ~0.01 (tolerance 0.04), of the std ~7 % (tolerance 25 %)
    assert abs(va.mean() - 0.6) < 0.04 and abs(va.std() - 0.15) < 0.25 * 0.15
    # correlation at one correlation length ~ 1/e (sampling error ~0.07, tolerance 0.15)
    x = va - va.mean()
    lag = 8  # grid spacing is correlation_length_m / 8
    assert abs(np.corrcoef(x[:-lag], x[lag:])[0, 1] - np.exp(-1)) < 0.15


@pytest.mark.parametrize(
    "terrain, match",
    [
        ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 5, "xt": 0.3}]}, "end_m: must be greater than start_m"),
        ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 8, "xt": 0.0}]}, r"patches\[0\]\.xt: must be greater than 0"),
        (
            {
                "xt": 0.9,
                "patches": [{"start_m": 5, "end_m": 8, "xt": 0.3, "ramp_m": 1}, {"start_m": 9, "end_m": 12, "xt": 0.3}],
            },
            r"patches\[1\]: overlaps patches\[0\]",
        ),
        ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 8, "xt": 0.3, "ramp": 1}]}, "Did you mean 'ramp_m'"),
        ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 8, "xt": 0.3, "ramp_m": -1}]}, "ramp_m: must be at least 0"),
        ({"profile": [[0, 0.9], [5, 0.3]], "patches": []}, "patches lie on a base X_t"),
        (
            {"xt": 0.9, "random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 5, "seed": 1, "length_m": 50}},
            "give exactly one of 'xt'",
        ),
        (
            {"random": {"mean": 0.6, "std": -0.1, "correlation_length_m": 5, "seed": 1, "length_m": 50}},
            r"random\.std: must be at least 0",
        ),
        (
            {"random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 0, "seed": 1, "length_m": 50}},
            r"random\.correlation_length_m: must be greater than 0",
        ),
        (
            {"random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 5, "length_m": 50}},
            r"random\.seed: is required",
        ),
        ({"random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 5, "seed": 1.5, "length_m": 50}}, "whole number"),
        (
            {"random": {"mean": 0.6, "std": 0.1, "correlation_length_m": 1e-4, "seed": 1, "length_m": 50}},
            "200000 grid points",
        ),
    ],
)
def test_terrain_validation_errors(terrain, match):
    with pytest.raises(ScenarioError, match=match):
        scenario_from_dict(_base(**terrain))


# ------------------------------------------------------------------ X_t domain (0, 1] everywhere (issue 15)
_RANDOM = {"mean": 0.6, "std": 0.15, "correlation_length_m": 5.0, "seed": 7, "length_m": 200.0}


@pytest.mark.parametrize(
    "terrain, where",
    [
        ({"xt": 1.5}, r"^terrain\.xt: must be at most 1"),
        ({"xt": 0.0}, r"^terrain\.xt: must be greater than 0"),
        ({"profile": [[0, 0.5], [10, 1.2]]}, r"^terrain\.profile\[1\]\[1\]: must be at most 1"),
        ({"xt": 0.9, "patches": [{"start_m": 5, "end_m": 8, "xt": 1.01}]}, r"patches\[0\]\.xt: must be at most 1"),
        ({"random": {**_RANDOM, "mean": 1.1}}, r"^terrain\.random\.mean: must be at most 1"),
        ({"random": {**_RANDOM, "min_xt": 2}}, r"^terrain\.random\.min_xt: must be at most 1"),
    ],
)
def test_xt_outside_0_1_is_rejected_with_the_domain(terrain, where):
    with pytest.raises(ScenarioError, match=where) as exc:
        scenario_from_dict(_base(**terrain))
    assert "(0, 1]" in str(exc.value)


def test_nan_in_a_profile_is_rejected():
    with pytest.raises(ScenarioError, match=r"^terrain\.profile\[1\]\[1\]: must be a finite number"):
        scenario_from_dict(_base(profile=[[0, 0.5], [10, float("nan")]]))


def test_random_profile_stays_in_0_1():
    p = scenario_from_dict(_base(random={**_RANDOM, "mean": 0.95, "std": 0.3})).terrain.compile()
    v = np.array(p.values)
    assert v.max() <= 1.0 and v.min() >= 0.05
    assert np.mean(v == 1.0) > 0.2  # mean 0.95, std 0.3: ~43 % of the draws exceed 1 before clipping


@pytest.mark.parametrize(
    "key, value, needle",
    [
        ("tau0", -0.1, "must be at least 0"),
        ("tau1", -1, "must be at least 0"),
        ("peak_exponent_d", 0, "must be greater than 0"),
        ("A", 0, "must be greater than 0"),
        ("A", -0.6, "must be greater than 0"),
        ("slip_eps_mps", 1e300, "must be at most 1 m/s"),
        ("b_tF", 1e300, "must be at most 100"),
    ],
)
def test_terrain_coefficients_have_their_physical_signs(key, value, needle):
    raw = _base(xt=0.5)
    raw["terrain"]["model"] = {key: value}
    with pytest.raises(ScenarioError, match=rf"^terrain\.model\.{key}: {needle}"):
        scenario_from_dict(raw)


@pytest.mark.parametrize(
    "path, value, limit",
    [
        (("tow", "force_N"), 1e300, "1e+06"),
        (("vehicle", "segments"), 10**8, "200"),
        (("simulation", "duration_s"), 1e300, "100000"),
        (("vehicle", "segment", "mass_kg"), 1e300, "100000"),
        (("vehicle", "links", "stiffness_N_per_m"), 1e300, "1e+09"),
        (("simulation", "atol_scale"), 1e300, "1000"),
    ],
)
def test_upper_bounds_name_the_limit(path, value, limit):
    raw = _base(xt=0.5)
    node = raw
    for p in path[:-1]:
        node = node.setdefault(p, {})
    node[path[-1]] = value
    with pytest.raises(ScenarioError, match=rf"^{re.escape('.'.join(path))}: must be at most {re.escape(limit)}"):
        scenario_from_dict(raw)


def test_output_samples_are_capped():
    raw = _base(xt=0.5)
    raw["simulation"]["output_dt_s"] = 1e-9
    with pytest.raises(ScenarioError, match=r"^simulation\.output_dt_s: .* output samples .*, over the 150000 allowed"):
        scenario_from_dict(raw)


def test_atol_scale_fields_names_a_state_field_and_a_positive_factor():
    raw = _base(xt=0.5)
    raw["simulation"]["atol_scale_fields"] = {"omega_frnt": 10}
    with pytest.raises(
        ScenarioError,
        match=r"^simulation\.atol_scale_fields\.omega_frnt: not a state field; use one of "
        r"x_m, .*Did you mean 'omega_front'",
    ):
        scenario_from_dict(raw)
    raw["simulation"]["atol_scale_fields"] = {"omega_front": 0}
    with pytest.raises(ScenarioError, match=r"^simulation\.atol_scale_fields\.omega_front: must be greater than 0"):
        scenario_from_dict(raw)
    raw["simulation"]["atol_scale_fields"] = {"omega_front": 10}
    assert scenario_from_dict(raw).simulation.atol_scale_fields == {"omega_front": 10.0}
