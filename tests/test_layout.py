"""Layout rules of the package (issue #12), checked from the source with ``ast``.

* Tests mirror modules: every module (but the faces and the version string) has one test file
  named after its path in the package, ``/`` becoming ``_``, defining at least one test:
  ``snoworm/dynamics.py`` -> ``tests/test_dynamics.py``, ``snoworm/config/scenario.py`` ->
  ``tests/test_config_scenario.py``, ``snoworm/studies/sweep/run.py`` ->
  ``tests/test_studies_sweep_run.py``.  Test files of no single module (``test_docs.py``,
  ``test_fuzz.py``, ...) may sit beside them.
* No module is over 500 lines and no function (or method) over 80 lines, also once the code is
  laid out by ``ruff format`` (so nothing is kept under a limit by joining lines).
* Which layer a module belongs to is the import-linter contract in pyproject.toml (``exhaustive``:
  a new module must be placed there), checked by tests/test_architecture.py; not repeated here.

The offenders are listed in the assertion messages.
"""

import ast
import shutil
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "snoworm"
TESTS = Path(__file__).resolve().parent
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80

#: modules without the mirror rule besides every __init__.py: the faces (tests/test_cli.py tests
#: the CLI) and the version string
EXEMPT = ("cli", "__main__", "_version")


def modules():
    """Every module of the package as ``name`` or ``package/name`` (no ``__init__``)."""
    return sorted(str(p.relative_to(PACKAGE).with_suffix("")) for p in PACKAGE.rglob("*.py") if p.name != "__init__.py")


def defines_tests(path: Path) -> bool:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return any(
        isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
        and n.name.startswith("test_")
        or isinstance(n, ast.ClassDef)
        and n.name.startswith("Test")
        for n in tree.body
    )


def test_every_module_has_a_test_file():
    missing = []
    for mod in modules():
        if mod in EXEMPT:
            continue
        mirror = TESTS / f"test_{mod.replace('/', '_')}.py"
        if not (mirror.exists() and defines_tests(mirror)):
            missing.append(f"snoworm/{mod}.py: tests/{mirror.name} does not exist or defines no test")
    assert not missing, "modules without a mirroring test file:\n  " + "\n  ".join(missing)


def long_modules(package: Path = PACKAGE) -> list:
    return [
        f"snoworm/{m}.py: {n} lines"
        for m in modules()
        if (n := len((package / f"{m}.py").read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES
    ]


def long_functions(package: Path = PACKAGE) -> list:
    long = []
    for m in modules():
        tree = ast.parse((package / f"{m}.py").read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1  # from ``def`` to the last line of the body
                if n > MAX_FUNCTION_LINES:
                    long.append(f"snoworm/{m}.py:{node.lineno} {node.name}: {n} lines")
    return long


def test_no_module_over_500_lines():
    long = long_modules()
    assert not long, f"modules over {MAX_MODULE_LINES} lines:\n  " + "\n  ".join(long)


def test_no_function_over_80_lines():
    long = long_functions()
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines:\n  " + "\n  ".join(long)


def test_the_sizes_hold_once_formatted(tmp_path):
    # no module or function is kept under a limit by joining lines: the limits hold for the code
    # as `ruff format` lays it out (run on a copy; ruff is in the test extra)
    shutil.copytree(PACKAGE, tmp_path / "snoworm", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(PACKAGE.parent / "pyproject.toml", tmp_path / "pyproject.toml")  # the line length
    r = subprocess.run(
        [sys.executable, "-m", "ruff", "format", "--quiet", "."],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    long = long_modules(tmp_path / "snoworm") + long_functions(tmp_path / "snoworm")
    assert not long, "over the size limits once formatted:\n  " + "\n  ".join(long)
