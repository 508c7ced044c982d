"""A sweep resumes only with the same inputs: file contents and the snoworm version (issue 24, high)."""

from __future__ import annotations

import json
import textwrap

import pytest
import yaml

from snoworm import run_sweep
from snoworm.config.schema import ScenarioError
from snoworm.studies.sweep import inputs
from snoworm.studies.sweep.inputs import changed_inputs, input_hashes, referenced_files
from snoworm.studies.sweep.spec import as_axes
from tests.conftest import SCENARIOS

CTL = """
    class Ctl:
        def __init__(self, params, scenario):
            self.v = {speed}
        def __call__(self, obs):
            return {{"wheel_speed_mps": [self.v] * len(obs.x_m)}}
"""


def _project(tmp_path, speed=0.5):
    (tmp_path / "ctl.py").write_text(textwrap.dedent(CTL.format(speed=speed)))
    raw = yaml.safe_load((SCENARIOS / "tow6_uniform.yaml").read_text())
    raw["mode"] = {"type": "controller", "controller": "ctl.py:Ctl", "period_s": 0.1, "params": {}}
    raw["simulation"]["duration_s"] = 1.0
    p = tmp_path / "s.yaml"
    p.write_text(yaml.safe_dump(raw))
    return p


def test_a_changed_controller_file_refuses_the_resume_naming_it_unless_restart(tmp_path):
    p = _project(tmp_path)
    out = tmp_path / "out"
    first = run_sweep(p, ["terrain.xt=0.8,0.9"], out_dir=out, progress=False, plot=False)
    _project(tmp_path, speed=1.5)  # the controller changed
    with pytest.raises(ScenarioError) as err:
        run_sweep(p, ["terrain.xt=0.8,0.9"], out_dir=out, progress=False, plot=False)
    assert str(tmp_path / "ctl.py") in str(err.value) and "--restart" in str(err.value)
    again = run_sweep(p, ["terrain.xt=0.8,0.9"], out_dir=out, progress=False, plot=False, restart=True)
    fresh = run_sweep(p, ["terrain.xt=0.8,0.9"], progress=False, plot=False)
    # the restarted rows are the new controller's: equal to a fresh run (same code path, same
    # solver settings: agreement to 1e-9 m), and unlike the old rows (1.0 vs 0.5 m/s commanded)
    for a, f, o in zip(again.rows, fresh.rows, first.rows):
        assert a["distance_m"] == pytest.approx(f["distance_m"], rel=1e-9)
        assert abs(a["distance_m"] - o["distance_m"]) > 0.2


def test_an_unchanged_sweep_still_resumes(tmp_path):
    p = _project(tmp_path)
    out = tmp_path / "out"
    run_sweep(p, ["terrain.xt=0.8"], out_dir=out, progress=False, plot=False)
    run_sweep(p, ["terrain.xt=0.8"], out_dir=out, progress=False, plot=False)
    d = json.loads((out / "sweep.json").read_text())["definition"]
    assert list(d["inputs"]) == [str((tmp_path / "ctl.py").resolve())] and d["snoworm_version"]


def test_another_snoworm_version_refuses_the_resume(tmp_path, monkeypatch):
    out = tmp_path / "out"
    run_sweep(
        SCENARIOS / "tow6_uniform.yaml",
        ["terrain.xt=0.8", "simulation.duration_s=1"],
        out_dir=out,
        progress=False,
        plot=False,
    )
    import snoworm.studies.sweep.run as plan_mod  # the resume key is the plan's (in run)

    monkeypatch.setattr(plan_mod, "__version__", "999.0")
    with pytest.raises(ScenarioError, match="run by snoworm .* this is 999.0"):
        run_sweep(
            SCENARIOS / "tow6_uniform.yaml",
            ["terrain.xt=0.8", "simulation.duration_s=1"],
            out_dir=out,
            progress=False,
            plot=False,
        )


def test_referenced_files_finds_parameter_sets_model_files_controllers_and_swept_paths(tmp_path):
    for name in ("ps.yaml", "m.yaml", "a.yaml", "b.yaml", "c.py"):
        (tmp_path / name).write_text("x: 1\n")
    raw = {
        "vehicle": {"parameter_set": "ps.yaml"},
        "terrain": {"model_file": "m.yaml"},
        "mode": {"controller": "c.py:C"},
        "description": "not/a/file and text:Here",
    }
    axes = as_axes(
        [("terrain.model_file", ["a.yaml", "b.yaml"]), ("mode.controller", ["tests.controller_helpers:Uniform"])]
    )
    found = referenced_files(raw, axes, tmp_path)
    names = sorted(p.rsplit("/", 1)[-1] for p in found)
    # a module controller: its source and its package's __init__.py (both run when it is imported)
    assert names == ["__init__.py", "a.yaml", "b.yaml", "c.py", "controller_helpers.py", "m.yaml", "ps.yaml"]
    h = input_hashes(raw, axes, tmp_path)
    (tmp_path / "m.yaml").write_text("x: 2\n")
    assert changed_inputs(h, input_hashes(raw, axes, tmp_path)) == [str((tmp_path / "m.yaml").resolve())]


WEIGHTS_CTL = """
    import numpy as np

    class Ctl:
        def __init__(self, params, scenario):
            self.v = float(np.load(params["weights"])["v"])
        def __call__(self, obs):
            return {"wheel_speed_mps": [self.v] * len(obs.x_m)}
"""


def test_a_changed_file_named_by_a_controller_param_refuses_the_resume_whatever_its_suffix(tmp_path, monkeypatch):
    """Issue 30: ``mode.params: {weights: w.npz}`` -- a file the controller reads, named by a value
    with a suffix the resume key ignored -- changed between two runs of a sweep: the resume mixed
    rows of the two weights.  Every file a value names is hashed now."""
    import numpy as np

    monkeypatch.chdir(tmp_path)  # the controller opens the value as given: from the working folder
    (tmp_path / "ctl.py").write_text(textwrap.dedent(WEIGHTS_CTL))
    np.savez(tmp_path / "w.npz", v=0.5)
    raw = yaml.safe_load((SCENARIOS / "tow6_uniform.yaml").read_text())
    raw["mode"] = {"type": "controller", "controller": "ctl.py:Ctl", "period_s": 0.1, "params": {"weights": "w.npz"}}
    raw["simulation"]["duration_s"] = 1.0
    p = tmp_path / "s.yaml"
    p.write_text(yaml.safe_dump(raw))
    out = tmp_path / "out"
    run_sweep(p, ["terrain.xt=0.8,0.9"], out_dir=out, progress=False, plot=False)
    inputs_now = json.loads((out / "sweep.json").read_text())["definition"]["inputs"]
    assert str((tmp_path / "w.npz").resolve()) in inputs_now
    np.savez(tmp_path / "w.npz", v=1.5)  # other weights
    with pytest.raises(ScenarioError, match="w.npz. changed since it ran"):
        run_sweep(p, ["terrain.xt=0.8,0.9"], out_dir=out, progress=False, plot=False)


def test_a_file_over_the_hash_bound_is_keyed_by_size_and_time(tmp_path, monkeypatch):
    monkeypatch.setattr(inputs, "MAX_HASHED_BYTES", 10)
    (tmp_path / "big.bin").write_bytes(b"x" * 11)
    (tmp_path / "small.bin").write_bytes(b"x" * 10)
    h = input_hashes({"a": "big.bin", "b": "small.bin"}, [], tmp_path)
    big, small = h[str(tmp_path / "big.bin")], h[str(tmp_path / "small.bin")]
    assert big.startswith("size 11 bytes") and len(small) == 64
    (tmp_path / "big.bin").write_bytes(b"y" * 12)
    assert changed_inputs(h, input_hashes({"a": "big.bin", "b": "small.bin"}, [], tmp_path)) == [
        str(tmp_path / "big.bin")
    ]
