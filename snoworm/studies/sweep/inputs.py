"""The files a sweep's scenario refers to, hashed into its resume key (issue 24).

A sweep resumes only with the same inputs: besides the scenario mapping and the axes, its
``sweep.json`` records the snoworm version and the SHA-256 of every file the scenario (or a swept
value) refers to -- a controller file or a ``package.module`` controller's source (and its
packages' ``__init__.py``), a parameter-set file, a terrain-model file, and any other file a value
names, whatever its suffix (a controller's ``mode.params: {weights: w.npz}``): a value that is the
path of an existing regular file, taken from the scenario's folder or the working folder.  A file
over :data:`MAX_HASHED_BYTES` is keyed by its size and modification time instead of its contents.
A change to any of them refuses the resume, naming the file (``--restart`` starts afresh).  A file
the controller finds by itself (a path it builds, not one a value names) is not tracked.
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path

from ...modes.codeload import code_files

__all__ = ["MAX_HASHED_BYTES", "referenced_files", "input_hashes", "changed_inputs"]

#: Largest file whose contents are hashed (bytes); a larger one is keyed by its size and mtime.
MAX_HASHED_BYTES = 256 * 2**20


def _strings(data):
    if isinstance(data, str):
        yield data
    elif isinstance(data, dict):
        for v in data.values():
            yield from _strings(v)
    elif isinstance(data, (list, tuple)):
        for v in data:
            yield from _strings(v)


def _candidates(text: str, bases):
    """Paths ``text`` may name: itself as a path (from each of ``bases`` if relative), or the
    files of a controller reference ``file.py:Name`` / ``package.module:Name``."""
    if not text.strip() or len(text) >= 4096 or "\x00" in text:
        return
    target, sep, name = text.rpartition(":")
    if sep and name.isidentifier() and target:
        if "/" not in target and not target.endswith(".py"):
            yield from code_files(text)  # package.module:Name (found statically)
        else:
            text = target
    p = Path(os.path.expanduser(text))
    yield from [p] if p.is_absolute() else [b / p for b in bases]


def referenced_files(raw, axes, base_dir) -> list:
    """Resolved paths of the regular files the scenario mapping ``raw`` or a swept value names."""
    try:
        cwd = [Path.cwd()]
    except OSError:  # the working folder was removed
        cwd = []
    bases = list(dict.fromkeys(([Path(base_dir)] if base_dir is not None else []) + cwd))
    texts = set(_strings(raw)) | {v for a in axes for v in _strings(list(a.values))}
    found = set()
    for text in texts:
        for p in _candidates(text, bases):
            try:
                if stat.S_ISREG(os.stat(p).st_mode):
                    found.add(os.path.realpath(p))
            except (OSError, ValueError):
                continue
    return sorted(found)


def _sha256(path) -> str:
    """The file's SHA-256 (hex), or ``"size N bytes, mtime_ns T"`` for one over
    :data:`MAX_HASHED_BYTES`; ``"unreadable"`` if it is not a regular file now (never blocks)."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            return "unreadable"
        if st.st_size > MAX_HASHED_BYTES:
            return f"size {st.st_size} bytes, mtime_ns {st.st_mtime_ns} (too large to hash)"
        h = hashlib.sha256()
        for chunk in iter(lambda: os.read(fd, 1 << 20), b""):
            h.update(chunk)
        return h.hexdigest()
    finally:
        os.close(fd)


def input_hashes(raw, axes, base_dir) -> dict:
    """``{path: sha256}`` of :func:`referenced_files` (a file unreadable now: ``"unreadable"``)."""
    out = {}
    for p in referenced_files(raw, axes, base_dir):
        try:
            out[p] = _sha256(p)
        except OSError:
            out[p] = "unreadable"
    return out


def changed_inputs(old: dict | None, new: dict | None) -> list:
    """Paths whose hash differs between two :func:`input_hashes` (added or removed ones too)."""
    old, new = old or {}, new or {}
    return sorted(p for p in set(old) | set(new) if old.get(p) != new.get(p))
