"""snoworm.studies.sweep.cases: the grid or zip of the axes, case ids and keys."""

from __future__ import annotations

import pytest

from snoworm.config.schema import ScenarioError
from snoworm.studies.sweep import build_cases, parse_sweep_option


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
