"""Reading never runs code; running code is a choice the user can see (issue 24, critical).

Every controller here leaves a marker file when its module is imported or its class constructed,
so each test can assert that reading a scenario, a result or a sweep ran nothing.
"""

from __future__ import annotations

import json
import os
import sys
import textwrap

import pytest
import yaml
from click.testing import CliRunner

from snoworm import load_result, load_scenario, load_sweep, run_sweep, simulate
from snoworm.cli import main
from snoworm.config.schema import ScenarioError
from snoworm.modes.codeload import check_reference, find_module_source, trust_problem
from tests.conftest import SCENARIOS

EVIL = """
    import pathlib
    pathlib.Path({marker!r}).write_text("imported")

    class Ctl:
        def __init__(self, params, scenario):
            pathlib.Path({marker!r} + ".init").write_text("constructed")
        def __call__(self, obs):
            return {{"wheel_speed_mps": [0.2] * len(obs.x_m)}}
"""


def cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _scenario(folder, controller, name="s.yaml"):
    raw = yaml.safe_load((SCENARIOS / "tow6_uniform.yaml").read_text())
    raw["mode"] = {"type": "controller", "controller": controller, "period_s": 0.1, "params": {}}
    raw["simulation"]["duration_s"] = 1.0
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / name
    p.write_text(yaml.safe_dump(raw))
    return p


def _controller(path, marker):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(EVIL.format(marker=str(marker))))
    return path


@pytest.fixture
def marker(tmp_path):
    return tmp_path / "MARKER"


def _ran(marker):
    return marker.exists() or marker.with_name(marker.name + ".init").exists()


def test_reading_a_scenario_never_imports_its_controller(tmp_path, marker):
    _controller(tmp_path / "proj" / "ctl.py", marker)
    p = _scenario(tmp_path / "proj", "ctl.py:Ctl")
    load_scenario(p)
    r = cli("validate", p)
    assert r.exit_code == 0, r.output
    r = cli(
        "validate",
        SCENARIOS / "tow6_uniform.yaml",
        "--set",
        f"mode={{type: controller, controller: '{tmp_path / 'proj' / 'ctl.py'}:Ctl', period_s: 0.1}}",
        "--allow-code",
        tmp_path / "proj",
    )
    assert r.exit_code == 0, r.output
    r = cli("mobility-map", p, "--xt", "0.7:0.9:2", "--tow", "0", "--out", tmp_path / "mm", "--no-plot")
    assert r.exit_code == 2  # a controller does not roll at one speed
    assert not _ran(marker)


def test_a_sweeps_planning_never_imports_and_the_run_does(tmp_path, marker):
    _controller(tmp_path / "proj" / "ctl.py", marker)
    p = _scenario(tmp_path / "proj", "ctl.py:Ctl")
    r = cli("sweep", p, "--set", "terrain.xt=0.7,0.9,1e9", "--set", "simulation.duration_s=-1", "--out", tmp_path / "s")
    assert r.exit_code == 2 and "every case of the sweep is invalid" in r.output
    assert not _ran(marker)
    table = run_sweep(p, ["terrain.xt=0.8"], out_dir=tmp_path / "ok", progress=False, plot=False)
    assert table.rows[0]["status"] == "ok" and _ran(marker)
    marker.unlink()
    marker.with_name(marker.name + ".init").unlink()
    load_sweep(tmp_path / "ok")
    assert not _ran(marker)


def test_load_result_never_runs_code_whatever_its_scenario_yaml_says(tmp_path, marker):
    _controller(tmp_path / "proj" / "ctl.py", marker)
    res = simulate(load_scenario(_scenario(tmp_path / "proj", "ctl.py:Ctl")))
    res.write(tmp_path / "run", plot=False)
    os.unlink(marker)
    os.unlink(marker.with_name(marker.name + ".init"))
    # a received folder: its scenario.yaml names a file inside it
    _controller(tmp_path / "run" / "evil.py", marker)
    sy = tmp_path / "run" / "scenario.yaml"
    sy.write_text(sy.read_text().replace(str(tmp_path / "proj" / "ctl.py"), str(tmp_path / "run" / "evil.py")))
    back = load_result(tmp_path / "run")
    assert back.scenario.mode.controller.startswith(str(tmp_path / "run" / "evil.py"))
    assert not _ran(marker)
    with pytest.raises(ScenarioError, match="load_result"):  # nor later, unless allowed
        simulate(back.scenario)
    assert not _ran(marker)
    simulate(back.scenario, allow_code=[tmp_path / "run"])
    assert _ran(marker)


def test_a_controller_outside_the_scenario_folder_needs_allow_code(tmp_path, marker):
    _controller(tmp_path / "elsewhere" / "ctl.py", marker)
    p = _scenario(tmp_path / "proj", "../elsewhere/ctl.py:Ctl")
    for cmd in (
        ["validate", p],
        ["run", p, "--out", tmp_path / "o", "--no-plot"],
        ["sweep", p, "--set", "terrain.xt=0.8", "--out", tmp_path / "s", "--no-plot"],
    ):
        r = cli(*cmd)
        assert r.exit_code == 2, r.output
        assert "outside the scenario's folder" in r.output and "--allow-code" in r.output
    assert not _ran(marker) and not (tmp_path / "o").exists() and not (tmp_path / "s" / "summary.csv").exists()
    with pytest.raises(ScenarioError, match="allow"):
        simulate(load_scenario(p))
    r = cli("run", p, "--out", tmp_path / "o", "--no-plot", "--allow-code", tmp_path / "elsewhere")
    assert r.exit_code == 0, r.output
    assert "running controller code" in r.output  # the notice (stderr) names the file
    assert str(tmp_path / "elsewhere" / "ctl.py") in r.output
    assert _ran(marker)


def test_a_symlink_cannot_escape_the_scenario_folder(tmp_path, marker):
    _controller(tmp_path / "elsewhere" / "ctl.py", marker)
    (tmp_path / "proj").mkdir()
    os.symlink(tmp_path / "elsewhere", tmp_path / "proj" / "link")
    p = _scenario(tmp_path / "proj", "link/ctl.py:Ctl")
    r = cli("run", p, "--out", tmp_path / "o", "--no-plot")
    assert r.exit_code == 2 and "outside the scenario's folder" in r.output, r.output
    assert not _ran(marker)


@pytest.mark.parametrize(
    "ref, words",
    [
        ("this:C", ["standard library"]),
        ("builtins:print", ["standard library"]),
        ("os.path:join", ["standard library"]),
        ("tests.controller_helpers:schedule", ["no class 'schedule'", "Uniform"]),
        ("tests.test_modes_codeload:ScenarioError", ["no class 'ScenarioError'"]),  # an import, not a definition
        ("ctl:Ctl", ["not found"]),
        ("a" * 5000 + ".py:C", ["longer than"]),
        ("ctl\x00.py:Ctl", ["NUL"]),
        ("ctl.txt/x:Ctl", ["does not end in .py"]),
        ("loop.py:Ctl", ["cannot be used"]),
        ("dir.py:Ctl", ["not a regular file"]),
        ("broken.py:Ctl", ["does not parse"]),
        ("fn.py:Ctl", ["no class 'Ctl'"]),
    ],
)
def test_bad_references_are_exit_2_naming_the_field_and_run_nothing(tmp_path, capsys, ref, words):
    (tmp_path / "proj").mkdir()
    os.symlink("loop.py", tmp_path / "proj" / "loop.py")
    (tmp_path / "proj" / "dir.py").mkdir()
    (tmp_path / "proj" / "broken.py").write_text("class Ctl(:\n")
    (tmp_path / "proj" / "fn.py").write_text("def Ctl(params, scenario):\n    return print\n")
    p = _scenario(tmp_path / "proj", ref)
    r = cli("validate", p)
    assert r.exit_code == 2, r.output
    assert "mode.controller" in r.output and "internal error" not in r.output
    for w in words:
        assert w in r.output
    assert "Beautiful is better than ugly" not in r.output + capsys.readouterr().out  # `this` never imported


def test_a_module_reference_is_found_without_importing_its_packages(tmp_path, marker, monkeypatch):
    pkg = tmp_path / "mypkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text(f"import pathlib\npathlib.Path({str(marker)!r}).write_text('parent')\n")
    (pkg / "sub" / "__init__.py").write_text("")
    _controller(pkg / "sub" / "ctl.py", marker)
    monkeypatch.syspath_prepend(str(tmp_path))
    assert find_module_source("mypkg.sub.ctl", "x") == (pkg / "sub" / "ctl.py").resolve()
    check_reference("mypkg.sub.ctl:Ctl")
    load_scenario(_scenario(tmp_path / "proj", "mypkg.sub.ctl:Ctl"))
    assert not _ran(marker) and "mypkg" not in sys.modules
    monkeypatch.delitem(sys.modules, "mypkg", raising=False)


def test_trust_problem_with_and_without_an_allowed_path(tmp_path):
    f = tmp_path / "a" / "c.py"
    assert trust_problem(f"{f}:C", tmp_path) is None
    assert "outside" in trust_problem(f"{f}:C", tmp_path / "b")
    allowed = [tmp_path / "a"]  # passed explicitly: no ambient state to leak into a later call
    assert trust_problem(f"{f}:C", tmp_path / "b", allowed=allowed) is None
    assert trust_problem(f"{f}:C", None, allowed=allowed) is None
    assert "outside" in trust_problem(f"{f}:C", tmp_path / "b")
    assert "load_result" in trust_problem(f"{f}:C", None)
    assert trust_problem("yaml:YAMLObject", None) is None  # installed code (site-packages): no file rule
    assert trust_problem("snoworm.modes.uniform:UniformMode", None) is None  # snoworm itself


def test_shipped_example_controllers_still_validate_and_run_from_their_folder(tmp_path):
    ex = SCENARIOS.parent / "examples" / "controllers" / "tow6_uniform_controller.yaml"
    r = cli("run", ex, "--out", tmp_path / "o", "--no-plot", "--set", "simulation.duration_s=1")
    assert r.exit_code == 0, r.output
    assert "running controller code" in r.output
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["controller_calls"] > 0


HUGE = """
    import os

    class Ctl:
        def __init__(self, params, scenario):
            if params.get("chdir"):
                os.chdir(params["chdir"])
        def __call__(self, obs):
            if obs.t_s > 0.15 and not self.__dict__.get("quiet"):
                raise RuntimeError("x" * 1_000_000)
            return {"wheel_speed_mps": [0.5] * len(obs.x_m)}
"""


def test_a_controller_raising_a_1_mb_message_prints_a_short_one(tmp_path):
    (tmp_path / "proj").mkdir()
    (tmp_path / "proj" / "ctl.py").write_text(textwrap.dedent(HUGE))
    p = _scenario(tmp_path / "proj", "ctl.py:Ctl")
    r = cli("run", p, "--out", tmp_path / "o", "--no-plot")
    assert r.exit_code == 1 and "controller raised at t = 0.2 s" in r.output, r.output[:500]
    assert len(r.output) < 5000 and "characters cut" in r.output


def test_a_controllers_chdir_does_not_move_a_relative_out(tmp_path, monkeypatch):
    (tmp_path / "proj").mkdir()
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "proj" / "ctl.py").write_text(textwrap.dedent(HUGE.replace("obs.t_s > 0.15", "obs.t_s > 1e9")))
    p = _scenario(tmp_path / "proj", "ctl.py:Ctl")
    monkeypatch.chdir(tmp_path)
    r = cli("run", p, "--out", "rel_out", "--no-plot", "--set", f"mode.params.chdir={tmp_path / 'elsewhere'}")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "rel_out" / "summary.json").exists() and not (tmp_path / "elsewhere" / "rel_out").exists()


def test_a_module_of_an_editable_install_is_found_without_importing_it(tmp_path, monkeypatch):
    """`pip install -e` maps a package with a meta path finder, not a sys.path entry: the static
    check asks the meta path's finders for the top-level package (the battery found such
    packages refused as 'not found on the Python path'), and still imports nothing."""
    import importlib.machinery

    from snoworm.modes.codeload import find_module_source

    pkg = tmp_path / "src" / "edctl_pkg"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("raise RuntimeError('imported')\n")
    (pkg / "pi.py").write_text("class PI:\n    pass\n")

    class EditableFinder:  # what setuptools' editable finder does: a mapping of names to folders
        @classmethod
        def find_spec(cls, fullname, path=None, target=None):
            if fullname == "edctl_pkg":
                return importlib.machinery.PathFinder.find_spec(fullname, [str(pkg.parent)])
            return None

    monkeypatch.setattr(sys, "meta_path", [*sys.meta_path, EditableFinder])
    assert find_module_source("edctl_pkg.pi", "s.yaml") == (pkg / "pi.py").resolve()
    assert "edctl_pkg" not in sys.modules
    with pytest.raises(ScenarioError, match="edctl_pkg.nope"):
        find_module_source("edctl_pkg.nope", "s.yaml")


# ------------------------------------------------------------------ issue 30: module references, bytecode, --allow-code ''
def _fresh_cli(*args, cwd, extra_path=None):
    """``python -m snoworm ARGS`` in a fresh process run from ``cwd`` (this worktree's snoworm)."""
    import subprocess

    root = str(SCENARIOS.parent)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([root] + ([str(extra_path)] if extra_path else []))}
    return subprocess.run(
        [sys.executable, "-m", "snoworm", *[str(a) for a in args]],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_a_module_in_the_working_folder_runs_only_when_allowed(tmp_path, marker):
    """`python -m snoworm` (and PYTHONPATH=., python -c, a notebook) puts the working folder on the
    path: a scenario naming `ctl:Ctl` ran the working folder's ctl.py without --allow-code."""
    _controller(tmp_path / "work" / "ctl.py", marker)
    p = _scenario(tmp_path / "proj", "ctl:Ctl")
    r = _fresh_cli("run", p, "--out", tmp_path / "o", "--no-plot", cwd=tmp_path / "work")
    assert r.returncode == 2, r.stderr
    assert "not installed code" in r.stderr and "--allow-code" in r.stderr and str(tmp_path / "work") in r.stderr
    assert "Traceback" not in r.stderr and not _ran(marker) and not (tmp_path / "o").exists()
    r = _fresh_cli("run", p, "--out", tmp_path / "o2", "--no-plot", cwd=tmp_path, extra_path=tmp_path / "work")
    assert r.returncode == 2 and not _ran(marker), r.stderr  # PYTHONPATH: the same rule
    r = _fresh_cli("run", p, "--out", tmp_path / "o", "--no-plot", "--allow-code", ".", cwd=tmp_path / "work")
    assert r.returncode == 0, r.stderr
    assert _ran(marker)


def test_a_module_named_by_a_read_back_result_never_runs_unless_allowed(tmp_path, marker, monkeypatch):
    _controller(tmp_path / "work" / "ctl.py", marker)
    monkeypatch.syspath_prepend(str(tmp_path / "work"))  # a notebook in that folder
    sc = load_scenario(_scenario(tmp_path / "proj", "ctl:Ctl"))
    with pytest.raises(ScenarioError, match="not installed code.*outside the scenario's folder"):
        simulate(sc)
    assert not _ran(marker)
    simulate(sc, allow_code=[tmp_path / "work"]).write(tmp_path / "run", plot=False)
    assert _ran(marker)
    marker.unlink()
    marker.with_name(marker.name + ".init").unlink()
    sys.modules.pop("ctl", None)
    back = load_result(tmp_path / "run")
    with pytest.raises(ScenarioError, match="load_result"):
        simulate(back.scenario)
    assert not _ran(marker)
    # in a scenario's own folder tree a module follows the file rule: it may run
    _controller(tmp_path / "proj" / "ctl2.py", marker)
    monkeypatch.syspath_prepend(str(tmp_path / "proj"))
    assert trust_problem("ctl2:Ctl", tmp_path / "proj") is None
    assert "load_result" in trust_problem("ctl2:Ctl", None)


def _plant_bytecode(source_py, evil_source):
    """A ``__pycache__`` file beside ``source_py`` holding ``evil_source`` compiled, stamped with
    the .py's mtime and size: Python's import would run it instead of the .py."""
    import importlib._bootstrap_external as be
    import importlib.util

    st = os.stat(source_py)
    code = compile(textwrap.dedent(evil_source), str(source_py), "exec")
    pyc = importlib.util.cache_from_source(str(source_py))
    os.makedirs(os.path.dirname(pyc), exist_ok=True)
    with open(pyc, "wb") as fh:
        fh.write(be._code_to_timestamp_pyc(code, int(st.st_mtime), st.st_size))
    return pyc


GOOD_CTL = """
class Ctl:
    def __init__(self, params, scenario):
        pass
    def __call__(self, obs):
        return {"wheel_speed_mps": [0.2] * len(obs.x_m)}
"""


def test_cached_bytecode_never_runs_instead_of_the_checked_source(tmp_path, marker, monkeypatch):
    """A crafted __pycache__/ctl.cpython-3XY.pyc with the .py's mtime and size ran instead of the
    harmless source that was checked and hashed; a module's package __init__ the same."""
    (tmp_path / "proj").mkdir()
    src = tmp_path / "proj" / "ctl.py"
    src.write_text(GOOD_CTL)
    _plant_bytecode(src, EVIL.format(marker=str(marker)))
    res = simulate(load_scenario(_scenario(tmp_path / "proj", "ctl.py:Ctl")))
    assert res.mode_summary["controller_calls"] > 0 and not _ran(marker)
    # a module that is not installed code: its package's __init__ and its own source, from the bytes
    pkg = tmp_path / "proj" / "cpkg30"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "mod.py").write_text(GOOD_CTL)
    _plant_bytecode(pkg / "__init__.py", f"import pathlib\npathlib.Path({str(marker)!r}).write_text('init')\n")
    _plant_bytecode(pkg / "mod.py", EVIL.format(marker=str(marker)))
    monkeypatch.syspath_prepend(str(tmp_path / "proj"))
    for m in ("cpkg30", "cpkg30.mod"):
        monkeypatch.delitem(sys.modules, m, raising=False)
    res = simulate(load_scenario(_scenario(tmp_path / "proj", "cpkg30.mod:Ctl")))
    assert res.mode_summary["controller_calls"] > 0 and not _ran(marker)
    assert sys.modules["cpkg30.mod"].__file__ == str(pkg / "mod.py")


def test_an_empty_allow_code_path_is_exit_2_not_the_whole_working_folder(tmp_path, marker, monkeypatch):
    _controller(tmp_path / "elsewhere" / "ctl.py", marker)
    p = _scenario(tmp_path / "proj", "../elsewhere/ctl.py:Ctl")
    monkeypatch.chdir(tmp_path)  # '' resolved to the working folder, holding elsewhere/
    for cmd in (
        ["run", p, "--out", tmp_path / "o", "--no-plot"],
        ["validate", p],
        ["sweep", p, "--out", tmp_path / "s"],
    ):
        r = cli(*cmd, "--allow-code", "")
        assert r.exit_code == 2, r.output
        assert "empty path" in r.output and "Traceback" not in r.output
    assert not _ran(marker) and not (tmp_path / "o").exists()
    with pytest.raises(ScenarioError, match="empty path"):
        simulate(load_scenario(p), allow_code=[""])
    with pytest.raises(ScenarioError, match="empty path"):
        run_sweep(p, ["terrain.xt=0.8"], out_dir=tmp_path / "s2", progress=False, plot=False, allow_code=[""])
    assert not _ran(marker)
