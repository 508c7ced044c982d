"""snoworm.infra.progress: a bar (tqdm, a dependency) on a terminal, one line per ~10 % otherwise."""

import io
import sys
from pathlib import Path

import pytest

from snoworm.infra import progress as P


class TTY(io.StringIO):
    def isatty(self):
        return True


def test_lines_mode_prints_one_line_per_tenth_when_not_a_terminal():
    s = io.StringIO()
    bar = P.Progress(200, "sweep", "cases", stream=s)
    assert bar.mode == "lines"
    for _ in range(200):
        bar.update(info="0 failed")
    bar.close()
    lines = s.getvalue().splitlines()
    assert len(lines) == 10  # 10 %, 20 %, ... 100 %, no duplicate at close
    assert lines[0].startswith("sweep:  10 % (20/200 cases, 0 failed)")
    assert lines[-1].startswith("sweep: 100 % (200/200 cases")


def test_simulated_time_counts_as_floats_and_a_jump_prints_one_line():
    s = io.StringIO()
    bar = P.Progress(56.0, "traverse_patch", "s simulated", stream=s)
    bar.set(0.5)  # under 10 %: nothing yet
    assert s.getvalue() == ""
    bar.set(30.0, 56.0)  # 54 %: one line, not five
    bar.set(31.0)  # still in the same tenth: no line
    bar.close()  # the state at the end: one more line
    lines = s.getvalue().splitlines()
    assert len(lines) == 2 and "54 % (30/56 s simulated)" in lines[0]
    assert "55 % (31/56 s simulated)" in lines[1]  # closed where it was: no fake 100 %


def test_nothing_is_printed_when_off_or_when_nothing_was_done():
    s = io.StringIO()
    with P.Progress(10, "x", stream=s, mode="off") as bar:
        bar.update(10)
    with P.Progress(10, "y", stream=s):
        pass
    assert s.getvalue() == ""


def test_tqdm_is_a_dependency_and_draws_every_bar():
    # tqdm is in [project].dependencies (not an optional extra): every bar on a terminal is tqdm's,
    # there is no home-made bar to fall back to
    import tqdm

    try:
        import tomllib
    except ImportError:  # Python 3.10
        import tomli as tomllib
    project = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())["project"]
    assert any(d.replace(" ", "").startswith("tqdm>=") for d in project["dependencies"])
    assert not any(d.startswith("tqdm") for d in project["optional-dependencies"].get("progress", []))
    assert not hasattr(P.Progress, "_plain")
    with P.Progress(4, "map", "runs", stream=TTY()) as bar:
        assert bar.mode == "bar" and isinstance(bar._bar, tqdm.tqdm)


def test_tqdm_draws_the_bar_on_a_terminal():
    s = TTY()
    with P.Progress(3, "sweep", "cases", stream=s) as bar:
        bar.update(info="1 failed")
        bar.set(3, 3)
    out = s.getvalue()
    assert "sweep" in out and "3/3" in out and "1 failed" in out


def test_total_may_grow_and_bad_mode_is_refused():
    s = io.StringIO()
    bar = P.Progress(1, "m", stream=s)
    bar(5, 10)  # callable as progress(done, total)
    assert bar.total == 10 and "50 % (5/10)" in s.getvalue()
    with pytest.raises(ValueError, match="mode"):
        P.Progress(1, "m", mode="loud")


def test_hms():
    assert P.hms(59.6) == "1:00" and P.hms(3725) == "1:02:05"


def test_default_stream_is_stderr(capsys):
    with P.Progress(1, "z", mode="lines") as bar:
        bar.update()
    assert "z: 100 %" in capsys.readouterr().err
    assert sys.stderr is not None


def test_counts_are_rounded_to_what_the_total_needs():
    s = io.StringIO()
    bar = P.Progress(100.0, "run", "s simulated", stream=s)
    bar.set(14.970594137667268)
    bar.close()
    assert "(15/100 s simulated)" in s.getvalue() and "14.97" not in s.getvalue()
    assert P._decimals(2000) == 0 and P._decimals(4.0) == 0 and P._decimals(2.5) == 2 and P._decimals(0.05) == 3


def test_tqdm_bar_shows_rounded_counts():
    s = TTY()
    with P.Progress(100.0, "run", "s simulated", stream=s) as bar:
        bar.set(14.970594137667268)
    out = s.getvalue()
    assert "15/100 s simulated" in out and "14.970594" not in out


def test_a_log_gets_a_line_every_few_seconds_while_work_advances(monkeypatch):
    clock = [0.0]
    monkeypatch.setattr(P.time, "perf_counter", lambda: clock[0])
    s = io.StringIO()
    bar = P.Progress(2000.0, "long", "s simulated", stream=s)
    for k in range(1, 40):  # 1 s simulated per 1 s of wall time: under 10 % for 200 s
        clock[0] = float(k)
        bar.set(float(k))
    lines = s.getvalue().splitlines()
    assert len(lines) == 39 // int(P.LINE_EVERY_S)  # one line per LINE_EVERY_S seconds of wall time
    assert lines[0].startswith("long:   0 % (5/2000 s simulated)")
    clock[0] = 100.0
    bar.set(39.0)  # advanced since the last line (35 s): a line
    assert len(s.getvalue().splitlines()) == len(lines) + 1
    clock[0] = 200.0
    bar.set(39.0)  # nothing new: no line
    assert len(s.getvalue().splitlines()) == len(lines) + 1


def test_progress_never_goes_back_for_the_same_total():
    bar = P.Progress(10.0, "x", stream=io.StringIO())
    bar.set(5.0)
    bar.set(4.9)
    assert bar.value == 5.0
    bar.set(3.0, total=3.0)  # a new total (a fit that ended early)
    assert bar.value == 3.0 and bar.total == 3.0
