"""Layout rules of the package (issue #12), checked from the source with ``ast``.

* Tests mirror modules: every module (but the faces and the version string) has one test file
  named after its path in the package, ``/`` becoming ``_``, defining at least one test:
  ``snoworm/dynamics.py`` -> ``tests/test_dynamics.py``, ``snoworm/config/scenario.py`` ->
  ``tests/test_config_scenario.py``, ``snoworm/studies/sweep/run.py`` ->
  ``tests/test_studies_sweep_run.py``.  Test files of no single module (``test_docs.py``,
  ``test_fuzz.py``, ...) may sit beside them.
* No length limits (issue 31): a module grows as long as its one idea needs.  What a reader must
  follow is held instead by ruff's complexity rules (``C901``, ``PLR0912``, ``PLR0915``; the maxima
  and why in pyproject.toml ``[tool.ruff.lint]``), which ``make lint`` runs; the test below checks
  they are in force.
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


#: the complexity rules and where their maxima are set in pyproject.toml
COMPLEXITY_RULES = {
    "C901": ("mccabe", "max-complexity"),
    "PLR0912": ("pylint", "max-branches"),
    "PLR0915": ("pylint", "max-statements"),
}


def _too_complex_function(n: int) -> str:
    """A function of ``n`` sequential ifs: complexity n + 1, n branches, 2 n + 1 statements."""
    body = "".join(f"    if x == {k}:\n        y = {k}\n" for k in range(n))
    return f"def f(x):\n    y = 0\n{body}    return y\n"


def test_the_complexity_rules_are_in_force(tmp_path):
    # the three rules are selected with stated maxima, and ruff run with the project's settings
    # flags a function just over each maximum and passes one at it
    try:
        import tomllib
    except ImportError:  # Python 3.10
        import tomli as tomllib
    pyproject = PACKAGE.parent / "pyproject.toml"
    lint = tomllib.loads(pyproject.read_text(encoding="utf-8"))["tool"]["ruff"]["lint"]
    assert set(COMPLEXITY_RULES) <= set(lint["select"])
    maxima = {rule: lint[section][key] for rule, (section, key) in COMPLEXITY_RULES.items()}
    assert all(isinstance(v, int) and v > 0 for v in maxima.values()), maxima
    n_ok = min(maxima["C901"] - 1, maxima["PLR0912"], (maxima["PLR0915"] - 1) // 2)
    n_over = max(maxima["C901"], maxima["PLR0912"] + 1, (maxima["PLR0915"] + 1) // 2)
    shutil.copy(pyproject, tmp_path / "pyproject.toml")
    (tmp_path / "ok.py").write_text(_too_complex_function(n_ok), encoding="utf-8")
    (tmp_path / "over.py").write_text(_too_complex_function(n_over), encoding="utf-8")
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "ruff",
            "check",
            "--no-cache",
            "--output-format",
            "concise",
            "--select",
            ",".join(COMPLEXITY_RULES),
            ".",
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert "ok.py" not in r.stdout, r.stdout
    assert all(f"over.py:1:5: {rule}" in r.stdout for rule in COMPLEXITY_RULES), r.stdout + r.stderr
