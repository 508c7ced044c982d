"""What the commands share (snoworm.commands.common): exit statuses, error handling, shared options.

Each command of tests/test_cli.py goes through these; here they are checked on a bare command
so that each mapping (exception -> message and exit status) is seen on its own.
"""

import logging
import os
import re
import signal
import subprocess
import sys

import click
import pytest
from click.testing import CliRunner

from snoworm.commands.common import (
    EXIT_INPUT,
    EXIT_SOLVER,
    CommandGroup,
    Terminated,
    command_line,
    configure_logging,
    handle_errors,
    out_option,
)
from snoworm.config.schema import ScenarioError
from snoworm.infra import folders
from snoworm.infra.folders import OutputError
from snoworm.modes.controller import ControllerError
from snoworm.results.result import ResultFileError
from snoworm.simulation.guard import SolverError


def _cli(exc=None, seen=None):
    @click.group(cls=CommandGroup)
    def group():
        pass

    @group.command()
    @out_option("where to write")
    @handle_errors
    def cmd(out_dir):
        if seen is not None:
            seen.append(command_line())
        if exc is not None:
            raise exc
        click.echo(f"ok {out_dir}")

    return group


@pytest.mark.parametrize(
    "exc, code, text",
    [
        (ScenarioError("tow.force_N: must be finite."), EXIT_INPUT, "Error: tow.force_N: must be finite.\n"),
        (OutputError("out/ is not empty."), EXIT_INPUT, "Error: out/ is not empty.\n"),
        (SolverError("every method failed"), EXIT_SOLVER, "Error: solver failure: every method failed\n"),
        (ControllerError("the controller raised"), EXIT_SOLVER, "Error: the controller raised\n"),
        (RecursionError(), EXIT_INPUT, "nested too deeply"),
        (KeyboardInterrupt(), 130, "interrupted; nothing half-written"),
        (Terminated(), 143, "interrupted; nothing half-written"),
        (ZeroDivisionError("boom"), EXIT_SOLVER, "internal error (ZeroDivisionError: boom). This is a bug"),
        (ResultFileError("d/series.nc: not a netCDF file"), EXIT_INPUT, "Error: d/series.nc: not a netCDF file\n"),
    ],
)
def test_each_failure_is_one_message_and_its_exit_status(monkeypatch, exc, code, text):
    monkeypatch.delenv("SNOWORM_DEBUG", raising=False)
    r = CliRunner().invoke(_cli(exc), ["cmd", "--out", "o"])
    assert r.exit_code == code
    assert text in r.stderr and "Traceback" not in r.stderr


def _raised_in_c_code(interrupt):
    """What a signal handler raising inside NumPy's C code gives: a SystemError caused by it."""
    try:
        raise interrupt
    except KeyboardInterrupt as cause:
        try:
            raise SystemError("<method 'tolist'> returned a result with an exception set") from cause
        except SystemError as exc:
            return exc


@pytest.mark.parametrize("interrupt, code", [(KeyboardInterrupt(), 130), (Terminated(), 143)])
def test_an_interrupt_inside_c_code_is_an_interruption_not_an_internal_error(monkeypatch, interrupt, code):
    """Hostile battery (benchmarks/hostile.py): SIGTERM to `snoworm run` mid-way ended as 'internal
    error (SystemError: <method 'tolist' ...> returned a result with an exception set)', exit 1."""
    monkeypatch.delenv("SNOWORM_DEBUG", raising=False)
    r = CliRunner().invoke(_cli(_raised_in_c_code(interrupt)), ["cmd", "--out", "o"])
    assert r.exit_code == code
    assert "interrupted; nothing half-written" in r.stderr and "internal error" not in r.stderr


def test_debug_shows_the_traceback_of_a_bug(monkeypatch):
    monkeypatch.setenv("SNOWORM_DEBUG", "1")
    r = CliRunner().invoke(_cli(ZeroDivisionError("boom")), ["cmd", "--out", "o"])
    assert isinstance(r.exception, ZeroDivisionError)


def test_a_command_knows_its_command_line_for_the_manifests():
    seen = []
    r = CliRunner().invoke(_cli(seen=seen), ["cmd", "--out", "res dir"])
    assert r.exit_code == 0 and r.stdout == "ok res dir\n"
    assert seen == ["snoworm cmd --out 'res dir'"]
    assert command_line() is None  # outside a command
    assert not hasattr(folders, "COMMAND")  # no module global: the CLI passes it (command=)


def test_sigterm_handler_is_restored_after_the_command():
    before = signal.getsignal(signal.SIGTERM)
    CliRunner().invoke(_cli(), ["cmd", "--out", "o"])
    assert signal.getsignal(signal.SIGTERM) == before


def test_out_refuses_an_empty_path():
    r = CliRunner().invoke(_cli(), ["cmd", "--out", " "])
    assert r.exit_code == 2 and "must name a directory, got an empty path" in r.stderr


def test_logging_is_configured_once_at_the_chosen_level():
    log = logging.getLogger("snoworm")
    old_level, old_handlers = log.level, list(log.handlers)
    try:
        configure_logging(True)
        configure_logging(False)
        assert log.level == logging.WARNING
        assert sum(type(h).__name__ == "StderrHandler" for h in log.handlers) == 1
    finally:
        log.setLevel(old_level)
        log.handlers[:] = old_handlers


def test_no_library_module_is_imported_at_import_time():
    """Like the CLI, the shared helpers import snoworm's modules only when a command runs (the
    package itself imports only its version string)."""
    code = (
        "import sys, snoworm.commands.common; print(sorted(m for m in sys.modules if m.startswith('snoworm.') "
        "and m not in ('snoworm.commands', 'snoworm.commands.common', 'snoworm._version')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "PYTHONWARNINGS": "ignore"},
    ).stdout
    assert out.strip() == "[]"


def test_echo_scenarios_and_echo_written(capsys):
    from snoworm.commands.common import echo_scenarios, echo_written
    from snoworm.config.scenario import shipped_scenarios

    echo_scenarios()
    lines = capsys.readouterr().out.splitlines()
    assert [ln.split()[0] for ln in lines] == list(shipped_scenarios())
    echo_written("report", ["a", "b"], "out/x")
    assert capsys.readouterr().out == "report\nwrote 2 files to out/x\n"


def test_long_paths_are_cut_in_messages_and_an_unusable_out_is_exit_2(tmp_path, monkeypatch):
    """Issue 30: a 3.7 kB path was echoed whole (twice in some messages: ~10 kB), and a path
    over the system's limits (ENAMETOOLONG) was an internal error."""
    from snoworm.cli import main

    monkeypatch.delenv("SNOWORM_DEBUG", raising=False)
    deep = str(tmp_path.joinpath(*["d" * 250] * 14))
    r = CliRunner().invoke(_cli(ScenarioError(f"{deep}/x.yaml: missing; {deep}/y.yaml too")), ["cmd", "--out", "o"])
    assert r.exit_code == EXIT_INPUT and len(deep) > 3500 and len(r.stderr) < 1200, len(r.stderr)
    assert "x.yaml: missing" in r.stderr and "characters]" in r.stderr
    too_long = "/".join(["d" * 200] * 40)  # 8 kB: over PATH_MAX
    for args in (["validate", too_long], ["run", "tow6_uniform", "--out", too_long, "--no-plot"]):
        r = CliRunner().invoke(main, args)
        assert r.exit_code == EXIT_INPUT and "internal error" not in r.output and len(r.output) < 1200, r.output[:300]


def test_cpu_clock_counts_this_process_and_its_exited_children():
    """Issue 34: the speed line gives CPU time beside wall time.  The clock's CPU seconds include
    a finished child process's own CPU time (as a worker pool's, once shut down), read from the
    child itself; the tolerance is the rusage accounting's granularity (a clock tick, 10 ms)."""
    from snoworm.commands.common import CpuClock

    clock = CpuClock()
    burn = "import time\ns=0\nfor i in range(3_000_000): s+=i*i\nprint(time.process_time())"
    child_cpu = float(subprocess.run([sys.executable, "-c", burn], capture_output=True, text=True, check=True).stdout)
    wall, cpu = clock.seconds()
    assert child_cpu > 0.05  # the child really worked
    assert cpu >= child_cpu - 0.02
    assert wall >= 0.0
    assert re.fullmatch(r"\d+\.\d\d s wall, \d+\.\d\d s CPU", clock.text())


def test_the_run_line_gives_wall_and_cpu_time(tmp_path):
    """``snoworm run``'s first line: "<name>: 2.0 s simulated in W s wall, C s CPU (Nx real time)"."""
    from snoworm.cli import main

    r = CliRunner().invoke(
        main, ["run", "tow6_uniform", "--out", str(tmp_path / "o"), "--set", "simulation.duration_s=2", "--no-plot"]
    )
    assert r.exit_code == 0, r.output
    m = re.search(r"tow6_uniform: 2\.0 s simulated in ([0-9.]+) s wall, ([0-9.]+) s CPU \((\d+)x real time\)", r.output)
    assert m, r.output
    assert float(m.group(1)) > 0.0 and float(m.group(2)) >= 0.0
