"""The API reference (docs/api.py, ``make docs``) and the tutorial (docs/tutorial.py) build and run.

Both run in a fresh interpreter, as a user would.  The tutorial runs as a script with a
non-default matplotlib backend set first, which must survive it, and as a notebook in a fresh
kernel, where its figures must show inline.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_api_reference_builds_without_warnings(tmp_path):
    out = tmp_path / "docs"
    r = subprocess.run(
        [sys.executable, str(ROOT / "docs" / "api.py"), str(out)],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stderr == ""  # no warnings
    page = (out / "snoworm" / "results" / "result.html").read_text(encoding="utf-8")
    for name in ("to_pandas", "to_xarray", "load_result", "SEGMENT_COLUMNS"):
        assert name in page, name
    assert (out / "snoworm" / "plotting" / "style.html").exists() and (out / "index.html").exists()
    # every module has its page: the layer packages' modules (walked by pdoc) and the faces' ones
    for mod in ("config/scenario", "studies/sweep/run", "studies/paper/claims", "infra/folders", "modes/inchworm"):
        assert (out / "snoworm" / f"{mod}.html").exists(), mod
    assert "__main__" not in " ".join(p.name for p in out.rglob("*.html"))


def test_tutorial_runs_and_keeps_the_backend(tmp_path):
    code = (
        "import sys, runpy, matplotlib\n"
        "matplotlib.use('svg')\n"
        f"g = runpy.run_path({str(ROOT / 'docs' / 'tutorial.py')!r}, run_name='__main__')\n"
        "assert matplotlib.get_backend() == 'svg', matplotlib.get_backend()\n"
        "print('figures', type(g['fig']).__name__, type(g['fig2']).__name__, len(g['df']))\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "figures Figure Figure 6" in r.stdout
    assert list(tmp_path.iterdir()) == []  # it wrote nothing in the working directory


def _percent_to_notebook(path):
    """The percent-format script as a notebook (jupytext's rules for ``# %%`` and
    ``# %% [markdown]`` cells), without needing jupytext."""
    import nbformat

    cells, kind, lines = [], None, []

    def flush():
        text = "\n".join(lines).strip("\n")
        if kind == "markdown":
            cells.append(
                nbformat.v4.new_markdown_cell(
                    "\n".join(ln[2:] if ln.startswith("# ") else ln.lstrip("#") for ln in text.splitlines())
                )
            )
        elif kind == "code" and text:
            cells.append(nbformat.v4.new_code_cell(text))

    for line in Path(path).read_text(encoding="utf-8").splitlines():
        if line.startswith("# %%"):
            flush()
            kind, lines = ("markdown" if "[markdown]" in line else "code"), []
        elif kind is not None:
            lines.append(line)
    flush()
    return nbformat.v4.new_notebook(cells=cells)


def test_tutorial_as_a_notebook_shows_its_figures(tmp_path, monkeypatch):
    """Executed headless in a fresh kernel (nbclient, ipykernel), as a user would open it: the
    cells ending with a figure show it inline (an image/png output, once), and nothing else
    fails.  No `%matplotlib inline` anywhere: the kernel's default backend does it."""
    pytest.importorskip("nbclient")
    from nbclient import NotebookClient

    monkeypatch.delenv("MPLBACKEND", raising=False)  # the kernel picks its own inline backend
    paths = [str(ROOT), *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))]
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(paths))  # the kernel imports this checkout's snoworm
    nb = _percent_to_notebook(ROOT / "docs" / "tutorial.py")
    assert "%matplotlib" not in "".join(c.source for c in nb.cells)
    NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    code = [c for c in nb.cells if c.cell_type == "code"]
    last = [c.source.splitlines()[-1] for c in code]
    ending = [c for c, ln in zip(code, last) if ln.split("#")[0].strip() in ("fig", "fig2")] + [
        c for c, ln in zip(code, last) if ln.startswith(("res.plot(", "plotting.compare(", "table.plot("))
    ]
    # issue 30: a figure assigned to a name (shown by the inline backend at the end of the cell), in
    # every cell and not only the first; and the user's own pyplot figure after snoworm's figures
    assigned = [c for c, ln in zip(code, last) if re.match(r"fig\w* = res\.plot\(", ln)]
    users = [c for c in code if "plt.plot(" in c.source]
    first_snoworm = code.index(next(c for c in code if "res.plot(" in c.source and "ax=" not in c.source))
    assert len(ending) >= 5 and len(assigned) >= 2 and users and code.index(users[0]) > code.index(assigned[-1])
    assert first_snoworm < code.index(assigned[0])  # pyplot is first imported in a snoworm figure
    for c in ending + assigned + users:
        images = [o for o in c.outputs if "image/png" in o.get("data", {})]
        assert len(images) == 1, (c.source.splitlines()[-1], [o.get("output_type") for o in c.outputs])
    errors = [o for c in nb.cells for o in c.get("outputs", ()) if o.get("output_type") == "error"]
    assert not errors
    sweep = next(c for c in nb.cells if "run_sweep(" in c.source)  # a bar in the notebook, not log lines
    bar = "".join(o.get("text", "") for o in sweep.outputs if o.get("name") == "stderr")
    assert "sweep:" in bar and "6/6 cases" in bar and "100%" in bar
    assert list(tmp_path.iterdir()) == []  # it wrote nothing in the working directory


def test_readme_figure_is_made_by_the_command_it_names(tmp_path):
    """README shows docs/figures/inchworm6_speeds_column.png as made by `snoworm run inchworm6
    --out out/inchworm6 --figure-size column`: the command is there, and running it gives a PNG
    of the same pixel size (3.5 in at 200 dpi: 700 px wide)."""
    import struct

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "`snoworm run inchworm6 --out out/inchworm6 --figure-size column`" in readme
    assert "docs/figures/inchworm6_speeds_column.png" in readme
    committed = (ROOT / "docs" / "figures" / "inchworm6_speeds_column.png").read_bytes()
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "snoworm",
            "run",
            "inchworm6",
            "--out",
            str(tmp_path / "inchworm6"),
            "--figure-size",
            "column",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    made = (tmp_path / "inchworm6" / "speeds.png").read_bytes()

    def size(png):
        return struct.unpack(">II", png[16:24])

    assert size(made) == size(committed) and size(made)[0] == 700


def _anchor(heading):
    """GitHub's anchor of a Markdown heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def _headings(md):
    return re.findall(r"^#+ (.+)$", md.read_text(encoding="utf-8"), re.M)


def test_markdown_links_and_cited_sections_exist():
    """Every relative link of README.md, CHANGELOG.md and docs/*.md reaches a file, and its
    ``#anchor`` a heading there; every ``docs/X.md, "Section"`` cited in the docs, the package or
    the tests names a heading of that file (a section a rewrite renames breaks them)."""
    pages = [ROOT / "README.md", ROOT / "CHANGELOG.md", *sorted((ROOT / "docs").glob("*.md"))]
    broken = []
    for page in pages:
        for target in re.findall(r"\]\(([^)\s]+)\)", page.read_text(encoding="utf-8")):
            if re.match(r"[a-z]+:", target):  # https:, mailto:
                continue
            path, _, anchor = target.partition("#")
            dest = (page.parent / path) if path else page
            if not dest.exists():
                broken.append(f"{page.name}: {target} (no such file)")
            elif anchor and dest.suffix == ".md" and anchor not in {_anchor(h) for h in _headings(dest)}:
                broken.append(f"{page.name}: {target} (no such heading)")
    cited = re.compile(r'(docs/[a-z_]+\.md)`?,? "([^"]+)"')
    sources = [*pages, *ROOT.glob("snoworm/**/*.py"), *ROOT.glob("tests/*.py"), *ROOT.glob("benchmarks/*.py")]
    for src in sources:
        for doc, section in cited.findall(src.read_text(encoding="utf-8")):
            heads = _headings(ROOT / doc) if (ROOT / doc).exists() else []
            if not any(h.strip().startswith(section) for h in heads):
                broken.append(f"{src.relative_to(ROOT)}: {doc}, {section!r} (no such section)")
    assert not broken, "\n".join(broken)


# ------------------------------------------------------------------ shell commands of the docs

#: An HTML comment on the line before a fenced block (invisible on GitHub) that keeps some of its
#: commands out of :func:`test_every_shell_command_of_the_docs_runs`, with the reason said:
#: ``<!-- docs-test: skip: REASON -->`` (the whole block) or ``<!-- docs-test: skip 1,3-5: REASON -->``
#: (those commands of the block, counted from 1).
SKIP_MARK = re.compile(r"<!-- docs-test: skip(?: ([\d,\-]+))?: (.+?) -->")
#: The first word of a command in an untagged block (a block of output has none of them).
COMMAND_WORDS = ("snoworm", "python", "make", "pip")


def _numbers(spec):
    out = set()
    for part in spec.split(","):
        a, _, b = part.partition("-")
        out.update(range(int(a), int(b or a) + 1))
    return out


def doc_commands(page):
    """``[(line, command, skip reason or None)]``: the shell commands of the fenced blocks of a
    Markdown page.  A ``console``/``sh``/``bash``/``shell`` block, or an untagged one whose first
    line starts with one of :data:`COMMAND_WORDS` or ``$``; in a block with ``$`` prompts only the
    prompted lines are commands (the rest is their output); a trailing ``\\`` continues a line."""
    text = page.read_text(encoding="utf-8")
    out = []
    for m in re.finditer(r"^```(\w*)\n(.*?)^```", text, re.S | re.M):
        lang, body = m.group(1), m.group(2)
        first = body.lstrip().split(" ", 1)[0]
        if not (lang in ("console", "sh", "bash", "shell") or (not lang and (first in COMMAND_WORDS or first == "$"))):
            continue
        prompted = any(ln.startswith("$ ") for ln in body.splitlines())
        commands, current = [], None
        for ln in body.splitlines():
            if current is not None:
                current += " " + ln.strip()
            elif prompted and not ln.startswith("$ "):
                continue
            else:
                current = ln.removeprefix("$ ").strip()
            if current.endswith("\\"):
                current = current[:-1].rstrip()
            else:
                if current:
                    commands.append(current)
                current = None
        before = text[: m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        mark = SKIP_MARK.fullmatch(before.strip())
        skipped = set(range(1, len(commands) + 1)) if mark and not mark.group(1) else set()
        if mark and mark.group(1):
            skipped = _numbers(mark.group(1))
            assert skipped <= set(range(1, len(commands) + 1)), f"{page.name}: {before} names no such command"
        line = text[: m.start()].count("\n") + 1
        out += [(line, c, mark.group(2) if k in skipped else None) for k, c in enumerate(commands, 1)]
    return out


def doc_pages():
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def test_the_docs_shell_commands_are_found_and_skips_say_why():
    """The reader of :func:`test_every_shell_command_of_the_docs_runs` finds the commands the docs
    show (a regression of the parser would silently run none), and every skip gives a reason."""
    found = {(p.name, c): why for p in doc_pages() for _, c, why in doc_commands(p)}
    assert (
        "sweeps.md",
        "snoworm sweep scenarios/tow6_uniform.yaml --set terrain.xt=0.6:1.0:9 "
        "--set tow.force_N=0,100,200 -j 2 --out sw/",
    ) in found
    assert found[("groundtruth.md", "snoworm groundtruth --out out/groundtruth")] is None
    assert found[("paper.md", "snoworm paper --out out/paper --quick    # CI: inchworm runs shortened to 10 s")] is None
    assert not any(c.startswith(("inchworm6:", "case", "sweep [")) for _, c in found)  # output is not run
    assert all(why is None or len(why) > 20 for why in found.values())


def test_every_shell_command_of_the_docs_runs(tmp_path):
    """Every shell command in a fenced block of README.md and docs/*.md (:func:`doc_commands`) runs
    with exit status 0 in a fresh folder (``scenarios/`` and ``examples/`` linked there, ``snoworm`` and ``python``
    this checkout's), each distinct command once; the ones marked with :data:`SKIP_MARK` do not."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name, line in (
        ("snoworm", f'exec "{sys.executable}" -m snoworm "$@"'),
        ("python", f'exec "{sys.executable}" "$@"'),
    ):
        (bin_dir / name).write_text(f"#!/bin/sh\n{line}\n")
        (bin_dir / name).chmod(0o755)
    work = tmp_path / "work"
    work.mkdir()
    (work / "scenarios").symlink_to(ROOT / "scenarios")
    (work / "examples").symlink_to(ROOT / "examples")  # e.g. the README's GPX track
    paths = [str(ROOT), *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))]
    env = dict(os.environ, PATH=f"{bin_dir}{os.pathsep}{os.environ['PATH']}", PYTHONPATH=os.pathsep.join(paths))
    env["MPLBACKEND"] = "agg"
    done, failed = set(), []
    for page in doc_pages():
        for line, command, why in doc_commands(page):
            key = " ".join(command.split("#", 1)[0].split())
            if why is not None or key in done:
                continue
            done.add(key)
            r = subprocess.run(["bash", "-c", command], cwd=work, env=env, capture_output=True, text=True, timeout=600)
            if r.returncode != 0:
                failed.append(f"{page.name}:{line}: {command}\n  exit {r.returncode}: {r.stderr[-1500:]}")
    assert done and not failed, "\n".join(failed)


def test_test_files_named_in_the_docs_exist():
    """Issue 34: the docs named tests/test_env.py, tests/test_vecenv.py and tests/test_mobility.py
    after the files were renamed.  Every ``tests/...py`` named in README.md, docs/, examples/ or the
    package's and the benchmarks' docstrings exists (CHANGELOG.md is history and keeps old names)."""
    sources = [
        ROOT / "README.md",
        *ROOT.glob("docs/*.md"),
        *ROOT.glob("docs/*.py"),
        *ROOT.glob("examples/**/*.md"),
        *ROOT.glob("examples/**/*.py"),
        *ROOT.glob("snoworm/**/*.py"),
        *ROOT.glob("benchmarks/*.py"),
    ]
    missing = [
        f"{src.relative_to(ROOT)}: {name}"
        for src in sources
        for name in sorted(set(re.findall(r"tests/[\w/]+\.py", src.read_text(encoding="utf-8"))))
        if not (ROOT / name).exists()
    ]
    assert not missing, "\n".join(missing)
