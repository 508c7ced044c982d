"""Writing results: atomic files, all-or-nothing output folders, folder locks.

* :func:`atomic_path` / :func:`atomic_write_text`: a reader never sees a half-written file, and
  the file gets the permissions of the user's umask (0644 under umask 022), not the 0600 of the
  temporary file.
* :func:`output_folder`: every command's results are written into a temporary sibling folder
  and moved into place at the end, with a manifest (:data:`MANIFEST`: the files, the snoworm
  version, the command).  A failure at any point leaves no result files.  An earlier snoworm
  folder is replaced as a whole; a non-empty folder snoworm did not write is refused unless
  ``overwrite`` (then same-named files are replaced and the others kept).  A folder that cannot
  be renamed as a whole is committed entry by entry behind a journal (:mod:`snoworm.infra.commit`):
  an interrupted commit is completed by the next command (:func:`check_output_folder`).
* :func:`folder_lock` (:mod:`snoworm.infra.locks`): one process at a time in a folder.  A sweep
  holds its folder's lock while it runs; :func:`output_folder` holds the lock of the folder it
  replaces (from the start if it exists, else from the commit), so no command replaces or writes
  into a folder another live process holds (:class:`FolderLocked`, exit status 2).  A lock left
  by a dead process is taken over.
* :func:`sync_files`: files written by :func:`atomic_write_text` inside the staging folder
  (:data:`STAGING`) skip their own ``fsync``; the commit syncs the whole staging folder, every
  file concurrently, before the rename, so the folder appears only with every file (plots and the
  manifest too) on disk.

I/O failures (disk full, read-only, a path under a file) raise :class:`OutputError` naming the
path and the operating system's reason (the CLI: exit status 2).
"""

from __future__ import annotations

import contextvars
import errno
import json
import os
import shlex
import shutil
import sys
import tempfile
import threading
import time
from contextlib import contextmanager
from pathlib import Path

from .._version import __version__
from . import manifest as _manifest
from .commit import commit_in_place, owns_stage, recover, unfinished_commit
from .locks import FolderLocked, OutputError, check_unlocked, folder_lock, os_error_message, pid_alive, try_folder_lock
from .manifest import (
    JOURNAL,
    LOCK,
    MANIFEST,
    STAGE as _STAGE,
    ManifestProblem,
    folder_files,
    listed_files,
    load_manifest,
)

__all__ = [
    "atomic_write_text",
    "atomic_path",
    "sync_files",
    "OutputError",
    "output_folder",
    "check_output_folder",
    "folder_state",
    "folder_report",
    "read_manifest",
    "write_manifest",
    "add_file",
    "remove_listed",
    "folder_lock",
    "FolderLocked",
    "MANIFEST",
    "LOCK",
    "os_error_message",
    "file_mode",
    "STAGING",
]

# ---------------------------------- durable: every staged file synced before the folder appears
#: the staging folder of the output folder being written (its files are synced at the commit)
STAGING = contextvars.ContextVar("snoworm_staging_folder", default=None)


def sync_files(folder) -> None:
    """``fsync`` every file under ``folder``, concurrently (the file system commits them together:
    5 files took 3-7 ms this way against 18-36 ms one after the other, measured on ext4)."""
    paths = [os.path.join(root, n) for root, _, names in os.walk(folder) for n in names]
    errors = []

    def sync(p):
        try:
            fd = os.open(p, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        except OSError as exc:
            errors.append(exc)

    threads = [threading.Thread(target=sync, args=(p,)) for p in paths]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    if errors:
        raise errors[0]


_OLD = ".snoworm-old-"


def file_mode(directory: bool = False) -> int:
    """The mode new files (0666) or folders (0777) get under the current umask."""
    mask = os.umask(0)
    os.umask(mask)
    return (0o777 if directory else 0o666) & ~mask


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; on success rename it onto ``path``.

    The file gets the umask's permissions (:func:`file_mode`).  On an exception the temporary
    file is removed and ``path`` is left as it was.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + path.suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, file_mode())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def atomic_write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (temporary file + ``os.replace``); returns the path.

    The file is flushed to disk (``fsync``) before it replaces ``path``; inside the staging folder
    of :func:`output_folder` that happens for every staged file at once when the folder is
    committed (:func:`sync_files`), which is when it must.
    """
    stage = STAGING.get()
    deferred = stage is not None and os.path.abspath(path).startswith(stage + os.sep)
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
            fh.flush()
            if not deferred:
                os.fsync(fh.fileno())
    return Path(path)


# ------------------------------------------------------------------------------ manifest
_files = folder_files


def read_manifest(folder) -> dict | None:
    """The manifest of a snoworm output folder, or None (none, or one that fails the checks of
    :func:`snoworm.infra.manifest.load_manifest`: never trusted then)."""
    try:
        return load_manifest(folder)
    except ManifestProblem:
        return None


def _command_line() -> str:
    """This process's command line (what a manifest records when no command is given)."""
    prog = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "python"
    if prog in ("__main__.py", "snoworm"):
        prog = "snoworm"
    return shlex.join([prog] + list(sys.argv[1:]))


def write_manifest(folder, command: str | None = None, **extra) -> Path:
    """Write :data:`MANIFEST` listing every file now in ``folder`` (and the SHA-256 of its ``inputs/``)."""
    folder = Path(folder)
    doc = {
        "snoworm_version": __version__,
        "command": command or _command_line(),
        "written_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        **extra,
        **_manifest.input_record(folder),
        "files": _files(folder),
    }
    return atomic_write_text(folder / MANIFEST, json.dumps(doc, indent=2) + "\n")


@contextmanager
def add_file(path):
    """Yield a temporary path beside ``path`` to write a file into; on success it replaces ``path``.

    Into a snoworm output folder (e.g. an animation into a run's folder, or into a sweep's case
    folder, inside the sweep's), under the lock of the outermost snoworm output folder holding it
    (:func:`folder_lock`; the inner ones checked unlocked: never while another snoworm process
    writes one of them), and
    their manifests list the file first, so the folders stay snoworm's (a later run into one
    replaces it as a whole; an interruption between the two leaves a listed file missing, which no
    reader minds).  Into any other folder: refused if another snoworm process holds its lock, else
    written atomically (:func:`atomic_path`).  Never touches another file.

    Raises
    ------
    OutputError
        A folder is locked by another process, is not a folder, or the write fails.
    """
    path = Path(os.path.abspath(path))
    folder = path.parent
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"{folder} is not a folder; give a file path inside a folder.")
    try:
        owners = _owners(folder)
        if not owners:
            if folder.is_dir():
                check_unlocked(folder)
            with atomic_path(path) as tmp:
                yield tmp
            return
        # the outermost folder's lock (a sweep holds its own for its whole run); the inner ones are
        # checked, not locked: a lock file inside would be an entry the outer manifest does not list
        with folder_lock(owners[-1]):
            for owner in owners[:-1]:
                check_unlocked(owner)
            if _owners(folder) != owners:  # changed before the lock was taken
                raise OutputError(f"{owners[0]} changed while the file was being prepared; try again.")
            with atomic_path(path) as tmp:
                yield tmp
                for owner in owners:
                    man = _manifest.load_manifest(owner) or {}
                    rel = path.relative_to(owner).as_posix()
                    if rel not in man.get("files", []):
                        man["files"] = sorted([*man.get("files", []), rel])
                        atomic_write_text(owner / MANIFEST, json.dumps(man, indent=2) + "\n")
    except OSError as exc:
        raise OutputError(f"cannot write the file: {os_error_message(exc, path)}") from None


def _owners(folder: Path) -> list:
    """The snoworm output folders holding ``folder`` (itself included), nearest first."""
    return [a for a in (folder, *folder.parents) if (a / MANIFEST).is_file() and folder_state(a) == "snoworm"]


def folder_report(path) -> tuple:
    """(:func:`folder_state`, why it is foreign or None)."""
    path = Path(path)
    if not path.exists():
        return "missing", None
    if not path.is_dir():
        return "file", None
    entries = [e for e in os.listdir(path) if e != LOCK and _STAGE not in e]
    if not entries:
        return "empty", None
    if unfinished_commit(path):  # never acted on as a snoworm folder until completed (recover)
        return "foreign", "it holds an unfinished commit"
    try:
        man = load_manifest(path)
        if man is None:
            return "foreign", f"it has no {MANIFEST} listing its files"
        listed_files(path, man)
    except ManifestProblem as exc:
        return "foreign", f"{exc}; snoworm acts on no entry of it"
    extra = sorted(set(_files(path)) - set(man["files"]))
    if extra:
        return "foreign", f"{path / extra[0]} is not listed in its {MANIFEST}"
    return "snoworm", None


def folder_state(path) -> str:
    """What ``path`` is as an output folder.

    ``"missing"``, ``"empty"``, ``"snoworm"`` (a manifest, passing the checks of
    :func:`snoworm.infra.manifest.load_manifest`, listing every file in it), ``"foreign"`` (non-empty,
    not all written by snoworm, or a manifest snoworm does not trust), ``"file"`` (not a folder).
    """
    return folder_report(path)[0]


def earlier_output_note(path, resumes: bool = False) -> str | None:
    """One line saying that ``path`` already holds snoworm output (its command and time, from a
    manifest that passes :func:`snoworm.infra.manifest.load_manifest`'s checks) and what happens
    to it, or None when it holds none.  ``resumes``: the command continues an earlier run there
    (a sweep) instead of replacing it."""
    man = read_manifest(path) if Path(path).is_dir() else None
    if man is None:
        return None
    try:
        check_unlocked(path)
    except FolderLocked:  # in use: the command refuses it, nothing is replaced or resumed
        return None
    command = " ".join(str(man.get("command") or "an earlier snoworm command").split())
    command = command if len(command) <= 120 else command[:117] + "..."
    what = f"{command}, {str(man.get('written_utc', 'time unknown'))[:40]}"
    if resumes:
        return f"note: {path} holds earlier results ({what}); its finished cases are kept (resumed) unless --restart."
    return f"note: {path} holds earlier results ({what}); they are replaced when this command finishes."


def _refusal(path, why=None) -> str:
    return (
        f"{path} is not empty and was not written by snoworm ({why or f'it has no {MANIFEST} listing its files'}). "
        "Give an empty or new --out folder, or pass --overwrite (overwrite=True in Python) to write into "
        "it anyway (same-named files are replaced, the others kept)."
    )


def check_output_folder(path, overwrite: bool = False) -> str:
    """Check that results may go to ``path`` before any work; returns :func:`folder_state`.

    Raises
    ------
    OutputError
        ``path`` is empty text, a file, under a file, or a non-empty folder snoworm did not
        write (unless ``overwrite``).
    """
    if str(path).strip() == "":
        raise OutputError("--out: the output folder is empty text. Name a folder, e.g. --out results/.")
    path = Path(path)
    for parent in [path, *path.parents]:
        if parent.exists() and not parent.is_dir():
            what = "is a file" if parent == path else f"is under {parent}, which is a file"
            raise OutputError(f"{path}: {what}, not a folder. Give a folder path for --out.")
        if parent.exists():
            break
    if path.is_dir():
        recover(path)  # a commit in place interrupted between its renames: completed first
    state, why = folder_report(path)
    if state == "foreign" and not overwrite:
        raise OutputError(_refusal(path, why))
    if state not in ("missing", "file"):
        check_unlocked(path)  # a sweep (or any command) writing there now: never replaced under it
    return state


# ------------------------------------------------------------------------------ output folders
def _clean_stale(parent: Path, name: str):
    """Remove staging folders of ``name`` left by killed processes (their PID is in the name):
    siblings of ``parent / name``, and those inside it; never one an unfinished commit needs."""
    target = parent / name
    places = [(parent, [f".{name}{_STAGE}", f".{name}{_OLD}"]), (target, [_STAGE, f"{JOURNAL}."])]
    for folder, prefixes in places:
        try:
            entries = os.listdir(folder)
        except OSError:
            continue
        for e in entries:
            for prefix in prefixes:
                if e.startswith(prefix):
                    pid = e[len(prefix) :].replace(".", "-").split("-")[0]
                    if pid.isdigit() and not pid_alive(int(pid)) and not owns_stage(target, folder / e):
                        if prefix.startswith(JOURNAL):  # a journal being written when its process died
                            os.unlink(folder / e)
                        else:
                            shutil.rmtree(folder / e, ignore_errors=True)


def _inside_cwd(path: Path) -> bool:
    try:
        cwd = Path.cwd().resolve()
    except OSError:
        return False
    p = path.resolve()
    return p == cwd or p in cwd.parents


def _make_stage(target: Path):
    """(staging folder, in_place): a sibling of ``target``; or inside it when the parent is not
    writable or ``target`` is a mount point (a folder on another mount than its parent: a file
    cannot be renamed into it from a sibling, nor the folder renamed as a whole)."""
    parent = target.parent
    parent.mkdir(parents=True, exist_ok=True)
    _clean_stale(parent, target.name)
    inside = target.is_dir() and os.path.ismount(target)
    if not inside:
        try:
            stage = Path(tempfile.mkdtemp(prefix=f".{target.name}{_STAGE}{os.getpid()}-", dir=parent))
        except PermissionError:
            if not target.is_dir():
                raise
            inside = True
        else:
            if target.is_dir() and not _renames_into(stage, target):  # a bind mount ismount misses
                shutil.rmtree(stage, ignore_errors=True)
                inside = True
    if inside:
        stage = Path(tempfile.mkdtemp(prefix=f"{_STAGE}{os.getpid()}-", dir=target))
    os.chmod(stage, file_mode(directory=True))
    return stage, inside


def _renames_into(stage: Path, target: Path) -> bool:
    """Whether a file of ``stage`` can be renamed into ``target`` (False: another mount, EXDEV)."""
    probe, dst = stage / "probe", target / f"{_STAGE}probe-{os.getpid()}"
    probe.touch()
    try:
        os.rename(probe, dst)
    except OSError as exc:
        return exc.errno != errno.EXDEV  # any other failure shows at the commit, as before
    os.unlink(dst)
    return True


def _commit_swap(stage: Path, target: Path):
    """Replace ``target`` (missing, empty or an earlier snoworm folder) by ``stage`` as a whole
    (committed in place instead if ``target`` cannot be renamed: a mount point, EBUSY)."""
    if not target.exists():
        os.rename(stage, target)
        return
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}{_OLD}{os.getpid()}-", dir=target.parent))
    os.rmdir(old)
    try:
        os.rename(target, old)
    except OSError as exc:
        if exc.errno != errno.EBUSY:
            raise
        commit_in_place(stage, target)  # nothing was moved yet
        return
    try:
        os.rename(stage, target)
    except BaseException:
        os.rename(old, target)
        raise
    shutil.rmtree(old, ignore_errors=True)


def remove_listed(folder) -> list:
    """Remove the files ``folder``'s manifest lists (only those passing the checks of
    :mod:`snoworm.infra.manifest`: regular files or symlinks inside ``folder``, reached without a symlink);
    a missing or untrusted manifest removes nothing.  Returns the removed paths."""
    try:
        man = load_manifest(folder)
        paths = listed_files(folder, man) if man is not None else []
    except ManifestProblem:
        return []
    for p in paths:
        os.unlink(p)
    return paths


@contextmanager
def output_folder(path, overwrite: bool = False, command: str | None = None):
    """Yield a staging folder for a command's results; on success they replace ``path``.

    Parameters
    ----------
    path : str or Path
        The output folder (created with its parents if missing).
    overwrite : bool
        Write into a non-empty folder snoworm did not write (same-named files replaced, other
        files kept) instead of refusing it.
    command : str, optional
        Recorded in the manifest (default: this process's command line).

    The staged files get a manifest and move into place only when the block ends without an
    exception; on an exception (solver failure, disk full, Ctrl-C) the staging folder is removed
    and ``path`` is left as it was.  An earlier snoworm folder (:func:`folder_state`
    ``"snoworm"``) is replaced as a whole, so none of its files remain beside the new ones.

    Raises
    ------
    OutputError
        See :func:`check_output_folder`; or an I/O failure, naming the path and the reason.
    """
    check_output_folder(path, overwrite)
    target = Path(os.path.abspath(path))
    with _Held(target) as held:
        held.take()  # an existing folder is held from the start: no sweep starts in it meanwhile
        try:
            stage, in_place = _make_stage(target)
        except OSError as exc:
            raise OutputError(f"cannot write results: {os_error_message(exc, target)}") from None
        token = STAGING.set(os.path.abspath(stage))
        try:
            try:
                yield stage
                write_manifest(stage, command)
            finally:
                STAGING.reset(token)
            sync_files(stage)  # every staged file on disk before the folder appears
            held.take()  # a folder made meanwhile (a sweep started there): its lock decides
            state = check_output_folder(target, overwrite) if held.lease is None else _recheck(target, overwrite)
            if in_place or state == "foreign" or target.is_symlink() or _inside_cwd(target) or os.path.ismount(target):
                commit_in_place(stage, target)
            else:
                _commit_swap(stage, target)
        except OSError as exc:
            if owns_stage(target, stage):  # a commit in place stopped half-way: completed by the next command
                raise OutputError(
                    f"cannot write results: {os_error_message(exc, target)}; the commit into {target} stopped "
                    f"half-way. Run the command again with the same --out: it completes the commit first."
                ) from None
            shutil.rmtree(stage, ignore_errors=True)
            raise OutputError(
                f"cannot write results: {os_error_message(exc, target)}; nothing was written to {target}."
            ) from None
        except BaseException:
            if not owns_stage(target, stage):
                shutil.rmtree(stage, ignore_errors=True)
            raise


def _recheck(target: Path, overwrite: bool) -> str:
    """:func:`check_output_folder` of a folder this process holds the lock of (its own lock not
    counted as another's)."""
    state, why = folder_report(target)
    if state == "foreign" and not overwrite:
        raise OutputError(_refusal(target, why))
    return state


class _Held:
    """The lock of an output folder, taken (:meth:`take`) once the folder exists, released at the end."""

    def __init__(self, target: Path):
        self.target, self.lease = target, None

    def take(self):
        if self.lease is None and self.target.is_dir():
            self.lease = try_folder_lock(self.target)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.lease is not None:
            self.lease.release()


def relocate(paths, stage, target) -> list:
    """The final paths of files written under ``stage`` once it has become ``target``."""
    stage, target = Path(stage), Path(target)
    return [target / Path(p).relative_to(stage) for p in paths]
