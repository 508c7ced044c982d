"""Code trust lives in one room (issue 31, seam 4): the controller mode and its loader.

The allow-list (``--allow-code``, ``allow_code=``) is passed explicitly from the entry points
(the CLI, ``simulate``, a sweep's task) to the mode that loads code; no ambient state carries it,
and the physics driver neither reads it nor restores the working directory a controller changed.
"""

import ast
from pathlib import Path

import snoworm

PKG = Path(snoworm.__file__).parent
#: the room that loads user code, and the entry points that receive the user's allow-list
ROOM = {"modes/codeload.py", "modes/controller.py", "modes/base.py"}
ENTRY_POINTS = {
    "cli.py",
    "commands/common.py",
    "simulation/driver.py",
    "studies/sweep/plan.py",
    "studies/sweep/run.py",
    "studies/sweep/metrics.py",
    "studies/odds/run.py",
    "studies/odds/outcome.py",
}


def _names(path):
    tree = ast.parse(path.read_text())
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    names |= {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    names |= {a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names}
    return names


def test_only_the_room_and_the_entry_points_name_the_allow_list():
    users = {p.relative_to(PKG).as_posix() for p in PKG.rglob("*.py") if "allow_code" in _names(p)}
    assert users <= ROOM | ENTRY_POINTS, users - ROOM - ENTRY_POINTS


def test_the_driver_knows_nothing_of_code_trust():
    src = (PKG / "simulation" / "driver.py").read_text()
    names = _names(PKG / "simulation" / "driver.py")
    assert "codeload" not in src and "chdir" not in src and "getcwd" not in src
    assert not names & {"allowed_paths", "trust_problem", "import_class", "allowed_roots"}


def test_no_ambient_allow_list():
    """The allow-list is an argument everywhere: no context variable or global holds it."""
    src = (PKG / "modes" / "codeload.py").read_text()
    assert "ContextVar" not in src and "contextvars" not in src
