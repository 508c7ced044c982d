"""A results folder is self-contained (snoworm.results.copies, issue 30 section 3): it holds copies
of the files its run read, named relative to it in scenario.yaml and checked against the SHA-256
its manifest records; it reads back and re-runs wherever it is moved, whatever happens to the
originals."""

import hashlib
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
import yaml

from snoworm import load_scenario, run_sweep, simulate
from snoworm.infra.manifest import MANIFEST
from snoworm.results.result import ResultFileError, load_result
from tests.conftest import ROOT, SCENARIOS

ROUTE = SCENARIOS / "routes" / "ramp_drift.csv"

#: A parameter-set file of the user's own vehicle (a value with its source tag).
ROVER = """\
base: frostyboy
segment:
  mass_kg: {value: 95.0, source: "[field data] weighed 2026-01"}
"""


def _sources(tmp_path):
    """A scenario reading a route and a parameter-set file, both relative to its folder."""
    src = tmp_path / "src"
    (src / "routes").mkdir(parents=True)
    shutil.copy(ROUTE, src / "routes" / "drift.csv")
    (src / "rover.yaml").write_text(ROVER, encoding="utf-8")
    raw = yaml.safe_load((SCENARIOS / "ramp_drift.yaml").read_text(encoding="utf-8"))
    raw["terrain"]["route"] = "routes/drift.csv"
    raw["vehicle"]["parameter_set"] = "rover.yaml"
    raw["simulation"]["duration_s"] = 3.0
    (src / "scenario.yaml").write_text(yaml.safe_dump(raw), encoding="utf-8")
    return src


@pytest.fixture
def written(tmp_path):
    """(result, its folder, the scenario's source folder)."""
    src = _sources(tmp_path)
    res = simulate(load_scenario(src / "scenario.yaml"))
    res.write(tmp_path / "res", plot=False)
    return res, tmp_path / "res", src


def _table(sc):
    """The route a scenario read: distances, elevations and X_t."""
    r = sc.terrain.route_data()
    return r.distance_m, r.elevation_m, r.xt


def _sha(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_the_folder_holds_its_inputs_with_their_sha256(written):
    res, out, src = written
    data = yaml.safe_load((out / "scenario.yaml").read_text(encoding="utf-8"))
    assert data["terrain"]["route"] == "inputs/drift.csv"  # relative to the folder, never absolute
    assert data["vehicle"]["parameter_set"] == "inputs/rover.yaml"
    assert (out / "inputs" / "drift.csv").read_bytes() == (src / "routes" / "drift.csv").read_bytes()
    assert (out / "inputs" / "rover.yaml").read_bytes() == (src / "rover.yaml").read_bytes()
    man = json.loads((out / MANIFEST).read_text(encoding="utf-8"))
    assert man["inputs"] == {
        "inputs/drift.csv": _sha(src / "routes" / "drift.csv"),
        "inputs/rover.yaml": _sha(src / "rover.yaml"),
    }
    assert {"inputs/drift.csv", "inputs/rover.yaml"} <= set(man["files"])


def test_a_moved_folder_reads_back_without_its_originals(written, tmp_path):
    res, out, src = written
    moved = tmp_path / "elsewhere" / "moved"
    moved.parent.mkdir()
    os.rename(out, moved)
    shutil.rmtree(src)  # the originals are gone
    back = load_result(moved)
    assert back.scenario.vehicle.parameter_set == str(moved / "inputs" / "rover.yaml")
    assert back.scenario.vehicle.segment == res.scenario.vehicle.segment
    assert back.scenario.sources == res.scenario.sources  # the parameter set's tags, from its copy
    assert _table(back.scenario) == _table(res.scenario)
    np.testing.assert_allclose(back.segments["v_mps"], res.segments["v_mps"], rtol=5e-6, atol=1e-12)


def test_an_edited_original_does_not_change_what_is_read_back(written):
    res, out, src = written
    route = src / "routes" / "drift.csv"
    route.write_text(route.read_text(encoding="utf-8").replace(",0.9", ",0.5"), encoding="utf-8")
    assert _table(load_scenario(src / "scenario.yaml")) != _table(res.scenario)
    back = load_result(out)
    assert _table(back.scenario) == _table(res.scenario)


def test_the_copy_is_what_the_run_read_even_if_the_original_changed_before_writing(tmp_path):
    src = _sources(tmp_path)
    res = simulate(load_scenario(src / "scenario.yaml"))
    before = (src / "routes" / "drift.csv").read_bytes()
    (src / "routes" / "drift.csv").write_bytes(before.replace(b",0.9", b",0.5"))
    res.write(tmp_path / "res", plot=False)
    assert (tmp_path / "res" / "inputs" / "drift.csv").read_bytes() == before


def test_a_changed_copy_is_refused(written):
    res, out, src = written
    copy = out / "inputs" / "drift.csv"
    copy.write_bytes(copy.read_bytes().replace(b",0.9", b",0.5"))
    with pytest.raises(ResultFileError, match=r"inputs/drift\.csv: changed since the run was written \(SHA-256"):
        load_result(out)


def test_a_copy_without_a_recorded_sha256_is_refused(written):
    res, out, src = written
    (out / MANIFEST).unlink()  # copied without its manifest
    with pytest.raises(ResultFileError, match=r"inputs/drift\.csv: its SHA-256 is not recorded"):
        load_result(out)


def test_the_folders_scenario_reruns_from_any_working_folder(written, tmp_path):
    """``cd /elsewhere && snoworm run /path/to/results/scenario.yaml --out new`` reproduces the
    run, with the originals gone."""
    res, out, src = written
    shutil.rmtree(src)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    r = subprocess.run(
        [sys.executable, "-m", "snoworm", "run", str(out / "scenario.yaml"), "--out", "new", "--no-plot"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=elsewhere,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert r.returncode == 0, r.stdout + r.stderr
    for name in ("segments.csv", "links.csv", "inputs/drift.csv", "inputs/rover.yaml"):
        assert (elsewhere / "new" / name).read_bytes() == (out / name).read_bytes(), name


def test_a_sweeps_case_folders_are_self_contained(tmp_path):
    src = _sources(tmp_path)
    run_sweep(src / "scenario.yaml", ["tow.force_N=0,50"], tmp_path / "sw", save_cases=True, plot=False, progress=False)
    moved = tmp_path / "moved"
    os.rename(tmp_path / "sw", moved)
    shutil.rmtree(src)
    cases = sorted((moved / "cases").iterdir())
    assert len(cases) == 2
    for case in cases:
        back = load_result(case)
        assert back.scenario.terrain.route == str(case / "inputs" / "drift.csv")
        assert back.scenario.vehicle.segment.mass_kg == 95.0
    copy = cases[0] / "inputs" / "drift.csv"
    copy.write_bytes(copy.read_bytes() + b"# edited\n")
    with pytest.raises(ResultFileError, match="changed since the run was written"):
        load_result(cases[0])


@pytest.mark.parametrize("how", ["symlinked copy", "fifo copy", "symlinked folder", "deleted copy", "added file"])
def test_hostile_input_copies_are_refused_unread(written, tmp_path, how):
    """A copy replaced by a symlink or a FIFO (never opened: no hang), ``inputs/`` a symlink, a
    recorded copy deleted or an unrecorded file added: one ResultFileError naming the path."""
    res, out, src = written
    copy = out / "inputs" / "drift.csv"
    if how == "symlinked copy":
        copy.unlink()
        copy.symlink_to(src / "routes" / "drift.csv")  # same bytes, but outside the folder
    elif how == "fifo copy":
        copy.unlink()
        os.mkfifo(copy)
    elif how == "symlinked folder":
        shutil.move(out / "inputs", tmp_path / "away")
        (out / "inputs").symlink_to(tmp_path / "away", target_is_directory=True)
    elif how == "deleted copy":
        copy.unlink()
    else:
        (out / "inputs" / "extra.csv").write_text("distance_m,elevation_m,xt\n")
    with pytest.raises(ResultFileError) as err:
        load_result(out)
    assert str(out / "inputs") in str(err.value) and len(str(err.value)) < 600


def test_groundtruth_and_calibrate_keep_the_field_data_they_read(tmp_path):
    """The field data a ground truth compared with, or a calibration fitted, is in its folder as read."""
    from snoworm.studies.calibrate import run_calibration
    from snoworm.studies.field_data import default_data_path
    from snoworm.studies.groundtruth import run_groundtruth

    data = tmp_path / "runs.csv"
    shutil.copy(default_data_path(), data)
    _, _, gt_paths = run_groundtruth(tmp_path / "gt", data, plot=False)
    _, _, cal_paths = run_calibration(data, ["tau0"], tmp_path / "cal")
    for out, paths in ((tmp_path / "gt", gt_paths), (tmp_path / "cal", cal_paths)):
        copy = out / "inputs" / "runs.csv"
        assert copy in paths and copy.read_bytes() == data.read_bytes()
        man = json.loads((out / MANIFEST).read_text(encoding="utf-8"))
        assert man["inputs"] == {"inputs/runs.csv": _sha(data)}
