"""The package face (snoworm/__init__.py): every public name is there, imported on first use.

The imports are checked in fresh interpreters, since this test process has long imported
everything.
"""

import subprocess
import sys

import pytest

import snoworm
from tests.conftest import SCENARIOS


def fresh(code: str) -> str:
    """Run ``code`` in a new interpreter and return its stdout (fails on a non-zero exit)."""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def test_every_public_name_resolves_and_is_listed():
    assert set(snoworm.__all__) <= set(dir(snoworm))
    for name in snoworm.__all__:
        assert getattr(snoworm, name) is not None, name
    assert snoworm.simulate.__module__ == "snoworm.simulation.driver"
    assert snoworm.Result.__module__ == "snoworm.results.result"
    assert snoworm.modes.MODES["uniform"].__name__ == "UniformMode"
    ns = {}
    exec("from snoworm import *", ns)
    assert set(snoworm.__all__) <= set(ns)


def test_unknown_attribute_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'simulat'"):
        snoworm.simulat  # noqa: B018
    assert not hasattr(snoworm, "_no_such_name")


def test_import_snoworm_imports_no_heavy_module():
    out = fresh(
        "import sys, snoworm; print(sorted(m for m in ('numpy', 'scipy', 'matplotlib', 'yaml', "
        "'snoworm.simulation.driver', 'snoworm.modes', 'snoworm.studies.sweep') if m in sys.modules))"
    )
    assert out.strip() == "[]"


def test_names_import_their_module_on_first_use():
    out = fresh(
        "import sys, snoworm\n"
        "from snoworm import load_scenario\n"
        "print('snoworm.config.scenario' in sys.modules, 'snoworm.studies.sweep' in sys.modules)\n"
        "snoworm.run_sweep\n"
        "print('snoworm.studies.sweep' in sys.modules)"
    )
    assert out.split() == ["True", "False", "True"]


def test_a_scenario_finds_the_built_in_modes_without_importing_them_first():
    # snoworm.config.scenario sits below the modes: its registry imports them when first read
    out = fresh(
        "import sys\n"
        "from snoworm.config.scenario import load_scenario, scenario_from_dict, read_yaml\n"
        "print('snoworm.modes' in sys.modules)\n"
        f"sc = load_scenario({str(SCENARIOS / 'inchworm6.yaml')!r})\n"
        "print(type(sc.mode).__name__, 'snoworm.modes' in sys.modules)"
    )
    assert out.split() == ["False", "InchwormConfig", "True"]


def test_a_run_imports_only_its_own_mode():
    out = fresh(
        "import sys\n"
        "from snoworm import load_scenario, simulate\n"
        f"simulate(load_scenario({str(SCENARIOS / 'tow6_uniform.yaml')!r}, [('simulation.duration_s', 1.0)]))\n"
        "print(sorted(m for m in sys.modules if m.startswith('snoworm.modes.')))"
    )
    # codeload: the controller allowance the driver sets (no mode of its own)
    assert (
        out.strip()
        == "['snoworm.modes.base', 'snoworm.modes.codeload', 'snoworm.modes.command', 'snoworm.modes.uniform']"
    )


def test_a_users_mode_registers_in_a_fresh_process():
    code = f"""
import numpy as np
from dataclasses import dataclass
from snoworm import Mode, ModeConfig, register_mode, scenario_from_dict, simulate
from snoworm.model.inputs import Controls
from snoworm.modes.base import Interval
from snoworm.config.mode_registry import MODES
from snoworm.config.scenario import apply_overrides, read_yaml
from snoworm.config.schema import field

@dataclass(frozen=True)
class MineConfig(ModeConfig):
    type: str = field(choices=("mine",), doc="mode name")

class Mine(Mode):
    name = "mine"
    config_class = MineConfig
    def interval(self, t, y):
        return Interval(np.inf, Controls.rolling(self.model.n, 1.0, 1.5), [], "mine")

register_mode(Mine)
raw = apply_overrides(read_yaml({str(SCENARIOS / "tow6_uniform.yaml")!r}),
                      [("mode", {{"type": "mine"}}), ("simulation.duration_s", 2.0)])
sc = scenario_from_dict(raw)
print(type(sc.mode).__name__, sorted(MODES), simulate(sc).summary()["distance_m"] > 0)
"""
    out = fresh(code)
    assert out.split(maxsplit=1)[0] == "MineConfig"
    assert "'mine'" in out and "'uniform'" in out and "'inchworm'" in out and out.split()[-1] == "True"


@pytest.mark.parametrize("package", ["snoworm", "snoworm.modes"])
def test_the_public_names_are_one_list(package):
    # the dict _EXPORTS (name -> module) is the one list: __all__ derives from it (no second literal
    # list of names), every name resolves from its module, and the imports for static tools
    # (TYPE_CHECKING) name exactly its entries, so the three cannot drift apart
    import ast
    import importlib
    from pathlib import Path

    mod = importlib.import_module(package)
    tree = ast.parse(Path(mod.__file__).read_text(encoding="utf-8"))
    literal_alls = [
        n
        for n in tree.body
        if isinstance(n, ast.Assign)
        and any(isinstance(t, ast.Name) and t.id == "__all__" for t in n.targets)
        and isinstance(n.value, ast.List)
        and all(isinstance(e, ast.Constant) for e in n.value.elts)
    ]
    assert not literal_alls, f"{package}.__all__ is a second literal list of the names"
    assert set(mod.__all__) - {"__version__"} == set(mod._EXPORTS)
    assert set(mod._EXPORTS) <= set(dir(mod))
    for name, module in mod._EXPORTS.items():
        assert getattr(mod, name) is getattr(importlib.import_module(f"{package}.{module}"), name), name
    guard = next(n for n in tree.body if isinstance(n, ast.If) and ast.unparse(n.test) == "TYPE_CHECKING")
    typed = {a.asname or a.name for n in guard.body if isinstance(n, ast.ImportFrom) for a in n.names}
    assert typed - {"modes"} == set(mod._EXPORTS)
