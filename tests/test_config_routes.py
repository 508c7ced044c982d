"""Grade inputs and route files (snoworm.config.routes): validation messages and what they compile to."""

import math
import os

import pytest

from snoworm import ScenarioError, load_scenario
from snoworm.config.routes import read_route
from snoworm.simulation.driver import chain_model
from snoworm.slope import MAX_GRADE_DEG


def _write(tmp_path, text, name="r.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_read_route_with_comments_and_extra_columns(tmp_path):
    p = _write(tmp_path, "# synthetic\nlat,distance_m,elevation_m,xt\n1,0,0,0.9\n2,10,1,0.8\n3,20,1.5,0.7\n")
    r = read_route(p)
    assert r.distance_m == (0.0, 10.0, 20.0) and r.elevation_m == (0.0, 1.0, 1.5) and r.xt == (0.9, 0.8, 0.7)
    prof = r.elevation_profile()
    assert float(prof.sin_grade(5.0, 0.5)) == pytest.approx(0.1)


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("distance_m,elevation_m\n0,0\n1,0\n", "lacks xt"),
        ("distance_m,elevation_m,xt\n0,0,0.9\n10,abc,0.9\n", "line 3, column 2 (elevation_m): expected a number"),
        ("distance_m,elevation_m,xt\n0,0,0.9\n0,1,0.9\n", "line 3: distances must increase strictly"),
        ("distance_m,elevation_m,xt\n0,0,0.9\n10,9,0.9\n", "over the 40 deg limit"),
        ("distance_m,elevation_m,xt\n0,0,0.9\n10,1,1.5\n", "line 3, column 3 (xt): X_t must be in (0, 1]"),
        ("distance_m,elevation_m,xt\n0,0,0.9\n10,nan,0.9\n", "expected a finite number"),
        ("distance_m,elevation_m,xt\n0,0,0.9\n", "at least two rows"),
        ("distance_m,elevation_m,xt\n0,0,0.9\n10,1\n", "line 3, column 3 (xt): missing"),
        # hostile battery (benchmarks/hostile.py): a cell beyond the header's columns was dropped silently
        ("distance_m,elevation_m,xt\n0,0,0.9\n10,0,5,0.9\n", "line 3: 4 cells, but the header names 3 columns"),
        # ... and a long bad cell came back whole in the message
        ("distance_m,elevation_m,xt\n0,0,0.9\n10,1," + "x" * 100_000 + "\n", "expected a number, got 'xxxxx"),
    ],
)
def test_route_errors_name_file_line_and_column(tmp_path, text, fragment):
    p = _write(tmp_path, text)
    with pytest.raises(ScenarioError) as e:
        read_route(p)
    msg = str(e.value)
    assert fragment in msg and str(p) in msg and "\n" not in msg and len(msg) < 1000


def test_route_relative_to_the_scenario_folder(tmp_path):
    _write(tmp_path, "distance_m,elevation_m,xt\n0,0,0.9\n50,5,0.6\n", "hill.csv")
    (tmp_path / "s.yaml").write_text(
        "name: r\nvehicle: {parameter_set: frostyboy, segments: 2, links: {type: fixed}}\n"
        "terrain: {route: hill.csv}\ntow: {force_N: 0}\nmode: {type: uniform, speed_mps: 1.0, start_time_s: 0}\n"
        "simulation: {duration_s: 1}\n"
    )
    sc = load_scenario(tmp_path / "s.yaml")
    assert sc.terrain.files() == [str((tmp_path / "hill.csv").resolve())]
    assert sc.terrain.compile()(25.0) == pytest.approx(0.75)
    assert float(sc.terrain.elevation_profile().elevation(25.0)) == pytest.approx(2.5)
    assert sc.to_dict()["terrain"]["route"] == str((tmp_path / "hill.csv").resolve())  # re-runnable from the output


@pytest.mark.parametrize(
    "sets, fragment",
    [
        (["terrain.grade_deg=45"], "terrain.grade_deg"),
        (["terrain.grade_deg=5", "terrain.elevation=[[0,0],[10,1]]"], "at most one of 'grade_deg', 'elevation'"),
        (["terrain.grade_patches=[{start_m: 0, end_m: 5, grade_deg: 3}]"], "give 'grade_deg'"),
        (["terrain.elevation=[[0,0],[0,1]]"], "distances must increase strictly"),
        (["terrain.elevation=[[0,0],[10,8]]"], "over the 40 deg limit"),
        (["terrain.grade_deg=30", "vehicle.segment.com_height_m=1.5"], "vehicle.segment.com_height_m: segment 0 tips"),
        (
            [
                "terrain.grade_deg=0",
                "terrain.grade_patches=[{start_m: 0, end_m: 5, grade_deg: 3}, {start_m: 4, end_m: 9, grade_deg: 3}]",
            ],
            "grade_patches[1]: overlaps",
        ),
    ],
)
def test_grade_validation_messages(sets, fragment):
    with pytest.raises(ScenarioError) as e:
        load_scenario("tow6_uniform", sets)
    assert fragment in str(e.value) and "\n" not in str(e.value)


def test_grade_limit_is_the_documented_one():
    assert MAX_GRADE_DEG == 40.0
    sc = load_scenario("tow6_uniform", ["terrain.grade_deg=-40"])
    assert chain_model(sc).elevation.grade_deg == -40.0
    assert math.isclose(sc.terrain.elevation_profile().max_abs_grade_deg(), 40.0)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_a_route_that_is_a_fifo_is_refused_at_once(tmp_path):
    p = tmp_path / "r.csv"
    os.mkfifo(p)
    with pytest.raises(ScenarioError, match=r"terrain\.route: .*r\.csv: the route file is not a regular file"):
        read_route(p)


# ------------------------------------------------------------------ issue 30: route files a spreadsheet or a hostile folder gives
ROUTE = "distance_m,elevation_m,xt\n0,0,0.9\n50,5,0.6\n"


def _scenario_with_route(tmp_path, route):
    import yaml

    raw = {
        "name": "r",
        "vehicle": {"parameter_set": "frostyboy", "segments": 2, "links": {"type": "fixed"}},
        "terrain": {"route": route},
        "tow": {"force_N": 0},
        "mode": {"type": "uniform", "speed_mps": 1.0, "start_time_s": 0},
        "simulation": {"duration_s": 1},
    }
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(raw))
    return tmp_path / "s.yaml"


def test_a_route_with_a_utf8_byte_order_mark_reads_as_without(tmp_path):
    """A spreadsheet's 'CSV UTF-8' starts with a BOM: it was read as part of the first column's
    name ("the header lacks distance_m")."""
    p = tmp_path / "bom.csv"
    p.write_bytes(b"\xef\xbb\xbf" + ROUTE.encode())
    r = read_route(p)
    assert (r.distance_m, r.elevation_m, r.xt) == ((0.0, 50.0), (0.0, 5.0), (0.9, 0.6))


@pytest.mark.parametrize(
    "make, fragment",
    [
        (lambda d: _write(d, "distance_m,elevation_m,xt\n0,0," + "8" * 140_000 + "\n50,5,0.6\n").name, "line 2"),
        (lambda d: os.symlink("loop.csv", d / "loop.csv") or "loop.csv", "symbolic link loop"),
        (lambda d: "a\x00b.csv", "NUL byte"),
    ],
    ids=["cell-over-128-kB", "symlink-loop", "nul-byte"],
)
def test_hostile_route_paths_and_cells_are_exit_2_not_internal_errors(tmp_path, make, fragment):
    from click.testing import CliRunner

    from snoworm.cli import main

    p = _scenario_with_route(tmp_path, make(tmp_path))
    with pytest.raises(ScenarioError, match=fragment) as e:
        load_scenario(p)
    assert "terrain.route" in str(e.value) and len(str(e.value)) < 600
    r = CliRunner().invoke(main, ["validate", str(p)])
    assert r.exit_code == 2 and "internal error" not in r.output and fragment in r.output, r.output


def test_a_long_route_path_is_shortened_in_messages(tmp_path):
    deep = tmp_path.joinpath(*["d" * 250] * 14)
    deep.mkdir(parents=True)
    p = deep / "missing.csv"
    with pytest.raises(ScenarioError) as e:
        read_route(p)
    msg = str(e.value)
    assert len(str(p)) > 3500 and len(msg) < 500 and "missing.csv" in msg and "characters]" in msg
