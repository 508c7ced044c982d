"""The controller mode (snoworm.modes.controller): loading, validation, the run, its errors."""

import os
import textwrap

import numpy as np
import pytest
import yaml

from snoworm import Simulator, load_scenario, simulate
from snoworm.config.schema import ScenarioError
from snoworm.modes import watchdog
from snoworm.modes.controller import ControllerError, load_controller
from snoworm.studies.sweep import SweepTask
from tests.conftest import ROOT, SCENARIOS
from tests.controller_helpers import schedule

#: the tests' own controllers are a module of this repository, not installed code: they run only
#: where the tests folder is allowed (docs/controllers.md, issue 30)
TESTS_ALLOWED = [ROOT / "tests"]


def _write(tmp_path, body, mode, name="scenario.yaml", base="tow6_uniform", sim=None):
    raw = yaml.safe_load((SCENARIOS / f"{base}.yaml").read_text())
    raw["mode"] = mode
    if sim:
        raw["simulation"].update(sim)
    if body is not None:
        (tmp_path / "ctl").mkdir(exist_ok=True)
        (tmp_path / "ctl" / "mine.py").write_text(textwrap.dedent(body))
    p = tmp_path / name
    p.write_text(yaml.safe_dump(raw))
    return p


GOOD = """
    class Const:
        def __init__(self, params, scenario):
            self.v = params["v"]
        def __call__(self, obs):
            return {"wheel_speed_mps": [self.v] * len(obs.x_m)}
    class Raises:
        def __init__(self, params, scenario):
            pass
        def __call__(self, obs):
            if obs.t_s > 0.3:
                return self.inner(obs)
            return {}
        def inner(self, obs):
            raise RuntimeError("my controller broke")
    class BadCommand:
        def __init__(self, params, scenario):
            pass
        def __call__(self, obs):
            return {"wheel_speed_mps": [1.0, 2.0]} if obs.t_s > 0.1 else {}
    class BadCtor:
        def __init__(self, params, scenario):
            raise KeyError("gain_missing")
"""


def _mode(cls, period=0.05, **params):
    return {"type": "controller", "controller": f"ctl/mine.py:{cls}", "period_s": period, "params": params}


def test_relative_path_resolved_from_scenario_folder_and_recorded(tmp_path, monkeypatch):
    p = _write(tmp_path, GOOD, _mode("Const", v=1.5))
    monkeypatch.chdir("/")  # not the scenario's folder
    sc = load_scenario(p)
    assert sc.mode.controller == f"{(tmp_path / 'ctl' / 'mine.py').resolve()}:Const"
    dumped = sc.to_dict()["mode"]
    assert dumped["controller"] == sc.mode.controller and dumped["params"] == {"v": 1.5}
    assert sc.with_({"mode.params.v": 1.2}).mode.params == {"v": 1.2}  # re-validates from the absolute path


@pytest.mark.parametrize(
    "mode, words",
    [
        (_mode("Nope"), ["mine.py", "no class 'Nope'", "Const"]),
        ({**_mode("Const"), "controller": "ctl/missing.py:Const"}, ["missing.py", "does not exist"]),
        ({**_mode("Const"), "controller": "ctl/mine.py"}, ["mode.controller", "ClassName"]),
        ({**_mode("Const"), "controller": "no_such_pkg_xyz.mod:Const"}, ["not found", "no_such_pkg_xyz"]),
        ({**_mode("Const", v=1.0), "period_s": 0}, ["mode.period_s", "at least 1e-06 s"]),
        # issue 30: a period far below any controller's (each period is an interval of the solve)
        ({**_mode("Const", v=1.0), "period_s": 1e-9}, ["mode.period_s", "at least 1e-06 s"]),
        # tow6_uniform: 20 s x 6 segments; 1e-4 s periods end on 1.2 million output samples
        (_mode("Const", period=1e-4, v=1.0), ["mode.period_s", "200000 control periods", "150000 allowed"]),
    ],
)
def test_bad_controller_is_scenario_error(tmp_path, mode, words):
    p = _write(tmp_path, GOOD, mode)
    with pytest.raises(ScenarioError) as err:
        load_scenario(p)
    for w in words:
        assert w in str(err.value)


def test_a_failing_constructor_is_scenario_error_when_the_run_starts_not_at_loading(tmp_path):
    sc = load_scenario(_write(tmp_path, GOOD, _mode("BadCtor")))  # loading runs no code
    with pytest.raises(ScenarioError) as err:
        simulate(sc)
    for w in ["mine.py:BadCtor", "constructing", "gain_missing"]:
        assert w in str(err.value)


def test_module_spec_loads_importable_class():
    cls = load_controller("tests.controller_helpers:Uniform", allow_code=TESTS_ALLOWED)
    assert cls.__name__ == "Uniform"


def test_controller_raising_reports_time_and_only_user_frames(tmp_path):
    sc = load_scenario(_write(tmp_path, GOOD, _mode("Raises"), sim={"duration_s": 1.0}))
    with pytest.raises(ControllerError) as err:
        simulate(sc)
    msg = str(err.value)
    assert msg.startswith("controller raised at t = 0.35 s:")
    assert "mine.py" in msg and "in inner" in msg and "my controller broke" in msg
    assert "snoworm" not in msg.replace(str(tmp_path), "")  # no frame of the package


LOOPING_STR = """
    class Loop(Exception):
        def __str__(self):
            while True:
                pass
    class RaisesLoop:
        def __init__(self, params, scenario):
            pass
        def __call__(self, obs):
            raise Loop()
"""


@pytest.mark.skipif(not watchdog.bounded(), reason="no POSIX interval timer here")
def test_an_exception_whose_str_loops_is_bounded_by_max_wall_s(tmp_path):
    """The controller's exception is formatted under the wall-clock guard: its __str__ is the
    user's code too (it hung the run before, found by the trust battery)."""
    sc = load_scenario(_write(tmp_path, LOOPING_STR, _mode("RaisesLoop"), sim={"duration_s": 1.0, "max_wall_s": 0.5}))
    with pytest.raises(ControllerError, match=r"^(controller raised at t = 0 s|simulation\.max_wall_s)"):
        simulate(sc)


def test_bad_command_names_key_and_time(tmp_path):
    sc = load_scenario(_write(tmp_path, GOOD, _mode("BadCommand"), sim={"duration_s": 1.0}))
    with pytest.raises(ControllerError, match=r"t = 0.15 s: command key 'wheel_speed_mps': expected 6 values"):
        simulate(sc)


def test_called_once_per_period_at_interval_starts():
    sc = load_scenario(SCENARIOS / "tow6_uniform.yaml").with_(
        {
            "mode": {
                "type": "controller",
                "controller": "tests.controller_helpers:Uniform",
                "period_s": 0.1,
                "params": {"speed_mps": 1.8, "start_time_s": 0.5},
            },
            "simulation.duration_s": 1.0,
        }
    )
    res = simulate(sc, allow_code=TESTS_ALLOWED)
    assert res.mode_summary["controller_calls"] == 10
    assert [p["t_start_s"] for p in res.phases] == pytest.approx(np.arange(10) * 0.1, abs=1e-12)
    # zero-order hold: motors off before the first call at or after 0.5 s, on from it
    on = res.segments["motor_torque_Nm"][:, 0] != 0
    assert not on[res.t < 0.5 - 1e-9].any() and on[res.t > 0.55].all()


def test_controller_run_equals_simulator_stepped_with_same_commands():
    """One stepping: a controller run and a Simulator stepped with the same commands give the same result."""
    base = load_scenario(SCENARIOS / "tow6_uniform.yaml").with_({"simulation.duration_s": 2.0})
    sc = base.with_(
        {
            "mode": {
                "type": "controller",
                "controller": "tests.controller_helpers:Scheduled",
                "period_s": 0.05,
                "params": {},
            }
        }
    )
    ran = simulate(sc, allow_code=TESTS_ALLOWED)
    sim = Simulator(base)
    obs = sim.reset()
    while sim.t_s < 2.0 - 1e-12:
        obs = sim.step(schedule(obs.t_s, 6), min(0.05, 2.0 - sim.t_s))
    stepped = sim.result()
    assert stepped.t.shape == ran.t.shape
    np.testing.assert_allclose(stepped.t, ran.t, rtol=0, atol=1e-12)
    for k in ("x_m", "v_mps", "motor_torque_Nm", "slip"):
        np.testing.assert_allclose(stepped.segments[k], ran.segments[k], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(stepped.links["force_N"], ran.links["force_N"], rtol=1e-12, atol=1e-9)


def test_sweep_over_mode_params(tmp_path):
    from snoworm.studies.sweep import run_sweep

    p = _write(tmp_path, GOOD, _mode("Const", v=1.0), sim={"duration_s": 2.0})
    table = run_sweep(p, ["mode.params.v=1.0,1.6"], out_dir=tmp_path / "sw", plot=False)
    rows = table.rows if hasattr(table, "rows") else None
    text = (tmp_path / "sw" / "summary.csv").read_text().splitlines()
    assert len(text) == 3 and all(",ok," in line for line in text[1:]), text
    import csv

    recs = list(csv.DictReader(text))
    d = [float(r["distance_m"]) for r in recs]
    assert d[1] > d[0] * 1.3  # faster wheels, farther
    assert rows is None or len(rows) == 2


def test_failing_controller_is_a_sweep_case_status(tmp_path):
    from snoworm.studies.sweep import STATUSES, run_case

    p = _write(tmp_path, GOOD, _mode("Raises"), sim={"duration_s": 1.0})
    raw = yaml.safe_load(p.read_text())
    out = run_case(SweepTask(0, raw=raw, source=str(p), base_dir=str(tmp_path)))
    assert out["status"] == "controller_failure" and "controller" in STATUSES[-1]
    assert "controller raised at t = 0.35 s" in out["error"] and "my controller broke" in out["error"]


def test_resolve_paths_takes_a_relative_file_from_the_given_folder_only(tmp_path):
    from snoworm.modes.controller import ControllerConfig

    raw = {"type": "controller", "controller": "ctl/my.py:Mine", "period_s": 0.1}
    out = ControllerConfig.resolve_paths(raw, tmp_path)
    assert out["controller"] == f"{(tmp_path / 'ctl' / 'my.py').resolve()}:Mine"
    assert raw["controller"] == "ctl/my.py:Mine"  # the given mapping is not changed
    for spec in ("tests.controller_helpers:Schedule", "/abs/file.py:X", 3):  # a module, absolute, not text
        assert ControllerConfig.resolve_paths({**raw, "controller": spec}, tmp_path)["controller"] == spec
    with pytest.raises(ScenarioError, match=r"^mode\.controller: expected 'file\.py:ClassName'"):
        ControllerConfig.resolve_paths({**raw, "controller": "no colon.py"}, tmp_path)


CHDIR = """
    import os
    class Wanders:
        def __init__(self, params, scenario):
            self.to = params["to"]
        def __call__(self, obs):
            os.chdir(self.to)
            return {}
"""


def test_a_controller_chdir_does_not_outlive_the_run(tmp_path, monkeypatch):
    """The caller's working directory is restored when simulate returns (a relative res.write
    after the run landed in the controller's folder before; found by the trust battery)."""
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path)
    sc = load_scenario(
        _write(tmp_path, CHDIR, _mode("Wanders", to=str(tmp_path / "elsewhere")), sim={"duration_s": 0.2})
    )
    simulate(sc)
    assert os.getcwd() == str(tmp_path)


def test_short_control_periods_are_steps_asked_not_a_stiff_run(tmp_path, monkeypatch):
    """Issue 30: as Simulator.step's short steps, a controller's short periods each cost a few
    evaluations that no simulated second pays for (LSODA restarts at every period), and they ended the
    run as "too stiff".  Its periods (bounded in number by the config) get the allowance of steps
    asked; with a base of the work limit 10 x smaller, 1 500 periods of 0.2 ms must still run."""
    from snoworm.simulation import guard

    monkeypatch.setattr(guard, "WORK_BASE_NFEV", guard.WORK_BASE_NFEV // 10)
    sc = load_scenario(
        _write(tmp_path, GOOD, _mode("Const", period=2e-4, v=1.0), sim={"duration_s": 0.3, "method": "LSODA"})
    )
    res = simulate(sc)
    assert res.stats["intervals"] == 1_500
    assert res.stats["nfev"] > guard.WORK_BASE_NFEV + guard.work_rate(sc.simulation) * 0.3  # past the old limit
    assert np.all(res.segments["x_m"][-1] > res.segments["x_m"][0])  # commanded from t = 0: it moved
