"""Scenarios (snoworm.config.scenario): every shipped scenario is valid; bad input fails naming the field and the fix;
Scenario.with_ and to_dict; the mode-config registry; a scenario is data (no kernel, no solver, no cache)."""

import dataclasses
import json
import os
import pickle
import subprocess
import sys

import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from hypothesis import given, settings, strategies as st

from snoworm.config.params import PARAMETER_SETS, parameter_entries
from snoworm.config.scenario import (
    ScenarioError,
    apply_overrides,
    dump_scenario,
    load_scenario,
    read_yaml,
    scenario_from_dict,
    scenario_path,
    shipped_scenarios,
)
from snoworm.simulation.driver import assemble, chain_model, check_assembly, simulate
from tests.conftest import ROOT, SCENARIOS

SHIPPED = sorted(SCENARIOS.glob("*.yaml"))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_scenarios_validate_and_round_trip(path):
    sc = load_scenario(path)
    again = scenario_from_dict(yaml.safe_load(dump_scenario(sc)), base_dir=path.parent)
    assert again == sc


def base():
    return read_yaml(SCENARIOS / "tow6_uniform.yaml")


@pytest.mark.parametrize(
    "overrides, field, words",
    [
        ([("vehicle.segment.mass_kg", -90)], "vehicle.segment.mass_kg", "greater than 0"),
        ([("terrain.xt", 0)], "terrain.xt", "greater than 0"),
        ([("vehicle.segments", 0)], "vehicle.segments", "at least 1"),
        ([("vehicle.segments", 2.5)], "vehicle.segments", "whole number"),
        ([("tow.force_N", "heavy")], "tow.force_N", "number"),
        ([("vehicle.segmnets", 3)], "vehicle.segmnets", "Did you mean 'segments'"),
        ([("terrain.model.b_tf", 0.7)], "terrain.model.b_tf", "Did you mean 'b_tF'"),
        ([("mode.type", "inchworn")], "mode.type", "unknown mode"),
        ([("mode.start_time_s", [1, 2])], "mode.start_time_s", "one per segment"),
        ([("simulation.method", "Euler")], "simulation.method", "must be one of"),
        ([("vehicle.parameter_set", "frostyboi")], "vehicle.parameter_set", "Did you mean 'frostyboy'"),
        ([("terrain.profile", [[0, 0.9], [0, 0.5]])], "terrain.profile[1]", "increase"),
        ([("vehicle.links.stroke_max_m", -1)], "vehicle.links.stroke_max_m", "greater than stroke_min_m"),
    ],
)
def test_bad_values_name_the_field(overrides, field, words):
    with pytest.raises(ScenarioError) as exc:
        scenario_from_dict(apply_overrides(base(), overrides))
    msg = str(exc.value)
    assert msg.startswith(field) and words in msg


def test_missing_required_section():
    raw = base()
    del raw["tow"]
    with pytest.raises(ScenarioError, match="^tow: is required"):
        scenario_from_dict(raw)


def test_unknown_top_level_key():
    raw = base()
    raw["terrian"] = {"xt": 1}
    with pytest.raises(ScenarioError, match="Did you mean 'terrain'"):
        scenario_from_dict(raw)


def test_malformed_yaml(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("vehicle:\n  segments: [1, 2\n")
    with pytest.raises(ScenarioError, match=r"bad.yaml, line 3, column 1: not valid YAML"):
        load_scenario(p)


def test_model_file_is_merged(tmp_path):
    (tmp_path / "tm.yaml").write_text("terrain_model: {tau0: 0.2, tau1: 1.5}\n")
    raw = base()
    raw["terrain"]["model_file"] = "tm.yaml"
    sc = scenario_from_dict(raw, base_dir=tmp_path)
    assert (sc.terrain.model.tau0, sc.terrain.model.tau1, sc.terrain.model.b_tF) == (0.2, 1.5, 0.7)


@settings(max_examples=25, deadline=None)
@given(xt=st.floats(0.05, 1.0), tow=st.floats(-500, 500), n=st.integers(1, 12), speed=st.floats(0, 5))
def test_round_trip_property(xt, tow, n, speed):
    """Any valid scenario survives dump -> load unchanged (the resolved scenario re-runs identically)."""
    sc = scenario_from_dict(
        apply_overrides(
            base(), [("terrain.xt", xt), ("tow.force_N", tow), ("vehicle.segments", n), ("mode.speed_mps", speed)]
        )
    )
    assert scenario_from_dict(yaml.safe_load(dump_scenario(sc))) == sc


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_scenarios_run(path):
    """Every shipped scenario runs (first 3 s) and produces finite results of the right shape."""
    import numpy as np

    from snoworm import simulate

    sc = load_scenario(path, ["simulation.duration_s=3"])
    res = simulate(sc)
    n = sc.vehicle.segments
    assert res.segments["x_m"].shape[1] == n and res.links["force_N"].shape[1] == n - 1
    assert res.t[-1] == pytest.approx(3.0)
    assert all(np.all(np.isfinite(a)) for a in res.segments.values())


# ------------------------------------------------------------------ Scenario.with_, to_dict, cached properties


def test_with_returns_a_validated_new_scenario():
    sc = load_scenario(SCENARIOS / "tow6_uniform.yaml")
    new = sc.with_({"tow.force_N": 150, "terrain.xt": 0.7}, name="lighter")
    assert (new.tow.force_N, new.terrain.xt, new.name) == (150.0, 0.7, "lighter")
    assert (sc.tow.force_N, sc.terrain.xt, sc.name) == (200.0, 0.9, "tow6_uniform")  # the original is unchanged
    assert new.vehicle == sc.vehicle and new.mode == sc.mode
    assert chain_model(new).tow_force_N == 150.0  # built from the new values


@pytest.mark.parametrize(
    "changes, match",
    [
        ({"terrain.xt": -1}, r"^terrain\.xt: must be greater than 0"),
        ({"vehicle.segmnets": 3}, r"Did you mean 'segments'"),
        ({"mode.speed_mps": [1.8, 1.8]}, r"^mode\.speed_mps: give one speed for all segments or 6"),
    ],
)
def test_with_raises_like_a_scenario_file(changes, match):
    sc = load_scenario(SCENARIOS / "tow6_uniform.yaml")
    with pytest.raises(ScenarioError, match=match):
        sc.with_(changes)


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_to_dict_round_trips(path):
    sc = load_scenario(path)
    d = sc.to_dict()
    assert scenario_from_dict(d, base_dir=path.parent) == sc
    assert yaml.safe_load(yaml.safe_dump(d)) == d  # plain YAML-able data


#: run in a fresh interpreter per scenario: load it, then list what loading imported
_LOAD_CHILD = """
import sys
from snoworm.config.scenario import load_scenario, read_yaml, scenario_from_dict
path = sys.argv[1]
sc = load_scenario(path)
again = scenario_from_dict(read_yaml(path), base_dir=sc.origin.base_dir)
assert again == sc
heavy = ("scipy.integrate", "scipy.optimize", "snoworm.dynamics", "snoworm.steady", "snoworm.simulation",
         "snoworm.model.floatkernel", "snoworm.modes.force_plan")
print(",".join(m for m in heavy if m in sys.modules))
"""


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_loading_a_scenario_builds_no_kernel_and_imports_no_solver(path):
    """A scenario is data (issue 31): validating it (load_scenario, scenario_from_dict) neither builds
    a chain model (snoworm.dynamics is not even imported) nor imports a solver, also for force
    control and the supervisor, whose plans need root finding when a run is assembled."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run(
        [sys.executable, "-c", _LOAD_CHILD, str(path)], capture_output=True, text=True, env=env, timeout=120
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip() == "", f"loading {path.name} imported {proc.stdout.strip()}"


@pytest.mark.parametrize("name", ["tow6_uniform", "pi3_equal"])
def test_a_scenario_holds_its_data_only_before_and_after_a_run(name):
    """Nothing derived is cached on a scenario: it holds its fields, and its pickle keeps its
    size through a run (issue 31: 3.7 kB after loading, 18.8 kB after a run)."""
    sc = load_scenario(SCENARIOS / f"{name}.yaml", [("simulation.duration_s", 2.0)])
    size = len(pickle.dumps(sc))
    fields = {f.name for f in dataclasses.fields(sc)}
    assert set(vars(sc)) == fields, set(vars(sc)) - fields
    simulate(sc)
    assert set(vars(sc)) == fields, set(vars(sc)) - fields
    assert len(pickle.dumps(sc)) == size
    assert pickle.loads(pickle.dumps(sc)) == sc


def test_each_assembly_builds_its_own_model_from_the_data():
    sc = load_scenario(SCENARIOS / "pi3_equal.yaml")
    a, b = assemble(sc), assemble(sc)
    assert a.model is not b.model and a.mode.plan is not b.mode.plan  # built once per run, not kept
    np.testing.assert_array_equal(a.mode.plan.link_ref_N, b.mode.plan.link_ref_N)
    assert chain_model(sc).tow_force_N == sc.tow.force_N


def test_a_target_the_chain_cannot_carry_is_refused_at_assembly():
    """The check needs the chain model, so it moved from loading to assembly: the scenario loads,
    and simulate (or check_assembly, which `snoworm validate` calls) raises the same ScenarioError
    before anything runs."""
    sc = load_scenario(SCENARIOS / "pi2_zero.yaml", [("tow.force_N", 400)])
    for call in (check_assembly, assemble, simulate):
        with pytest.raises(ScenarioError, match=r"mode\.targets.*impossible target.*segment 1"):
            call(sc)


def test_mode_configs_registry_holds_the_built_in_modes():
    from snoworm.config.mode_registry import MODES

    assert {"uniform", "force_control", "inchworm", "supervisor"} <= set(MODES)
    sc = load_scenario(SCENARIOS / "inchworm6.yaml")
    assert type(sc.mode) is MODES.config_class("inchworm")


# ------------------------------------------------------------------ shipped names, vehicles as files, sources


def test_shipped_scenarios_by_name_from_anywhere(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert sorted(shipped_scenarios()) == sorted(p.stem for p in SCENARIOS.glob("*.yaml"))
    assert all(d.endswith(".") and "\n" not in d for _, d in shipped_scenarios().values())
    assert load_scenario("inchworm6").name == "inchworm6"
    assert scenario_path("inchworm6.yaml").resolve() == (SCENARIOS / "inchworm6.yaml").resolve()
    with pytest.raises(ScenarioError, match="snoworm scenarios"):
        load_scenario("no_such_scenario")


def _vehicle_file(tmp_path, text):
    (tmp_path / "rover.yaml").write_text(text)
    sc = yaml.safe_load((SCENARIOS / "tow6_uniform.yaml").read_text())
    sc["vehicle"]["parameter_set"] = "rover.yaml"
    (tmp_path / "sc.yaml").write_text(yaml.safe_dump(sc))
    return tmp_path / "sc.yaml"


def test_a_vehicle_file_based_on_a_named_set_carries_every_source(tmp_path):
    path = _vehicle_file(
        tmp_path,
        "name: my_rover\nbase: frostyboy\nsegment:\n"
        "  mass_kg: {value: 120.0, source: '[field data] weighed 2026-01'}\n"
        "  wheel_radius_m: 0.3\n",
    )
    sc = load_scenario(path)
    assert sc.vehicle.segment.mass_kg == 120.0 and sc.vehicle.segment.wheel_radius_m == 0.3
    src = sc.sources
    assert src["vehicle.segment.mass_kg"] == "[field data] weighed 2026-01"
    assert src["vehicle.segment.wheel_radius_m"] == "[user] rover.yaml"
    assert src["terrain.model.b_tF"] == PARAMETER_SETS["frostyboy"]["terrain_model"]["b_tF"][1]
    n_values = sum(len(v) for v in PARAMETER_SETS["frostyboy"].values())
    assert len(src) == n_values
    # the written scenario.yaml loads back with the same values and sources; summary.json has them
    res_dir = tmp_path / "out"
    r = CliRunner().invoke(
        __import__("snoworm.cli", fromlist=["main"]).main,
        ["run", str(path), "--out", str(res_dir), "--no-plot", "--set", "simulation.duration_s=1"],
    )
    assert r.exit_code == 0, r.output
    text = (res_dir / "scenario.yaml").read_text()
    assert "#   vehicle.segment.mass_kg: [field data] weighed 2026-01" in text
    again = load_scenario(res_dir / "scenario.yaml")
    assert again.sources == src and again.vehicle.segment == sc.vehicle.segment
    assert json.loads((res_dir / "summary.json").read_text())["sources"] == src


def test_scenario_values_and_sources_notes_are_tagged(tmp_path):
    sc = load_scenario(SCENARIOS / "tow6_weak_segment.yaml")
    assert sc.sources["vehicle.segment_overrides.2.torque_limit_Nm"] == "[user] scenario"
    assert sc.sources["vehicle.segment.mass_kg"] == "[Lines] incl. wheels"
    noted = sc.with_({"sources": {"vehicle.segment.mass_kg": "[field data] scale"}})
    assert noted.sources["vehicle.segment.mass_kg"] == "[field data] scale"
    changed = noted.with_({"vehicle.segment.mass_kg": 95.0})  # the note no longer applies
    assert changed.sources["vehicle.segment.mass_kg"] == "[user] scenario"
    with pytest.raises(ScenarioError, match=r"sources.vehicle.segment.mass_kg: a source must start with"):
        sc.with_({"sources": {"vehicle.segment.mass_kg": "weighed"}})


@pytest.mark.parametrize(
    "text, words",
    [
        ("segment:\n  mass_kg: 100\n", "missing wheel_radius_m"),  # no base: every value
        ("base: frostyboy\nsegment:\n  mas_kg: 100\n", "Did you mean 'mass_kg'"),
        ("base: frostyboi\n", "base: unknown set"),
        ("base: frostyboy\nsegment: [1, 2]\n", "expected a mapping"),
        ("base: frostyboy\nsegment:\n  mass_kg: {value: 1, source: guessed}\n", "a source must start with"),
        ("base: frostyboy\nsegment:\n  mass_kg: -5\n", "vehicle.segment.mass_kg"),
        ("- 1\n", "must hold a mapping"),
        ("base: frostyboy\nwheels: 4\n", "unknown key 'wheels'"),
    ],
)
def test_bad_vehicle_files_are_bad_input(tmp_path, text, words):
    path = _vehicle_file(tmp_path, text)
    with pytest.raises(ScenarioError, match="parameter_set|mass_kg") as err:
        load_scenario(path)
    assert words in str(err.value)
    r = CliRunner().invoke(__import__("snoworm.cli", fromlist=["main"]).main, ["validate", str(path)])
    assert r.exit_code == 2 and "Traceback" not in r.output


def test_a_missing_vehicle_file_names_it(tmp_path):
    with pytest.raises(ScenarioError, match="vehicle.parameter_set: .*nope.yaml: no such file"):
        parameter_entries("nope.yaml", tmp_path)


def test_copy_tree_copies_every_level_and_leaves_the_original_alone():
    import numpy as np

    from snoworm.config.scenario import _copy_tree

    shared = {"k": [1, 2]}
    data = {"a": shared, "b": shared, "c": [{"x": 1.5, "s": "t", "n": None}], "arr": np.arange(3.0)}
    out = _copy_tree(data)
    assert out["a"] == data["a"] and out["c"] == data["c"] and np.array_equal(out["arr"], data["arr"])
    out["a"]["k"].append(3)
    out["c"][0]["x"] = 2.0
    out["arr"][0] = 9.0
    assert data == {"a": {"k": [1, 2]}, "b": {"k": [1, 2]}, "c": [{"x": 1.5, "s": "t", "n": None}], "arr": data["arr"]}
    assert data["arr"][0] == 0.0
    assert out["b"]["k"] == [1, 2]  # a YAML alias's two places are two copies


def test_override_of_an_aliased_section_changes_only_the_named_place():
    raw = {"a": {"v": 1}}
    raw["b"] = raw["a"]  # what a YAML alias gives
    out = apply_overrides(raw, [("a.v", 2)])
    assert out["a"]["v"] == 2 and out["b"]["v"] == 1 and raw["a"]["v"] == 1


def test_the_origin_keeps_the_folder_and_the_notes_through_edits(tmp_path, monkeypatch):
    path = _vehicle_file(tmp_path, "name: my_rover\nbase: frostyboy\nsegment:\n  mass_kg: 120.0\n")
    sc = load_scenario(path)
    assert sc.origin.base_dir == tmp_path and sc.sources["vehicle.segment.mass_kg"] == "[user] rover.yaml"
    noted = sc.with_({"sources": {"vehicle.segment.wheel_radius_m": "[field data] tape"}})
    assert noted.origin.base_dir == tmp_path  # with_ validates from the same folder
    # dataclasses.replace keeps the notes and the parameter set's tags (before: they were lost)
    edited = dataclasses.replace(noted, description="edited")
    assert edited.sources == noted.sources
    assert edited.sources["vehicle.segment.wheel_radius_m"] == "[field data] tape"
