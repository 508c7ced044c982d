"""Build the API reference from the docstrings with pdoc: ``python docs/api.py [OUT_DIR]``.

Every module of the package but the command-line entry points is documented (numpydoc
docstrings); any warning pdoc raises (a broken cross-reference, a docstring it cannot parse, an
import failing) is printed and makes the build fail (exit status 1).  ``make docs`` runs it into
``out/docs``; tests/test_docs.py runs it in the test suite.
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import sys
import warnings
from pathlib import Path

import pdoc
import pdoc.render

import snoworm

#: Modules that run something when imported, or are only the CLI's plumbing.
SKIP = {"snoworm.__main__"}
#: Modules of an optional extra that import it when imported: documented where it is installed.
OPTIONAL = {"snoworm.env.sb3": "stable_baselines3"}


def modules() -> list:
    """``snoworm`` and every submodule, in import order, each named once.

    pdoc documents the submodules of a package without ``__all__`` (a layer package such as
    ``snoworm.config``) on its own, so those are not named again (pdoc warns about a module named
    twice); a package with ``__all__`` (its public face, e.g. ``snoworm.modes``) has its submodules
    named here.
    """
    names = ["snoworm"] + [m.name for m in pkgutil.walk_packages(snoworm.__path__, "snoworm.")]
    walked, out = set(), []  # walked: packages whose submodules pdoc reaches by itself
    for name in names:
        if name in SKIP or (name in OPTIONAL and importlib.util.find_spec(OPTIONAL[name]) is None):
            continue
        if name.rpartition(".")[0] not in walked:
            out.append(name)
        mod = importlib.import_module(name)
        if hasattr(mod, "__path__") and not hasattr(mod, "__all__"):
            walked.add(name)
    return out


def build(out_dir) -> list:
    """Write the HTML reference to ``out_dir``; return the warnings raised (as text)."""
    pdoc.render.configure(docformat="numpy", footer_text=f"snoworm {snoworm.__version__}", search=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.pdoc(*modules(), output_directory=Path(out_dir))
    return [f"{w.category.__name__}: {w.message}" for w in caught]


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/docs")
    problems = build(out)
    for p in problems:
        print(p, file=sys.stderr)
    pages = sum(1 for p in out.rglob("*.html") if p.name not in ("index.html", "search.html"))
    print(
        f"API reference of {pages} modules in {out}/index.html"
        + (f"; {len(problems)} warning(s): failed" if problems else "")
    )
    sys.exit(1 if problems else 0)
