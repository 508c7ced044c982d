"""Committing a staged output folder entry by entry ("in place"), recoverably.

:func:`snoworm.infra.folders.output_folder` renames its staging folder into place as a whole
when it can.  Where it cannot (``--out`` is the working folder or one of its parents, a symlink, a
mount point, a folder of yours written with ``--overwrite``, or its parent is not writable) the
staged entries are moved into the folder one by one (:func:`commit_in_place`): a process killed
between two of those renames would leave the old manifest over a mix of old and new files.

So the commit first writes a journal, :data:`~snoworm.infra.manifest.JOURNAL`, into the folder
(synced to disk before the first rename): the staging folder, the entries to move (the manifest
last), the earlier run's files to remove and the SHA-256 of the new manifest.  Every step is
idempotent, so an interrupted commit is completed (rolled forward: the staging folder holds the
new files, all synced) by :func:`finish_commit`, which the next command writing to the folder runs
under the folder's lock (:func:`recover`).  Until then readers refuse the folder
(:func:`unfinished_commit`), naming the journal and the fix.  The journal is acted on only under
the checks of a manifest (:mod:`snoworm.infra.manifest`): its staging folder is a staging folder of
this folder, its entries plain names, its files to remove regular files inside the folder.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import stat
from pathlib import Path

from .locks import OutputError, os_error_message, try_folder_lock
from .manifest import (
    JOURNAL,
    MANIFEST,
    STAGE,
    ManifestProblem,
    entry_problem,
    folder_files,
    lexists_inside,
    listed_files,
    load_manifest,
    read_small_file,
)

__all__ = ["commit_in_place", "finish_commit", "recover", "unfinished_commit", "owns_stage"]

#: Largest journal read (bytes): it lists the earlier manifest's files.
MAX_JOURNAL_BYTES = 64 * 2**20


def _ours(path: Path, listed: set, root: Path) -> bool:
    """Whether the folder ``path`` holds only files the manifest lists (so snoworm wrote it)."""
    rels = [(path / f).relative_to(root).as_posix() for f in folder_files(path)]
    return all(r in listed for r in rels)


def _check_in_place(stage: Path, target: Path, listed: set, entries):
    """Refuse (before anything is touched) to replace a folder of ``target`` snoworm did not write."""
    for e in entries:
        dst = target / e
        if (stage / e).exists() and dst.is_dir() and not dst.is_symlink() and not _ours(dst, listed, target):
            raise OutputError(
                f"{dst} is a folder snoworm did not write, and a result file of the same name "
                f"would replace it; nothing was written. Move it away or give another --out."
            )


def _listed(target: Path) -> set:
    """The entries of ``target``'s trusted manifest (none if missing or untrusted)."""
    try:
        man = load_manifest(target)
        listed_files(target, man or {"files": []})
        return set((man or {}).get("files", []))
    except ManifestProblem:
        return set()


def _sha256(path: Path) -> str:
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def _sync_dir(folder: Path):
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _write_journal(target: Path, doc: dict):
    tmp = target / f"{JOURNAL}.{os.getpid()}.tmp"
    fd = os.open(tmp, os.O_CREAT | os.O_TRUNC | os.O_WRONLY | getattr(os, "O_NOFOLLOW", 0), 0o644)
    try:
        os.write(fd, (json.dumps(doc, indent=1) + "\n").encode("utf-8"))
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(tmp, target / JOURNAL)
    _sync_dir(target)  # the journal is on disk before the first rename


def commit_in_place(stage: Path, target: Path):
    """Move the staged entries into ``target`` one by one, journaled (see the module docstring):
    the earlier trusted manifest's files that no new entry replaces are removed, a folder snoworm
    did not write is never removed, and the manifest moves last."""
    target.mkdir(parents=True, exist_ok=True)
    target = Path(os.path.realpath(target))
    listed = _listed(target)
    entries = sorted(os.listdir(stage), key=lambda n: n == MANIFEST)  # the manifest last
    _check_in_place(stage, target, listed, entries)
    doc = {
        "pid": os.getpid(),
        "stage": stage.name,
        "inside": stage.parent.resolve() == target,
        "entries": entries,
        "remove": sorted(f for f in listed if f.split("/")[0] not in entries),
        "listed": sorted(listed),
        "manifest_sha256": _sha256(stage / MANIFEST),
    }
    _write_journal(target, doc)
    _apply(target, stage, doc)


def _apply(target: Path, stage: Path, doc: dict):
    """Every step of a journaled commit (each idempotent), then the journal removed."""
    for entry in doc["remove"]:
        st = _lstat_inside(target, entry)
        if st is not None and (stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode)):
            os.unlink(target / entry)
    for entry in doc["remove"]:  # the folders the removed files leave empty (never one holding anything)
        parts = entry.split("/")[:-1]
        for k in range(len(parts), 0, -1):
            st = _lstat_inside(target, "/".join(parts[:k]))
            if st is None or not stat.S_ISDIR(st.st_mode):
                break
            try:
                os.rmdir(target.joinpath(*parts[:k]))
            except OSError:
                break
    for e in doc["entries"]:
        src, dst = stage / e, target / e
        if not os.path.lexists(src):
            continue  # moved already
        if dst.is_dir() and not dst.is_symlink():
            shutil.rmtree(dst)
        elif os.path.lexists(dst) and src.is_dir() and not src.is_symlink():
            os.unlink(dst)  # a file where a folder goes: a rename would fail
        os.replace(src, dst)
    _sync_dir(target)  # every rename on disk before the journal goes
    shutil.rmtree(stage, ignore_errors=True)
    os.unlink(target / JOURNAL)


def _lstat_inside(target: Path, entry: str):
    """``lstat`` of ``target/entry`` reached without a symlink on the way (None if missing or not)."""
    try:
        return lexists_inside(target, entry)
    except ManifestProblem:
        return None


def _journal_problem(target: Path, doc) -> str | None:
    """Why the journal ``doc`` of ``target`` is not one snoworm acts on (None if it is)."""
    if not isinstance(doc, dict):
        return "not a JSON object"
    name, entries, remove = doc.get("stage"), doc.get("entries"), doc.get("remove")
    if not isinstance(name, str) or STAGE not in name or "/" in name or name in (".", ".."):
        return "its staging folder is not a staging folder of this folder"
    if not isinstance(entries, list) or not isinstance(remove, list) or not isinstance(doc.get("listed"), list):
        return "no 'entries', 'remove' and 'listed' lists"
    if not isinstance(doc.get("manifest_sha256"), str) or not entries or entries[-1] != MANIFEST:
        return "no new manifest to commit"
    for e in entries[:-1]:
        if entry_problem(e) is not None or "/" in e:
            return f"entry {e!r} is not a plain name"
    for e in remove + doc["listed"]:
        why = entry_problem(e)
        if why is not None:
            return why
    return None


def _read_journal(target: Path) -> dict:
    path = target / JOURNAL
    try:
        doc = json.loads(read_small_file(path, MAX_JOURNAL_BYTES).decode("utf-8"))
    except (ManifestProblem, UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise OutputError(_stuck(target, f"{path} is unreadable ({exc})")) from None
    why = _journal_problem(target, doc)
    if why is not None:
        raise OutputError(_stuck(target, f"{path}: {why}"))
    return doc


def _stuck(target: Path, why: str) -> str:
    return (
        f"{target} holds an unfinished commit that snoworm cannot complete ({why}); nothing was "
        f"touched. Its files may mix two runs: delete the folder (or move it away) and run the "
        "command again."
    )


def unfinished_commit(folder) -> str | None:
    """A message for readers if ``folder`` holds an interrupted commit (its journal), else None."""
    path = Path(folder) / JOURNAL
    if not os.path.lexists(path):
        return None
    return (
        f"{folder} holds an unfinished commit ({path}): a snoworm command was interrupted while moving "
        "its files into place, so they may mix two runs. Run the command again with the same --out "
        "(it completes the commit first), or delete the folder."
    )


def finish_commit(target) -> bool:
    """Complete an interrupted commit of ``target`` (its lock held by the caller); True if there was one.

    Raises
    ------
    OutputError
        The journal is not one snoworm acts on, or its staging folder is gone before every entry
        was moved (the folder is left as it is; the message names the fix).
    """
    given = Path(os.path.abspath(target))
    if not os.path.lexists(given / JOURNAL):
        return False
    target = Path(os.path.realpath(given))
    doc = _read_journal(target)
    # a sibling of the folder as named (a symlink's, a mount point's) or of its real path; or inside it
    places = [target] if doc["inside"] is True else [given.parent, target.parent]
    stage = next((p / doc["stage"] for p in places if (p / doc["stage"]).is_dir()), places[0] / doc["stage"])
    if stage.is_symlink():
        raise OutputError(_stuck(target, f"its staging folder {stage} is a symbolic link"))
    if not stage.is_dir():
        try:
            done = _sha256(target / MANIFEST) == doc["manifest_sha256"]
        except OSError:
            done = False
        if not done:
            raise OutputError(_stuck(target, f"its staging folder {stage} is gone"))
        stage.mkdir()  # every entry moved: only the clean-up is left
    _check_in_place(stage, target, set(doc["listed"]), doc["entries"])
    try:
        _apply(target, stage, doc)
    except OSError as exc:
        raise OutputError(
            f"cannot complete the unfinished commit of {target}: {os_error_message(exc)}. Fix that and run "
            "the command again, or delete the folder."
        ) from None
    return True


def recover(folder) -> bool:
    """Complete an interrupted commit of ``folder`` if it holds one, under its lock (another live
    process holding it: :class:`~snoworm.infra.locks.FolderLocked`).  True if one was completed."""
    folder = Path(folder)
    if not os.path.lexists(folder / JOURNAL):
        return False
    lease = try_folder_lock(folder)
    try:
        return finish_commit(folder)
    finally:
        if lease is not None:
            lease.release()


def owns_stage(target: Path, stage: Path) -> bool:
    """Whether ``target``'s journal names ``stage`` (an interrupted commit needs it: never removed)."""
    try:
        doc = json.loads(read_small_file(Path(target) / JOURNAL, MAX_JOURNAL_BYTES).decode("utf-8"))
        return isinstance(doc, dict) and doc.get("stage") == Path(stage).name
    except (OSError, ManifestProblem, UnicodeDecodeError, ValueError, RecursionError):
        return False
