"""Declarative validation of configs (snoworm.config.schema): on construction, on replace, from mappings."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from snoworm import load_scenario
from snoworm.config.schema import Config, ScenarioError, build, dump, field, suggest
from snoworm.config.sections import SimulationConfig, TowConfig
from tests.conftest import SCENARIOS


@pytest.fixture(scope="module")
def sc():
    return load_scenario(SCENARIOS / "tow6_uniform.yaml")


@dataclasses.dataclass(frozen=True)
class Probe(Config):
    """A small config exercising every kind of field."""

    _section = "probe"
    count: int = field(ge=1, doc="a whole number")
    ratio: float = field(0.5, gt=0, le=1, doc="a fraction")
    values: tuple[float, ...] = field((1.0,), ge=0, unit="m", doc="non-negative lengths")
    kind: str = field("a", choices=("a", "b"), doc="a choice")
    flag: bool = field(False, doc="a switch")
    limit: float | None = field(None, gt=0, doc="an optional bound")


# ------------------------------------------------------------------ validation on construction


def test_replace_validates_and_names_the_field(sc):
    with pytest.raises(ScenarioError, match=r"^terrain\.xt: must be greater than 0"):
        dataclasses.replace(sc.terrain, xt=-1)
    with pytest.raises(ScenarioError, match=r"^vehicle\.links\.stroke_max_m: must be greater than stroke_min_m"):
        dataclasses.replace(sc.vehicle.links, stroke_max_m=-1)  # a rule across fields (_check)
    with pytest.raises(ScenarioError, match=r"^tow\.force_N: expected a number"):
        dataclasses.replace(sc, tow={"force_N": "heavy"})  # a nested mapping is built and checked


def test_direct_construction_validates():
    with pytest.raises(ScenarioError, match=r"^tow\.force_N: must be a finite number"):
        TowConfig(force_N=float("inf"))
    with pytest.raises(ScenarioError, match=r"^tow\.force_N: expected a number.*got bool"):
        TowConfig(force_N=True)
    with pytest.raises(ScenarioError, match=r"^probe\.count: expected a whole number"):
        Probe(count=2.5)
    with pytest.raises(ScenarioError, match=r"^probe\.ratio: must be at most 1"):
        Probe(count=1, ratio=1.5)
    with pytest.raises(ScenarioError, match=r"^probe\.values\[1\]: must be at least 0"):
        Probe(count=1, values=(1.0, -2.0))
    with pytest.raises(ScenarioError, match=r"^probe\.kind: must be one of 'a', 'b'"):
        Probe(count=1, kind="c")
    with pytest.raises(ScenarioError, match=r"^probe\.flag: expected true or false"):
        Probe(count=1, flag=1)


def test_numpy_scalars_and_arrays_accepted(sc):
    t = TowConfig(force_N=np.float64(150.0))
    assert type(t.force_N) is float and t.force_N == 150.0
    v = dataclasses.replace(sc.vehicle, segments=np.int64(3))
    assert type(v.segments) is int and v.segments == 3
    p = Probe(
        count=np.int64(2), ratio=np.float32(0.25), values=np.array([0.5, 1.5]), kind=np.str_("b"), limit=np.array(3.0)
    )
    assert (p.count, p.ratio, p.values, p.kind, p.limit) == (2, 0.25, (0.5, 1.5), "b", 3.0)
    assert type(p.values) is tuple and all(type(x) is float for x in p.values)
    m = dataclasses.replace(sc.mode, speed_mps=np.full(6, 1.7))
    assert m.speed_mps == (1.7,) * 6
    assert Probe(count=1, values=2.0).values == (2.0,)  # a scalar where a list is expected


def test_optional_field():
    assert Probe(count=1).limit is None
    with pytest.raises(ScenarioError, match=r"^probe\.limit: must be greater than 0"):
        Probe(count=1, limit=0.0)


# ------------------------------------------------------------------ build from mappings


def test_build_unknown_key_suggests():
    with pytest.raises(ScenarioError, match=r"^tow\.force_n: unknown key\. Did you mean 'force_N'\?"):
        build(TowConfig, {"force_n": 1.0}, "tow")
    with pytest.raises(ScenarioError, match="Known keys here: count, ratio, values, kind, flag, limit"):
        build(Probe, {"cuont": 1}, "probe")


@pytest.mark.parametrize(
    "data, path, match",
    [
        ({}, "tow", r"^tow\.force_N: is required but missing"),
        ([1, 2], "tow", r"^tow: expected a mapping of keys, got list"),
        ({"force_N": "heavy"}, "tow", r"^tow\.force_N: expected a number.*got the text 'heavy'"),
        ({"force_N": [1.0]}, "tow", r"^tow\.force_N: expected a number"),
    ],
)
def test_build_error_paths(data, path, match):
    with pytest.raises(ScenarioError, match=match):
        build(TowConfig, data, path)


def test_build_uses_given_path_and_defaults():
    s = build(SimulationConfig, {"duration_s": "2.5"}, "simulation")  # a numeric string converts
    assert s.duration_s == 2.5 and s.method == "LSODA" and s.max_step_s is None
    with pytest.raises(ScenarioError, match=r"^numerics\.rtol: must be less than 1"):
        build(SimulationConfig, {"duration_s": 1, "rtol": 2}, "numerics")
    with pytest.raises(ScenarioError, match=r"^tow\.force_N: is required"):
        build(TowConfig, None, "tow")  # None is an empty mapping


def test_suggest():
    assert suggest("segmnets", ["segments", "segment"]) == " Did you mean 'segments' or 'segment'?"
    assert suggest("zzz", ["segments"]) == ""


def test_dump_round_trips_through_build():
    p = Probe(count=3, values=(0.5, 2.0), kind="b", limit=4.0)
    d = dump(p)
    assert d == {"count": 3, "ratio": 0.5, "values": [0.5, 2.0], "kind": "b", "flag": False, "limit": 4.0}
    assert build(Probe, d, "probe") == p


# ------------------------------------------------------------------ domains (issue 15)


def test_whole_numbers_reject_nan_inf_and_fractions():
    from snoworm.config.schema import check_field
    from snoworm.config.sections import VehicleConfig

    for bad, needle in (
        (float("nan"), "finite"),
        (float("inf"), "finite"),
        (2.5, "whole number"),
        (10**400, "finite"),
        ([3], "expected a number"),
        ({"a": 1}, "expected a number"),
    ):
        with pytest.raises(ScenarioError, match=needle):
            check_field(VehicleConfig, "segments", bad)
    assert check_field(VehicleConfig, "segments", 6.0) == 6


def test_check_field_uses_the_declared_domain():
    from snoworm.config.schema import check_field
    from snoworm.config.sections import TerrainConfig

    assert check_field(TerrainConfig, "xt", "0.5", "--xt") == 0.5
    with pytest.raises(ScenarioError, match=r"^--xt: must be at most 1 .*allowed range is \(0, 1\]"):
        check_field(TerrainConfig, "xt", 1.5, "--xt")
    with pytest.raises(ScenarioError, match=r"^terrain\.xt: must be greater than 0"):
        check_field(TerrainConfig, "xt", 0.0)


def test_domain_text_marks_open_and_closed_ends():
    from snoworm.config.schema import domain_text

    assert domain_text({"gt": 0, "le": 1}) == "(0, 1]"
    assert domain_text({"ge": -1e6, "le": 1e6}) == "[-1e+06, 1e+06]"
    assert domain_text({"gt": 0}) == "(0, inf)"
    assert domain_text({}) == ""


def test_messages_quote_at_most_about_100_characters():
    from snoworm.config.schema import quote

    huge = "x" * 2_000_000
    with pytest.raises(ScenarioError) as exc:
        build(SimulationConfig, {"duration_s": huge}, "simulation")
    assert len(str(exc.value)) < 400
    assert "2000000 characters" in str(exc.value)
    with pytest.raises(ScenarioError) as exc:
        build(SimulationConfig, {"duration_s": list(range(10**6))}, "simulation")
    assert len(str(exc.value)) < 400
    assert len(quote(list(range(10**5)))) <= 130


def test_a_huge_unknown_key_is_cut_in_the_message():
    with pytest.raises(ScenarioError) as exc:
        build(SimulationConfig, {"duration_s": 1.0, "k" * 100_000: 1}, "simulation")
    assert len(str(exc.value)) < 300 and "unknown key" in str(exc.value)


def test_values_are_converted_before_the_frozen_object_is_made():
    tow = TowConfig(force_N=3)  # an int, converted to a float before construction
    assert type(tow.force_N) is float and tow.force_N == 3.0
    again = dataclasses.replace(tow, force_N=np.int64(5))
    assert type(again.force_N) is float and again.force_N == 5.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        tow.force_N = 1.0
    with pytest.raises(TypeError, match="multiple values"):
        TowConfig(1.0, force_N=2.0)


def test_no_config_object_is_changed_after_it_is_made():
    # frozen means frozen: nothing in the config layer or the modes sets an attribute of a made
    # object (modes/command.py's Observation, a read-only view computed on first read, is no config)
    root = Path(__file__).resolve().parents[1] / "snoworm"
    files = [p for d in ("config", "modes") for p in (root / d).glob("*.py") if p.name != "command.py"]
    offenders = [str(p.relative_to(root)) for p in files if "object.__setattr__" in p.read_text(encoding="utf-8")]
    assert files and offenders == []


def test_an_internal_field_is_no_setting(sc):
    assert "origin" not in dump(sc) and sc.origin is not None
    with pytest.raises(ScenarioError, match=r"^origin: unknown key"):
        build(type(sc), {**dump(sc), "origin": None})
    assert dataclasses.replace(sc, origin=None) == sc  # not compared
    assert dataclasses.replace(sc, description="x").origin is sc.origin  # kept by edits
