"""snoworm.studies.sweep.summary: SweepTable, summary.csv / sweep.json, resumption and refusal, and the
table's figures (plot_table, SweepTable.plot)."""

from __future__ import annotations

import csv
import json
import os

import numpy as np
import pytest
from click.testing import CliRunner

import snoworm.studies.sweep as sweep_mod
import snoworm.studies.sweep.run as run_mod
from snoworm.cli import main
from snoworm.plotting import FIGURE_SIZES, headless
from snoworm.studies.sweep import load_sweep, run_sweep
from snoworm.studies.sweep.summary import SweepTable, plot_table
from tests.figure_checks import problems
from tests.sweep_helpers import SHORT, TOW6, comparable, csv_rows


def test_interrupted_sweep_resumes_without_recomputing(tmp_path, monkeypatch):
    sets = ["terrain.xt=0.7,0.8,0.9", "tow.force_N=0,200", SHORT]
    full = run_sweep(TOW6, sets, out_dir=tmp_path, plot=False)
    summary = tmp_path / "summary.csv"
    lines = summary.read_text().splitlines(keepends=True)
    assert len(lines) == 7
    # an interrupted sweep: header, two finished rows and half of the third
    summary.write_text("".join(lines[:3]) + lines[3][: len(lines[3]) // 2])
    kept = {next(csv.reader([ln]))[0] for ln in lines[1:3]}

    calls = []
    real = run_mod.run_case  # where run_sweep looks run_case up

    def counting(task):
        calls.append(task.index)
        return real(task)

    monkeypatch.setattr(run_mod, "run_case", counting)
    resumed = run_sweep(TOW6, sets, out_dir=tmp_path, plot=False)
    assert len(calls) == 4  # 6 cases - 2 kept
    assert not {f"{i:04d}" for i in calls} & kept
    assert comparable(resumed) == comparable(full)
    rows = csv_rows(summary)
    assert sorted(r["case_id"] for r in rows) == [f"{i:04d}" for i in range(6)]
    # complete now: a third run computes nothing
    calls.clear()
    run_sweep(TOW6, sets, out_dir=tmp_path, plot=False)
    assert calls == []


def test_another_sweep_in_the_same_directory_is_refused(tmp_path):
    run_sweep(TOW6, ["terrain.xt=0.8,0.9", SHORT], out_dir=tmp_path, plot=False)
    r = CliRunner().invoke(main, ["sweep", TOW6, "--set", "terrain.xt=0.7,0.9", "--set", SHORT, "--out", str(tmp_path)])
    assert r.exit_code == 2 and "holds another sweep" in r.output
    assert json.loads((tmp_path / "sweep.json").read_text())["definition"]["axes"][0]["values"] == [0.8, 0.9]


def test_table_round_trips_through_csv(tmp_path):
    table = run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], out_dir=tmp_path, plot=False)
    back = sweep_mod.SweepTable.from_csv(tmp_path / "summary.csv")
    assert comparable(back) == comparable(table)
    assert table.to_csv().splitlines()[0].startswith("case_id,case_key,terrain.xt,simulation.duration_s,status")


def test_summary_cells_full_precision_and_empty_for_none(tmp_path):
    cols = ["case_id", "case_key", "mode.speed_mps", "status", "error", "distance_m", "immobilised", "n_segments"]
    table = sweep_mod.SweepTable(
        cols,
        [
            {
                "case_id": "0001",
                "case_key": "k1",
                "mode.speed_mps": [1.8, 1.5],
                "status": "ok",
                "error": "",
                "distance_m": 0.1 + 0.2,
                "immobilised": False,
                "n_segments": 6,
            },
            {
                "case_id": "0000",
                "case_key": "k0",
                "mode.speed_mps": [1.0, 1.0],
                "status": "invalid",
                "error": "a, b",
                "distance_m": None,
                "immobilised": None,
                "n_segments": None,
            },
        ],
        ["mode.speed_mps"],
    )
    assert table.to_csv(tmp_path / "summary.csv") == (
        "case_id,case_key,mode.speed_mps,status,error,distance_m,immobilised,n_segments\n"
        '0000,k0,"[1.0,1.0]",invalid,"a, b",,,\n'
        '0001,k1,"[1.8,1.5]",ok,,0.30000000000000004,false,6\n'
    )
    back = sweep_mod.SweepTable.from_csv(tmp_path / "summary.csv")
    assert back.rows[1]["distance_m"] == 0.1 + 0.2 and back.rows[1]["mode.speed_mps"] == [1.8, 1.5]
    assert back.rows[0]["immobilised"] is None and back.rows[1]["immobilised"] is False


# ------------------------------------------------------------------ tampered sweep folders (issue 24)
@pytest.fixture(scope="module")
def sweep_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("sw") / "s"
    run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], out_dir=out, plot=False, progress=False)
    return out


def _copy(src, tmp_path):
    import shutil

    dst = tmp_path / "s"
    shutil.copytree(src, dst)
    return dst


@pytest.mark.parametrize(
    "name, text",
    [
        ("sweep.json", "{not json"),
        ("sweep.json", "[" * 100000),
        ("sweep.json", '{"definition": {"axes": [3]}}'),
        ("sweep.json", '{"definition": {"axes": [{"key": 5}]}}'),
        ("sweep.json", '{"definition": []}'),
        ("summary.csv", "a,b,c\n1,2,3\n"),
        ("summary.csv", ""),
    ],
)
def test_a_tampered_sweep_folder_raises_one_error_type_naming_the_file(sweep_dir, tmp_path, name, text):
    from snoworm.results.result import ResultFileError

    d = _copy(sweep_dir, tmp_path)
    (d / name).write_text(text)
    with pytest.raises(ResultFileError, match=name.replace(".", r"\.")):
        load_sweep(d)


def test_dropped_rows_are_reported(sweep_dir, tmp_path):
    d = _copy(sweep_dir, tmp_path)
    lines = (d / "summary.csv").read_text().splitlines(keepends=True)
    (d / "summary.csv").write_text(lines[0] + "0000,garbage\n" + "".join(lines[1:]))
    with pytest.warns(UserWarning, match="1 line\\(s\\) dropped"):
        table = load_sweep(d)
    assert table.dropped == 1 and len(table) == 2


@pytest.mark.parametrize("bad", ["nan", "-inf", "inf"])
def test_a_non_finite_metric_drops_its_line_with_a_warning(sweep_dir, tmp_path, bad):
    """Metrics are finite or empty: a NaN or infinite cell is a tampered line, dropped and reported."""
    d = _copy(sweep_dir, tmp_path)
    lines = (d / "summary.csv").read_text().splitlines(keepends=True)
    header = lines[0].rstrip("\n").split(",")
    cells = lines[1].rstrip("\n").split(",")
    cells[header.index("distance_m")] = bad
    (d / "summary.csv").write_text(lines[0] + ",".join(cells) + "\n" + "".join(lines[2:]))
    with pytest.warns(UserWarning, match="1 line\\(s\\) dropped"):
        table = load_sweep(d)
    assert table.dropped == 1 and len(table) == len(lines) - 2  # the header and the tampered line
    assert all(np.isfinite(r["distance_m"]) for r in table.rows)


# ------------------------------------------------------------------ issue 30
def test_an_8_gb_sparse_summary_csv_is_one_result_file_error_and_exit_2(sweep_dir, tmp_path):
    """An 8 GB summary.csv (a sparse file) was read whole: a MemoryError, an internal error."""
    from snoworm.results.result import ResultFileError
    from snoworm.studies.sweep.summary import MAX_SUMMARY_BYTES

    d = _copy(sweep_dir, tmp_path)
    os.truncate(d / "summary.csv", 8 * 2**30)
    assert MAX_SUMMARY_BYTES < 8 * 2**30
    with pytest.raises(ResultFileError, match=r"summary\.csv is 8589934592 bytes, more than the"):
        load_sweep(d)
    r = CliRunner().invoke(main, ["sweep", TOW6, "--set", "terrain.xt=0.7,0.9", "--set", SHORT, "--out", str(d)])
    assert r.exit_code == 2 and "internal error" not in r.output and "summary.csv" in r.output, r.output[-500:]


def test_load_sweep_keeps_the_first_line_of_a_repeated_case_and_says_so(sweep_dir, tmp_path):
    d = _copy(sweep_dir, tmp_path)
    lines = (d / "summary.csv").read_text().splitlines(keepends=True)
    (d / "summary.csv").write_text("".join(lines + lines[1:2] + lines[1:2]))  # case 0 three times
    with pytest.warns(UserWarning, match=r"2 line\(s\) repeat a case already listed \(0+, 0+\); the first"):
        table = load_sweep(d)
    assert len(table) == 2 and [r["case_id"] for r in table.rows] == sorted({r["case_id"] for r in table.rows})
    assert table.dropped == 2


# --------------------------------------------------------------------------- the table's figures
def _table(keys, values, zip_=False):
    rows = []
    for i, vals in enumerate(values):
        r = {
            "case_id": f"c{i:03d}",
            "case_key": "",
            "status": "ok" if i != 1 else "failed",
            "error": "",
            "mean_speed_mps": 0.1 * i if i != 1 else None,
            "mean_slip": 0.01 * i,
            "max_link_force_N": 10.0 * i,
            "energy_per_m_J": 100.0 + i,
            "immobilised": i == 2,
        }
        r.update(dict(zip(keys, vals)))
        rows.append(r)
    cols = [
        "case_id",
        "case_key",
        *keys,
        "status",
        "error",
        "mean_speed_mps",
        "mean_slip",
        "max_link_force_N",
        "energy_per_m_J",
        "immobilised",
    ]
    return SweepTable(cols, rows, keys)


def test_one_key_gives_metric_panels():
    t = _table(["tow.force_N"], [[0.0], [100.0], [200.0], [300.0]])
    with headless():
        fig = t.plot(size="column")
    assert [a.get_ylabel() for a in fig.axes][:2] == ["mean speed [m/s]", "mean slip (2nd half)"]
    assert fig.axes[-1].get_xlabel() == "tow force [N]"
    assert problems(fig, FIGURE_SIZES["column"]) == []
    one = plot_table(t, "mean_slip")
    assert len(one.axes) == 1


def test_two_keys_on_a_grid_give_a_heat_map_in_the_sweeps_order():
    vals = [[x, f] for f in (0.0, 50.0) for x in (1.0, 0.6)]
    t = _table(["terrain.xt", "tow.force_N"], vals)
    fig = t.plot()
    a = fig.axes[0]
    assert [lab.get_text() for lab in a.get_xticklabels()] == ["1.0", "0.6"]
    assert sorted(txt.get_text() for txt in a.texts) == sorted(["0.00", "failed", "0.20\nimmob.", "0.30"])
    assert problems(fig) == []


def test_two_keys_zipped_give_lines():
    t = _table(["terrain.xt", "tow.force_N"], [[0.6, 0.0], [0.8, 50.0], [1.0, 100.0]])
    fig = t.plot("mean_speed_mps")
    assert len(fig.axes) == 1 and fig.axes[0].get_xlabel() == "terrain coefficient X_t"
    y = fig.axes[0].get_lines()[0].get_ydata()
    assert np.isnan(y[1]) and y[2] == pytest.approx(0.2)
