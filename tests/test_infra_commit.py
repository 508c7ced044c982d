"""A commit in place (entry by entry) interrupted between its renames (issue 30, section 2): readers
refuse the folder, the next command completes the commit; never an old manifest over a mix."""

from __future__ import annotations

import errno
import json
import multiprocessing
import os
import signal

import pytest
from click.testing import CliRunner

from snoworm.cli import main
from snoworm.infra.folders import MANIFEST, OutputError, check_output_folder, folder_state, output_folder
from snoworm.results.result import ResultFileError, load_result

CTX = multiprocessing.get_context("fork")
pytestmark = pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="needs fork")
JOURNAL = ".snoworm-commit.json"


def _write(out, files):
    with output_folder(out) as stage:
        for name, text in files.items():
            (stage / name).write_text(text)


def _killed_at_move(n, fn, *args):
    """Run ``fn(*args)`` in a child killed (SIGKILL) when it moves its n-th staged entry into place."""

    def child():
        real, moves = os.replace, []

        def replace(src, dst, *a, **kw):
            if ".snoworm-tmp-" in os.fspath(src) and ".snoworm-tmp-" not in os.fspath(dst):
                moves.append(dst)
                if len(moves) == n:
                    os.kill(os.getpid(), signal.SIGKILL)
            return real(src, dst, *a, **kw)

        os.replace = replace
        fn(*args)
        os._exit(0)

    p = CTX.Process(target=child)
    p.start()
    p.join(120)
    assert p.exitcode == -signal.SIGKILL


@pytest.fixture
def linked(tmp_path):
    """--out is a symlink (as a mount point, it cannot be renamed as a whole: committed in place)."""
    real = tmp_path / "real"
    real.mkdir()
    out = tmp_path / "out"
    out.symlink_to(real)
    return out, real


OLD = {"a.csv": "old a\n", "b.csv": "old b\n", "gone.csv": "old only\n"}
NEW = {"a.csv": "new a\n", "b.csv": "new b\n", "c.csv": "new c\n"}


def _contents(real):
    return {n: (real / n).read_text() for n in sorted(os.listdir(real)) if n.endswith(".csv")}


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_a_commit_killed_between_its_renames_is_completed_by_the_next_command(linked, n):
    out, real = linked
    _write(out, OLD)
    _killed_at_move(n, _write, out, NEW)  # the 4th move is the manifest's
    assert folder_state(out) == "foreign"  # never taken for a finished snoworm folder
    check_output_folder(out)  # the next command: completes the commit first
    assert _contents(real) == NEW
    assert sorted(json.loads((real / MANIFEST).read_text())["files"]) == sorted(NEW)
    assert folder_state(out) == "snoworm"
    assert sorted(os.listdir(out.parent)) == ["out", "real"]  # no staging folder left
    assert not (real / JOURNAL).exists()


def test_a_run_folder_with_an_unfinished_commit_is_refused_by_readers_and_completed_by_a_rerun(linked):
    out, real = linked
    args = ["run", "tow6_uniform", "--no-plot", "--out", str(out)]
    assert CliRunner().invoke(main, args + ["--set", "simulation.duration_s=2"]).exit_code == 0
    old = load_result(out)
    _killed_at_move(3, CliRunner().invoke, main, args + ["--set", "simulation.duration_s=3"])
    with pytest.raises(ResultFileError, match="unfinished commit"):
        load_result(out)  # segments.csv of one run, links.csv of the other: refused, not mixed
    r = CliRunner().invoke(main, args + ["--set", "simulation.duration_s=1"])  # any command there completes it
    assert r.exit_code == 0, r.output
    res = load_result(out)
    assert res.t[-1] == pytest.approx(1.0) and old.t[-1] == pytest.approx(2.0)
    assert not (real / JOURNAL).exists()


def test_an_unfinishable_commit_is_refused_naming_the_fix(linked):
    out, real = linked
    _write(out, OLD)
    _killed_at_move(2, _write, out, NEW)
    for e in os.listdir(out.parent):
        if ".snoworm-tmp-" in e:
            for f in os.listdir(out.parent / e):
                os.unlink(out.parent / e / f)
            os.rmdir(out.parent / e)
    with pytest.raises(OutputError, match="unfinished commit that snoworm cannot complete .* delete the folder"):
        check_output_folder(out)
    assert (real / JOURNAL).exists()


def test_a_crafted_journal_moves_nothing_from_outside_the_folder(tmp_path):
    outside = tmp_path / "elsewhere" / ".x.snoworm-tmp-1-a"
    outside.mkdir(parents=True)
    (outside / "secret.txt").write_text("keep")
    out = tmp_path / "out"
    out.mkdir()
    journal = {"stage": "../elsewhere/.x.snoworm-tmp-1-a", "inside": False, "entries": ["secret.txt", MANIFEST]}
    journal.update(remove=[], listed=[], manifest_sha256="0" * 64)
    (out / JOURNAL).write_text(json.dumps(journal))
    with pytest.raises(OutputError, match="staging folder is not a staging folder of this folder"):
        check_output_folder(out)
    assert (outside / "secret.txt").read_text() == "keep" and not (out / "secret.txt").exists()


def test_a_mount_point_out_is_committed_in_place_from_a_staging_folder_inside_it(tmp_path, monkeypatch):
    """--out a mount point (simulated: renaming it is EBUSY, renaming into it from outside EXDEV):
    every run exited 2 "Device or resource busy"; a staging folder beside it cannot reach it."""
    out = tmp_path / "mnt"
    out.mkdir()

    def inside(p):
        p = os.path.abspath(p)
        return p.startswith(str(out) + os.sep)

    def mount(real):
        def rename(src, dst, *a, **kw):
            if str(out) in (os.path.abspath(src), os.path.abspath(dst)):
                raise OSError(errno.EBUSY, "Device or resource busy", str(src))
            if inside(src) != inside(dst):
                raise OSError(errno.EXDEV, "Invalid cross-device link", str(src))
            return real(src, dst, *a, **kw)

        return rename

    monkeypatch.setattr(os, "rename", mount(os.rename))
    monkeypatch.setattr(os, "replace", mount(os.replace))
    _write(out, OLD)
    _write(out, NEW)
    assert _contents(out) == NEW and folder_state(out) == "snoworm"
    assert sorted(os.listdir(tmp_path)) == ["mnt"]
    assert sorted(os.listdir(out)) == sorted([*NEW, MANIFEST])  # no staging folder, probe or journal left


def test_load_sweep_refuses_a_folder_with_an_unfinished_commit(linked):
    from snoworm.studies.sweep import load_sweep, run_sweep
    from tests.sweep_helpers import SHORT, TOW6

    out, real = linked
    run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], out_dir=out, plot=False, progress=False)
    assert len(load_sweep(out)) == 2
    _killed_at_move(1, _write, out, NEW)  # another command's commit into it, killed half-way
    with pytest.raises(ResultFileError, match="unfinished commit"):
        load_sweep(out)


def test_a_journal_half_written_by_a_dead_process_is_cleaned_up(linked):
    out, real = linked
    _write(out, OLD)
    (real / f"{JOURNAL}.999999999.tmp").write_text('{"stage": ')
    _write(out, NEW)
    assert sorted(os.listdir(real)) == sorted([*NEW, MANIFEST])
