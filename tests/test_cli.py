"""The CLI contract of issue 2: files, exit codes, messages (click.testing.CliRunner)."""

import functools
import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

from snoworm.cli import main
from tests.conftest import SCENARIOS


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_run_writes_contract_files(tmp_path):
    out = tmp_path / "o"
    r = run("run", SCENARIOS / "tow6_uniform.yaml", "--out", out, "--set", "simulation.duration_s=8")
    assert r.exit_code == 0, r.output
    for f in ("segments.csv", "links.csv", "summary.json", "scenario.yaml", "forces.png"):
        assert (out / f).stat().st_size > 0
    head = (out / "segments.csv").read_text().splitlines()[0].split(",")
    assert head[:10] == [
        "t_s",
        "segment",
        "x_m",
        "v_mps",
        "wheel_speed_mps",
        "slip",
        "traction_N",
        "resistance_N",
        "net_force_N",
        "motor_torque_Nm",
    ]
    assert (out / "links.csv").read_text().splitlines()[0].split(",")[:4] == ["t_s", "link", "force_N", "length_m"]
    s = json.loads((out / "summary.json").read_text())
    assert np.allclose(s["final_link_forces_N"], np.arange(1, 6) * 200 / 6, atol=1.0)
    assert s["solver"]["nfev"] > 0 and s["snoworm_version"]
    # the resolved scenario re-runs to the same result
    r2 = run("run", out / "scenario.yaml", "--out", tmp_path / "o2", "--no-plot")
    assert r2.exit_code == 0, r2.output
    s2 = json.loads((tmp_path / "o2" / "summary.json").read_text())
    assert s2["final_link_forces_N"] == pytest.approx(s["final_link_forces_N"], rel=1e-9)
    assert not (tmp_path / "o2" / "forces.png").exists()
    assert (
        r.output.splitlines()[-1]
        == s["status_reason"]
        == f"moving at the end (t = 8.0 s, x = {s_x(out):.1f} m, " + (f"mean speed {s['mean_speed_mps']:.2f} m/s)")
    )


def s_x(out):
    """The leader's last position in a run folder's segments.csv."""
    rows = [r.split(",") for r in (out / "segments.csv").read_text().splitlines()[1:]]
    return float([r for r in rows if r[1] == "0"][-1][2])


def test_run_ends_with_the_verdict(tmp_path):
    """The last line of `snoworm run` says where, when and why the chain stopped (issue 32)."""
    r = run("run", SCENARIOS / "rolling6_xt025.yaml", "--out", tmp_path / "o", "--no-plot")
    assert r.exit_code == 0, r.output
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert s["status"] == "immobilised" and s["immobilised_at_m"] == pytest.approx(0.0, abs=0.05)
    assert r.output.splitlines()[-1] == s["status_reason"]
    m = re.fullmatch(
        r"immobilised at x = 0\.0 m, t = (\S+) s \(X_t 0\.25, grade 0\.0 deg, slip (\S+)\)", s["status_reason"]
    )
    assert m, s["status_reason"]
    assert 0.5 <= float(m[1]) <= 0.5 + 0.05 + 0.05  # the motors start at 0.5 s (one output step, rounding)
    assert float(m[2]) > 0.8  # the wheels spin


@pytest.mark.parametrize(
    "sets, words",
    [
        (["vehicle.segments=0"], "vehicle.segments"),
        (["terrain.xt=-0.3"], "terrain.xt"),
        (["tow.forc_N=3"], "Did you mean 'force_N'"),
        (["notakey"], "KEY=VALUE"),
    ],
)
def test_bad_input_exit_2_no_traceback_nothing_written(tmp_path, sets, words):
    out = tmp_path / "o"
    args = ["run", SCENARIOS / "tow6_uniform.yaml", "--out", out]
    for s in sets:
        args += ["--set", s]
    r = run(*args)
    assert r.exit_code == 2
    assert words in r.output and "Traceback" not in r.output
    assert not out.exists()


def test_missing_file_exit_2(tmp_path):
    r = run("validate", tmp_path / "nope.yaml")
    assert r.exit_code == 2 and "no such file" in r.output


def test_validate_ok():
    r = run("validate", SCENARIOS / "tow6_uniform.yaml")
    assert r.exit_code == 0 and "valid" in r.output


def test_solver_failure_exit_1_nothing_written(tmp_path, monkeypatch):
    import importlib

    S = importlib.import_module("snoworm.simulation.driver")

    def boom(sc, progress=None, allow_code=()):
        raise S.SolverError("solve_ivp (LSODA) failed near t = 3 s: test")

    monkeypatch.setattr(S, "simulate", boom)
    out = tmp_path / "o"
    r = run("run", SCENARIOS / "tow6_uniform.yaml", "--out", out)
    assert r.exit_code == 1 and "solver failure" in r.output
    assert not out.exists()


def _controller_scenario(tmp_path, body):
    import textwrap

    import yaml

    (tmp_path / "c.py").write_text(textwrap.dedent(body))
    raw = yaml.safe_load((SCENARIOS / "tow6_uniform.yaml").read_text())
    raw["mode"] = {"type": "controller", "controller": "c.py:C", "period_s": 0.1, "params": {}}
    raw["simulation"]["duration_s"] = 1.0
    p = tmp_path / "s.yaml"
    p.write_text(yaml.safe_dump(raw))
    return p


def test_controller_raising_exit_1_user_frames_nothing_written(tmp_path):
    p = _controller_scenario(
        tmp_path,
        """
        class C:
            def __init__(self, params, scenario):
                pass
            def __call__(self, obs):
                if obs.t_s > 0.45:
                    raise ValueError("gain schedule exhausted")
                return {}
    """,
    )
    out = tmp_path / "o"
    r = run("run", p, "--out", out)
    assert r.exit_code == 1
    assert "controller raised at t = 0.5 s:" in r.output and "c.py" in r.output
    assert "gain schedule exhausted" in r.output and "snoworm/" not in r.output
    assert not out.exists()


def test_controller_bad_command_exit_1_and_bad_class_exit_2(tmp_path):
    p = _controller_scenario(
        tmp_path,
        """
        class C:
            def __init__(self, params, scenario):
                pass
            def __call__(self, obs):
                return {"wheel_speed_mps": [1.0] * 6, "brake": 1}
    """,
    )
    out = tmp_path / "o"
    r = run("run", p, "--out", out)
    assert r.exit_code == 1 and "'brake'" in r.output and "t = 0 s" in r.output and not out.exists()
    r = run("run", p, "--out", out, "--set", "mode.controller=c.py:D")
    assert r.exit_code == 2 and "no class 'D'" in r.output and "Traceback" not in r.output


def test_plot_format_and_sweep_series(tmp_path):
    r = run(
        "run",
        SCENARIOS / "pi3_equal.yaml",
        "--out",
        tmp_path / "r",
        "--set",
        "simulation.duration_s=1",
        "--plot-format",
        "pdf",
    )
    assert r.exit_code == 0, r.output
    pdfs = sorted(p.name for p in (tmp_path / "r").glob("*.pdf"))
    assert pdfs == ["force_diagram.pdf", "forces.pdf", "positions.pdf", "speeds.pdf"]
    assert not list((tmp_path / "r").glob("*.png"))
    r = run(
        "sweep",
        SCENARIOS / "tow6_uniform.yaml",
        "--set",
        "tow.force_N=0,100",
        "--set",
        "simulation.duration_s=1",
        "--out",
        tmp_path / "s",
        "--series",
        "netcdf",
        "--plot-format",
        "svg",
    )
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "s").iterdir()) == [
        ".snoworm-manifest.json",
        "series.nc",
        "summary.csv",
        "sweep.json",
        "sweep.svg",
    ]
    r = run("run", SCENARIOS / "pi3_equal.yaml", "--out", tmp_path / "x", "--plot-format", "jpg")
    assert r.exit_code == 2 and "'jpg' is not one of 'png', 'pdf', 'svg'" in r.output


def test_figure_size_column_pdfs_for_journals(tmp_path):
    """--figure-size column --plot-format pdf: every PDF 3.5 in (252 pt) wide, TrueType fonts,
    no Type 3 font; the sweep's SVG keeps its text as <text>; a bad size is exit 2, one line."""
    import re

    r = run(
        "run",
        SCENARIOS / "inchworm6.yaml",
        "--out",
        tmp_path / "r",
        "--set",
        "simulation.duration_s=3",
        "--plot-format",
        "pdf",
        "--figure-size",
        "column",
    )
    assert r.exit_code == 0, r.output
    pdfs = sorted((tmp_path / "r").glob("*.pdf"))
    assert [p.name for p in pdfs] == ["forces.pdf", "positions.pdf", "speeds.pdf"]
    for p in pdfs:
        data = p.read_bytes()
        width = float(re.search(rb"/MediaBox \[\s*0 0 ([0-9.]+) ", data).group(1))
        assert width == pytest.approx(3.5 * 72, abs=0.01) and b"/Subtype /Type3" not in data and b"/FontFile2" in data
    r = run(
        "sweep",
        SCENARIOS / "tow6_uniform.yaml",
        "--set",
        "tow.force_N=0,100",
        "--set",
        "simulation.duration_s=1",
        "--out",
        tmp_path / "s",
        "--plot-format",
        "svg",
        "--figure-size",
        "3.5x4",
    )
    assert r.exit_code == 0, r.output
    svg = (tmp_path / "s" / "sweep.svg").read_text(encoding="utf-8")
    assert "<text" in svg and 'width="252pt"' in svg and 'height="288pt"' in svg
    r = run("run", SCENARIOS / "pi3_equal.yaml", "--out", tmp_path / "x", "--figure-size", "half")
    assert r.exit_code == 2 and "--figure-size" in r.output and "column, page or WxH" in r.output
    assert "Traceback" not in r.output and not (tmp_path / "x").exists()


def test_a_route_with_a_weak_patch_ends_immobilised_where_the_steady_limit_says(tmp_path):
    """Issue 32: three segments roll at 1.8 m/s along a route file whose X_t drops from 0.9 to 0.35
    (below the rolling limit) at 15 m; `snoworm run` ends "immobilised at x = ..." within one segment
    length of where the steady laws stop the chain: the first leader position at which the sum over
    its axles of max_drawbar_N(X_t under the axle) / 2 is no longer positive (route X_t interpolated
    here by hand)."""
    import yaml

    from snoworm import load_scenario, steady

    dist, xt = [0.0, 14.9, 15.0, 60.0, 60.1, 100.0], [0.9, 0.9, 0.35, 0.35, 0.9, 0.9]
    (tmp_path / "weak.csv").write_text(
        "distance_m,elevation_m,xt\n" + "".join(f"{d},0,{x}\n" for d, x in zip(dist, xt))
    )
    scenario = {
        "name": "weak_route",
        "vehicle": {"parameter_set": "frostyboy", "segments": 3, "links": {"type": "fixed"}},
        "terrain": {"route": "weak.csv"},
        "tow": {"force_N": 0},
        "mode": {"type": "uniform", "speed_mps": 1.8, "start_time_s": 0.5},
        "simulation": {"duration_s": 30, "output_dt_s": 0.05},
    }
    (tmp_path / "weak.yaml").write_text(yaml.safe_dump(scenario))
    out = tmp_path / "o"
    r = run("run", tmp_path / "weak.yaml", "--out", out, "--no-plot")
    assert r.exit_code == 0, r.output
    m = re.fullmatch(
        r"immobilised at x = (\S+) m, t = (\S+) s \(X_t (\S+), grade 0\.0 deg, slip (\S+)\)", r.output.splitlines()[-1]
    )
    assert m, r.output
    rows = [list(map(float, ln.split(","))) for ln in (out / "segments.csv").read_text().splitlines()[1:4]]
    x0 = np.array([row[2] for row in rows])  # the segments' positions at t = 0
    spacing = x0[0] - x0[1]
    sc = load_scenario(tmp_path / "weak.yaml")
    seg, tp = sc.vehicle.segment_params()[0], sc.terrain.model.params()
    half = seg.wheelbase_m / 2.0
    pull = functools.cache(lambda X: steady.max_drawbar_N(X, seg, tp, 1.8))
    stop = next(
        s
        for s in np.arange(0.0, 60.0, 0.01)
        if sum(
            pull(round(float(np.interp(a, dist, xt)), 4)) for a in np.r_[s + x0 - x0[0] + half, s + x0 - x0[0] - half]
        )
        <= 0
    )
    assert abs(float(m[1]) - stop) <= spacing, (m[1], stop)
    assert 0.35 < float(m[3]) < 0.9 and float(m[4]) > 0.9
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "immobilised" and abs(s["immobilised_at_m"] - stop) <= spacing
