"""Folder locks: one snoworm process at a time writes a folder, and it knows if the folder is still the one it locked.

* :func:`folder_lock` holds a folder's lock (:data:`~snoworm.infra.manifest.LOCK`, an ``flock``
  on a file holding the PID) and yields a :class:`FolderLease`, whose :meth:`~FolderLease.check`
  says whether the folder at that path is still the one locked (a folder removed, moved away or
  replaced behind the holder's back fails it).  A sweep locks its folder for its whole run;
  every other command (:func:`snoworm.infra.folders.output_folder`) holds the lock of the folder
  it replaces while it works and commits, so it never replaces a folder another process holds.
* :func:`check_unlocked` refuses a folder another live process holds, without creating anything.

The errors of output folders live here, at the bottom of the output code, because the lock
raises them: :class:`OutputError` (the CLI: exit status 2) and :class:`FolderLocked`.
"""

from __future__ import annotations

import errno
import os
import secrets
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None  # type: ignore[assignment]  # checked before each use

from .manifest import LOCK

__all__ = [
    "OutputError",
    "FolderLocked",
    "FolderLease",
    "os_error_message",
    "pid_alive",
    "folder_lock",
    "try_folder_lock",
    "check_unlocked",
    "lock_token_matches",
]

#: errno values of a lock file that cannot be created (a read-only folder or file system)
_CANNOT_CREATE = (errno.EACCES, errno.EPERM, errno.EROFS)


class OutputError(Exception):
    """An output path cannot be used or written (bad ``--out``, disk full, read-only, a folder in
    use by another process): bad input or environment, never a bug (the CLI exits with status 2)."""


class FolderLocked(OutputError):
    """Another live process holds the folder's lock (:func:`folder_lock`)."""


def os_error_message(exc: OSError, path: str | os.PathLike[str] | None = None) -> str:
    """``<path>: <OS reason>`` of an OSError, e.g. ``out/a.csv: No space left on device``."""
    where = exc.filename if exc.filename is not None else path
    reason = exc.strerror or str(exc) or type(exc).__name__
    return f"{where}: {reason}" if where is not None else reason


def pid_alive(pid: int) -> bool:
    """Whether a process ``pid`` exists (one of another user counts as alive)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


def _holder(lock_path: Path) -> str:
    try:
        fd = os.open(lock_path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
        try:
            text = _first_word(os.read(fd, 64))
        finally:
            os.close(fd)
    except OSError:
        text = ""
    return f"process {text}" if text.isdigit() else "another process"


def _first_word(data: bytes) -> str:
    words = data.decode("ascii", errors="replace").split()
    return words[0] if words else ""


def lock_token_matches(folder: str | os.PathLike[str], token: str) -> bool:
    """Whether ``folder``'s lock file holds ``token`` (:attr:`FolderLease.token`): the folder is still
    the one its holder locked.  Works where a worker cannot compare the folder's identity (another
    machine of a Dask cluster on a shared file system)."""
    try:
        fd = os.open(Path(folder) / LOCK, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
        try:
            words = os.read(fd, 128).decode("ascii", errors="replace").split()
        finally:
            os.close(fd)
    except OSError:
        return False
    return len(words) == 2 and words[1] == token


def _busy(lp: Path) -> FolderLocked:
    return FolderLocked(
        f"{lp.parent} is in use by {_holder(lp)} (lock file {lp}): another snoworm command is "
        "writing there, and nothing was written. Wait for it to finish, or give another --out folder."
    )


class FolderLease:
    """A folder's lock held by this process (made by :func:`folder_lock`).

    Attributes
    ----------
    folder : Path
        The locked folder.
    path : Path
        Its lock file.
    token : str
        A random token written into the lock file after the PID (:func:`lock_token_matches`).
    """

    def __init__(self, folder: Path, fd: int, token: str):
        self.folder, self.path, self.fd, self.token = folder, folder / LOCK, fd, token
        self._ident = _ident(os.stat(folder))

    def is_current(self) -> bool:
        """Whether ``folder`` is still the folder locked, with this lease's lock file in it."""
        try:
            here = os.stat(self.folder)
            lock = os.lstat(self.path)
        except OSError:
            return False
        return _ident(here) == self._ident and os.path.samestat(os.fstat(self.fd), lock)

    def check(self, doing: str = "writing") -> None:
        """Raise :class:`OutputError` if ``folder`` is no longer the folder locked (removed, moved
        away or replaced since): nothing more may be written to that path."""
        if not self.is_current():
            raise OutputError(
                f"{self.folder} was removed, moved or replaced while this process was {doing} it "
                f"(its lock file {self.path} is not the one taken): stopped without writing "
                "anything more there. Look at what replaced it; re-run into a new --out folder."
            )

    def release(self) -> None:
        """Remove the lock file (only if it is still this lease's) and drop the lock."""
        try:
            if os.path.samestat(os.fstat(self.fd), os.lstat(self.path)):
                os.unlink(self.path)
        except OSError:
            pass
        os.close(self.fd)


def _ident(st: os.stat_result) -> tuple:
    return st.st_dev, st.st_ino


@contextmanager
def folder_lock(folder: str | os.PathLike[str]) -> Iterator[FolderLease]:
    """Hold ``folder``'s lock (:data:`~snoworm.infra.manifest.LOCK`, with this process's PID) for
    the block; yields the :class:`FolderLease`.

    A lock whose holder is dead is taken over (the kernel's ``flock`` ends with its process;
    without ``fcntl`` a PID check decides).  The lock file is never a symbolic link (refused).

    Raises
    ------
    FolderLocked
        Another live process holds it; the message names its PID.
    OutputError
        The lock file cannot be created or locked (naming it and the reason).
    """
    lease = try_folder_lock(folder, required=True)
    assert lease is not None  # required=True: raises rather than returning None
    try:
        yield lease
    finally:
        lease.release()


def try_folder_lock(folder: str | os.PathLike[str], required: bool = False) -> FolderLease | None:
    """Take ``folder``'s lock and return the :class:`FolderLease` (the caller releases it).

    With ``required`` False, a lock file that cannot be created (a read-only folder) returns None
    after :func:`check_unlocked`: nobody else can write there either.

    Raises
    ------
    FolderLocked, OutputError
        As :func:`folder_lock`.
    """
    folder = Path(folder)
    lp = folder / LOCK
    token = secrets.token_hex(8)
    try:
        fd = _acquire(lp, token)
    except OSError as exc:  # FolderLocked is not an OSError: it passes unchanged
        if not required and exc.errno in _CANNOT_CREATE:
            check_unlocked(folder)
            return None
        raise OutputError(f"cannot lock the folder: {os_error_message(exc, lp)}") from None
    try:
        return FolderLease(folder, fd, token)
    except OSError as exc:
        os.close(fd)
        raise OutputError(f"cannot lock the folder: {os_error_message(exc, folder)}") from None


def check_unlocked(folder: str | os.PathLike[str]) -> None:
    """Raise :class:`FolderLocked` if another live process holds ``folder``'s lock; creates nothing.

    A lock file that cannot be opened (not a regular file, unreadable) is left to the writer,
    whose own lock fails then with a message naming it."""
    lp = Path(folder) / LOCK
    try:
        fd = os.open(lp, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
    except OSError:
        return
    try:
        if fcntl is None:  # pragma: no cover - not POSIX
            pid = _holder(lp).split()[-1]
            if pid.isdigit() and pid_alive(int(pid)) and int(pid) != os.getpid():
                raise _busy(lp)
            return
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                raise _busy(lp) from None
    finally:
        os.close(fd)  # drops the probe's flock too


def _acquire(lp: Path, token: str) -> int:
    nofollow = getattr(os, "O_NOFOLLOW", 0)
    for _ in range(20):
        if fcntl is None:  # pragma: no cover - not POSIX
            try:
                fd = os.open(lp, os.O_CREAT | os.O_EXCL | os.O_RDWR | nofollow, 0o644)
            except FileExistsError:
                pid = _holder(lp).split()[-1]
                if pid.isdigit() and not pid_alive(int(pid)):
                    os.unlink(lp)
                    continue
                raise _busy(lp) from None
        else:
            fd = os.open(lp, os.O_CREAT | os.O_RDWR | nofollow | os.O_NONBLOCK, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                os.close(fd)
                if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                    raise _busy(lp) from None
                raise
            try:  # the file may have been unlinked by its releasing holder
                same = os.path.samestat(os.fstat(fd), os.lstat(lp))
            except FileNotFoundError:
                same = False
            if not same:
                os.close(fd)
                continue
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            raise OSError(errno.EINVAL, "not a regular file", str(lp))
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()} {token}".encode())
        return fd
    raise _busy(lp)
