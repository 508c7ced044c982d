"""The files a sweep's scenario refers to, hashed into its resume key (issue 24).

A sweep resumes only with the same inputs: besides the scenario mapping and the axes, its
``sweep.json`` records the snoworm version and the SHA-256 of every file the scenario (or a swept
value) refers to -- a controller file or a ``package.module`` controller's source, a parameter-set
file, a terrain-model file, any other ``.py``/``.yaml``/``.yml``/``.json``/``.csv`` file named by a
value.  A change to any of them refuses the resume, naming the file (``--restart`` starts afresh).
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path

from ...modes.codeload import code_files

__all__ = ["FILE_SUFFIXES", "referenced_files", "input_hashes", "changed_inputs"]

#: Suffixes of values taken as file references (a value naming an existing file).
FILE_SUFFIXES = (".py", ".yaml", ".yml", ".json", ".csv")


def _strings(data):
    if isinstance(data, str):
        yield data
    elif isinstance(data, dict):
        for v in data.values():
            yield from _strings(v)
    elif isinstance(data, (list, tuple)):
        for v in data:
            yield from _strings(v)


def _candidates(text: str, base: Path):
    """Paths ``text`` may name: a file path (holding a ``/`` or ending in a :data:`FILE_SUFFIXES`
    suffix), or a controller reference ``file.py:Name`` / ``package.module:Name``."""
    if len(text) >= 4096 or "\x00" in text:
        return
    target, sep, name = text.rpartition(":")
    if sep and name.isidentifier() and target:
        if "/" not in target and not target.endswith(".py"):
            yield from code_files(text)  # package.module:Name (found statically)
            return
        text = target
    if "/" in text or text.endswith(FILE_SUFFIXES):
        p = Path(os.path.expanduser(text))
        yield p if p.is_absolute() else base / p


def referenced_files(raw, axes, base_dir) -> list:
    """Resolved paths of the regular files the scenario mapping ``raw`` or a swept value names."""
    base = Path(base_dir) if base_dir is not None else Path.cwd()
    texts = list(_strings(raw)) + [v for a in axes for v in _strings(list(a.values))]
    found = set()
    for text in texts:
        for p in _candidates(text, base):
            try:
                if stat.S_ISREG(os.stat(p).st_mode):
                    found.add(os.path.realpath(p))
            except (OSError, ValueError):
                continue
    return sorted(found)


def _sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def input_hashes(raw, axes, base_dir) -> dict:
    """``{path: sha256}`` of :func:`referenced_files` (a file unreadable now: ``"unreadable"``)."""
    out = {}
    for p in referenced_files(raw, axes, base_dir):
        try:
            out[p] = _sha256(p)
        except OSError:
            out[p] = "unreadable"
    return out


def changed_inputs(old: dict, new: dict) -> list:
    """Paths whose hash differs between two :func:`input_hashes` (added or removed ones too)."""
    old, new = old or {}, new or {}
    return sorted(p for p in set(old) | set(new) if old.get(p) != new.get(p))
