"""Folder locks (snoworm.infra.locks): no command replaces or writes a folder another process holds,
and a sweep writes nothing into a folder that is no longer the one it locked (issue 30, section 2)."""

from __future__ import annotations

import json
import multiprocessing
import os

import pytest
from click.testing import CliRunner

from snoworm.cli import main
from snoworm.infra.folders import LOCK, MANIFEST, FolderLocked, OutputError, folder_lock, output_folder
from snoworm.infra.locks import check_unlocked, try_folder_lock
from snoworm.studies.field_data import default_data_path
from snoworm.studies.sweep import run_sweep
from snoworm.studies.sweep.executors import SerialExecutor
from tests.sweep_helpers import SHORT, TOW6, csv_rows

CTX = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")


def _hold(folder, ready, release):
    with folder_lock(folder):
        ready.set()
        release.wait(60)


@pytest.fixture
def held(tmp_path):
    """A folder holding a sweep's results, locked by another live process (its PID)."""
    out = tmp_path / "X"
    run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], out_dir=out, plot=False, progress=False)
    before = {p: (out / p).read_bytes() for p in os.listdir(out)}
    ready, release = CTX.Event(), CTX.Event()
    p = CTX.Process(target=_hold, args=(out, ready, release))
    p.start()
    try:
        assert ready.wait(20)
        yield out, p.pid, before
    finally:
        release.set()
        p.join(20)


def _unchanged(out, before):
    after = {p: (out / p).read_bytes() for p in os.listdir(out) if p != LOCK}
    assert after == {p: b for p, b in before.items() if p != LOCK}


COMMANDS = {
    "run": ["run", "tow6_uniform", "--set", "simulation.duration_s=2", "--no-plot"],
    "terrain-curves": ["terrain-curves", "--xt", "0.5", "--no-plot"],
    "groundtruth": ["groundtruth", "--no-plot"],
    "mobility-map": ["mobility-map", "tow6_uniform", "--no-inching", "--xt", "0.5,0.9", "--no-plot"],
    "calibrate": ["calibrate", str(default_data_path()), "--fit", "tau0"],
    "paper": ["paper", "--quick"],
    "sweep": ["sweep", "tow6_uniform", "--set", "terrain.xt=0.7", "--set", "simulation.duration_s=2", "--no-plot"],
}


@pytest.mark.parametrize("overwrite", [False, True])
@pytest.mark.parametrize("cmd", list(COMMANDS))
def test_every_command_refuses_a_folder_another_process_holds(held, cmd, overwrite):
    out, pid, before = held
    args = COMMANDS[cmd] + ["--out", str(out)] + (["--overwrite"] if overwrite else [])
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2, r.output
    assert f"{out} is in use by process {pid}" in r.output and "another --out folder" in r.output
    assert "Traceback" not in r.output and "replaced when this command finishes" not in r.output
    _unchanged(out, before)


def test_result_write_refuses_a_folder_another_process_holds(held):
    from snoworm import simulate
    from snoworm.config.scenario import load_scenario

    out, pid, before = held
    res = simulate(load_scenario(TOW6, ["simulation.duration_s=1"]))
    with pytest.raises(FolderLocked, match=f"in use by process {pid}"):
        res.write(out, plot=False, overwrite=True)
    _unchanged(out, before)


def test_a_folder_locked_while_the_command_works_is_not_replaced_at_its_commit(tmp_path):
    """A sweep that starts in the folder after the command checked it (the folder was missing then)
    holds it at the commit: the command writes nothing (exit 2), the sweep's folder stays."""
    out = tmp_path / "X"
    with pytest.raises(FolderLocked, match="in use by process"):
        with output_folder(out) as stage:
            (stage / "a.csv").write_text("1\n")
            out.mkdir()
            (out / "mine.csv").write_text("sweep\n")
            p = CTX.Process(target=_hold, args=(out, ready := CTX.Event(), release := CTX.Event()))
            p.start()
            assert ready.wait(20)
    release.set()
    p.join(20)
    assert sorted(os.listdir(out)) == ["mine.csv"]
    assert [e for e in os.listdir(tmp_path) if e != "X"] == []  # no staging folder left


def test_a_folder_being_written_is_held_so_no_sweep_starts_in_it(tmp_path):
    out = tmp_path / "X"
    out.mkdir()
    with output_folder(out) as stage:
        (stage / "a.csv").write_text("1\n")
        with pytest.raises(FolderLocked, match=f"in use by process {os.getpid()}"):
            run_sweep(TOW6, ["terrain.xt=0.7", SHORT], out_dir=out, plot=False, progress=False)
    assert sorted(os.listdir(out)) == sorted(["a.csv", MANIFEST])  # the lock file is gone


def test_check_unlocked_creates_nothing_and_a_released_lock_is_free(tmp_path):
    check_unlocked(tmp_path)
    assert os.listdir(tmp_path) == []
    lease = try_folder_lock(tmp_path)
    with pytest.raises(FolderLocked):
        check_unlocked(tmp_path)
    lease.release()
    check_unlocked(tmp_path)
    assert os.listdir(tmp_path) == []


def test_a_symlinked_lock_file_is_never_written_through(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep")
    out = tmp_path / "X"
    out.mkdir()
    (out / LOCK).symlink_to(victim)
    with pytest.raises(OutputError, match="cannot lock the folder"):
        with folder_lock(out):
            pass
    assert victim.read_text() == "keep"


class _Replacing(SerialExecutor):
    """Runs the cases; before the second, the sweep's folder is moved away and a new one made there
    (as ``mv X Y; mkdir X`` or an older snoworm replacing it would)."""

    def __init__(self, out):
        super().__init__()
        self.out = out

    def map_unordered(self, fn, tasks):
        for i, task in enumerate(tasks):
            if i == 1:
                os.rename(self.out, self.out.parent / "moved")
                self.out.mkdir()
                (self.out / "theirs.txt").write_text("theirs\n")
            yield fn(task)


@pytest.mark.parametrize("save", [False, True], ids=["rows", "save-cases"])
def test_a_sweep_writes_nothing_into_a_folder_that_replaced_the_one_it_locked(tmp_path, save):
    out = tmp_path / "X"
    with pytest.raises(OutputError, match="removed, moved or replaced while"):
        run_sweep(
            TOW6,
            ["terrain.xt=0.6,0.7,0.8,0.9", SHORT],
            out_dir=out,
            executor=_Replacing(out),
            progress=False,
            save_cases=save,
        )
    assert sorted(os.listdir(out)) == ["theirs.txt"]  # no manifest, row, case folder or plot in the new folder
    moved = tmp_path / "moved"
    assert json.loads((moved / MANIFEST).read_text())["status"] == "running"  # never claims complete
    assert len(csv_rows(moved / "summary.csv")) == 1  # the row of the case before the move only
