"""CLI output folders, progress, shipped scenarios by name, `python -m snoworm` (issues 13 and 15)."""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import time

import pytest
from click.testing import CliRunner

from snoworm.cli import main
from snoworm.infra import folders
from snoworm.infra.folders import MANIFEST
from tests.conftest import SCENARIOS

SHORT = ["--set", "simulation.duration_s=2"]


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture
def umask022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def test_a_run_into_a_folder_of_another_run_leaves_only_its_own_files(tmp_path, umask022):
    out = tmp_path / "o"
    r = run("run", "pi2_zero", "--out", out, *SHORT)  # force control: force_diagram.png
    assert r.exit_code == 0, r.output
    assert (out / "force_diagram.png").exists()
    r = run("run", "tow6_uniform", "--out", out, *SHORT)
    assert r.exit_code == 0, r.output
    files = sorted(os.listdir(out))
    man = json.loads((out / MANIFEST).read_text())
    assert "force_diagram.png" not in files
    assert sorted(man["files"] + [MANIFEST]) == files
    assert "tow6_uniform" in man["command"] and man["snoworm_version"]
    assert all(stat.S_IMODE(os.stat(out / f).st_mode) == 0o644 for f in files)
    assert json.loads((out / "summary.json").read_text())["scenario"] == "tow6_uniform"


def test_a_foreign_folder_is_refused_before_the_run_and_overwrite_writes_into_it(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "thesis.tex").write_text("precious")
    r = run("run", "tow6_uniform", "--out", out, *SHORT, "--no-plot")
    assert r.exit_code == 2 and str(out) in r.output and "--overwrite" in r.output
    assert "simulated" not in r.output  # refused before running
    assert os.listdir(out) == ["thesis.tex"]
    r = run("run", "tow6_uniform", "--out", out, *SHORT, "--no-plot", "--overwrite")
    assert r.exit_code == 0, r.output
    assert (out / "thesis.tex").read_text() == "precious" and (out / "summary.json").exists()


def test_disk_full_during_a_run_is_exit_2_naming_the_path_and_nothing_is_written(tmp_path, monkeypatch):
    real = os.replace

    def full(src, dst):
        if str(dst).endswith("links.csv"):
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(folders.os, "replace", full)
    out = tmp_path / "o"
    r = run("run", "tow6_uniform", "--out", out, *SHORT, "--no-plot")
    assert r.exit_code == 2, r.output
    assert "No space left on device" in r.output and str(out) in r.output and "internal error" not in r.output
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "cmd",
    [
        ["run", "tow6_uniform", *SHORT],
        ["terrain-curves", "--xt", "0.5"],
        ["groundtruth"],
        ["mobility-map", "tow6_uniform", "--no-inching", "--xt", "0.5,0.9"],
    ],
)
def test_out_under_a_file_is_exit_2_for_every_command(tmp_path, cmd):
    (tmp_path / "f").write_text("x")
    r = run(*cmd, "--out", tmp_path / "f" / "sub", "--no-plot")
    assert r.exit_code == 2, r.output
    assert "which is a file" in r.output and "Traceback" not in r.output


def test_terrain_curves_replaces_its_earlier_folder_and_refuses_a_foreign_one(tmp_path):
    out = tmp_path / "c"
    assert run("terrain-curves", "--xt", "0.5", "--out", out).exit_code == 0
    assert run("terrain-curves", "--xt", "0.9", "--out", out, "--no-plot").exit_code == 0
    assert sorted(os.listdir(out)) == sorted([MANIFEST, "terrain_curves.csv"])  # the old png is gone
    (out / "extra.txt").write_text("user")
    r = run("terrain-curves", "--xt", "0.5", "--out", out)
    assert r.exit_code == 2 and "--overwrite" in r.output


def test_run_shows_progress_in_simulated_time_on_stderr(tmp_path):
    r = run("run", "inchworm2", "--out", tmp_path / "o", *SHORT, "--no-plot")
    assert r.exit_code == 0, r.output
    assert "inchworm2: 100 % (2/2 s simulated)" in r.output


def test_verbose_logs_solver_fallbacks(tmp_path, monkeypatch):
    import logging

    from snoworm.simulation import interval

    real = interval.solve_ivp
    calls = []

    def flaky(*a, **kw):
        calls.append(kw["method"])
        if len(calls) == 1:
            raise ValueError("injected failure")
        return real(*a, **kw)

    monkeypatch.setattr(interval, "solve_ivp", flaky)
    try:
        r = run("-v", "run", "frostyboy_case1", "--out", tmp_path / "o", *SHORT, "--no-plot")
    finally:
        logging.getLogger("snoworm").setLevel(logging.WARNING)
    assert r.exit_code == 0, r.output
    assert "snoworm: interval" in r.output and "injected failure" in r.output and "retried with BDF" in r.output


def test_shipped_scenarios_by_name_and_listed(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # outside the repository
    r = run("scenarios")
    assert r.exit_code == 0
    names = [line.split()[0] for line in r.output.splitlines()]
    assert names == sorted(p.stem for p in SCENARIOS.glob("*.yaml"))
    assert all(len(line.split(None, 1)) == 2 for line in r.output.splitlines())  # name + description
    assert run("validate", "inchworm6").exit_code == 0
    r = run("run", "inchworm6.yaml", "--out", "o", "--set", "simulation.duration_s=1", "--no-plot")
    assert r.exit_code == 0, r.output
    r = run("validate", "inchworm7")
    assert r.exit_code == 2 and "inchworm6" in r.output and "snoworm scenarios" in r.output


def test_a_path_wins_over_a_shipped_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    text = (SCENARIOS / "tow6_uniform.yaml").read_text().replace("name: tow6_uniform", "name: my_local")
    (tmp_path / "inchworm6").write_text(text)
    r = run("validate", "inchworm6")
    assert r.exit_code == 0 and "mode uniform" in r.output


def test_python_dash_m_snoworm_runs_the_cli(tmp_path):
    p = subprocess.run([sys.executable, "-m", "snoworm", "scenarios"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert "inchworm6" in p.stdout
    p = subprocess.run([sys.executable, "-m", "snoworm", "--help"], capture_output=True, text=True, timeout=120)
    assert p.stdout.startswith("Usage: snoworm")


def test_jobs_option_on_every_command_that_runs_cases_in_parallel():
    import inspect

    from snoworm.studies import calibrate, groundtruth, mobility
    from snoworm.studies.paper import report
    from snoworm.studies.sweep import run as sweep_run

    parallel = {"sweep": sweep_run, "mobility-map": mobility, "paper": report}
    serial = {"calibrate": calibrate, "groundtruth": groundtruth}
    for name, mod in parallel.items():
        assert "ProcessExecutor" in inspect.getsource(mod)
        assert "-j" in [o for p in main.commands[name].params for o in p.opts], name
    for name, mod in serial.items():  # no worker processes: no -j
        assert "ProcessExecutor" not in inspect.getsource(mod), name


# ------------------------------------------------------------------ sweeps
def _sweep(out, *extra):
    return run(
        "sweep",
        "tow6_uniform",
        "--set",
        "terrain.xt=0.7,0.9",
        "--set",
        "simulation.duration_s=2",
        "--out",
        out,
        "--no-plot",
        *extra,
    )


def test_a_sweep_into_a_locked_folder_exits_2_naming_the_pid(tmp_path):
    import multiprocessing

    from tests.test_infra_folders import _hold

    ctx = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
    ready, release = ctx.Event(), ctx.Event()
    out = tmp_path / "s"
    out.mkdir()
    p = ctx.Process(target=_hold, args=(out, ready, release))
    p.start()
    try:
        assert ready.wait(20)
        r = _sweep(out)
        assert r.exit_code == 2, r.output
        assert f"process {p.pid}" in r.output
        assert not (out / "summary.csv").exists()
    finally:
        release.set()
        p.join(20)
    r = _sweep(out)  # released: runs
    assert r.exit_code == 0, r.output
    assert json.loads((out / MANIFEST).read_text())["status"] == "complete"


def test_an_unreachable_scheduler_writes_nothing(tmp_path, monkeypatch):
    from snoworm.config.schema import ScenarioError
    from snoworm.studies.sweep import run as sweep_run

    seen = []

    def refuse(scheduler, batch, jobs):
        seen.append(scheduler)
        raise ScenarioError(f"--scheduler {scheduler}: cannot connect to the Dask scheduler (test).")

    monkeypatch.setattr(sweep_run, "_make_executor", refuse)
    out = tmp_path / "s"
    r = _sweep(out, "--scheduler", "tcp://127.0.0.1:1")
    assert r.exit_code == 2 and seen == ["tcp://127.0.0.1:1"]
    assert not out.exists()


def test_a_sweep_refuses_a_foreign_folder_and_replaces_another_commands_output(tmp_path):
    out = tmp_path / "s"
    assert run("terrain-curves", "--xt", "0.5", "--out", out).exit_code == 0
    r = _sweep(out)
    assert r.exit_code == 0, r.output
    assert not (out / "terrain_curves.csv").exists() and (out / "summary.csv").exists()
    r = _sweep(tmp_path / "s", "--set", "tow.force_N=0,10")  # another sweep: refused ...
    assert r.exit_code == 2 and "--overwrite" in r.output
    r = _sweep(tmp_path / "s", "--set", "tow.force_N=0,10", "--overwrite")  # ... or replaced
    assert r.exit_code == 0, r.output
    assert "4 cases: 4 ok" in r.output
    (out / "x.txt").write_text("mine")
    foreign = tmp_path / "f"
    foreign.mkdir()
    (foreign / "x.txt").write_text("mine")
    r = _sweep(foreign)
    assert r.exit_code == 2 and "--overwrite" in r.output


@pytest.mark.slow
def test_sigterm_ends_a_sweep_with_a_message_keeping_finished_rows(tmp_path):
    out = tmp_path / "s"
    cmd = [
        sys.executable,
        "-m",
        "snoworm",
        "sweep",
        "tow6_uniform",
        "--set",
        "tow.force_N=0:100:40",
        "--set",
        "simulation.duration_s=3",
        "--out",
        str(out),
        "--no-plot",
    ]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    summary = out / "summary.csv"
    t0 = time.time()
    while time.time() - t0 < 60:
        if summary.exists() and len(summary.read_text().splitlines()) >= 3:
            break
        time.sleep(0.1)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 143, err
    assert "terminated (SIGTERM)" in err and "run the same command again to resume" in err
    lines = summary.read_text().splitlines()
    assert len(lines) >= 3 and summary.read_text().endswith("\n")
    assert not (out / folders.LOCK).exists()
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)  # resumes
    assert r.returncode == 0, r.stderr
    assert f"{len(lines) - 1} resumed" in r.stderr and "40 cases: 40 ok" in r.stdout


def test_disk_full_while_appending_sweep_rows_is_exit_2_naming_the_file(tmp_path, monkeypatch):
    from snoworm.studies.sweep import run as sweep_run

    real = os.write

    def full(fd, data):
        if data.startswith(b"000"):  # a row (case ids 0000, 0001)
            raise OSError(28, "No space left on device")
        return real(fd, data)

    monkeypatch.setattr(sweep_run.os, "write", full)
    out = tmp_path / "s"
    r = _sweep(out)
    assert r.exit_code == 2, r.output
    assert "No space left on device" in r.output and str(out / "summary.csv") in r.output
    assert "re-run the same command to resume" in r.output and "internal error" not in r.output
    assert not (out / folders.LOCK).exists()


def test_rerunning_into_the_same_out_says_so_in_one_line(tmp_path):
    out = tmp_path / "o"
    r = run("run", "pi2_zero", "--out", out, "--no-plot", *SHORT)
    assert r.exit_code == 0, r.output and "note:" not in r.output
    r = run("run", "pi2_zero", "--out", out, "--no-plot", *SHORT)
    assert r.exit_code == 0, r.output
    notes = [ln for ln in r.output.splitlines() if ln.startswith("note:")]
    assert len(notes) == 1 and "holds earlier results (snoworm run pi2_zero" in notes[0] and "replaced" in notes[0]
    s = tmp_path / "s"
    args = ("sweep", "pi2_zero", "--set", "tow.force_N=0,10", *SHORT, "--out", s, "--no-plot")
    assert run(*args).exit_code == 0
    r = run(*args)
    notes = [ln for ln in r.output.splitlines() if ln.startswith("note:")]
    assert r.exit_code == 0 and len(notes) == 1 and "resumed" in notes[0]
