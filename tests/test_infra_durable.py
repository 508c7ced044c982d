"""Durable output folders (snoworm.infra.durable): every staged file is on disk before the folder appears."""

import errno
import os

import pytest

from snoworm.infra import folders
from snoworm.infra.durable import sync_files
from snoworm.infra.folders import MANIFEST, OutputError, output_folder


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
