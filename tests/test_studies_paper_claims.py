"""Claim types and the run context (snoworm/studies/paper/claims.py)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from snoworm.studies import paper
from snoworm.studies.paper import claims


def test_make_claim_stores_plain_json_values():
    c = claims.make_claim(
        "x.y",
        "Fig 6",
        "s",
        {"v": np.float64(1.23456789), "a": np.array([1, 2]), "ok": np.bool_(True), "nan": math.nan},
        "tol",
        np.bool_(False),
    )
    assert c.computed["v"] == 1.23457 and type(c.computed["v"]) is float
    assert c.computed["a"] == [1, 2] and type(c.computed["a"][0]) is int
    assert c.computed["ok"] is True and math.isnan(c.computed["nan"])
    assert c.holds is False and type(c.holds) is bool and c.source == "paper"
    json.dumps(c.to_dict())  # numpy types would raise here


def test_find_claim_searches_main_claims_only():
    main_claim = claims.make_claim("a.b", "Fig 3", "s", {"v": 1}, "tol", True)
    variant_claim = claims.make_claim("c.d", "Fig 3", "s", {"v": 1}, "tol", False)
    sec = claims.Section("a", "A", "", claims=[main_claim], variants=[claims.Variant("alt", {}, [variant_claim])])
    assert paper.find_claim([sec], "a.b") is main_claim
    with pytest.raises(KeyError):
        paper.find_claim([sec], "c.d")


def test_context_overrides_and_child():
    ctx = paper.Context(model={"tau1": 0.5}, scenario_overrides={"pi2_zero": ["tow.force_N=100"]}, out_dir="/tmp/x")
    assert ctx.overrides("pi2_zero", ["terrain.xt=0.5"]) == [
        "terrain.model.tau1=0.5",
        "tow.force_N=100",
        "terrain.xt=0.5",
    ]
    assert ctx.overrides("tow6_uniform") == ["terrain.model.tau1=0.5"]
    child = ctx.child({"peak_exponent_d": 1})
    assert child.model == {"tau1": 0.5, "peak_exponent_d": 1} and ctx.model == {"tau1": 0.5}
    assert child.figure("f.png") is None and ctx.figure("f.png").name == "f.png"
    assert ctx.child(plot=True).out_dir == ctx.out_dir
    assert child._runs is not ctx._runs


def test_scenario_dir_is_package_data_with_every_scenario_the_report_runs():
    assert claims.SCENARIO_DIR.parent.name == "snoworm" and claims.SCENARIO_DIR.name == "scenarios"
    names = [
        "inchworm6",
        "rolling6_xt025",
        "tow6_uniform",
        "tow6_staggered",
        "pi2_zero",
        "pi3_equal",
        "pi3_middle_positive",
    ] + [f"frostyboy_case{c}" for c in paper.TABLE2_CASES]
    missing = [n for n in names if not (claims.SCENARIO_DIR / f"{n}.yaml").is_file()]
    assert not missing, missing


def test_context_run_is_memoised():
    ctx = paper.Context()
    a = ctx.run("frostyboy_case1")
    assert ctx.run("frostyboy_case1") is a
    assert ctx.run("frostyboy_case1", ["terrain.xt=0.9"]) is not a
