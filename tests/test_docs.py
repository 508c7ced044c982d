"""The API reference (docs/api.py, ``make docs``) and the tutorial (docs/tutorial.py) build and run.

Both run in a fresh interpreter, as a user would.  The tutorial runs with a non-default
matplotlib backend set first, which must survive it, and without pyplot ever being imported.
"""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_api_reference_builds_without_warnings(tmp_path):
    out = tmp_path / "docs"
    r = subprocess.run([sys.executable, str(ROOT / "docs" / "api.py"), str(out)], capture_output=True, text=True,
                       timeout=600, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stderr == ""                     # no warnings
    page = (out / "snoworm" / "results" / "result.html").read_text(encoding="utf-8")
    for name in ("to_pandas", "to_xarray", "load_result", "SEGMENT_COLUMNS"):
        assert name in page, name
    assert (out / "snoworm" / "plotting" / "style.html").exists() and (out / "index.html").exists()
    # every module has its page: the layer packages' modules (walked by pdoc) and the faces' ones
    for mod in ("config/scenario", "studies/sweep/run", "studies/paper/claims", "infra/folders", "modes/gait"):
        assert (out / "snoworm" / f"{mod}.html").exists(), mod
    assert "__main__" not in " ".join(p.name for p in out.rglob("*.html"))


def test_tutorial_runs_and_keeps_the_backend(tmp_path):
    code = (
        "import sys, runpy, matplotlib\n"
        "matplotlib.use('svg')\n"
        f"g = runpy.run_path({str(ROOT / 'docs' / 'tutorial.py')!r}, run_name='__main__')\n"
        "assert matplotlib.get_backend() == 'svg', matplotlib.get_backend()\n"
        "assert 'matplotlib.pyplot' not in sys.modules\n"
        "print('figures', type(g['fig']).__name__, type(g['fig2']).__name__, len(g['df']))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "figures Figure Figure 6" in r.stdout
    assert list(tmp_path.iterdir()) == []     # it wrote nothing in the working directory
