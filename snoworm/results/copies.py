"""A results folder holds copies of the files its run read (issue 30): it is self-contained.

A run folder's ``scenario.yaml`` must read back (:func:`~snoworm.results.result.load_result`) and
re-run (``snoworm run FOLDER/scenario.yaml``) the same run wherever the folder is moved, from any
working folder, whatever happens to the original files.  So :meth:`Result.write
<snoworm.results.result.Result.write>` copies every file the scenario read
(:meth:`Scenario.data_files <snoworm.config.scenario.Scenario.data_files>`: a route file, a
parameter-set file) into ``inputs/`` (:func:`copy_inputs`), and the written ``scenario.yaml``
names the copies relative to the folder (relative paths of a scenario file are read from its
folder).  The folder's manifest records each copy's SHA-256
(:func:`snoworm.infra.manifest.input_digests`); :func:`input_problem` finds a copy changed since,
which ``load_result`` refuses before reading it.

Controller code is not copied (docs/controllers.md: code runs only from where the user trusts it).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from ..config.params import read_parameter_file
from ..config.schema import ScenarioError
from ..infra.files import FileProblem, read_regular_file
from ..infra.folders import OutputError, atomic_path
from ..infra.manifest import INPUTS, MANIFEST, ManifestProblem, folder_files, load_manifest, read_small_file

__all__ = ["INPUTS", "MAX_INPUT_BYTES", "copy_inputs", "write_copies", "input_problem"]

#: Largest input file copied or checked (bytes): the largest route file read (64 MiB).
MAX_INPUT_BYTES = 64 * 2**20

#: The order in which files get their names in ``inputs/``: a parameter-set file first, since its
#: name is part of its values' source tags (``[user] my_rover.yaml``).
_ORDER = ("vehicle.parameter_set", "terrain.route")


def _free_name(name: str, used: set) -> str:
    """``name``, or ``stem-2.suffix``, ``stem-3.suffix``, ... if a copy has that name already."""
    stem, suffix = os.path.splitext(name)
    out, k = name, 1
    while out in used:
        k += 1
        out = f"{stem}-{k}{suffix}"
    used.add(out)
    return out


def _bytes_read(sc, key: str, path: Path) -> bytes:
    """The bytes of the file behind ``key`` as the scenario read them: the route's bytes kept when
    it was read; a parameter-set file read again (and checked against its values after copying)."""
    if key == "terrain.route":
        data = sc.terrain.route_data().data
        if data:
            return data
    try:
        return read_regular_file(path, MAX_INPUT_BYTES)
    except (OSError, FileProblem) as exc:
        raise OutputError(f"{key}: cannot copy {path} into the results folder ({exc}).") from None


def write_copies(stage, files: dict) -> dict:
    """Write ``{key: (file name, bytes)}`` into ``stage/inputs/`` (a name taken twice becomes
    ``stem-2.suffix``, in the order given); return ``{key: path relative to stage}``.  The folder's
    manifest then records each copy's SHA-256 (:func:`snoworm.infra.folders.write_manifest`)."""
    used, out = set(), {}
    for key, (name, data) in files.items():
        name = _free_name(name, used)
        with atomic_path(Path(stage) / INPUTS / name) as tmp:
            tmp.write_bytes(data)
        out[key] = f"{INPUTS}/{name}"
    return out


def copy_inputs(sc, stage) -> dict:
    """Copy each file ``sc`` read into ``stage/inputs/``; return ``{dotted key: path relative to
    stage}`` for :func:`~snoworm.config.scenario.dump_scenario`.

    Raises
    ------
    OutputError
        A file cannot be read again, or a parameter-set file changed since the scenario read it
        (the folder would not hold what the run used).
    """
    files = sc.data_files()
    keys = sorted(files, key=lambda k: _ORDER.index(k) if k in _ORDER else len(_ORDER))
    out = write_copies(stage, {k: (Path(files[k]).name, _bytes_read(sc, k, Path(files[k]))) for k in keys})
    ps = out.get("vehicle.parameter_set")
    if ps is not None and sc.origin is not None and _entries(Path(stage) / ps) != sc.origin.entries:
        raise OutputError(
            f"vehicle.parameter_set: {files['vehicle.parameter_set']} changed since the scenario was read; "
            "its results would not hold the values the run used. Run the scenario again."
        )
    return out


def _entries(path):
    try:
        return read_parameter_file(path)
    except ScenarioError:
        return None


def input_problem(folder) -> str | None:
    """Why the copies in ``folder/inputs/`` cannot be trusted, or None: a copy whose SHA-256 is
    not the one the folder's manifest recorded when the run was written, a copy the manifest does
    not record (copied without the manifest, or added), one missing, or not a regular file."""
    d = Path(folder)
    base = d / INPUTS
    if not os.path.lexists(base):
        return None  # the run read no file (or a folder written before issue 30, naming its originals)
    if base.is_symlink() or not base.is_dir():
        return f"{base}: not a folder (a symbolic link or a file); a run's input copies are a folder"
    try:
        man = load_manifest(d)
    except ManifestProblem as exc:
        return str(exc)
    recorded = (man or {}).get("inputs")
    recorded = recorded if isinstance(recorded, dict) else {}
    present = [f"{INPUTS}/{rel}" for rel in folder_files(base)]
    for entry in present:
        want = recorded.get(entry)
        if not isinstance(want, str):
            return (
                f"{d / entry}: its SHA-256 is not recorded in {d / MANIFEST} (the folder was copied "
                f"without its {MANIFEST}, or the file was added); snoworm reads no input it cannot check. "
                "Copy the results folder whole, or run the scenario again"
            )
        try:
            data = read_small_file(d / entry, MAX_INPUT_BYTES)  # a regular file: not a FIFO, a device or a link
        except (ManifestProblem, OSError) as exc:
            return str(exc)
        got = hashlib.sha256(data).hexdigest()
        if got != want:
            return (
                f"{d / entry}: changed since the run was written (SHA-256 {got[:16]}..., the manifest "
                f"records {want[:16]}...), so the folder no longer holds what the run read. Restore the "
                "file, or run the scenario again"
            )
    missing = sorted(set(recorded) - set(present))
    if missing:
        return f"{d / str(missing[0])}: missing; the run read it ({d / MANIFEST} records it)"
    return None
