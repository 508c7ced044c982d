"""The three walkthroughs of docs/architecture.md run as written, so they cannot drift.

Each walkthrough's code blocks are read from the doc.  A block starting ``# file: PATH`` is an
edit: its ``# before: TEXT`` (or ``# replace: TEXT``) line names the line(s) of PATH, stripped,
that start with TEXT; the rest of the block is inserted before each of them (or replaces the
first).  The edits are applied to a copy of the package in a temporary folder, and the changed
package runs in a fresh interpreter, which must show the new coefficient, mode or series having
its effect.  An edit whose line is no longer in the code fails here.
"""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "architecture.md"
SCENARIO = ROOT / "scenarios" / "tow6_uniform.yaml"


def section(title: str) -> str:
    text = DOC.read_text(encoding="utf-8")
    start = text.index(f"### {title}")
    end = text.find("\n### ", start + 1)
    return text[start:] if end < 0 else text[start:end]


def blocks(title: str) -> list:
    return re.findall(r"```python\n(.*?)```", section(title), re.S)


def apply_edit(pkg_root: Path, block: str):
    lines = block.splitlines()
    path = pkg_root / lines[0].removeprefix("# file:").strip()
    how, _, anchor = lines[1].removeprefix("# ").partition(": ")
    assert how in ("before", "replace"), lines[1]
    new = lines[2:]
    old = path.read_text(encoding="utf-8").splitlines()
    hits = [i for i, line in enumerate(old) if line.strip().startswith(anchor)]
    assert hits, f"{path.name}: no line starts with {anchor!r} (the walkthrough drifted from the code)"
    if how == "replace":
        old[hits[0] : hits[0] + 1] = new
    else:
        for i in reversed(hits):
            old[i:i] = new
    path.write_text("\n".join(old) + "\n", encoding="utf-8")


def package_copy(tmp_path: Path) -> Path:
    root = tmp_path / "pkg"
    shutil.copytree(ROOT / "snoworm", root / "snoworm", ignore=shutil.ignore_patterns("__pycache__"))
    return root


def run(code: str, pythonpath: Path, cwd: Path) -> str:
    """Run ``code`` in a fresh interpreter that imports snoworm from ``pythonpath``."""
    head = (
        f"import sys; sys.path.insert(0, {str(pythonpath)!r})\n"
        "import snoworm\n"
        f"assert snoworm.__file__.startswith({str(pythonpath)!r}), snoworm.__file__\n"
    )
    proc = subprocess.run([sys.executable, "-c", head + code], capture_output=True, text=True, timeout=300, cwd=cwd)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def test_adding_a_terrain_coefficient(tmp_path):
    edits = [b for b in blocks("Adding a terrain coefficient") if b.startswith("# file:")]
    assert len(edits) >= 3
    root = package_copy(tmp_path)
    for b in edits:
        apply_edit(root, b)
    out = run(
        f"""
from snoworm import load_scenario, simulate
base = load_scenario({str(SCENARIO)!r}, ["simulation.duration_s=6"])
assert base.terrain.model.c_v == 0.0 and base.to_dict()["terrain"]["model"]["c_v"] == 0.0
print(base.sources["terrain.model.c_v"])
r0, r1 = simulate(base), simulate(base.with_({{"terrain.model.c_v": 0.5}}))
print(r0.summary()["distance_m"], r1.summary()["distance_m"])
print(r0.segments["resistance_N"][-1].sum(), r1.segments["resistance_N"][-1].sum())
""",
        root,
        tmp_path,
    ).splitlines()
    assert out[0] == "[assumed] no speed dependence"
    d0, d1 = map(float, out[1].split())
    f0, f1 = map(float, out[2].split())
    # a resistance growing with speed: more resistance at the end, less distance covered
    assert f1 > 1.05 * f0 and d1 < d0


MODE_RUN = f"""
import numpy as np
from snoworm import load_scenario, simulate
sc = load_scenario({str(SCENARIO)!r}, ["mode={{type: cruise, speed_mps: 1.2}}", "simulation.duration_s=6"])
r = simulate(sc)
print(type(sc.mode).__name__, r.phases[0]["label"], np.mean(r.segments["wheel_speed_mps"][-1]))
"""


def _check_cruise(out: str):
    name, label, speed = out.split()
    # the wheel-speed PI holds the cruise set-point (zero steady error of its integral action)
    assert name == "CruiseConfig" and label == "cruise" and float(speed) == pytest.approx(1.2, rel=0.02)


def test_adding_a_users_mode_from_a_fresh_interpreter(tmp_path):
    code = [b for b in blocks("Adding a mode") if "@register_mode" in b]
    assert len(code) == 1
    (tmp_path / "my_mode.py").write_text(code[0], encoding="utf-8")
    # "import your module before loading the scenario"
    _check_cruise(run("import my_mode\n" + MODE_RUN, ROOT, tmp_path))


def test_adding_a_built_in_mode_from_a_fresh_interpreter(tmp_path):
    sec = section("Adding a mode")
    code = [b for b in blocks("Adding a mode") if "@register_mode" in b][0]
    line = re.search(r'`("cruise": "snoworm\.modes\.cruise")` to `BUILT_IN_MODES`', sec).group(1)
    root = package_copy(tmp_path)
    (root / "snoworm" / "modes" / "cruise.py").write_text(code, encoding="utf-8")
    reg = root / "snoworm" / "config" / "mode_registry.py"
    text = reg.read_text(encoding="utf-8")
    assert text.count("BUILT_IN_MODES = {") == 1
    reg.write_text(text.replace("BUILT_IN_MODES = {", "BUILT_IN_MODES = {" + line + ", "), encoding="utf-8")
    # nothing imported first: the registry finds the built-in mode itself
    _check_cruise(run(MODE_RUN, root, tmp_path))


def test_adding_an_output_series(tmp_path):
    edits = [b for b in blocks("Adding an output series") if b.startswith("# file:")]
    assert len(edits) >= 2
    root = package_copy(tmp_path)
    for b in edits:
        apply_edit(root, b)
    out = run(
        f"""
import numpy as np
from snoworm import load_scenario, simulate
r = simulate(load_scenario({str(SCENARIO)!r}, ["simulation.duration_s=3"]))
p = r.segments["traction_power_W"]
assert np.allclose(p, r.segments["traction_N"] * r.segments["v_mps"], rtol=1e-12, atol=0), "not the product"
r.write("run", plot=False)
print("traction_power_W" in open("run/segments.csv").readline().strip().split(","), float(np.max(p)) > 0)
""",
        root,
        tmp_path,
    )
    assert out.split() == ["True", "True"]
