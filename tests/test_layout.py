"""Layout rules of the package (issue #12), checked from the source with ``ast``.

* Tests mirror modules: every module of layers 1-6 has ``tests/test_<name>.py`` (a module of a
  subpackage may instead have ``tests/test_<package>_<name>.py``) defining at least one test.
* No module is over 500 lines and no function (or method) over 80 lines.
* Every module is placed in a layer below or named as an application (layer 7, no mirror rule),
  so a new module cannot slip past the rules.

The offenders are listed in the assertion messages.
"""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "snoworm"
TESTS = Path(__file__).resolve().parent
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80

#: layers 0-6 (docs/architecture.md; the import order itself is checked by import-linter, see
#: tests/test_architecture.py), modules as paths relative to snoworm/ without ``.py``
LAYERS = {
    0: ("fileio",),                                                                    # utilities
    1: ("terrain", "drivetrain", "links", "control", "steady"),                       # laws
    2: ("controls", "jacobian", "dynamics"),                                           # model
    3: ("schema", "params", "sections", "scenario", "yamlio"),                         # config
    4: ("modes/base", "modes/uniform", "modes/force_control", "modes/inchworm", "modes/supervisor"),   # modes
    5: ("plotting", "energy", "results", "driver"),                                    # driver and results
    6: ("parallel", "tables", "sweep/spec", "sweep/cases", "sweep/metrics", "sweep/table", "sweep/executors",
        "sweep/run", "groundtruth", "calibrate", "mobility", "paper/claims", "paper/fig3_table2", "paper/fig5",
        "paper/fig6_11", "paper/readings", "paper/render", "paper/report"),           # studies
}
#: layer 7: the faces (no mirror rule; tests/test_cli.py tests the CLI)
APPLICATIONS = ("cli",)
EXEMPT = ("cli", "__main__", "_version")     # besides every __init__.py


def modules():
    """Every module of the package as ``name`` or ``package/name`` (no ``__init__``)."""
    return sorted(str(p.relative_to(PACKAGE).with_suffix("")) for p in PACKAGE.rglob("*.py")
                  if p.name != "__init__.py")


def defines_tests(path: Path) -> bool:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return any(isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.name.startswith("test_")
               or isinstance(n, ast.ClassDef) and n.name.startswith("Test") for n in tree.body)


def test_every_module_is_placed_in_a_layer():
    placed = {m for mods in LAYERS.values() for m in mods} | set(APPLICATIONS) | set(EXEMPT)
    unplaced = sorted(set(modules()) - placed)
    assert not unplaced, f"modules in no layer (add them to LAYERS or APPLICATIONS in {Path(__file__).name}): {unplaced}"
    gone = sorted(placed - set(modules()) - set(EXEMPT))
    assert not gone, f"LAYERS/APPLICATIONS name modules that do not exist: {gone}"


def test_every_layer_module_has_a_test_file():
    missing = []
    for layer, mods in LAYERS.items():
        for mod in mods:
            if mod in EXEMPT:
                continue
            *pkg, name = mod.split("/")
            candidates = [TESTS / f"test_{name}.py"] + ([TESTS / f"test_{'_'.join(pkg)}_{name}.py"] if pkg else [])
            if not any(c.exists() and defines_tests(c) for c in candidates):
                missing.append(f"layer {layer} snoworm/{mod}.py: none of {[c.name for c in candidates]} defines tests")
    assert not missing, "modules without a mirroring test file:\n  " + "\n  ".join(missing)


def test_no_module_over_500_lines():
    long = [f"snoworm/{m}.py: {n} lines" for m in modules()
            if (n := len((PACKAGE / f"{m}.py").read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES]
    assert not long, f"modules over {MAX_MODULE_LINES} lines:\n  " + "\n  ".join(long)


def test_no_function_over_80_lines():
    long = []
    for m in modules():
        tree = ast.parse((PACKAGE / f"{m}.py").read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1          # from ``def`` to the last line of the body
                if n > MAX_FUNCTION_LINES:
                    long.append(f"snoworm/{m}.py:{node.lineno} {node.name}: {n} lines")
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines:\n  " + "\n  ".join(long)
