"""User code bounded by simulation.max_wall_s; a controller never ends the process (issue 24, high)."""

from __future__ import annotations

import signal
import textwrap
import time

import pytest
import yaml
from click.testing import CliRunner

from snoworm import load_scenario, run_sweep, simulate
from snoworm.cli import main
from snoworm.modes.controller import ControllerError
from snoworm.modes.watchdog import WallLimit, bounded, wall_limit
from tests.conftest import SCENARIOS

CTL = """
    import sys

    class Ctl:
        def __init__(self, params, scenario):
            self.where = params["where"]
            if self.where == "init":
                while True:
                    pass
            if self.where == "exit_init":
                sys.exit(0)

        def __call__(self, obs):
            if obs.t_s > 0.25 and self.where == "call":
                while True:                      # swallows one alarm: the timer repeats
                    try:
                        while True:
                            pass
                    except Exception:
                        pass
            if obs.t_s > 0.25 and self.where == "exit":
                sys.exit(0)
            return {"wheel_speed_mps": [0.5] * len(obs.x_m)}
"""


def _scenario(tmp_path, where, max_wall_s=1.0):
    (tmp_path / "ctl.py").write_text(textwrap.dedent(CTL))
    raw = yaml.safe_load((SCENARIOS / "tow6_uniform.yaml").read_text())
    raw["mode"] = {"type": "controller", "controller": "ctl.py:Ctl", "period_s": 0.1, "params": {"where": where}}
    raw["simulation"].update(duration_s=1.0, max_wall_s=max_wall_s)
    p = tmp_path / "s.yaml"
    p.write_text(yaml.safe_dump(raw))
    return p


@pytest.mark.skipif(not bounded(), reason="needs POSIX timers in the main thread")
@pytest.mark.parametrize(
    "where, words", [("call", ["max_wall_s", "at t = 0.3 s", "endless loop"]), ("init", ["max_wall_s", "constructing"])]
)
def test_a_controller_looping_forever_is_stopped_by_max_wall_s(tmp_path, where, words):
    sc = load_scenario(_scenario(tmp_path, where))
    with pytest.raises(ControllerError) as err:
        simulate(sc)
    for w in words:
        assert w in str(err.value)
    assert signal.getsignal(signal.SIGALRM) in (signal.SIG_DFL, None)  # restored
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)


@pytest.mark.parametrize(
    "where, words", [("exit", ["sys.exit(0)", "at t = 0.3 s"]), ("exit_init", ["sys.exit(0)", "constructing"])]
)
def test_a_controller_calling_sys_exit_is_exit_1_and_a_sweep_row(tmp_path, where, words):
    p = _scenario(tmp_path, where, max_wall_s=60)
    r = CliRunner().invoke(main, ["run", str(p), "--out", str(tmp_path / "o"), "--no-plot"])
    assert r.exit_code == 1, r.output
    for w in words:
        assert w in r.output
    table = run_sweep(p, ["terrain.xt=0.8,0.9"], progress=False, plot=False)
    assert [row["status"] for row in table.rows] == ["controller_failure"] * 2
    assert all("sys.exit(0)" in row["error"] for row in table.rows)


@pytest.mark.skipif(not bounded(), reason="needs POSIX timers in the main thread")
def test_wall_limit_interrupts_a_loop_and_leaves_no_timer_behind():
    with pytest.raises(WallLimit):
        with wall_limit(time.perf_counter() + 0.2):
            while True:
                pass
    with wall_limit(time.perf_counter() + 30):  # returns in time: nothing raised, timer stopped
        x = sum(range(1000))
    assert x == 499500 and signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    with wall_limit(None):  # no limit: a plain block
        pass
    with pytest.raises(WallLimit):  # a deadline already passed
        with wall_limit(time.perf_counter() - 1):
            pass
