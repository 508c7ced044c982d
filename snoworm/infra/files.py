"""Reading a user's small file without hanging on it or filling the memory.

A path given by a user or named in a file (a scenario, a route, field data, a manifest) may be a
FIFO (``mkfifo``), a device (``/dev/zero``), a folder or a huge file.  A plain ``open().read()``
blocks forever on a FIFO and reads a device without end.  :func:`read_regular_file` opens with
``O_NONBLOCK`` (never blocks on a FIFO), checks with ``fstat`` that the file is a regular one of
at most ``limit`` bytes before a byte is read, and reads at most ``limit`` bytes.
"""

from __future__ import annotations

import os
import stat

__all__ = ["FileProblem", "read_regular_file"]


class FileProblem(ValueError):
    """A file that is not read; the message says what it is, without the path (``f"{path} is {exc}"``).

    ``too_large`` is True when the file is a regular one larger than the limit."""

    def __init__(self, message: str, too_large: bool = False):
        super().__init__(message)
        self.too_large = too_large


def read_regular_file(path, limit: int, follow_symlinks: bool = True) -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    limit : int
        Most bytes accepted.
    follow_symlinks : bool
        False: a symbolic link is refused (``O_NOFOLLOW``; an ``OSError`` from ``open``).

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    OSError
        It cannot be opened (permissions, a symlink loop, a symlink with ``follow_symlinks=False``).
    FileProblem
        It is not a regular file (a FIFO, a device or a folder), is larger than ``limit``, or grew
        beyond it while being read.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    if not follow_symlinks:
        flags |= getattr(os, "O_NOFOLLOW", 0)
    fd = os.open(path, flags)
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise FileProblem("not a regular file (a FIFO, a device or a folder)")
        if st.st_size > limit:
            raise FileProblem(f"{st.st_size} bytes, more than the {limit} accepted", too_large=True)
        chunks, size = [], 0
        while size <= limit:
            chunk = os.read(fd, min(1 << 20, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > limit:
            raise FileProblem(f"more than {limit} bytes once read (it grew while being read)", too_large=True)
        return b"".join(chunks)
    finally:
        os.close(fd)
