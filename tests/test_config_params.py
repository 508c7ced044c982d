"""Named parameter sets with source tags (snoworm.config.params, docs/model.md sections 1, 2 and 4)."""

import dataclasses

import pytest

from snoworm.config.params import PARAMETER_SETS, parameter_set, parameter_sources, terrain_params
from snoworm.config.sections import LinkConfig, SegmentConfig, TerrainModelConfig
from snoworm.terrain import TerrainParams

TAGS = ("[paper]", "[Lines]", "[derived]", "[fitted]", "[assumed]")


@pytest.mark.parametrize("name", sorted(PARAMETER_SETS))
def test_every_value_has_a_source_tag(name):
    sources = parameter_sources(name)
    assert set(sources) == {"segment", "terrain_model", "links"}
    for section, entries in sources.items():
        assert entries, section
        for key, tag in entries.items():
            assert tag.startswith(TAGS), f"{name}.{section}.{key}: source {tag!r} has no tag of {TAGS}"


@pytest.mark.parametrize("name", sorted(PARAMETER_SETS))
def test_sets_fill_every_physical_field(name):
    """A set names exactly the fields of the sections it fills (no stray or missing values)."""
    values = parameter_set(name)
    for section, cls in (("segment", SegmentConfig), ("terrain_model", TerrainModelConfig)):
        scenario_only = {"drivetrain"} if cls is SegmentConfig else set()  # a segment's condition, the scenario's
        assert set(values[section]) == {f.name for f in dataclasses.fields(cls)} - scenario_only, section
    link_fields = {f.name for f in dataclasses.fields(LinkConfig)} - {"type"}  # the type is the scenario's
    assert set(values["links"]) == link_fields


def test_frostyboy_values():
    """docs/model.md sections 1, 2 and 4, exact as stored."""
    v = parameter_set("frostyboy")
    s, t, lk = v["segment"], v["terrain_model"], v["links"]
    assert (s["mass_kg"], s["wheel_radius_m"], s["wheel_inertia_kgm2"], s["wheelbase_m"]) == (90.0, 0.265, 0.415, 1.094)
    assert (s["motor_slope_Nms_per_rad"], s["no_load_speed_radps"], s["torque_limit_Nm"]) == (10.0507, 18.326, 88.64)
    assert (t["b_tF"], t["b_trF"], t["A"], t["peak_exponent_d"], t["tau0"], t["tau1"]) == (
        0.7,
        0.165,
        0.6,
        2.0,
        0.1710,
        1.7096,
    )
    assert (lk["stiffness_N_per_m"], lk["damping_Ns_per_m"], lk["rest_spacing_m"]) == (2.0e4, 1.5e3, 1.5)
    assert parameter_sources("frostyboy")["terrain_model"]["tau0"].startswith("[fitted]")
    assert parameter_sources("frostyboy")["segment"]["mass_kg"].startswith("[Lines]")


@pytest.mark.parametrize("name", sorted(PARAMETER_SETS))
def test_terrain_params_match_the_set(name):
    tp = terrain_params(name)
    assert isinstance(tp, TerrainParams)
    assert dataclasses.asdict(tp) == parameter_set(name)["terrain_model"]


def test_parameter_set_returns_a_fresh_copy():
    a = parameter_set("frostyboy")
    a["segment"]["mass_kg"] = 1.0
    del a["links"]
    b = parameter_set("frostyboy")
    assert b["segment"]["mass_kg"] == 90.0 and "links" in b
    assert PARAMETER_SETS["frostyboy"]["segment"]["mass_kg"] == (90.0, "[Lines] incl. wheels")
    assert parameter_set("frostyboy") is not parameter_set("frostyboy")


def test_unknown_set_raises_key_error():
    with pytest.raises(KeyError):
        parameter_set("no_such_rover")
