"""A controller reference checked without running it; its code imported only when a simulation starts.

A scenario with ``mode: {type: controller, controller: ...}`` is a program: running it runs the
named Python code.  Reading it never does (issue 24):

* :func:`check_reference` (at validation: ``validate``, ``load_scenario``, ``load_result``,
  ``load_sweep``, a sweep's planning, ``--set mode.controller=...``) checks the reference
  statically.  ``file.py:Name``: the file exists, is a regular ``.py`` file of at most
  :data:`MAX_SOURCE_BYTES`, parses, and defines ``class Name`` at its top level (read from the
  syntax tree).  ``package.module:Name``: the module's source is found on ``sys.path`` (parents
  located with :class:`importlib.machinery.PathFinder`, never imported), it is not the standard
  library, and its syntax tree defines ``class Name``.
* :func:`trust_problem` (static too): a file controller must lie inside the scenario's own folder
  tree (both resolved, so a symlink cannot escape) or inside a folder the user allowed
  (:func:`allow_code`, ``--allow-code PATH``, ``allow_code=`` in Python).  A scenario read back
  by ``load_result`` trusts no folder of its own.
* :func:`import_class` (when a simulation starts) runs both checks again, imports the code and
  checks that ``Name`` is a class defined in that module (not a function, not a re-export).
"""

from __future__ import annotations

import ast
import contextvars
import hashlib
import importlib
import importlib.machinery
import importlib.util
import os
import stat
import sys
import sysconfig
from contextlib import contextmanager
from pathlib import Path

from ..config.schema import ScenarioError, quote

__all__ = [
    "MAX_SOURCE_BYTES",
    "MAX_SPEC_CHARS",
    "split_spec",
    "is_file_spec",
    "resolve_spec",
    "check_reference",
    "trust_problem",
    "allow_code",
    "allowed_roots",
    "import_class",
    "code_files",
]

#: Largest controller source file read (bytes).
MAX_SOURCE_BYTES = 4 * 2**20
#: Longest controller reference accepted (characters).
MAX_SPEC_CHARS = 4096

_ALLOWED = contextvars.ContextVar("snoworm_allowed_code", default=())


def split_spec(spec, path):
    """(target, class name) of ``'file.py:Name'`` or ``'package.module:Name'`` (ScenarioError if malformed)."""
    text = str(spec)
    if len(text) > MAX_SPEC_CHARS or "\x00" in text:
        raise ScenarioError(
            f"{path}: {quote(spec)} is longer than {MAX_SPEC_CHARS} characters or holds a NUL byte. "
            "Give 'file.py:ClassName' or 'package.module:ClassName'."
        )
    target, sep, name = text.rpartition(":")
    if not sep or not target or not name.isidentifier():
        raise ScenarioError(
            f"{path}: expected 'file.py:ClassName' or 'package.module:ClassName', got {quote(spec)}. "
            "Name the class after a colon."
        )
    return target, name


def is_file_spec(target: str) -> bool:
    """Whether a reference's target is a file path (ends in .py or holds a path separator)."""
    return target.endswith(".py") or "/" in target or "\\" in target


def resolve_spec(spec, path, base: Path) -> str:
    """``spec`` with a file path made absolute (from ``base``, the scenario file's folder)."""
    target, name = split_spec(spec, path)
    if is_file_spec(target):
        if not target.endswith(".py"):
            raise ScenarioError(
                f"{path}: controller file {quote(target)} does not end in .py. Name a Python file "
                "('file.py:ClassName')."
            )
        p = Path(os.path.expanduser(target))
        target = os.path.realpath(base / p if not p.is_absolute() else p)
    return f"{target}:{name}"


# ------------------------------------------------------------------------------ static checks
def _read_source(p: Path, path) -> str:
    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise ScenarioError(
            f"{path}: controller file {quote(str(p))} does not exist (a relative path is taken from "
            "the scenario file's folder). Fix the path."
        ) from None
    except (OSError, ValueError) as exc:  # a symlink loop, a name too long
        raise ScenarioError(
            f"{path}: controller file {quote(str(p))} cannot be used: "
            f"{getattr(exc, 'strerror', None) or exc}. Fix the path."
        ) from None
    if not stat.S_ISREG(st.st_mode):
        raise ScenarioError(f"{path}: controller file {quote(str(p))} is not a regular file. Name a .py file.")
    if st.st_size > MAX_SOURCE_BYTES:
        raise ScenarioError(
            f"{path}: controller file {quote(str(p))} is {st.st_size} bytes, over the "
            f"{MAX_SOURCE_BYTES} accepted. Name a controller's source file."
        )
    try:
        with open(p, "rb") as fh:
            data = fh.read(MAX_SOURCE_BYTES + 1)
    except OSError as exc:
        raise ScenarioError(f"{path}: controller file {quote(str(p))} cannot be read: {exc.strerror or exc}.") from None
    return data.decode("utf-8", errors="replace")


def _top_level_classes(tree) -> list:
    """Names of the classes a module defines at its top level (also under top-level if/try)."""
    names, todo = [], list(tree.body)
    while todo:
        node = todo.pop(0)
        if isinstance(node, ast.ClassDef):
            names.append(node.name)
        elif isinstance(node, (ast.If, ast.Try)):
            todo += node.body + node.orelse + getattr(node, "finalbody", [])
            for h in getattr(node, "handlers", []):
                todo += h.body
    return names


def _check_class(source: str, name: str, where: str, path):
    try:
        tree = ast.parse(source)
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        line = f" (line {exc.lineno})" if getattr(exc, "lineno", None) else ""
        raise ScenarioError(
            f"{path}: {where} does not parse as Python{line}: {type(exc).__name__}: {quote(str(exc))}."
        ) from None
    found = _top_level_classes(tree)
    if name not in found:
        listed = ", ".join(sorted(n for n in found if not n.startswith("_"))[:20])
        raise ScenarioError(
            f"{path}: {where} defines no class {name!r}"
            + (f" (it defines: {listed})." if listed else ".")
            + " A controller is a class defined in that file or module."
        )


def _stdlib_dirs() -> list:
    paths = sysconfig.get_paths()
    return [Path(paths[k]).resolve() for k in ("stdlib", "platstdlib") if paths.get(k)]


def _find_top_level(name: str):
    """The spec of top-level module ``name`` without importing it: on ``sys.path``, else from the
    other finders of ``sys.meta_path`` (an editable install, ``pip install -e``, maps its packages
    with one), the interpreter's own built-in and frozen modules excepted."""
    spec = importlib.machinery.PathFinder.find_spec(name)
    if spec is not None:
        return spec
    skip = (importlib.machinery.BuiltinImporter, importlib.machinery.FrozenImporter, importlib.machinery.PathFinder)
    for finder in sys.meta_path:
        if finder in skip or not hasattr(finder, "find_spec"):
            continue
        try:
            spec = finder.find_spec(name, None)
        except Exception:  # a third-party finder's failure is "not found" here
            spec = None
        if spec is not None:
            return spec
    return None


def find_module_source(target: str, path) -> Path:
    """The source file of module ``target``, found on ``sys.path`` without importing it or its parents."""
    parts = target.split(".")
    if not all(p.isidentifier() for p in parts):
        raise ScenarioError(f"{path}: {quote(target)} is neither a module name (dotted identifiers) nor a .py file.")
    if parts[0] in sys.stdlib_module_names or parts[0] in sys.builtin_module_names:
        raise ScenarioError(
            f"{path}: {quote(target)} is part of Python's standard library, not a controller. "
            "Name your own module or file."
        )
    search, spec = None, None
    for i, part in enumerate(parts):
        try:
            spec = importlib.machinery.PathFinder.find_spec(part, search) if i else _find_top_level(part)
        except (ImportError, ValueError, OSError):
            spec = None
        if spec is None:
            raise ScenarioError(
                f"{path}: module {quote('.'.join(parts[: i + 1]))} is not found on the Python path. "
                "Give an importable module or a file path ending in .py."
            )
        search = spec.submodule_search_locations
        if i < len(parts) - 1 and search is None:
            raise ScenarioError(f"{path}: {quote('.'.join(parts[: i + 1]))} is a module, not a package.")
    origin = spec.origin
    if not origin or not origin.endswith(".py"):
        raise ScenarioError(
            f"{path}: module {quote(target)} has no Python source file (a namespace package or "
            "a compiled module). Name a module written in Python."
        )
    src = Path(origin).resolve()
    if any(src.is_relative_to(d) for d in _stdlib_dirs()) and not {"site-packages", "dist-packages"} & set(src.parts):
        raise ScenarioError(f"{path}: {quote(target)} is part of Python's standard library, not a controller.")
    return src


#: references found good: (source path, modification time, size, class name) -> True; a sweep
#: validates the same reference once per case, and parsing the file each time would dominate
_CHECKED: dict = {}


def _check_source(src: Path, name: str, where: str, path):
    try:
        st = os.stat(src)
        key = (str(src), st.st_mtime_ns, st.st_size, st.st_ino, name)
    except (OSError, ValueError):
        key = None
    if key is not None and key in _CHECKED:
        return
    _check_class(_read_source(src, path), name, where, path)
    if key is not None:
        if len(_CHECKED) > 1000:
            _CHECKED.clear()
        _CHECKED[key] = True


def check_reference(spec: str, path: str = "mode.controller"):
    """Check a resolved reference statically (nothing imported or run); ScenarioError if it is wrong."""
    target, name = split_spec(spec, path)
    if is_file_spec(target):
        _check_source(Path(target), name, f"controller file {quote(target)}", path)
    else:
        src = find_module_source(target, path)
        _check_source(src, name, f"module {target} ({src})", path)


# ------------------------------------------------------------------------------ trust
@contextmanager
def allow_code(paths=()):
    """Within the block, controller files under ``paths`` (files or folders) may run, wherever
    the scenario lies (``--allow-code PATH``).  Nests: the allowed paths add up."""
    extra = tuple(os.path.realpath(os.path.expanduser(str(p))) for p in (paths or ()))
    token = _ALLOWED.set(_ALLOWED.get() + extra)
    try:
        yield
    finally:
        _ALLOWED.reset(token)


def allowed_roots() -> tuple:
    """The paths allowed in this context (resolved)."""
    return _ALLOWED.get()


def trust_problem(spec: str, root, path: str = "mode.controller") -> str | None:
    """Why the controller ``spec`` may not run (None if it may): a file outside ``root`` (the
    scenario's folder, resolved; None: no folder is trusted, a read-back scenario) and outside
    every allowed path."""
    target, _ = split_spec(spec, path)
    if not is_file_spec(target):
        return None
    real = Path(os.path.realpath(target))
    roots = [Path(r) for r in allowed_roots()] + ([Path(os.path.realpath(root))] if root is not None else [])
    if any(real == r or real.is_relative_to(r) for r in roots):
        return None
    where = (
        f"outside the scenario's folder {root}"
        if root is not None
        else "named by a scenario read back from a results folder (load_result), which never runs code"
    )
    return (
        f"{path}: controller file {quote(str(real))} is {where}. A scenario with a controller is a program: "
        f"snoworm runs it only if you allow it. Pass --allow-code {quote(str(real.parent))} "
        "(allow_code=[...] in Python), or move the file into the scenario's folder."
    )


#: loaded controller files: absolute path -> (SHA-256 of the source, module)
_FILES: dict = {}


def _exec_file(p: Path, path):
    digest = hashlib.sha256(p.read_bytes()).hexdigest()  # <= MAX_SOURCE_BYTES (check_reference)
    cached = _FILES.get(str(p))
    if cached and cached[0] == digest:
        return cached[1]
    modname = "snoworm_controller_" + hashlib.sha1(str(p).encode()).hexdigest()[:12]
    spec = importlib.util.spec_from_file_location(modname, p)
    module = importlib.util.module_from_spec(spec)
    sys.modules[modname] = module
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # noqa: BLE001 - any error in the user's file is bad input
        sys.modules.pop(modname, None)
        raise ScenarioError(
            f"{path}: importing controller file {p} failed: {type(exc).__name__}: {quote(str(exc))}"
        ) from None
    _FILES[str(p)] = (digest, module)
    return module


def import_class(spec: str, root, path: str = "mode.controller"):
    """Import the controller class of ``spec`` (when a simulation starts): the static checks and
    the trust check again, then the import; ``Name`` must be a class defined in that module."""
    check_reference(spec, path)
    why = trust_problem(spec, root, path)
    if why is not None:
        raise ScenarioError(why)
    target, name = split_spec(spec, path)
    if is_file_spec(target):
        module = _exec_file(Path(target), path)
    else:
        try:
            module = importlib.import_module(target)
        except Exception as exc:  # noqa: BLE001 - a broken module is bad input
            raise ScenarioError(
                f"{path}: cannot import module {quote(target)} ({type(exc).__name__}: {quote(str(exc))})."
            ) from None
    cls = vars(module).get(name)
    if not isinstance(cls, type) or cls.__module__ != module.__name__:
        raise ScenarioError(
            f"{path}: {name!r} in {target} is not a class defined there (a function, an import "
            "or a re-export). Name a controller class defined in that file or module."
        )
    return cls


def code_files(spec: str) -> list:
    """The source files a reference runs (for the resume key and the CLI's notice): a file
    controller's path, or a module's source found statically; [] if it cannot be found."""
    target, _, _ = str(spec).rpartition(":")
    if is_file_spec(target):
        return [Path(target)]
    try:
        return [find_module_source(target, "mode.controller")]
    except ScenarioError:
        return []
