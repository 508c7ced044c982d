"""Bad input never becomes an internal error, a hang or silent nonsense (issue 15).

A hypothesis fuzz test mutates every shipped scenario (wrong types, NaN/inf, huge and tiny values,
unknown keys) and runs it through the CLI: each run ends in exit 0 with finite output, exit 2
(bad input) or exit 1 with a solver failure, never "internal error".  The time of each run is
bounded by the driver's work limit (``WORK_BASE_NFEV`` + ``work_rate`` right-hand-side
evaluations per simulated second), checked on every successful run; runs are 1.5 s of simulated
time.  ``SNOWORM_FUZZ_EXAMPLES`` raises the number of examples (default 40, derandomised so CI is
reproducible).

Issue 24 adds three derandomised fuzzers (``SNOWORM_FUZZ_TRUST_EXAMPLES``, default 25 each): hostile
manifests never touch a file outside the output folder, controller references never run code
when read, and mutated run folders load consistently or raise ResultFileError naming the file.
Issue 30 adds tampered sweep ``series.nc`` files (bytes overwritten, truncated, dimensions and
variables rewritten): read back and resumed, each loads or raises one ResultFileError naming it.

Then the categories of the issue, one representative set each: the former hangs, the former
internal errors, the 1e300 solver breakdowns, the command options, and YAML abuse.  The former
hangs run as subprocesses with a generous timeout (60 s; they now end in about a second).
"""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings, strategies as st

from snoworm import load_scenario
from snoworm.cli import main
from snoworm.simulation.guard import WORK_BASE_NFEV, work_rate
from tests.conftest import SCENARIOS

SHIPPED = sorted(SCENARIOS.glob("*.yaml"))
FUZZ_DURATION_S = 1.5
BAD_VALUES = [
    math.nan,
    math.inf,
    -math.inf,
    1e300,
    -1e300,
    1e-300,
    0,
    -1,
    10**30,
    2.5,
    "text",
    "",
    [1, 2],
    {"a": 1},
    None,
    True,
    "x" * 5000,
]


def _leaves(node, prefix=()):
    """Dotted paths of every leaf (and of every mapping, for unknown keys) of a scenario mapping."""
    if isinstance(node, dict):
        yield prefix, node
        for k, v in node.items():
            yield from _leaves(v, prefix + (k,))
    elif isinstance(node, list):
        for j, v in enumerate(node):
            yield from _leaves(v, prefix + (j,))
    else:
        yield prefix, node


def _set(raw, path, value):
    node = raw
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value


def _run_cli(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _assert_clean_end(r, out):
    """Exit 0 with finite files, 2 (bad input) or 1 (solver failure); never an internal error."""
    assert r.exit_code in (0, 1, 2), r.output
    assert "internal error" not in r.output and "Traceback" not in r.output, r.output
    if r.exit_code == 1:
        assert "solver failure" in r.output, r.output
    if r.exit_code != 0:
        assert len(r.output) < 1500, r.output[:300]  # short messages (the value quoted briefly)
        assert not (out / "segments.csv").exists()
        return
    summary = json.loads((out / "summary.json").read_text())
    sim = load_scenario(out / "scenario.yaml").simulation
    assert summary["solver"]["nfev"] <= WORK_BASE_NFEV + work_rate(sim) * summary["duration_s"]
    for name in ("segments.csv", "links.csv"):
        rows = (out / name).read_text().splitlines()[1:]  # links.csv is empty for one segment
        data = np.array([[float(x) for x in row.split(",")] for row in rows])
        assert np.all(np.isfinite(data)), name
    for key in ("distance_m", "mean_speed_mps"):
        assert math.isfinite(summary[key]), key


@settings(
    max_examples=int(os.environ.get("SNOWORM_FUZZ_EXAMPLES", 40)),
    deadline=None,
    derandomize=not os.environ.get("SNOWORM_FUZZ_RANDOM"),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(data=st.data())
def test_mutated_scenarios_end_cleanly(data, tmp_path):
    path = data.draw(st.sampled_from(SHIPPED), label="scenario")
    raw = load_scenario(path).to_dict()  # every value written out, so every value can be mutated
    raw["simulation"]["duration_s"] = FUZZ_DURATION_S
    where, node = data.draw(st.sampled_from(list(_leaves(raw))[1:]), label="path")
    kind = data.draw(st.sampled_from(["value", "scale", "unknown_key"]), label="kind")
    if kind == "unknown_key" or (isinstance(node, dict) and kind == "value"):
        target = node if isinstance(node, dict) else raw
        target[data.draw(st.sampled_from(["bogus", "xt_", "Mass_kg", "0"]), label="key")] = 1
    elif kind == "scale" and isinstance(node, (int, float)) and not isinstance(node, bool):
        _set(raw, where, node * 10.0 ** data.draw(st.sampled_from([-12, -6, 3, 6, 12]), label="exponent"))
    else:
        _set(raw, where, data.draw(st.sampled_from(BAD_VALUES), label="value"))
    run_dir = tmp_path / f"case{len(list(tmp_path.iterdir()))}"
    run_dir.mkdir()
    f = run_dir / "s.yaml"
    f.write_text(yaml.safe_dump(raw, sort_keys=False))
    _assert_clean_end(_run_cli(["run", f, "--out", run_dir / "out", "--no-plot"]), run_dir / "out")


# ------------------------------------------------------------------ the categories of issue 15


def _tow6(tmp_path, *sets, duration=3):
    out = tmp_path / "out"
    args = [
        "run",
        SCENARIOS / "tow6_uniform.yaml",
        "--out",
        out,
        "--no-plot",
        "--set",
        f"simulation.duration_s={duration}",
    ]
    for s in sets:
        args += ["--set", s]
    return _run_cli(args), out


@pytest.mark.parametrize(
    "setting, needle",
    [
        ("terrain.xt=1.5", r"terrain.xt: must be at most 1"),
        ("terrain.model.tau0=-1", "tau0: must be at least 0"),
        ("terrain.model.tau1=-1", "tau1: must be at least 0"),
        ("terrain.model.peak_exponent_d=0", "peak_exponent_d: must be greater than 0"),
        ("terrain.model.A=0", "A: must be greater than 0"),
        ("terrain.model.slip_eps_mps=1e300", "slip_eps_mps: must be at most 1 m/s"),
        ("simulation.atol_scale=1e300", "atol_scale: must be at most 1000"),
        ("simulation.output_dt_s=1e-9", "output samples (times x segments), over the"),
    ],
)
def test_former_silent_nonsense_is_bad_input(tmp_path, setting, needle):
    r, out = _tow6(tmp_path, setting)
    assert r.exit_code == 2, r.output
    assert needle in r.output
    assert not out.exists()


@pytest.mark.parametrize(
    "setting",
    [
        ".nan",
        ".inf",
        "1.5",
        "1e300",
        "[6]",
        "{a: 1}",
    ],
)
def test_whole_number_fields_reject_non_integers(tmp_path, setting):
    for key in ("vehicle.segments", "vehicle.segment.wheels_per_axle"):
        r, _ = _tow6(tmp_path, f"{key}={setting}")
        assert r.exit_code == 2, r.output
        assert key in r.output and "internal error" not in r.output


@pytest.mark.parametrize(
    "setting, needle",
    [
        (
            "vehicle.parameter_set=[a]",
            "vehicle.parameter_set: unknown set ['a']. Known sets: frostyboy; or give a YAML",
        ),
        ("mode.type=[a]", "mode.type: expected the name of a mode"),
        ("mode.type={a: 1}", "mode.type: expected the name of a mode"),
        ("vehicle.segment_overrides.0=5", "vehicle.segment_overrides.0: expected a mapping"),
        ("vehicle.segments=100000000", "vehicle.segments: must be at most 200"),
        ("simulation.duration_s=1e300", "simulation.duration_s: must be at most 100000 s"),
    ],
)
def test_former_internal_errors_are_bad_input(tmp_path, setting, needle):
    r, _ = _tow6(tmp_path, setting)
    assert r.exit_code == 2, r.output
    assert needle in r.output


@pytest.mark.parametrize(
    "key",
    [
        "vehicle.segment.mass_kg",
        "vehicle.segment.wheel_radius_m",
        "vehicle.segment.gravity_mps2",
        "vehicle.links.damping_Ns_per_m",
        "terrain.model.b_tF",
        "terrain.model.b_trF",
        "terrain.model.A",
        "terrain.model.tau0",
        "terrain.model.tau1",
        "terrain.xt",
    ],
)
def test_former_1e300_solver_breakdowns_are_bad_input(tmp_path, key):
    r, _ = _tow6(tmp_path, f"{key}=1e300")
    assert r.exit_code == 2, r.output
    assert f"{key}: must be at most" in r.output and "the allowed range is" in r.output


@pytest.mark.parametrize(
    "setting", ["tow.force_N=1e6", "vehicle.segment.wheel_inertia_kgm2=1e-300", "simulation.max_step_s=1e-7"]
)
def test_extreme_valid_values_end_as_solver_failures(tmp_path, setting):
    """Runaway (1 MN tow), singular Newton matrix, work limit: exit 1 with the solver's message."""
    r, out = _tow6(tmp_path, setting)
    assert r.exit_code == 1, r.output
    lines = [ln for ln in r.output.splitlines() if not ln.startswith("tow6_uniform: ")]  # progress lines
    assert lines[0].startswith("Error: solver failure: ") and "internal error" not in r.output
    assert "Warning" not in r.output  # numpy/scipy warnings captured, not printed
    assert not out.exists()


# former hangs: each ran past 60 s before; a subprocess with a generous timeout proves they end
HANGS = [
    ["run", "tow6_uniform", "--set", "tow.force_N=1e300"],
    ["run", "tow6_uniform", "--set", "vehicle.links.stiffness_N_per_m=1e300"],
    ["run", "inchworm2", "--set", "mode.speed_gain_Ns_per_m=1e300"],
    ["run", "tow6_uniform", "--set", "vehicle.segments=100000000"],
    ["sweep", "tow6_uniform", "--set", "tow.force_N=0:1:10000000"],
]


@pytest.mark.parametrize("args", HANGS, ids=[a[-1] for a in HANGS])
def test_former_hangs_end_with_exit_2(tmp_path, args):
    cmd, name, *rest = args
    full = [
        sys.executable,
        "-m",
        "snoworm.cli",
        cmd,
        str(SCENARIOS / f"{name}.yaml"),
        "--out",
        str(tmp_path / "o"),
        "--no-plot",
        *rest,
    ]
    p = subprocess.run(full, capture_output=True, text=True, timeout=60)
    assert p.returncode == 2, p.stderr
    assert "must be at most" in p.stderr or "COUNT 10000000 is over" in p.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    "args, needle",
    [
        (["terrain-curves", "--xt", "inf"], "--xt: must be a finite number"),
        (["terrain-curves", "--xt", "1.5"], "--xt: must be at most 1"),
        (["mobility-map", "tow6_uniform", "--xt", "nan,0.5", "--no-inching"], "--xt: must be a finite number"),
        (["mobility-map", "tow6_uniform", "--xt", "0.2:1.5:3", "--no-inching"], "--xt: must be at most 1"),
        (
            ["mobility-map", "tow6_uniform", "--rolling-speed", "-1", "--no-inching"],
            "--rolling-speed: must be greater than 0",
        ),
        (["mobility-map", "tow6_uniform", "--tow", "1e300", "--no-inching"], "--tow: must be at most 1e+06 N"),
        (
            ["sweep", "tow6_uniform", "--set", "tow.force_N=0:1:1000", "--set", "terrain.xt=0.1:1:1000"],
            "the sweep has 1000000 cases, over the 100000 allowed",
        ),
    ],
)
def test_command_options_meet_the_same_domains(tmp_path, args, needle):
    args = [str(SCENARIOS / f"{a}.yaml") if a == "tow6_uniform" else a for a in args]
    r = _run_cli(args + ["--out", tmp_path / "o", "--no-plot"])
    assert r.exit_code == 2, r.output
    assert needle in r.output
    assert not (tmp_path / "o").exists()


def test_empty_out_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = _run_cli(["run", SCENARIOS / "tow6_uniform.yaml", "--out", "", "--no-plot"])
    assert r.exit_code == 2 and "must name a directory" in r.output
    assert list(Path(tmp_path).iterdir()) == []


def test_calibrated_xt_stays_in_its_domain(tmp_path):
    r = _run_cli(
        [
            "calibrate",
            Path(__file__).parents[1] / "snoworm" / "data" / "frostyboy_2020.csv",
            "--fit",
            "xt",
            "--out",
            tmp_path / "o",
        ]
    )
    assert r.exit_code == 0, r.output
    xts = json.loads((tmp_path / "o" / "calibration.json").read_text())["xt"]
    assert xts and all(0 < v <= 1 for v in xts.values())


def _yaml_abuse(tmp_path):
    base = (SCENARIOS / "tow6_uniform.yaml").read_text()
    bomb = ["a0: &a0 [x,x,x,x,x,x,x,x,x]"] + [
        f"a{i}: &a{i} [" + ",".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 10)
    ]
    files = {
        "bomb": ("\n".join(bomb) + "\n" + base.replace("force_N: 200", "force_N: *a9")).encode(),
        "deep": base.replace("force_N: 200", "force_N: " + "[" * 5000 + "]" * 5000).encode(),
        "utf16": base.encode("utf-16"),
        "latin1": base.replace("Paper", "Pap\xe9r").encode("latin-1"),
        "duplicate": base.replace("force_N: 200", "force_N: 200\n  force_N: 300").encode(),
        "bigstring": base.replace("force_N: 200", 'force_N: "' + "x" * 2_000_000 + '"').encode(),
    }
    for name, content in files.items():
        (tmp_path / f"{name}.yaml").write_bytes(content)
    return sorted(files)


def test_yaml_abuse_is_bad_input(tmp_path):
    for name in _yaml_abuse(tmp_path):
        r = _run_cli(["run", tmp_path / f"{name}.yaml", "--out", tmp_path / "o", "--no-plot"])
        assert r.exit_code == 2, (name, r.output[:300])
        assert len(r.output) < 600, (name, r.output[:300])
        assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------ issue 24: manifests, controllers, read-back
TRUST_EXAMPLES = int(os.environ.get("SNOWORM_FUZZ_TRUST_EXAMPLES", 25))
_ENTRY = st.one_of(
    st.sampled_from(
        [
            "a.csv",
            "sub/b.csv",
            "../outside/thesis.tex",
            "/OUTSIDE/thesis.tex",
            "link/thesis.tex",
            "./a.csv",
            "a//b",
            "a\\b",
            "",
            ".",
            "..",
            "\x00",
            "x" * 5000,
            ".snoworm-manifest.json",
        ]
    ),
    st.text(min_size=0, max_size=30),
    st.integers(),
    st.none(),
    st.floats(allow_nan=True),
    st.lists(st.integers(), max_size=2),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)


@settings(
    max_examples=TRUST_EXAMPLES,
    deadline=None,
    derandomize=not os.environ.get("SNOWORM_FUZZ_RANDOM"),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(
    entries=st.lists(_ENTRY, max_size=6),
    shape=st.sampled_from(["object", "list", "bytes", "files_not_list"]),
    junk=st.binary(max_size=200),
    symlinked=st.booleans(),
    overwrite=st.booleans(),
)
def test_fuzzed_manifests_never_touch_a_file_outside(tmp_path_factory, entries, shape, junk, symlinked, overwrite):
    from snoworm.infra.folders import MANIFEST, OutputError, atomic_write_text, output_folder

    root = tmp_path_factory.mktemp("m")
    outside = root / "outside"
    outside.mkdir()
    (outside / "thesis.tex").write_text("precious")
    out = root / "out"
    (out / "sub").mkdir(parents=True)
    (out / "a.csv").write_text("old")
    (out / "sub" / "b.csv").write_text("old")
    if symlinked:
        os.symlink(outside, out / "link")
    entries = [str(outside / "thesis.tex") if e == "/OUTSIDE/thesis.tex" else e for e in entries]
    doc = {"object": {"files": entries}, "list": entries, "files_not_list": {"files": "a.csv"}}
    if shape == "bytes":
        (out / MANIFEST).write_bytes(junk)
    else:
        (out / MANIFEST).write_text(json.dumps(doc[shape]))
    try:
        with output_folder(out, overwrite=overwrite) as stage:
            atomic_write_text(stage / "a.csv", "new")
    except OutputError as exc:
        assert len(str(exc)) < 1500
    assert (outside / "thesis.tex").read_text() == "precious"
    assert sorted(os.listdir(outside)) == ["thesis.tex"]


_REF_PART = st.sampled_from(
    [
        "ctl.py",
        "../ctl.py",
        "/",
        "sub/",
        "ctl",
        "x" * 300,
        "\x00",
        "this",
        "builtins",
        "os.path",
        "tests.controller_helpers",
        "json",
        ".py",
        ":",
        "Ctl",
        "print",
        "Uniform",
        "schedule",
        "..",
        "~",
        "\\",
        " ",
        "é",
    ]
)


@settings(
    max_examples=TRUST_EXAMPLES,
    deadline=None,
    derandomize=not os.environ.get("SNOWORM_FUZZ_RANDOM"),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(parts=st.lists(_REF_PART, min_size=1, max_size=5), name=st.sampled_from(["Ctl", "Uniform", "print", "C", ""]))
def test_fuzzed_controller_references_never_run_code_when_read(tmp_path_factory, parts, name):
    from snoworm import scenario_from_dict
    from snoworm.config.schema import ScenarioError

    root = tmp_path_factory.mktemp("c")
    marker = root / "MARKER"
    (root / "proj" / "sub").mkdir(parents=True)
    code = f"import pathlib\npathlib.Path({str(marker)!r}).write_text('ran')\nclass Ctl:\n    pass\n"
    for f in (root / "ctl.py", root / "proj" / "ctl.py", root / "proj" / "sub" / "ctl.py"):
        f.write_text(code)
    raw = load_scenario(SCENARIOS / "tow6_uniform.yaml").to_dict()
    raw["mode"] = {"type": "controller", "controller": "".join(parts) + ":" + name, "period_s": 0.1, "params": {}}
    try:
        sc = scenario_from_dict(raw, "fuzz", base_dir=root / "proj")
        assert sc.mode.controller.endswith(":" + name)
    except ScenarioError as exc:
        assert len(str(exc)) < 1500
    assert not marker.exists()


@pytest.fixture(scope="module")
def good_run(tmp_path_factory):
    from snoworm import simulate

    d = tmp_path_factory.mktemp("r") / "run"
    simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml", ["simulation.duration_s=0.5"])).write(d, plot=False)
    return d


@settings(
    max_examples=TRUST_EXAMPLES,
    deadline=None,
    derandomize=not os.environ.get("SNOWORM_FUZZ_RANDOM"),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(
    name=st.sampled_from(["segments.csv", "links.csv", "summary.json", "scenario.yaml"]),
    how=st.sampled_from(["truncate", "cell", "drop_line", "dup_line", "append", "empty"]),
    pos=st.floats(0, 1),
    token=st.sampled_from(["nan", "inf", "-1e300", "x", "", "1,2", "[", "{}", "7"]),
)
def test_fuzzed_result_folders_load_or_raise_one_error(tmp_path_factory, good_run, name, how, pos, token):
    import shutil

    from snoworm.results.result import ResultFileError, load_result

    d = tmp_path_factory.mktemp("t") / "run"
    shutil.copytree(good_run, d)
    text = (d / name).read_text()
    lines = text.splitlines(keepends=True)
    k = min(int(pos * len(lines)), len(lines) - 1)
    if how == "truncate":
        text = text[: int(pos * len(text))]
    elif how == "cell":
        cells = lines[k].rstrip("\n").split(",")
        cells[min(int(pos * len(cells)), len(cells) - 1)] = token
        lines[k] = ",".join(cells) + "\n"
        text = "".join(lines)
    elif how == "drop_line":
        text = "".join(lines[:k] + lines[k + 1 :])
    elif how == "dup_line":
        text = "".join(lines[: k + 1] + lines[k:])
    elif how == "append":
        text = text + token + "\n"
    else:
        text = ""
    (d / name).write_text(text)
    try:
        res = load_result(d)
    except ResultFileError as exc:
        assert name in str(exc) or str(d) in str(exc)
        return
    n = res.scenario.vehicle.segments
    assert res.segments["x_m"].shape == (res.t.size, n) and res.links["force_N"].shape == (res.t.size, n - 1)
    assert all(np.all(np.isfinite(v)) for v in (*res.segments.values(), *res.links.values(), res.t))


@pytest.fixture(scope="module")
def good_series(tmp_path_factory):
    from snoworm import run_sweep

    d = tmp_path_factory.mktemp("nc") / "s"
    run_sweep(
        SCENARIOS / "tow6_uniform.yaml",
        ["terrain.xt=0.7,0.9", "simulation.duration_s=0.5"],
        out_dir=d,
        plot=False,
        progress=False,
        series="netcdf",
    )
    return d


def _tamper_series(path, how, pos, value):
    """Rewrite ``path`` (a series.nc): bytes overwritten or cut, or the dataset rewritten with a
    dimension resized, a variable dropped or retyped, or its values replaced."""
    import xarray as xr

    data = path.read_bytes()
    k = min(int(pos * len(data)), len(data) - 1)
    if how == "bytes":
        path.write_bytes(data[:k] + bytes([value % 256]) * 16 + data[k + 16 :])
    elif how == "truncate":
        path.write_bytes(data[:k])
        return
    else:
        with xr.open_dataset(path, engine="h5netcdf") as ds:
            ds = ds.load()
        names = sorted(ds.data_vars)
        name = names[min(int(pos * len(names)), len(names) - 1)]
        if how == "drop":
            ds = ds.drop_vars(name)
        elif how == "values":
            ds[name] = ds[name].copy(data=np.full(ds[name].shape, value).astype(ds[name].dtype))  # wraps
        elif how == "retype":
            ds[name] = ds[name].astype(str)
        else:  # "resize": the time axis cut or grown by a few samples (a huge one: test_studies_sweep_series)
            step = max(min(value, 50), -5)
            ds = ds.isel(time=slice(0, max(ds.sizes["time"] + step, 1))) if step < 0 else ds.pad(time=(0, step))
        path.unlink()
        ds.to_netcdf(path, engine="h5netcdf")


@settings(
    max_examples=TRUST_EXAMPLES,
    deadline=None,
    derandomize=not os.environ.get("SNOWORM_FUZZ_RANDOM"),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(
    how=st.sampled_from(["bytes", "truncate", "drop", "values", "retype", "resize"]),
    pos=st.floats(0, 1),
    value=st.sampled_from([-(2**31), -5, -1, 0, 1, 3, 255, 2**31 - 1]),
)
def test_fuzzed_series_nc_loads_or_raises_one_error(tmp_path_factory, good_series, how, pos, value):
    import shutil

    from snoworm import load_sweep
    from snoworm.results.result import ResultFileError
    from snoworm.studies.sweep.series import _from_old

    d = tmp_path_factory.mktemp("t") / "s"
    shutil.copytree(good_series, d)
    _tamper_series(d / "series.nc", how, pos, value)
    try:
        ds = load_sweep(d).series()
    except ResultFileError as exc:
        assert "series.nc" in str(exc) and len(str(exc)) < 1000
    else:
        assert ds.sizes["terrain_xt"] == 2 and ds["x_m"].ndim == 4
    try:  # what a resume reads: the cases' arrays, trimmed of their padding
        old = _from_old(d / "series.nc", 2, {"terrain_xt": 2, "simulation_duration_s": 1})
    except ResultFileError as exc:
        assert "series.nc" in str(exc)
    else:
        assert all(a["t_s"].ndim == 1 and a["segments/x_m"].shape[0] == a["t_s"].size for a in old.values())
