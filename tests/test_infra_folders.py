"""Atomic file writing (snoworm.infra.folders): a reader never sees a half-written file; durable output
folders: every staged file is on disk before the folder appears."""

import errno
import os

import pytest

from snoworm.infra import folders
from snoworm.infra.folders import MANIFEST, OutputError, atomic_path, atomic_write_text, output_folder, sync_files


def test_atomic_write_text_writes_and_replaces(tmp_path):
    p = tmp_path / "sub" / "out.csv"
    assert atomic_write_text(p, "a,b\n1,2\n") == p  # creates the directory
    assert p.read_text() == "a,b\n1,2\n"
    atomic_write_text(p, "new\n")
    assert p.read_text() == "new\n"
    assert sorted(x.name for x in p.parent.iterdir()) == ["out.csv"]


def test_failure_leaves_no_temp_file_and_the_old_file_intact(tmp_path):
    p = tmp_path / "summary.json"
    p.write_text("old")
    with pytest.raises(RuntimeError, match="disk full"):
        with atomic_path(p) as tmp:
            tmp.write_text("half of the new conte")
            assert tmp.parent == p.parent and tmp.exists()
            raise RuntimeError("disk full")
    assert p.read_text() == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["summary.json"]


def test_failure_before_any_file_leaves_nothing(tmp_path):
    p = tmp_path / "new.txt"
    with pytest.raises(KeyboardInterrupt):  # BaseException too: interrupted writes clean up
        with atomic_path(p):
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_failure_of_text_encoding_leaves_no_temp_file(tmp_path):
    p = tmp_path / "bad.txt"
    with pytest.raises(UnicodeEncodeError):
        atomic_write_text(p, "surrogate \udcff")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ file modes
import json  # noqa: E402
import multiprocessing  # noqa: E402
import stat  # noqa: E402

from snoworm.infra.folders import (  # noqa: E402
    LOCK,
    FolderLocked,
    check_output_folder,
    folder_lock,
    folder_state,
    read_manifest,
)


@pytest.fixture
def umask022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def mode(p):
    return stat.S_IMODE(os.stat(p).st_mode)


def test_files_honour_the_umask_not_the_temp_files_0600(tmp_path, umask022):
    p = atomic_write_text(tmp_path / "a.csv", "x\n")
    assert mode(p) == 0o644
    os.umask(0o077)
    assert mode(atomic_write_text(tmp_path / "b.csv", "x\n")) == 0o600


def _write(folder, names):
    with output_folder(folder, command="test") as stage:
        for n in names:
            atomic_write_text(stage / n, n)
    return folder


def test_output_folder_writes_a_manifest_and_the_umask_modes(tmp_path, umask022):
    out = _write(tmp_path / "run", ["segments.csv", "sub/x.txt"])
    man = read_manifest(out)
    assert man["files"] == ["segments.csv", "sub/x.txt"] and man["command"] == "test"
    assert man["snoworm_version"] == folders.__version__
    assert mode(out) == 0o755 and mode(out / "segments.csv") == 0o644
    assert folder_state(out) == "snoworm"
    assert sorted(os.listdir(tmp_path)) == ["run"]  # no staging folder left


def test_an_earlier_runs_files_never_remain_beside_the_new_ones(tmp_path):
    out = _write(tmp_path / "run", ["segments.csv", "force_diagram.png"])
    _write(out, ["segments.csv", "links.csv"])
    assert sorted(os.listdir(out)) == sorted([MANIFEST, "segments.csv", "links.csv"])
    assert (out / "segments.csv").read_text() == "segments.csv"
    assert sorted(os.listdir(tmp_path)) == ["run"]


def test_a_foreign_folder_is_refused_naming_it_and_overwrite(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    with pytest.raises(OutputError) as err:
        _write(out, ["a.csv"])
    assert str(out) in str(err.value) and "--overwrite" in str(err.value)
    assert sorted(os.listdir(tmp_path)) == ["mine"] and os.listdir(out) == ["notes.txt"]
    with output_folder(out, overwrite=True) as stage:  # overwrite: same-named replaced, others kept
        atomic_write_text(stage / "a.csv", "new")
    assert sorted(os.listdir(out)) == sorted(["notes.txt", "a.csv", MANIFEST])
    assert (out / "notes.txt").read_text() == "keep me"


def test_a_snoworm_folder_with_a_users_extra_file_counts_as_foreign(tmp_path):
    out = _write(tmp_path / "run", ["a.csv"])
    (out / "my_notes.md").write_text("x")
    assert folder_state(out) == "foreign"
    with pytest.raises(OutputError, match="--overwrite"):
        _write(out, ["a.csv"])


def test_a_failure_at_any_point_leaves_no_result_files(tmp_path):
    out = tmp_path / "run"
    with pytest.raises(RuntimeError):
        with output_folder(out) as stage:
            atomic_write_text(stage / "segments.csv", "half")
            raise RuntimeError("solver failed after the first file")
    assert list(tmp_path.iterdir()) == []
    old = _write(out, ["old.csv"])  # an earlier run stays whole
    with pytest.raises(KeyboardInterrupt):
        with output_folder(old) as stage:
            atomic_write_text(stage / "new.csv", "x")
            raise KeyboardInterrupt
    assert sorted(os.listdir(old)) == sorted(["old.csv", MANIFEST])


def test_disk_full_is_one_output_error_naming_the_path_and_reason(tmp_path, monkeypatch):
    real_replace = os.replace

    def full(src, dst):
        if str(dst).endswith("summary.json"):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_replace(src, dst)

    monkeypatch.setattr(folders.os, "replace", full)
    out = tmp_path / "run"
    with pytest.raises(OutputError) as err:
        _write(out, ["segments.csv", "summary.json"])
    msg = str(err.value)
    assert "No space left on device" in msg and str(out) in msg and "\n" not in msg
    assert list(tmp_path.iterdir()) == []  # nothing half-written


def test_unusable_paths_are_refused_before_any_work(tmp_path):
    (tmp_path / "f").write_text("a file")
    for bad, needle in [(tmp_path / "f", "is a file"), (tmp_path / "f" / "sub", "which is a file"), ("", "empty")]:
        with pytest.raises(OutputError, match=needle):
            check_output_folder(bad)


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_parent_is_an_output_error(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        with pytest.raises(OutputError, match="Permission denied"):
            _write(ro / "run", ["a.csv"])
    finally:
        ro.chmod(0o755)


def test_the_current_folder_is_written_in_place_not_renamed(tmp_path, monkeypatch):
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    _write(".", ["a.csv"])
    _write(".", ["b.csv"])
    assert sorted(os.listdir(here)) == sorted(["b.csv", MANIFEST])  # a.csv of the earlier run removed
    assert sorted(os.listdir(tmp_path)) == ["here"]


def test_stale_staging_folders_of_dead_processes_are_removed(tmp_path):
    dead = tmp_path / f".run{folders._STAGE}999999999-abc"
    dead.mkdir()
    _write(tmp_path / "run", ["a.csv"])
    assert sorted(os.listdir(tmp_path)) == ["run"]


# ------------------------------------------------------------------ folder locks
def _hold(folder, ready, release):
    with folder_lock(folder):
        ready.set()
        release.wait(20)


def test_a_second_locker_is_refused_naming_the_pid_and_a_dead_holders_lock_is_taken_over(tmp_path):
    ctx = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
    ready, release = ctx.Event(), ctx.Event()
    p = ctx.Process(target=_hold, args=(tmp_path, ready, release))
    p.start()
    try:
        assert ready.wait(20)
        with pytest.raises(FolderLocked) as err:
            with folder_lock(tmp_path):
                pass
        assert f"process {p.pid}" in str(err.value) and str(tmp_path) in str(err.value)
    finally:
        p.kill()  # dies holding the lock
        p.join()
    assert (tmp_path / LOCK).exists()  # stale lock file left behind
    with folder_lock(tmp_path) as lease:  # taken over
        assert lease.path.read_text().split()[0] == str(os.getpid())
    assert not (tmp_path / LOCK).exists()


def test_manifest_json_is_plain_data(tmp_path):
    out = _write(tmp_path / "r", ["a"])
    doc = json.loads((out / MANIFEST).read_text())
    assert set(doc) >= {"snoworm_version", "command", "written_utc", "files"}


def test_a_symlinked_output_folder_stays_a_link(tmp_path):
    real = tmp_path / "scratch"
    real.mkdir()
    link = tmp_path / "out"
    link.symlink_to(real)
    _write(link, ["a.csv"])
    _write(link, ["b.csv"])
    assert link.is_symlink() and sorted(os.listdir(real)) == sorted(["b.csv", MANIFEST])
    assert sorted(os.listdir(tmp_path)) == ["out", "scratch"]


def test_an_unwritable_parent_stages_inside_the_output_folder(tmp_path, monkeypatch):
    out = tmp_path / "shared" / "mine"
    out.mkdir(parents=True)
    real = folders.tempfile.mkdtemp

    def no_siblings(prefix="", dir=None):
        if os.path.samefile(dir, out.parent):
            raise PermissionError(errno.EACCES, "Permission denied", str(out.parent))
        return real(prefix=prefix, dir=dir)

    monkeypatch.setattr(folders.tempfile, "mkdtemp", no_siblings)
    _write(out, ["a.csv"])
    _write(out, ["b.csv"])
    assert sorted(os.listdir(out)) == sorted(["b.csv", MANIFEST]) and os.listdir(out.parent) == ["mine"]


def test_earlier_output_note(tmp_path):
    from snoworm.infra.folders import earlier_output_note, write_manifest

    assert earlier_output_note(tmp_path / "none") is None
    (tmp_path / "a.csv").write_text("x\n")
    assert earlier_output_note(tmp_path) is None  # not snoworm's: no manifest
    write_manifest(tmp_path, command="snoworm run x --out d")
    note = earlier_output_note(tmp_path)
    assert note.startswith(f"note: {tmp_path} holds earlier results (snoworm run x --out d, ") and "\n" not in note
    assert "resumed" in earlier_output_note(tmp_path, resumes=True)


# ------------------------------------ durable: every staged file on disk before the folder appears
def _write(out, names):
    with output_folder(out, command="test") as stage:
        for n in names:
            folders.atomic_write_text(stage / n, n)
    return out


def test_sync_files_syncs_every_file_of_a_tree(tmp_path, monkeypatch):
    (tmp_path / "sub").mkdir()
    for n in ("a.csv", "sub/b.png"):
        (tmp_path / n).write_text("x")
    synced = []
    real = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: synced.append(os.readlink(f"/proc/self/fd/{fd}")) or real(fd))
    sync_files(tmp_path)
    assert sorted(os.path.relpath(p, tmp_path) for p in synced) == ["a.csv", "sub/b.png"]


def test_every_staged_file_is_synced_to_disk_before_the_folder_appears(tmp_path, monkeypatch):
    """Files staged by atomic_write_text skip their own fsync; the commit syncs every staged file
    (plots and the manifest included) before the rename; outside a stage each file syncs itself."""
    synced, events = [], []
    real_fsync, real_rename = os.fsync, os.rename

    def fsync(fd):
        synced.append(os.path.basename(os.readlink(f"/proc/self/fd/{fd}")))
        events.append("fsync")
        return real_fsync(fd)

    def rename(src, dst):
        events.append("rename")
        return real_rename(src, dst)

    monkeypatch.setattr(folders.os, "fsync", fsync)
    monkeypatch.setattr(folders.os, "rename", rename)
    with output_folder(tmp_path / "run", command="test") as stage:
        folders.atomic_write_text(stage / "summary.json", "{}\n")
        (stage / "plot.png").write_bytes(b"png")  # a file written by another writer
        assert synced == []  # deferred to the commit
    assert sorted(synced) == sorted([MANIFEST, "plot.png", "summary.json"])
    assert events[-1] == "rename" and "rename" not in events[:-1]  # all synced, then the folder appears
    synced.clear()
    folders.atomic_write_text(tmp_path / "alone.txt", "x")
    assert len(synced) == 1  # not in a stage: synced at once


def test_a_failed_sync_at_the_commit_writes_nothing(tmp_path, monkeypatch):
    def no_disk(fd):
        raise OSError(errno.EIO, os.strerror(errno.EIO))

    monkeypatch.setattr(folders.os, "fsync", no_disk)
    with pytest.raises(OutputError, match="Input/output error"):
        _write(tmp_path / "run", ["segments.csv"])
    assert list(tmp_path.iterdir()) == []


def test_add_file_keeps_a_snoworm_folder_snoworms_and_writes_all_or_nothing(tmp_path):
    """issue 34 (an animation into a results folder): the file is listed in the folder's manifest, so
    the folder stays snoworm's; a failed write leaves nothing; another process's folder is refused."""
    run = tmp_path / "run"
    with output_folder(run) as stage:
        atomic_write_text(stage / "a.csv", "1\n")
    with folders.add_file(run / "video.gif") as tmp:
        tmp.write_bytes(b"GIF89a")
    assert (run / "video.gif").read_bytes() == b"GIF89a"
    assert folders.folder_state(run) == "snoworm" and "video.gif" in folders.read_manifest(run)["files"]
    with pytest.raises(RuntimeError):  # the writer fails: the earlier file stays, no temporary is left
        with folders.add_file(run / "video.gif") as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("the writer failed")
    assert (run / "video.gif").read_bytes() == b"GIF89a"
    assert set(os.listdir(run)) - {folders.LOCK} == {MANIFEST, "a.csv", "video.gif"}
    plain = tmp_path / "plain"
    plain.mkdir()
    with folders.add_file(plain / "x.txt") as tmp:
        tmp.write_text("x")
    assert os.listdir(plain) == ["x.txt"]  # a folder snoworm did not write gets the file and nothing else
    with folders.folder_lock(plain):
        with pytest.raises(OutputError, match="in use|process"):
            with folders.add_file(plain / "y.txt") as tmp:
                tmp.write_text("y")
    assert not (plain / "y.txt").exists()


def test_add_file_into_a_folder_inside_snoworm_folders_lists_it_in_each(tmp_path):
    """A sweep's case folder is a snoworm folder inside the sweep's: a file added to it (or to a new
    subfolder of it) is listed by both manifests, so neither folder turns foreign."""
    outer = tmp_path / "sweep"
    with output_folder(outer) as stage:
        atomic_write_text(stage / "summary.csv", "a\n")
    inner = outer / "cases" / "c1"
    with output_folder(inner) as stage:
        atomic_write_text(stage / "segments.csv", "1\n")
    folders.write_manifest(outer)  # as the sweep does after its cases: it lists the cases' files too
    with folders.add_file(inner / "videos" / "a.gif") as tmp:
        tmp.write_bytes(b"GIF89a")
    assert folders.folder_state(inner) == "snoworm" and folders.folder_state(outer) == "snoworm"
    assert "videos/a.gif" in folders.read_manifest(inner)["files"]
    assert "cases/c1/videos/a.gif" in folders.read_manifest(outer)["files"]
    with folders.folder_lock(outer):  # the sweep's folder is another process's: refused
        with pytest.raises(OutputError):
            with folders.add_file(inner / "b.gif") as tmp:
                tmp.write_bytes(b"GIF89a")
    assert not (inner / "b.gif").exists()
