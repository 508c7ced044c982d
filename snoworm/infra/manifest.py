"""Output-folder manifests, read defensively: snoworm never touches a path outside ``--out``.

A snoworm output folder holds :data:`MANIFEST`, a JSON file listing (as relative POSIX paths)
the files snoworm wrote there (and, under ``inputs``, the SHA-256 of the copies of the files a
run read: :func:`input_digests`).  A folder received from someone else (a shared results folder,
an archive, a cloned repository) may hold a manifest crafted to name other files, so every
manifest is checked before any of its entries is acted on:

* the manifest is a regular file (not a symlink, a FIFO or a device: opened with
  ``O_NONBLOCK | O_NOFOLLOW`` and checked with ``fstat`` before a byte is read), at most
  :data:`MAX_MANIFEST_BYTES` long, holding a JSON object whose ``files`` is a list of strings;
* every entry is a relative path in normal form (no ``..``, ``.``, empty part, backslash or NUL,
  at most :data:`MAX_ENTRY_CHARS` characters);
* an entry acted on resolves inside the folder without passing through a symlink (each part is
  checked with ``lstat``), and is a regular file or a symlink (removing a symlink removes the link,
  never its target).

A manifest failing any check is a :class:`ManifestProblem` (its message names the manifest and
the problem); the folder is then foreign (:func:`snoworm.infra.folders.folder_state`): nothing in it is
removed on the manifest's word.
"""

from __future__ import annotations

import hashlib
import json
import os
import stat
from pathlib import Path

from .files import FileProblem, read_regular_file

__all__ = [
    "MANIFEST",
    "LOCK",
    "STAGE",
    "JOURNAL",
    "MAX_MANIFEST_BYTES",
    "MAX_ENTRY_CHARS",
    "ManifestProblem",
    "read_small_file",
    "load_manifest",
    "entry_problem",
    "lexists_inside",
    "listed_files",
    "folder_files",
    "short",
    "INPUTS",
    "input_digests",
    "input_record",
    "sha256_of",
]

#: Name of the manifest a snoworm output folder holds.
MANIFEST = ".snoworm-manifest.json"
#: Name of the lock file of a folder in use (:func:`snoworm.infra.folders.folder_lock`).
LOCK = ".snoworm-lock"
#: Part of the name of a staging folder (never listed, never a reason to call a folder foreign).
STAGE = ".snoworm-tmp-"
#: Folder of a results folder holding copies of the files its run read (a route, a parameter-set
#: file): the manifest records the SHA-256 of each (:func:`input_digests`, issue 30).
INPUTS = "inputs"
#: Name of the journal of a commit in place (:mod:`snoworm.infra.commit`; never listed).
JOURNAL = ".snoworm-commit.json"
#: Largest manifest read (bytes): a sweep of 100 000 saved cases lists about 600 000 files (~40 MB).
MAX_MANIFEST_BYTES = 64 * 2**20
#: Longest entry accepted (characters): PATH_MAX on Linux.
MAX_ENTRY_CHARS = 4096


class ManifestProblem(ValueError):
    """A manifest (or a path it names) that snoworm will not act on; the message says why."""


def short(value, limit: int = 100) -> str:
    """``repr`` of a user's value cut to about ``limit`` characters (messages stay short)."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def read_small_file(path, limit: int) -> bytes:
    """The bytes of ``path``, a regular file of at most ``limit`` bytes.

    Opened with ``O_NONBLOCK | O_NOFOLLOW`` and checked with ``fstat`` before reading, so a FIFO,
    a device (``/dev/zero``), a symlink or an oversized file is refused at once, unread.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ManifestProblem
        ``path`` is not a regular file, or is larger than ``limit``; the message names it.
    """
    try:
        return read_regular_file(path, limit, follow_symlinks=False)
    except FileNotFoundError:
        raise
    except OSError as exc:
        kind = "a symbolic link" if os.path.islink(path) else f"unreadable ({exc.strerror or exc})"
        raise ManifestProblem(f"{path} is {kind}, not a regular file") from None
    except FileProblem as exc:
        raise ManifestProblem(f"{path} is {exc}") from None


def entry_problem(entry) -> str | None:
    """Why ``entry`` is not an acceptable manifest entry (None if it is): a relative POSIX path
    in normal form, inside the folder."""
    if not isinstance(entry, str):
        return f"entry {short(entry)} is not a text path"
    if not entry or len(entry) > MAX_ENTRY_CHARS:
        return f"entry {short(entry)} is empty or longer than {MAX_ENTRY_CHARS} characters"
    if "\x00" in entry or "\\" in entry:
        return f"entry {short(entry)} holds a NUL or a backslash"
    if entry.startswith("/"):  # what PurePosixPath(entry).is_absolute() says, without building the path
        return f"entry {short(entry)} is an absolute path"
    parts = entry.split("/")
    if any(part in ("", ".", "..") for part in parts):
        return f"entry {short(entry)} is not a plain relative path inside the folder (no '..', '.' or '//')"
    if parts[0] in (MANIFEST, LOCK) or STAGE in parts[0] or parts[0].startswith(JOURNAL):
        return f"entry {short(entry)} names snoworm's own bookkeeping file"
    return None


def load_manifest(folder) -> dict | None:
    """The manifest of ``folder``, checked (see the module docstring), or None if it has none.

    Raises
    ------
    ManifestProblem
        The manifest exists but is not a small regular file of the expected shape, or an entry
        is not a plain relative path.
    """
    path = Path(folder) / MANIFEST
    try:
        data = read_small_file(path, MAX_MANIFEST_BYTES)
    except FileNotFoundError:
        return None
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise ManifestProblem(f"{path} is not valid JSON") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("files"), list):
        raise ManifestProblem(f"{path} is not a JSON object with a 'files' list")
    digest = hashlib.sha256(data).digest()
    if digest != _LAST_CHECKED[0]:  # the entries' checks depend on the bytes only: once per content
        for entry in doc["files"]:
            why = entry_problem(entry)
            if why is not None:
                raise ManifestProblem(f"{path}: {why}")
        _LAST_CHECKED[0] = digest
    return doc


#: SHA-256 of the last manifest whose entries passed :func:`load_manifest`'s checks (a command
#: reads its folder's manifest several times; a large sweep's lists ~600 000 entries)
_LAST_CHECKED = [None]


def lexists_inside(root, entry: str) -> os.stat_result | None:
    """``lstat`` of ``root/entry`` reached without passing through a symlink (None if missing).

    ``entry`` is a checked manifest entry (:func:`entry_problem`).

    Raises
    ------
    ManifestProblem
        A folder on the way is a symlink or not a folder.
    """
    cur = str(root)
    parts = entry.split("/")
    for i, part in enumerate(parts):
        cur = os.path.join(cur, part)
        try:
            st = os.lstat(cur)
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise ManifestProblem(f"{cur}: {exc.strerror or exc}") from None
        if i < len(parts) - 1:
            if stat.S_ISLNK(st.st_mode):
                raise ManifestProblem(
                    f"{cur} is a symbolic link: the entry {short(entry)} would lead outside the folder"
                )
            if not stat.S_ISDIR(st.st_mode):
                return None
    return st


def listed_files(folder, manifest: dict) -> list:
    """The paths ``folder/entry`` of the manifest's entries that exist, each checked to be a
    regular file or a symlink reached without passing through a symlink.

    Raises
    ------
    ManifestProblem
        An entry passes through a symlink, or names a folder, a FIFO or a device.
    """
    out = []
    for entry in manifest["files"]:
        st = lexists_inside(folder, entry)
        if st is None:
            continue
        if not (stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode)):
            raise ManifestProblem(f"{Path(folder) / entry} is listed in {MANIFEST} but is not a file")
        out.append(Path(folder) / entry)
    return out


def folder_files(folder) -> list:
    """Relative paths (POSIX) of every entry under ``folder`` that is not a folder (files, symlinks
    - to folders too -, FIFOs...) but the manifest, the lock, a commit's journal and staging
    folders; symlinks are not followed."""
    folder = Path(folder)
    out = []
    for root, dirs, names in os.walk(folder):
        keep = []
        for d in dirs:
            if STAGE in d:
                continue
            if os.path.islink(os.path.join(root, d)):
                names.append(d)  # a symlink to a folder: an entry, never walked
            else:
                keep.append(d)
        dirs[:] = keep
        for n in names:
            rel = (Path(root) / n).relative_to(folder).as_posix()
            if rel not in (MANIFEST, LOCK) and not rel.startswith(JOURNAL):
                out.append(rel)
    return sorted(out)


def sha256_of(path) -> str:
    """The SHA-256 (hex) of the file at ``path``, read in 1 MiB chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def input_digests(folder) -> dict:
    """``{entry: SHA-256}`` of the regular files under ``folder/inputs/`` (:data:`INPUTS`): what a
    manifest records of the copies of a run's input files ({} without that folder)."""
    base = Path(folder) / INPUTS
    if base.is_symlink() or not base.is_dir():
        return {}
    out = {}
    for rel in folder_files(base):
        p = base / rel
        if p.is_file() and not p.is_symlink():
            out[f"{INPUTS}/{rel}"] = sha256_of(p)
    return out


def input_record(folder) -> dict:
    """``{"inputs": input_digests(folder)}`` for a manifest, or {} without copies."""
    digests = input_digests(folder)
    return {"inputs": digests} if digests else {}
