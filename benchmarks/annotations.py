"""The annotated share of the public API (issue 31): how many public functions and methods carry
complete type annotations.

The public surface is docs/architecture.md's: the names of ``snoworm.__all__``,
``snoworm.modes.__all__`` and ``snoworm.env.__all__``.  The modules measured are those three
packages' ``__init__`` and every module defining one of their names (found by importing the
packages and reading each class's or function's ``__module__``; ``snoworm.env`` needs the
``gym`` extra).  In each module the script counts, with :mod:`ast`:

* every module-level function whose name does not start with ``_``;
* in every class whose name does not start with ``_``, every method (properties included) whose
  name does not start with ``_``, and ``__init__`` (a constructor's parameters are public).

A function is *fully annotated* when every parameter but the first of a method (``self``/``cls``;
a ``staticmethod``'s first parameter counts) is annotated, ``*args`` and ``**kwargs`` included,
and so is its return (``__init__`` may leave its return out, as PEP 484 allows).

Run from the repository (or with the tree to measure on ``PYTHONPATH``)::

    python benchmarks/annotations.py            # the share, and the functions left incomplete
    python benchmarks/annotations.py --json     # the numbers as JSON
"""

from __future__ import annotations

import argparse
import ast
import importlib
import json
import sys
from pathlib import Path

PACKAGES = ("snoworm", "snoworm.modes", "snoworm.env")


def public_modules() -> dict[str, Path]:
    """The modules defining the public names (and the three packages): module name -> file."""
    modules: dict[str, Path] = {}
    for package_name in PACKAGES:
        package = importlib.import_module(package_name)
        names = {package_name}
        for name in package.__all__:
            value = getattr(package, name)
            module_name = getattr(value, "__module__", None)
            if isinstance(module_name, str) and module_name.startswith("snoworm"):
                names.add(module_name)
        for module_name in names:
            modules[module_name] = Path(importlib.import_module(module_name).__file__)
    return dict(sorted(modules.items()))


def _is_staticmethod(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    return any(isinstance(d, ast.Name) and d.id == "staticmethod" for d in node.decorator_list)


def missing_annotations(node: ast.FunctionDef | ast.AsyncFunctionDef, method: bool) -> list[str]:
    """The parts of ``node``'s signature left without an annotation (``return`` for the return)."""
    args = node.args
    positional = [*args.posonlyargs, *args.args]
    if method and not _is_staticmethod(node) and positional:
        positional = positional[1:]  # self / cls
    params = [*positional, *args.kwonlyargs]
    params += [a for a in (args.vararg, args.kwarg) if a is not None]
    missing = [a.arg for a in params if a.annotation is None]
    if node.returns is None and node.name != "__init__":
        missing.append("return")
    return missing


def public_functions(tree: ast.Module):
    """Yield ``(qualified name, node, is_method)`` for the public functions and methods of a module."""
    functions = (ast.FunctionDef, ast.AsyncFunctionDef)
    for node in tree.body:
        if isinstance(node, functions) and not node.name.startswith("_"):
            yield node.name, node, False
        elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
            for item in node.body:
                if isinstance(item, functions) and (not item.name.startswith("_") or item.name == "__init__"):
                    yield f"{node.name}.{item.name}", item, True


def measure() -> dict:
    """Count the public functions and the fully annotated ones, per module and in total."""
    per_module = {}
    incomplete = []
    for module_name, path in public_modules().items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        total = annotated = 0
        for qualname, node, method in public_functions(tree):
            total += 1
            missing = missing_annotations(node, method)
            if missing:
                incomplete.append(f"{module_name}.{qualname}: {', '.join(missing)}")
            else:
                annotated += 1
        per_module[module_name] = {"functions": total, "annotated": annotated}
    total = sum(m["functions"] for m in per_module.values())
    annotated = sum(m["annotated"] for m in per_module.values())
    return {
        "modules": len(per_module),
        "functions": total,
        "annotated": annotated,
        "share": annotated / total if total else 1.0,
        "per_module": per_module,
        "incomplete": incomplete,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", action="store_true", help="print the numbers as JSON")
    options = parser.parse_args(argv)
    numbers = measure()
    if options.json:
        print(json.dumps(numbers, indent=2))
        return 0
    for module_name, counts in numbers["per_module"].items():
        print(f"{module_name:40s} {counts['annotated']:3d} / {counts['functions']:3d}")
    for line in numbers["incomplete"]:
        print("  incomplete:", line)
    print(
        f"fully annotated: {numbers['annotated']} of {numbers['functions']} public functions and methods "
        f"in {numbers['modules']} modules ({100 * numbers['share']:.0f} %)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
