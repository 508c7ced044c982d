"""Results of a run (snoworm.results.result): documented columns only, CSV files that match the arrays."""

import csv
import io
import json
import os

import numpy as np
import pytest
import yaml

from snoworm import load_scenario, scenario_from_dict, simulate
from snoworm.results.result import LINK_COLUMNS, SEGMENT_COLUMNS, ResultFileError, load_result
from tests.conftest import SCENARIOS

#: ``%.6g`` in the CSV files: half a unit in the 6th significant digit, relative
CSV_RTOL = 5e-6 * (1 + 1e-9)


@pytest.fixture(scope="module", params=["tow6_uniform", "inchworm2"])
def short_run(request):
    """A short run with fixed links (tow6_uniform) and with prismatic joints (inchworm2)."""
    return simulate(load_scenario(SCENARIOS / f"{request.param}.yaml", ["simulation.duration_s=1.5"]))


def test_series_keys_are_exactly_the_documented_columns(short_run):
    assert list(short_run.segments) == list(SEGMENT_COLUMNS)
    assert list(short_run.links) == list(LINK_COLUMNS)
    assert not any(k.startswith("_") for k in [*short_run.segments, *short_run.links])
    n_t, n = short_run.t.size, short_run.scenario.vehicle.segments
    assert all(a.shape == (n_t, n) for a in short_run.segments.values())
    assert all(a.shape == (n_t, n - 1) for a in short_run.links.values())


def _parse(text):
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], np.array(rows[1:], dtype=float)


@pytest.mark.parametrize(
    "table, columns, index", [("segments", SEGMENT_COLUMNS, "segment"), ("links", LINK_COLUMNS, "link")]
)
def test_csv_round_trip(short_run, tmp_path, table, columns, index):
    """The written CSV parses back to the arrays at the printed precision (%.6g; t_s %.4f)."""
    short_run.write(tmp_path, plot=False)
    header, data = _parse((tmp_path / f"{table}.csv").read_text())
    assert header == ["t_s", index, *columns]
    series = getattr(short_run, table)
    n_t, n = series[next(iter(columns))].shape
    assert data.shape == (n_t * n, len(header))
    np.testing.assert_allclose(data[:, 0], np.repeat(short_run.t, n), rtol=0, atol=5e-5 * (1 + 1e-9))
    np.testing.assert_array_equal(data[:, 1], np.tile(np.arange(n), n_t))
    for j, name in enumerate(columns, start=2):
        np.testing.assert_allclose(data[:, j], series[name].reshape(-1), rtol=CSV_RTOL, atol=0, err_msg=name)


def test_written_summary_and_scenario(short_run, tmp_path):
    paths = short_run.write(tmp_path, plot=False)
    assert sorted(p.name for p in paths) == ["links.csv", "scenario.yaml", "segments.csv", "summary.json"]
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["final_link_forces_N"] == pytest.approx(short_run.links["force_N"][-1].tolist(), rel=1e-12)
    assert s["energy"]["total_J"] == pytest.approx(short_run.summary()["energy"]["total_J"], rel=1e-12)
    # the resolved scenario re-loads to the same scenario
    again = scenario_from_dict(yaml.safe_load((tmp_path / "scenario.yaml").read_text()))
    assert again == short_run.scenario
    assert not list(tmp_path.glob(".*.tmp*"))  # no temporary files left behind


def test_time_stamps_resolve_the_output_interval(scenario_path):
    """output_dt_s = 1e-5: every printed t_s distinct (4 decimals used to print 180 000 duplicates)."""
    from snoworm.results.result import time_decimals

    assert time_decimals(0.05) == 4 and time_decimals(0.02) == 4 and time_decimals(1e-5) == 6
    sc = load_scenario(
        scenario_path("tow6_uniform"), [("simulation.output_dt_s", 1e-5), ("simulation.duration_s", 0.002)]
    )
    res = simulate(sc)
    rows = list(csv.reader(io.StringIO(res.segments_csv())))[1:]
    t = [r[0] for r in rows if r[1] == "0"]
    assert len(t) == len(set(t)) == res.t.size
    np.testing.assert_allclose([float(x) for x in t], res.t, atol=1e-6)  # printed to 6 decimals


@pytest.mark.parametrize("name", ["tow6_uniform", "inchworm2"])
def test_load_result_round_trip(tmp_path, name):
    """simulate -> write -> load_result gives the arrays back within the CSV's printed precision
    (values 6 significant digits: rtol CSV_RTOL; times 4 decimals: atol 5e-5 s), the same
    scenario, solver statistics, events and mode metrics."""
    res = simulate(load_scenario(SCENARIOS / f"{name}.yaml", ["simulation.duration_s=2"]))
    res.write(tmp_path, plot=False)
    back = load_result(tmp_path)
    assert back.scenario == res.scenario
    np.testing.assert_allclose(back.t, res.t, rtol=0, atol=5e-5 * (1 + 1e-9))
    for table, columns in (("segments", SEGMENT_COLUMNS), ("links", LINK_COLUMNS)):
        got, want = getattr(back, table), getattr(res, table)
        assert list(got) == list(columns)
        for c in columns:
            assert got[c].shape == want[c].shape, c
            np.testing.assert_allclose(got[c], want[c], rtol=CSV_RTOL, atol=0, err_msg=c)
    assert back.stats == json.loads(json.dumps(res.stats))
    assert back.events == json.loads(json.dumps(res.events))
    assert back.mode_summary == json.loads(json.dumps(res.mode_summary))
    assert back.summary()["distance_m"] == pytest.approx(res.summary()["distance_m"], rel=1e-5)


def test_load_result_of_a_folder_that_is_not_a_run(tmp_path):
    (tmp_path / "segments.csv").write_text("t_s,segment\n")
    with pytest.raises(ResultFileError, match="links.csv, summary.json, scenario.yaml missing"):
        load_result(tmp_path)


def test_result_plot_returns_the_figure(short_run):
    from matplotlib.figure import Figure

    ax = Figure().subplots()
    assert short_run.plot("positions", ax=ax) is ax.figure
    assert isinstance(short_run.plot("forces"), Figure)
    with pytest.raises(ValueError, match="unknown plot kind 'nope'; kinds: forces, speeds"):
        short_run.plot("nope")


def test_a_run_folder_written_before_the_grade_columns_reads_back_level(tmp_path):
    """segments.csv without grade_deg, elevation_m, gravity_N (written before slopes existed, so on
    level ground) or without sinkage_m (written before slip-sinkage) reads back with those columns
    zero; any other column set is refused."""
    from snoworm import load_result, load_scenario, simulate

    res = simulate(load_scenario("tow6_uniform", ["simulation.duration_s=1"]))
    res.write(tmp_path / "run")
    path = tmp_path / "run" / "segments.csv"
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    for older in (
        ("grade_deg", "elevation_m", "gravity_N"),
        ("sinkage_m",),
        ("grade_deg", "elevation_m", "gravity_N", "sinkage_m"),
    ):
        keep = [j for j, c in enumerate(header) if c not in older]
        path.write_text("\n".join(",".join(row.split(",")[j] for j in keep) for row in lines) + "\n")
        back = load_result(tmp_path / "run")
        np.testing.assert_array_equal(back.segments[older[-1]], 0.0)
        np.testing.assert_allclose(back.segments["v_mps"], res.segments["v_mps"], rtol=1e-5, atol=1e-9)
    keep = [j for j, c in enumerate(header) if c != "slip"]  # drop another column
    path.write_text("\n".join(",".join(row.split(",")[j] for j in keep) for row in lines) + "\n")
    with pytest.raises(ValueError, match="unexpected columns"):
        load_result(tmp_path / "run")


# ------------------------------------------------------------------ tampered folders (issue 24)
def _tamper_csv(name, fn):
    def tamper(d):
        lines = (d / name).read_text().splitlines()
        (d / name).write_text("\n".join(fn(lines)) + "\n")

    return tamper


def _set_yaml(key, value):
    def tamper(d):
        import yaml

        raw = yaml.safe_load((d / "scenario.yaml").read_text())
        raw["vehicle" if key == "segments" else "simulation"][key] = value
        (d / "scenario.yaml").write_text(yaml.safe_dump(raw))

    return tamper


TAMPERED = {
    "nan_value": (
        "segments.csv",
        _tamper_csv("segments.csv", lambda ls: ls[:3] + [ls[3].rsplit(",", 1)[0] + ",nan"] + ls[4:]),
    ),
    "text_value": (
        "segments.csv",
        _tamper_csv("segments.csv", lambda ls: ls[:3] + [ls[3].replace(",", ",x", 1)] + ls[4:]),
    ),
    "header": ("segments.csv", _tamper_csv("segments.csv", lambda ls: ["t_s,segment,foo"] + ls[1:])),
    "segment_index": ("segments.csv", _tamper_csv("segments.csv", lambda ls: [ls[0], ls[2], ls[1]] + ls[3:])),
    "row_dropped": ("segments.csv", _tamper_csv("segments.csv", lambda ls: ls[:5] + ls[6:])),
    "header_only": ("segments.csv", _tamper_csv("segments.csv", lambda ls: ls[:1])),
    "links_shorter": ("links.csv", _tamper_csv("links.csv", lambda ls: ls[:-5])),
    "more_segments": ("segments.csv", _set_yaml("segments", 200)),
    "fewer_segments": ("segments.csv", _set_yaml("segments", 2)),
    "summary_not_json": ("summary.json", lambda d: (d / "summary.json").write_text("{not json")),
    "summary_a_list": ("summary.json", lambda d: (d / "summary.json").write_text("[1, 2]")),
    "summary_deep": ("summary.json", lambda d: (d / "summary.json").write_text("[" * 100000)),
    "summary_events": ("summary.json", lambda d: (d / "summary.json").write_text('{"events": 3}')),
    "scenario_broken": ("scenario.yaml", lambda d: (d / "scenario.yaml").write_text("vehicle: [\n")),
    "scenario_deep": ("scenario.yaml", lambda d: (d / "scenario.yaml").write_text("a: " + "[" * 5000)),
    "fifo": ("segments.csv", lambda d: ((d / "segments.csv").unlink(), os.mkfifo(d / "segments.csv"))),
}


@pytest.mark.parametrize("kind", sorted(TAMPERED))
def test_a_tampered_run_folder_raises_one_error_type_naming_the_file(tmp_path, kind):
    res = simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml", ["simulation.duration_s=0.5"]))
    d = tmp_path / "run"
    res.write(d, plot=False)
    load_result(d)  # intact: reads back
    name, tamper = TAMPERED[kind]
    tamper(d)
    with pytest.raises(ResultFileError) as err:
        load_result(d)
    assert name in str(err.value) and len(str(err.value)) < 700


def test_write_records_the_command_it_is_given(short_run, tmp_path):
    from snoworm.infra.folders import read_manifest

    short_run.write(tmp_path / "given", plot=False, command="snoworm run x.yaml --out given")
    assert read_manifest(tmp_path / "given")["command"] == "snoworm run x.yaml --out given"
    short_run.write(tmp_path / "default", plot=False)  # default: this process's command line
    assert read_manifest(tmp_path / "default")["command"] != "snoworm run x.yaml --out given"


def test_csv_text_is_what_numpy_savetxt_writes():
    """The CSV writer formats all rows in one operation: byte for byte the text of ``np.savetxt``
    with the same formats (time decimals, integer index, 6 significant digits), special values
    and signed zeros included."""
    from snoworm.results.result import _csv

    rng = np.random.default_rng(1)
    data = rng.normal(size=(50, 5)) * 10.0 ** rng.integers(-12, 12, size=(50, 5))
    data[:, 0], data[:, 1] = np.arange(50) * 0.0125, np.arange(50) % 6
    data[3, 2], data[4, 3], data[5, 4], data[6, 2] = np.nan, np.inf, -np.inf, -0.0
    buf = io.StringIO()
    np.savetxt(buf, data, fmt=["%.4f", "%d", "%.6g", "%.6g", "%.6g"], delimiter=",")
    assert _csv(["t", "i", "a", "b", "c"], data, int_cols=(1,)) == "t,i,a,b,c\n" + buf.getvalue()
    assert _csv(["t", "i"], np.empty((0, 2)), int_cols=(1,)) == "t,i\n"


def test_summary_carries_the_verdict(tmp_path):
    """summary.json's status, immobilised_at_m and status_reason are the run's verdict; a folder
    read back gives the same verdict (they are not taken for the mode's metrics)."""
    res = simulate(load_scenario(SCENARIOS / "rolling6_xt025.yaml", ["simulation.duration_s=8"]))
    v = res.verdict()
    s = res.summary()
    assert v.status == "immobilised"
    assert (s["status"], s["immobilised_at_m"], s["status_reason"]) == (v.status, v.x_m, v.reason)
    assert v.x_m == res.segments["x_m"][int(np.searchsorted(res.t, v.t_s)), 0]
    res.write(tmp_path, plot=False)
    back = load_result(tmp_path)
    assert not {"status", "immobilised_at_m", "status_reason"} & set(back.mode_summary)
    assert back.summary()["status"] == "immobilised"
    assert back.summary()["immobilised_at_m"] == pytest.approx(v.x_m, abs=1e-5)
    moving = simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml", ["simulation.duration_s=8"])).summary()
    assert moving["status"] == "moving" and moving["immobilised_at_m"] is None
    assert moving["status_reason"].startswith("moving at the end (t = 8.0 s")
