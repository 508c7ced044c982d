"""snoworm.studies.sweep.series: every case's time series in one netCDF file (run_sweep series='netcdf')."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from snoworm import load_scenario, load_sweep, simulate
from snoworm.config.schema import ScenarioError
from snoworm.results.result import ResultFileError
from snoworm.studies.sweep import run_sweep
from tests.sweep_helpers import TOW6, comparable

SETS = ["terrain.xt=0.7,0.9", "tow.force_N=0,200", "simulation.duration_s=1.5"]
NC = dict(plot=False, progress=False, series="netcdf")


def _direct(xt, tow):
    return simulate(load_scenario(TOW6, [f"terrain.xt={xt}", f"tow.force_N={tow}", "simulation.duration_s=1.5"]))


@pytest.mark.parametrize("batch", [0, 4])
def test_grid_series_in_one_file(tmp_path, batch):
    table = run_sweep(TOW6, SETS, out_dir=tmp_path, plot=False, series="netcdf", batch=batch)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        ".snoworm-manifest.json",
        "series.nc",
        "summary.csv",
        "sweep.json",
    ]  # no cases/
    ds = table.series()
    assert ds["v_mps"].dims == ("terrain_xt", "tow_force_N", "simulation_duration_s", "time", "segment")
    assert ds["force_N"].dims[-1] == "link" and ds["force_N"].attrs["units"] == "N"
    assert ds["terrain_xt"].values.tolist() == [0.7, 0.9] and ds["tow_force_N"].values.tolist() == [0.0, 200.0]
    assert ds["tow_force_N"].attrs["key"] == "tow.force_N" and ds["tow_force_N"].attrs["units"] == "N"
    assert ds["ok"].values.all()
    res = _direct(0.9, 200)
    case = ds.sel(terrain_xt=0.9, tow_force_N=200.0, simulation_duration_s=1.5)
    np.testing.assert_array_equal(case["t_s"].values, res.t)
    np.testing.assert_array_equal(ds["time"].values, res.t)  # the same output times for every case
    # unbatched, a case is the same code path as the direct run on the same machine (exact
    # equality is safe); one stacked solve (batch) agrees with a solve of its own within the
    # solver tolerance
    tol = dict(rtol=0, atol=0) if batch == 0 else dict(rtol=1e-3, atol=1e-3)
    np.testing.assert_allclose(case["x_m"].values, res.segments["x_m"], **tol)
    np.testing.assert_allclose(case["force_N"].values, res.links["force_N"], **tol)


def test_zip_series_and_resume(tmp_path):
    sets = ["terrain.xt=0.7,0.8,0.9", "tow.force_N=0,100,200"]
    base = load_scenario(TOW6, ["simulation.duration_s=1.5"])
    full = run_sweep(base, sets, zip_=True, out_dir=tmp_path, plot=False, series="netcdf")
    first = full.series()
    assert first["v_mps"].dims == ("case", "time", "segment") and first["tow_force_N"].dims == ("case",)
    # an interrupted sweep: the summary has lost its last case, whose series must be recomputed;
    # the others' series are kept from the earlier series.nc
    summary = tmp_path / "summary.csv"
    lines = summary.read_text().splitlines(keepends=True)
    summary.write_text("".join(lines[:3]))
    resumed = run_sweep(base, sets, zip_=True, out_dir=tmp_path, plot=False, series="netcdf")
    assert comparable(resumed) == comparable(full)
    xr.testing.assert_identical(resumed.series(), first)


def test_load_sweep_round_trip(tmp_path):
    table = run_sweep(TOW6, SETS, out_dir=tmp_path, plot=False)
    back = load_sweep(tmp_path)
    assert back.keys == ["terrain.xt", "tow.force_N", "simulation.duration_s"]
    assert back.columns == table.columns and back.rows == table.rows
    df = back.to_pandas()
    assert list(df.columns) == table.columns and len(df) == 4
    assert df["mean_speed_mps"].tolist() == table["mean_speed_mps"]
    assert df["terrain.xt"].tolist() == [0.7, 0.7, 0.9, 0.9]
    with pytest.raises(FileNotFoundError, match="--series netcdf"):
        back.series()
    with pytest.raises(ResultFileError, match="not a sweep's output directory"):
        load_sweep(tmp_path / "nowhere")


def test_unknown_series_format():
    with pytest.raises(ScenarioError, match="series: expected one of folders, netcdf, got 'hdf'"):
        run_sweep(TOW6, SETS, series="hdf")


def test_netcdf_without_xarray_is_bad_input(monkeypatch, tmp_path):
    monkeypatch.setitem(__import__("sys").modules, "xarray", None)  # import xarray -> ImportError
    with pytest.raises(
        ScenarioError, match=r"--series netcdf needs xarray and h5netcdf: pip install 'snoworm\[data\]'"
    ):
        run_sweep(TOW6, SETS, out_dir=tmp_path, series="netcdf")
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_netcdf4_with_units_on_every_variable_and_coordinate(tmp_path):
    """h5netcdf (HDF5, no xarray) opens series.nc; every variable and coordinate has CF units and
    a long_name without a unit; data are compressed; dimension names are identifiers."""
    import h5netcdf

    run_sweep(
        TOW6,
        ["terrain.xt=0.7,0.9", "tow.force_N=0,100", "simulation.duration_s=1"],
        out_dir=tmp_path,
        plot=False,
        series="netcdf",
    )
    path = tmp_path / "series.nc"
    assert path.read_bytes()[:4] == b"\x89HDF"  # netCDF4 is HDF5
    with h5netcdf.File(path, "r") as f:
        names = set(f.variables)
        dims = set(f.dimensions)
        assert {"terrain_xt", "tow_force_N", "time", "segment", "link"} <= dims
        assert all(d.isidentifier() for d in dims)
        for name in names:
            v = f.variables[name]
            assert "units" in v.attrs and "long_name" in v.attrs, name
            assert not str(v.attrs["long_name"]).rstrip().endswith("]"), name  # no unit in the long name
        assert f.variables["v_mps"].compression == "gzip"
        assert (
            f.variables["terrain_xt"].attrs["units"] == "1" and f.variables["terrain_xt"].attrs["key"] == "terrain.xt"
        )
    ds = load_sweep(tmp_path).series()
    assert all("units" in ds[c].attrs for c in ds.coords)
    label = ds["v_mps"].attrs["long_name"] + " [" + ds["v_mps"].attrs["units"] + "]"
    assert label == "ground speed [m/s]"


def test_netcdf3_of_earlier_versions_still_loads(tmp_path):
    from snoworm.studies.sweep.series import load_series

    run_sweep(TOW6, ["terrain.xt=0.7,0.9", "simulation.duration_s=1"], out_dir=tmp_path / "s", **NC)
    new = load_series(tmp_path / "s" / "series.nc")
    new.to_netcdf(tmp_path / "old.nc", engine="scipy")  # netCDF3, as earlier versions wrote it
    old = load_series(tmp_path / "old.nc")
    assert old["v_mps"].shape == new["v_mps"].shape == (2, 1, 21, 6)
    np.testing.assert_array_equal(old["v_mps"].values, new["v_mps"].values)


# ------------------------------------------------------------------ issue 30: series.nc read as a hostile file
@pytest.fixture(scope="module")
def nc_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("nc") / "s"
    run_sweep(TOW6, ["terrain.xt=0.7,0.9", "simulation.duration_s=1"], out_dir=out, **NC)
    return out


def _copy(src, tmp_path):
    import shutil

    shutil.copytree(src, tmp_path / "s")
    return tmp_path / "s"


def test_a_fifo_series_nc_is_refused_at_once_by_a_reader_and_a_resume(nc_sweep, tmp_path):
    """A FIFO at series.nc hung load_sweep(d).series() and a resume (open() waits for a writer)."""
    import os
    import subprocess
    import sys

    d = _copy(nc_sweep, tmp_path)
    (d / "series.nc").unlink()
    os.mkfifo(d / "series.nc")
    lines = (d / "summary.csv").read_text().splitlines(keepends=True)
    (d / "summary.csv").write_text("".join(lines[:2]))  # an interrupted sweep: one case to run
    code = f"""
import snoworm
from snoworm.results.result import ResultFileError
try:
    snoworm.load_sweep({str(d)!r}).series()
except ResultFileError as exc:
    print("READ", exc)
try:
    snoworm.run_sweep({TOW6!r}, ["terrain.xt=0.7,0.9", "simulation.duration_s=1"], out_dir={str(d)!r},
                      plot=False, progress=False, series="netcdf")
except ResultFileError as exc:
    print("RESUME", exc)
"""
    root = str(Path(__file__).resolve().parents[1])
    r = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONPATH": root},
    )
    assert r.returncode == 0, r.stderr
    assert "READ" in r.stdout and "RESUME" in r.stdout and r.stdout.count("not a regular file") == 2, r.stdout


@pytest.mark.parametrize("kind", ["folder", "symlink_loop"])
def test_a_series_nc_that_is_a_folder_or_a_symlink_loop_is_a_result_file_error(nc_sweep, tmp_path, kind):
    """Hostile battery (benchmarks/hostile.py): a folder at series.nc was an IsADirectoryError from
    os.fdopen, and a symlink loop a FileNotFoundError claiming there is no series.nc."""
    import os

    from snoworm import load_sweep
    from snoworm.results.result import ResultFileError

    d = _copy(nc_sweep, tmp_path)
    (d / "series.nc").unlink()
    if kind == "folder":
        (d / "series.nc").mkdir()
    else:
        os.symlink(d / "series.nc", d / "series.nc")
    with pytest.raises(ResultFileError, match="series.nc: (not a regular file|cannot be opened)"):
        load_sweep(d).series()


def test_a_series_nc_with_flipped_bytes_is_one_error_without_library_tracebacks(nc_sweep, tmp_path):
    """Hostile battery (benchmarks/hostile.py): on some flipped bytes h5netcdf fails half-way through
    opening the file and, when that half-open file is collected, prints 'Exception ignored in
    File.close' with a traceback on stderr, beside snoworm's one-line ResultFileError."""
    import os
    import subprocess
    import sys

    copies = []
    for seed in range(12):
        d = _copy(nc_sweep, tmp_path / str(seed))
        data = bytearray((d / "series.nc").read_bytes())
        rng = np.random.default_rng(seed)
        for k in rng.integers(0, len(data), 8):
            data[k] ^= 0xFF
        (d / "series.nc").write_bytes(bytes(data))
        copies.append(str(d))
    code = f"""
import snoworm
from snoworm.results.result import ResultFileError
for d in {copies!r}:
    try:
        snoworm.load_sweep(d).series()
    except ResultFileError:
        print("refused")
"""
    root = str(Path(__file__).resolve().parents[1])
    r = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "PYTHONPATH": root},
    )
    assert r.returncode == 0, r.stderr[-2000:]
    assert "refused" in r.stdout
    assert "Exception ignored" not in r.stderr and "Traceback" not in r.stderr, r.stderr[-2000:]


def test_a_huge_dimension_in_series_nc_is_refused_before_allocating(nc_sweep, tmp_path):
    """A tampered series.nc declaring a 10**12-sample time axis (chunks never written: a tiny
    file) made xarray allocate terabytes (a MemoryError)."""
    import h5netcdf

    d = _copy(nc_sweep, tmp_path)
    with h5netcdf.File(d / "series.nc", "w") as f:
        f.dimensions = {"terrain_xt": 2, "simulation_duration_s": 1, "time": 10**12, "segment": 6, "link": 5}
        for name, dims in (("ok", ()), ("n_time", ()), ("n_segments", ()), ("t_s", ("time",))):
            f.create_variable(name, ("terrain_xt", "simulation_duration_s", *dims), "f8", chunks=True)
        f.create_variable("x_m", ("terrain_xt", "simulation_duration_s", "time", "segment"), "f8", chunks=True)
        f.create_variable("force_N", ("terrain_xt", "simulation_duration_s", "time", "link"), "f8", chunks=True)
    assert (d / "series.nc").stat().st_size < 100_000
    with pytest.raises(ResultFileError, match=r"series\.nc: its arrays would take .* more than a"):
        load_sweep(d).series()


def test_a_series_nc_of_another_sweep_shape_is_refused(nc_sweep, tmp_path):
    d = _copy(nc_sweep, tmp_path)
    other = tmp_path / "o"
    run_sweep(TOW6, ["terrain.xt=0.6,0.7,0.9", "simulation.duration_s=1"], out_dir=other, **NC)
    (d / "series.nc").write_bytes((other / "series.nc").read_bytes())
    with pytest.raises(ResultFileError, match=r"series\.nc: its swept dimensions .*terrain_xt.: 3.* not the sweep's"):
        load_sweep(d).series()


def test_a_resume_adding_series_netcdf_runs_the_cases_without_series_again(tmp_path, caplog):
    """A sweep run without --series netcdf, resumed with it, left its finished cases without series
    in series.nc (ok = 0), silently; they are run again now, with a warning naming them."""
    sets = ["terrain.xt=0.7,0.9", "simulation.duration_s=1"]
    out = tmp_path / "s"
    first = run_sweep(TOW6, sets, out_dir=out, plot=False, progress=False)
    lines = (out / "summary.csv").read_text().splitlines(keepends=True)
    (out / "summary.csv").write_text("".join(lines[:2]))  # interrupted after case 0
    with caplog.at_level("WARNING", logger="snoworm"):
        table = run_sweep(TOW6, sets, out_dir=out, **NC)
    assert (
        re.search(r"1 finished case\(s\) \(0+\) have no saved time series", caplog.text) and "run again" in caplog.text
    )
    ds = table.series()
    assert ds["ok"].values.all() and np.isfinite(ds["x_m"].values).all()
    assert comparable(table) == comparable(first)
    assert len((out / "summary.csv").read_text().splitlines()) == 3  # no repeated line for case 0
    again = run_sweep(TOW6, sets, out_dir=out, **NC)  # every case has its series: nothing re-runs
    xr.testing.assert_identical(again.series(), ds)


def test_a_resume_adding_save_cases_runs_the_cases_without_a_folder_again(tmp_path):
    sets = ["terrain.xt=0.7,0.9", "simulation.duration_s=1"]
    out = tmp_path / "s"
    run_sweep(TOW6, sets, out_dir=out, plot=False, progress=False)
    lines = (out / "summary.csv").read_text().splitlines(keepends=True)
    (out / "summary.csv").write_text("".join(lines[:2]))
    table = run_sweep(TOW6, sets, out_dir=out, plot=False, progress=False, save_cases=True)
    assert sorted(p.name for p in (out / "cases").iterdir()) == [r["case_id"] for r in table.rows]
    assert len((out / "summary.csv").read_text().splitlines()) == 3
