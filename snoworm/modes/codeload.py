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
  (``--allow-code PATH``, ``allow_code=`` in Python), passed explicitly from the entry point
  that asked for the run (the CLI, ``simulate``, a sweep's task) to the controller mode that
  loads the code: no other layer holds or reads the allow-list.  A scenario read back
  by ``load_result`` trusts no folder of its own.  A module controller is trusted as installed
  code when its source lies in the installed packages (site-packages, a folder an editable
  install maps, snoworm itself); otherwise its source and its packages' ``__init__.py`` follow
  the file rule (``python -m snoworm``, ``PYTHONPATH=.``, ``python -c`` and a notebook put the
  working folder on the path: a module there is not trusted for being importable).
* :func:`import_class` (when a simulation starts) runs both checks again, then runs exactly the
  bytes it checked: a file controller's (and a not-installed module's) source is read once,
  checked and compiled from those bytes, never from a cached ``__pycache__/*.pyc``; installed
  modules are imported as usual.  ``Name`` must be a class defined in that module (not a
  function, not a re-export).
"""

from __future__ import annotations

import ast
import hashlib
import importlib
import importlib.machinery
import importlib.util
import os
import site
import sys
import sysconfig
from functools import lru_cache
from pathlib import Path

from ..config.schema import ScenarioError, quote
from ..infra.files import FileProblem, read_regular_file

__all__ = [
    "MAX_SOURCE_BYTES",
    "MAX_SPEC_CHARS",
    "split_spec",
    "is_file_spec",
    "resolve_spec",
    "check_reference",
    "trust_problem",
    "allowed_paths",
    "module_sources",
    "import_class",
    "code_files",
]

#: Largest controller source file read (bytes).
MAX_SOURCE_BYTES = 4 * 2**20
#: Longest controller reference accepted (characters).
MAX_SPEC_CHARS = 4096

_PKG_DIR = Path(__file__).resolve().parents[1]


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
def _read_source(p: Path, path) -> bytes:
    """The bytes of controller file ``p`` (a regular file of at most :data:`MAX_SOURCE_BYTES`),
    read once without blocking on a FIFO (ScenarioError naming the file otherwise)."""
    try:
        return read_regular_file(p, MAX_SOURCE_BYTES)
    except FileNotFoundError:
        raise ScenarioError(
            f"{path}: controller file {quote(str(p))} does not exist (a relative path is taken from "
            "the scenario file's folder). Fix the path."
        ) from None
    except FileProblem as exc:
        if exc.too_large:
            raise ScenarioError(
                f"{path}: controller file {quote(str(p))} is {exc}. Name a controller's source file."
            ) from None
        raise ScenarioError(
            f"{path}: controller file {quote(str(p))} is not a regular file. Name a .py file."
        ) from None
    except (OSError, ValueError) as exc:  # a symlink loop, a name too long, no permission
        raise ScenarioError(
            f"{path}: controller file {quote(str(p))} cannot be used: "
            f"{getattr(exc, 'strerror', None) or exc}. Fix the path."
        ) from None


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


def _check_class(source: bytes, name: str, where: str, path):
    try:
        tree = ast.parse(source)  # bytes: decoded as Python decodes a source file (coding cookie, BOM)
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
    """(spec, mapped) of top-level module ``name`` without importing it: on ``sys.path``
    (``mapped`` False), else from the other finders of ``sys.meta_path`` (an editable install,
    ``pip install -e``, maps its packages with one: ``mapped`` True), the interpreter's own
    built-in and frozen modules excepted; (None, False) if not found."""
    spec = importlib.machinery.PathFinder.find_spec(name)
    if spec is not None:
        return spec, False
    skip = (importlib.machinery.BuiltinImporter, importlib.machinery.FrozenImporter, importlib.machinery.PathFinder)
    for finder in sys.meta_path:
        if finder in skip or not hasattr(finder, "find_spec"):
            continue
        try:
            spec = finder.find_spec(name, None)
        except Exception:  # a third-party finder's failure is "not found" here
            spec = None
        if spec is not None:
            return spec, True
    return None, False


def _module_specs(target: str, path) -> tuple:
    """(specs of ``target``'s packages and of itself, whether an installed finder maps its
    top-level package), found without importing any of them (ScenarioError if not found)."""
    parts = target.split(".")
    if not all(p.isidentifier() for p in parts):
        raise ScenarioError(f"{path}: {quote(target)} is neither a module name (dotted identifiers) nor a .py file.")
    if parts[0] in sys.stdlib_module_names or parts[0] in sys.builtin_module_names:
        raise ScenarioError(
            f"{path}: {quote(target)} is part of Python's standard library, not a controller. "
            "Name your own module or file."
        )
    search, specs, mapped = None, [], False
    for i in range(len(parts)):
        full = ".".join(parts[: i + 1])
        try:
            if i:
                spec = importlib.machinery.PathFinder.find_spec(full, search)
            else:
                spec, mapped = _find_top_level(full)
        except (ImportError, ValueError, OSError):
            spec = None
        if spec is None:
            raise ScenarioError(
                f"{path}: module {quote(full)} is not found on the Python path. "
                "Give an importable module or a file path ending in .py."
            )
        specs.append(spec)
        search = spec.submodule_search_locations
        if i < len(parts) - 1 and search is None:
            raise ScenarioError(f"{path}: {quote(full)} is a module, not a package.")
    origin = specs[-1].origin
    if not origin or not origin.endswith(".py"):
        raise ScenarioError(
            f"{path}: module {quote(target)} has no Python source file (a namespace package or "
            "a compiled module). Name a module written in Python."
        )
    src = Path(origin).resolve()
    if any(src.is_relative_to(d) for d in _stdlib_dirs()) and not {"site-packages", "dist-packages"} & set(src.parts):
        raise ScenarioError(f"{path}: {quote(target)} is part of Python's standard library, not a controller.")
    return specs, mapped


def _sources(specs) -> list:
    """The source files (resolved) that importing ``specs`` runs: packages' ``__init__.py``, the module."""
    return [Path(s.origin).resolve() for s in specs if s.origin and s.origin.endswith(".py")]


def find_module_source(target: str, path) -> Path:
    """The source file of module ``target``, found on ``sys.path`` without importing it or its parents."""
    return _sources(_module_specs(target, path)[0])[-1]


@lru_cache(maxsize=64)
def _pth_dirs(site_dir: str, mtime_ns: int) -> tuple:
    """The folders the ``.pth`` files of ``site_dir`` put on the path (an editable install's
    source folder), as :mod:`site` reads them (``import`` lines and comments skipped)."""
    out = []
    for n in sorted(os.listdir(site_dir)):
        if not n.endswith(".pth"):
            continue
        try:
            text = read_regular_file(os.path.join(site_dir, n), 1 << 20).decode("utf-8", "replace")
        except (OSError, ValueError):
            continue
        for line in text.splitlines():
            line = line.rstrip()
            if line and not line.startswith(("#", "import ", "import\t")):
                d = os.path.join(site_dir, line)
                if os.path.isdir(d):
                    out.append(Path(os.path.realpath(d)))
    return tuple(out)


def installed_roots() -> list:
    """The folders of installed code: the site-packages folders, the folders their ``.pth`` files
    add (editable installs), the standard library and snoworm's own package (resolved)."""
    dirs = list(getattr(site, "getsitepackages", list)())
    if site.ENABLE_USER_SITE:
        dirs.append(site.getusersitepackages())
    roots = [*_stdlib_dirs(), _PKG_DIR]
    for d in dirs:
        try:
            roots += [Path(os.path.realpath(d)), *_pth_dirs(d, os.stat(d).st_mtime_ns)]
        except (OSError, ValueError):
            continue
    return roots


def module_sources(target: str, path="mode.controller") -> tuple:
    """(source files importing module ``target`` runs: its packages' ``__init__.py`` and its own,
    whether it is installed code), found statically.  Installed: an installed finder maps its
    top-level package (``pip install -e``) or every file lies in :func:`installed_roots`."""
    specs, mapped = _module_specs(target, path)
    files = _sources(specs)
    roots = installed_roots()
    return files, mapped or all(any(f.is_relative_to(r) for r in roots) for f in files)


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
def allowed_paths(paths) -> tuple:
    """``paths`` (files or folders whose controller code may run) resolved; ScenarioError for an
    empty path, which would resolve to the whole working folder."""
    out = []
    for p in paths or ():
        text = os.fspath(p) if isinstance(p, os.PathLike) else str(p)
        if not text.strip() or "\x00" in text:
            raise ScenarioError(
                f"--allow-code {quote(text)}: an empty path (or one holding a NUL byte) would allow the "
                "code of the whole working folder. Name the file or folder whose controller code may run."
            )
        out.append(os.path.realpath(os.path.expanduser(text)))
    return tuple(out)


def trust_problem(spec: str, root, path: str = "mode.controller", allowed=()) -> str | None:
    """Why the controller ``spec`` may not run (None if it may): a file outside ``root`` (the
    scenario's folder, resolved; None: no folder is trusted, a read-back scenario) and outside
    every path of ``allowed`` (the user's ``--allow-code`` / ``allow_code=``, resolved by
    :func:`allowed_paths`); a module whose source is not installed code (:func:`module_sources`)
    follows the same rule for its source and its packages' ``__init__.py``."""
    target, _ = split_spec(spec, path)
    if is_file_spec(target):
        files, what = [Path(os.path.realpath(target))], "controller file"
    else:
        files, installed = module_sources(target, path)
        if installed:
            return None
        what = f"module {target} is not installed code (not in site-packages or an editable install), and its source"
    roots = [Path(r) for r in allowed_paths(allowed)] + ([Path(os.path.realpath(root))] if root is not None else [])
    outside = [f for f in files if not any(f == r or f.is_relative_to(r) for r in roots)]
    if not outside:
        return None
    where = (
        f"outside the scenario's folder {quote(str(root), 200)}"
        if root is not None
        else "named by a scenario read back from a results folder (load_result), which never runs code"
    )
    allow = Path(os.path.commonpath([f.parent for f in outside]))
    return (
        f"{path}: {what} {quote(str(outside[-1]), 200)} is {where}. A scenario with a controller is a program: "
        f"snoworm runs it only if you allow it. Pass --allow-code {quote(str(allow), 200)} "
        "(allow_code=[...] in Python), or move the file into the scenario's folder"
        + ("." if is_file_spec(target) else " (or install its package: pip install).")
    )


#: loaded controller files: absolute path -> (SHA-256 of the source, module)
_FILES: dict = {}


def _run_bytes(data: bytes, spec, where: str, path):
    """A fresh module of ``spec`` (in ``sys.modules``) with ``data``, the bytes checked, compiled
    and run: never a cached ``.pyc`` (which a folder may hold beside a harmless-looking source)."""
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        exec(compile(data, spec.origin, "exec", dont_inherit=True), module.__dict__)  # noqa: S102 - the user's checked code
    except Exception as exc:  # noqa: BLE001 - any error in the user's file is bad input
        sys.modules.pop(spec.name, None)
        raise ScenarioError(f"{path}: importing {where} failed: {type(exc).__name__}: {quote(str(exc))}") from None
    return module


def _exec_file(p: Path, name: str, path):
    data = _read_source(p, path)  # read once: these bytes are hashed, checked, compiled and run
    digest = hashlib.sha256(data).hexdigest()
    cached = _FILES.get(str(p))
    if cached and cached[0] == digest:
        return cached[1]
    where = f"controller file {quote(str(p), 200)}"
    _check_class(data, name, where, path)
    modname = "snoworm_controller_" + hashlib.sha1(str(p).encode()).hexdigest()[:12]
    module = _run_bytes(data, importlib.util.spec_from_file_location(modname, p), where, path)
    _FILES[str(p)] = (digest, module)
    return module


def _import_checked(target: str, name: str, path):
    """Import module ``target`` (not installed code) and its packages from their sources, each
    read once, the module's checked for class ``name``: no cached bytecode runs.  A package or
    module already imported from the same file is reused; from another file, refused."""
    specs, _ = _module_specs(target, path)
    module = None
    for i, spec in enumerate(specs):
        last = i == len(specs) - 1
        have = sys.modules.get(spec.name)
        if have is not None:
            file = getattr(have, "__file__", None)
            if file is not None and spec.origin and os.path.realpath(file) != os.path.realpath(spec.origin):
                raise ScenarioError(
                    f"{path}: module {spec.name} is already imported from {quote(file, 200)}, not from "
                    f"{quote(spec.origin, 200)} found on the path. Run it in a fresh process."
                )
            module = have
            continue
        if spec.origin and spec.origin.endswith(".py"):
            data = _read_source(Path(spec.origin), path)
            if last:
                _check_class(data, name, f"module {target} ({spec.origin})", path)
            child = _run_bytes(data, spec, f"module {spec.name} ({spec.origin})", path)
        else:  # a namespace package: no code
            child = importlib.util.module_from_spec(spec)
            sys.modules[spec.name] = child
        if module is not None:
            setattr(module, spec.name.rpartition(".")[2], child)
        module = child
    return module


def import_class(spec: str, root, path: str = "mode.controller", allowed=()):
    """Import the controller class of ``spec`` (when a simulation starts): the static checks and
    the trust check again, then the import; ``Name`` must be a class defined in that module.
    A file, or a module that is not installed code, runs from the bytes checked (never a
    ``__pycache__`` file); an installed module is imported as usual."""
    check_reference(spec, path)
    why = trust_problem(spec, root, path, allowed)
    if why is not None:
        raise ScenarioError(why)
    target, name = split_spec(spec, path)
    if is_file_spec(target):
        module = _exec_file(Path(target), name, path)
    elif not module_sources(target, path)[1]:
        module = _import_checked(target, name, path)
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
    controller's path, or a module's source and its packages' ``__init__.py`` found statically;
    [] if they cannot be found."""
    target, _, _ = str(spec).rpartition(":")
    if is_file_spec(target):
        return [Path(target)]
    try:
        return module_sources(target, "mode.controller")[0]
    except ScenarioError:
        return []
