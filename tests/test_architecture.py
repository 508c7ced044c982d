"""The architecture as executable rules (docs/architecture.md).

* The layer contract of pyproject.toml ([tool.importlinter]) holds: ``lint-imports`` passes.
* No import cycle between snoworm modules, counting imports inside functions too.
* The tree, the contract and docs/architecture.md tell one story: every package and top-level
  module of ``snoworm/`` is a tier of the contract, and the doc's layer table lists the contract's
  tiers in the contract's order.
* An import inside a function is only for an optional or slow-to-import dependency (or in the
  CLI, for start-up time), and says why in a comment on its line or the line above.
"""

import ast
import re
import subprocess
import sys
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: tomli (a dependency of import-linter there)
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "snoworm"
DOC = ROOT / "docs" / "architecture.md"
#: the heading of the doc's layer table (the first table after it)
DOC_TABLE_HEADING = "## The layers, highest first"

#: Dependencies that may be imported inside a function: optional extras, and the heavy imports
#: that runs not needing them should not pay for at start-up.  ``matplotlib`` covers
#: ``matplotlib.pyplot``, imported only when a figure is drawn without the user's ax/fig (so it
#: shows in a notebook or with plt.show(); files are drawn headless and never import it).
#: ``h5netcdf``: the netCDF4 engine of sweeps' series (optional extra ``data``).
#: ``IPython``: only inside ``NotebookFigure._ipython_display_``, which only IPython calls.
#: ``snoworm.steady`` and ``snoworm.modes.force_plan``: root finding (scipy.optimize, about 0.3-0.9 s to
#: import), loaded by the modes when a run is assembled, so validating a scenario imports no solver.
LAZY_OK = {
    "dask",
    "distributed",
    "pandas",
    "xarray",
    "h5netcdf",
    "gymnasium",
    "tqdm",
    "matplotlib",
    "threadpoolctl",
    "multiprocessing",
    "threading",
    "concurrent",
    "snoworm.plotting",
    "snoworm.plotting.odds",  # a module of the package above, not imported by its __init__
    "snoworm.plotting.animation",  # matplotlib, as the package
    "IPython",
    "snoworm.steady",
    "snoworm.modes.force_plan",
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path):
    """(imported module, line, inside a function?) for every import statement of a module."""
    name = _module_name(path)
    pkg = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    tree = ast.parse(path.read_text())
    out = []

    def visit(node, in_func):
        for child in ast.iter_child_nodes(node):
            f = in_func or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef))
            if isinstance(child, ast.Import):
                out.extend((a.name, child.lineno, f) for a in child.names)
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = pkg.split(".")
                    base = base[: len(base) - child.level + 1]
                    mod = ".".join(base + ([child.module] if child.module else []))
                else:
                    mod = child.module
                for a in child.names:  # `from . import x` may import a submodule x
                    sub = f"{mod}.{a.name}"
                    out.append(
                        (
                            sub
                            if (ROOT / Path(*sub.split("."))).with_suffix(".py").exists()
                            or (ROOT / Path(*sub.split("."))).is_dir()
                            else mod,
                            child.lineno,
                            f,
                        )
                    )
            visit(child, f)

    visit(tree, False)
    return out


def _modules():
    return sorted(p for p in PKG.rglob("*.py"))


def test_layer_contract_holds():
    exe = Path(sys.executable).with_name("lint-imports")
    proc = subprocess.run([str(exe)], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert "KEPT" in proc.stdout and "BROKEN" not in proc.stdout


def test_no_import_cycle():
    graph = {}
    for p in _modules():
        me = _module_name(p)
        graph[me] = {m for m, _, _ in _imports(p) if m.startswith("snoworm") and m != me}
    # package __init__ files re-export their children; an edge child -> parent package is the
    # import of the package object itself (e.g. `from . import x`), not a cycle of the layers
    for me in graph:
        graph[me] = {m for m in graph[me] if not me.startswith(m + ".")}
    index, low, stack, on, cycles = {}, {}, [], set(), []
    counter = [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in graph:
                continue
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    sys.setrecursionlimit(10_000)
    for v in sorted(graph):
        if v not in index:
            strong(v)
    assert not cycles, f"import cycles: {cycles}"


def test_function_level_imports_are_justified():
    bad = []
    for p in _modules():
        lines = p.read_text().splitlines()
        cli = p.name in ("cli.py", "__main__.py") or p.parent.name == "commands"
        for mod, line, in_func in _imports(p):
            if not in_func:
                continue
            top = mod.split(".")[0]
            allowed = cli or top in LAZY_OK or mod in LAZY_OK
            text = lines[line - 1] + (lines[line - 2] if line >= 2 else "")
            if not allowed or "#" not in text:
                bad.append(
                    f"{p.relative_to(ROOT)}:{line} imports {mod} inside a function"
                    + ("" if allowed else " (not an optional or slow dependency)")
                    + ("" if "#" in text else " without a comment saying why")
                )
    assert not bad, "\n".join(bad)


# ------------------------------------------------------------------ tree, contract and doc agree


def tree_entries(pkg: Path = PKG) -> set:
    """The packages and modules at the top of the package (``config``, ``dynamics``, ...)."""
    names = {p.stem for p in pkg.glob("*.py") if p.name != "__init__.py"}
    return names | {p.name for p in pkg.iterdir() if p.is_dir() and (p / "__init__.py").exists()}


def contract_tiers(pyproject: Path = ROOT / "pyproject.toml") -> list:
    """The tiers of the top-level layers contract (the one whose container is ``snoworm``), highest first."""
    contracts = tomllib.loads(pyproject.read_text(encoding="utf-8"))["tool"]["importlinter"]["contracts"]
    (top,) = [c for c in contracts if c["type"] == "layers" and c["containers"] == ["snoworm"]]
    return [" | ".join(n.strip() for n in re.split(r"[|:]", tier)) for tier in top["layers"]]


def doc_tiers(text: str) -> list:
    """The first column (a backticked contract entry) of the doc's layer table, top to bottom."""
    table = []
    for ln in text.split(DOC_TABLE_HEADING, 1)[1].splitlines():
        if ln.startswith("|"):
            table.append(ln)
        elif table:  # the first table ends at its first non-table line
            break
    cells = [re.split(r"(?<!\\)\|", ln)[1].strip() for ln in table[2:]]  # skip header and separator
    return [re.fullmatch(r"`(.+)`", c).group(1).replace("\\|", "|") if re.fullmatch(r"`(.+)`", c) else c for c in cells]


def layer_mismatches(tree: set, tiers: list, documented: list) -> list:
    """Every disagreement between the tree, the contract's tiers and the documented tiers."""
    in_contract = {n.strip() for tier in tiers for n in tier.split("|")}
    problems = [f"snoworm/{n} is in no tier of the contract" for n in sorted(tree - in_contract)]
    problems += [f"the contract names {n!r}, which is not in snoworm/" for n in sorted(in_contract - tree)]
    if documented != tiers:
        problems.append(f"docs/architecture.md's layer table lists {documented}, the contract {tiers}")
    return problems


def test_tree_contract_and_doc_name_the_same_layers():
    tiers = contract_tiers()
    assert len(tiers) <= 15, f"{len(tiers)} tiers: the contract should name folders, not every module"
    problems = layer_mismatches(tree_entries(), tiers, doc_tiers(DOC.read_text(encoding="utf-8")))
    assert not problems, "\n".join(problems)


def test_layer_check_reports_each_kind_of_disagreement(tmp_path):
    """The check above can fail: a new package, a stale contract entry and a reordered doc table."""
    tiers = contract_tiers()
    doc = doc_tiers(DOC.read_text(encoding="utf-8"))
    tree = tree_entries()
    assert layer_mismatches(tree | {"newpkg"}, tiers, doc) == ["snoworm/newpkg is in no tier of the contract"]
    assert layer_mismatches(tree - {"infra"}, tiers, doc) == ["the contract names 'infra', which is not in snoworm/"]
    assert len(layer_mismatches(tree, tiers, doc[::-1])) == 1
    # a package made on disk is found by tree_entries
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "__init__.py").write_text("")
    (tmp_path / "mod.py").write_text("")
    (tmp_path / "data").mkdir()  # a data folder is not a package
    assert tree_entries(tmp_path) == {"pkg", "mod"}
