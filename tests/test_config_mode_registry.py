"""The mode section's registry (snoworm.config.mode_registry): lazy import of built-in modes,
config-class checks, and the messages of a bad ``mode:`` section."""

import sys
import types

import pytest

from snoworm.config.mode_registry import MODES, ModeConfig, ModeRegistry, build_mode_config
from snoworm.config.schema import ScenarioError


def _fake_mode(name):
    return type(f"Fake{name}", (), {"name": name, "config_class": ModeConfig})


def test_mode_registry_imports_a_built_in_modes_module_when_it_is_looked_up(tmp_path, monkeypatch):
    reg = ModeRegistry({"first": "h6_fake_first", "second": "h6_fake_second"})
    monkeypatch.setitem(sys.modules, "h6_registry_host", types.SimpleNamespace(reg=reg))
    monkeypatch.syspath_prepend(str(tmp_path))
    for key in ("first", "second"):
        (tmp_path / f"h6_fake_{key}.py").write_text(
            "import h6_registry_host\n"
            f"h6_registry_host.reg.register(type('M', (), {{'name': {key!r}, 'config_class': "
            "__import__('snoworm.config.mode_registry').config.mode_registry.ModeConfig}))\n"
        )
        monkeypatch.delitem(sys.modules, f"h6_fake_{key}", raising=False)
    users = reg.register(_fake_mode("users"))  # registering imports nothing
    assert "h6_fake_first" not in sys.modules and "h6_fake_second" not in sys.modules
    assert reg["first"].name == "first" and "users" in reg and "unknown" not in reg
    assert "h6_fake_first" in sys.modules and "h6_fake_second" not in sys.modules  # only the one looked up
    assert list(reg) == ["first", "second", "users"] and len(reg) == 3  # listing imports all, built-ins first
    assert reg["users"] is users and reg.config_class("users") is ModeConfig
    reg.unregister("users")
    assert list(reg) == ["first", "second"]


def test_mode_registry_reports_a_failed_import_each_time():
    reg = ModeRegistry({"x": "h6_no_such_module"})
    for _ in range(2):
        with pytest.raises(ModuleNotFoundError):
            reg["x"]


def test_register_refuses_a_class_without_a_name_or_a_mode_config():
    with pytest.raises(TypeError, match="with a name"):
        MODES.register(type("Nameless", (), {"name": "", "config_class": ModeConfig}))
    with pytest.raises(TypeError, match="must subclass snoworm.ModeConfig"):
        MODES.register(type("NotAConfig", (), {"name": "h6_not_a_config", "config_class": dict}))
    assert "h6_not_a_config" not in MODES


@pytest.mark.parametrize(
    "raw, message",
    [
        ([1, 2], r"^mode: expected a mapping with a 'type' key \(controller, force_control, inchworm"),
        ({}, r"^mode\.type: is required but missing\. Choose one of: controller, force_control"),
        ({"type": 3}, r"^mode\.type: expected the name of a mode .*, got int 3\."),
        ({"type": "unifrom"}, r"^mode\.type: unknown mode 'unifrom'\. Did you mean 'uniform'\?"),
    ],
)
def test_a_bad_mode_section_names_the_field_and_the_choices(raw, message):
    with pytest.raises(ScenarioError, match=message):
        build_mode_config(raw)


def test_a_registered_type_builds_its_config_class():
    cfg = build_mode_config({"type": "uniform", "speed_mps": 1.5, "start_time_s": 1.0})
    assert isinstance(cfg, ModeConfig) and type(cfg) is MODES.config_class("uniform") is MODES["uniform"].config_class
