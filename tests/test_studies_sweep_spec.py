"""snoworm.studies.sweep.spec: SPEC parsing (lists, START:STOP:COUNT ranges) and its CLI messages; the
grid or zip of the axes, case ids and keys."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from snoworm.cli import main
from snoworm.config.schema import ScenarioError
from snoworm.studies.sweep import build_cases, parse_spec, parse_sweep_option
from snoworm.studies.sweep.spec import as_axes
from tests.sweep_helpers import TOW6


def test_list_spec_parses_numbers_and_yaml():
    assert parse_spec("tow.force_N", "0,100,200") == (0, 100, 200)
    assert parse_spec("terrain.xt", "0.5") == (0.5,)
    assert parse_spec("simulation.rtol", "1e-5,1e-6") == (1e-5, 1e-6)
    assert parse_spec("mode.speed_mps", "[1.8, 1.5],[1.0, 1.0]") == ([1.8, 1.5], [1.0, 1.0])
    assert parse_spec("simulation.method", "LSODA,BDF") == ("LSODA", "BDF")


def test_range_spec_is_inclusive_with_count_values():
    v = parse_spec("terrain.xt", "0.3:1.0:15")
    assert len(v) == 15
    assert v[0] == 0.3 and v[-1] == 1.0
    assert v[1] == pytest.approx(0.35, abs=1e-12)
    assert parse_spec("terrain.xt", "0.6:1.0:9")[2] == 0.7  # linspace noise rounded away
    ints = parse_spec("tow.force_N", "0:200:3")
    assert ints == (0, 100, 200) and all(isinstance(x, int) for x in ints)
    assert parse_spec("terrain.xt", "0.5:0.5:1") == (0.5,)


@pytest.mark.parametrize(
    "sets, needle",
    [
        (["terrain.xt=0.3:1.0"], "START:STOP:COUNT"),
        (["terrain.xt=0.3:1.0:0"], "COUNT must be at least 1"),
        (["terrain.xt=0.3:1.0:x"], "COUNT must be a whole number"),
        # hostile battery (benchmarks/hostile.py): more than two colons was an internal error
        (["terrain.xt=:::"], "has 3 colons, not 2"),
        (["terrain.xt=0.2:1.0:3:4"], "has 3 colons, not 2"),
        (["terrain.xt=a:b:3"], "START and STOP must be numbers"),
        (["terrain.xt=0,,1"], "empty item"),
        (["terrain.xt=0.5,0.5"], "appears twice"),
        (["terrain.xt"], "expected KEY=SPEC"),
        (["terrain.xt=0.5", "terrain.xt=0.6"], "more than once"),
        (["terrain.xtt=0.5,0.6"], "Did you mean 'xt'"),
        (["terrain.xt=0.5,0.6", "tow.force_N=1,2,3", "--zip"], "same number of values"),
    ],
)
def test_bad_spec_exits_2_with_a_clear_message(tmp_path, sets, needle):
    args = ["sweep", TOW6, "--out", str(tmp_path / "o")]
    for s in sets:
        args += ["--zip"] if s == "--zip" else ["--set", s]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2, r.output
    assert needle in r.output
    assert "Traceback" not in r.output
    assert not (tmp_path / "o" / "summary.csv").exists()


def test_messages_name_the_option_given():
    with pytest.raises(ScenarioError, match=r"^--xt '0\.2:1\.0:0': COUNT must be at least 1"):
        parse_spec("--xt", "0.2:1.0:0", option="--xt '0.2:1.0:0'")
    with pytest.raises(ScenarioError, match=r"^--set terrain\.xt=1,1: the value 1 appears twice"):
        parse_spec("terrain.xt", "1,1")


def test_axes_from_strings_pairs_and_none():
    axes = as_axes(["terrain.xt=0.5,0.6", ("tow.force_N", [0, 100])])
    assert [(a.key, a.values) for a in axes] == [("terrain.xt", (0.5, 0.6)), ("tow.force_N", (0, 100))]
    with pytest.raises(ScenarioError, match="needs at least one key"):
        as_axes([])


def test_a_yaml_alias_bomb_in_a_swept_value_is_refused_at_once():
    levels = ["a: &a [x,x,x,x,x,x,x,x,x]"] + [
        f"{c}: &{c} [{', '.join(['*' + p] * 9)}]" for p, c in zip("abcdef", "bcdefg")
    ]
    bomb = "{" + ", ".join(levels) + "}"
    with pytest.raises(ScenarioError, match=r"mode\.params.*alias"):
        parse_spec("mode.params", bomb)


# ------------------------------------------------------------------ the cases (build_cases)
def test_grid_and_zip_cases():
    axes = [parse_sweep_option("terrain.xt=0.6:1.0:9"), parse_sweep_option("tow.force_N=0,100,200")]
    grid = build_cases(axes)
    assert len(grid) == 27
    assert grid[0].values == (0.6, 0) and grid[1].values == (0.6, 100) and grid[-1].values == (1.0, 200)
    assert len({c.key for c in grid}) == 27 and [c.case_id for c in grid][:2] == ["0000", "0001"]
    # stable keys: same values give the same key whatever else is in the sweep
    again = build_cases([parse_sweep_option("terrain.xt=0.6,1.0"), parse_sweep_option("tow.force_N=0,100,200")])
    assert again[0].key == grid[0].key
    zipped = build_cases([parse_sweep_option("terrain.xt=0.6,0.7"), parse_sweep_option("tow.force_N=0,100")], zip_=True)
    assert [c.values for c in zipped] == [(0.6, 0), (0.7, 100)]


def test_case_ids_widen_past_9999_and_zip_needs_equal_lengths():
    cases = build_cases([parse_sweep_option("terrain.xt=0.1:1.0:101"), parse_sweep_option("tow.force_N=0:99:100")])
    assert len(cases) == 10100
    assert cases[0].case_id == "00000" and cases[-1].case_id == "10099"
    assert cases[5].overrides(
        [parse_sweep_option("terrain.xt=0.1:1.0:101"), parse_sweep_option("tow.force_N=0:99:100")]
    ) == [("terrain.xt", 0.1), ("tow.force_N", 5)]
    with pytest.raises(ScenarioError, match="terrain.xt has 2, tow.force_N has 3"):
        build_cases([parse_sweep_option("terrain.xt=0.5,0.6"), parse_sweep_option("tow.force_N=1,2,3")], zip_=True)
