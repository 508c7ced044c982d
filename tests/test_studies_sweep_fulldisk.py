"""A full disk while a sweep saves its cases' series is an output error (issue 30, section 2): exit 2
naming the folder, the finished cases kept, the failed case not recorded (a resume runs it), and
never a crash of the netCDF writer."""

from __future__ import annotations

import errno
import os
import resource
import signal
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

from snoworm.cli import main
from snoworm.infra.folders import MANIFEST
from snoworm.results import result as result_module
from snoworm.studies.sweep import load_sweep, series as series_module
from tests.sweep_helpers import ROOT, TOW6, csv_rows

pytest.importorskip("h5netcdf")

AXES = ["--set", "terrain.xt=0.6,0.7,0.8,0.9", "--set", "simulation.duration_s=3"]


def _sweep(out, *extra):
    return CliRunner().invoke(main, ["sweep", TOW6, *AXES, "--out", str(out), "--no-plot", "--save-cases", *extra])


def _full_for(marker):
    """A stand-in for a writer that raises ENOSPC when the path it writes names ``marker``."""

    def write(real):
        def wrapped(path, *a, **kw):
            if marker in str(path):
                raise OSError(errno.ENOSPC, "No space left on device", str(path))
            return real(path, *a, **kw)

        return wrapped

    return write


def _ids(out):
    return sorted(r["case_id"] for r in csv_rows(out / "summary.csv"))


@pytest.mark.parametrize("how", [[], ["--batch", "4"]], ids=["serial", "batched"])
def test_a_full_disk_saving_a_case_folder_stops_the_sweep_with_exit_2_and_a_resume_runs_that_case(
    tmp_path, monkeypatch, how
):
    out = tmp_path / "s"
    real = result_module.atomic_write_text
    monkeypatch.setattr(result_module, "atomic_write_text", _full_for(".0002.")(real))  # case 0002's staging folder
    r = _sweep(out, *how)
    assert r.exit_code == 2, r.output
    assert "No space left on device" in r.output and str(out) in r.output and "re-run" in r.output
    assert "Traceback" not in r.output
    assert _ids(out) == ["0000", "0001"]  # finished cases kept; 0002 not recorded (never as "error")
    saved = set(os.listdir(out / "cases"))  # batched: a later member of the group may be saved, unrecorded
    assert {"0000", "0001"} <= saved and "0002" not in saved
    monkeypatch.setattr(result_module, "atomic_write_text", real)  # space freed
    r = _sweep(out)
    assert r.exit_code == 0, r.output
    assert _ids(out) == ["0000", "0001", "0002", "0003"]
    assert {row["status"] for row in csv_rows(out / "summary.csv")} == {"ok"}
    assert sorted(os.listdir(out / "cases")) == ["0000", "0001", "0002", "0003"]


def test_a_full_disk_saving_a_cases_npz_stops_a_netcdf_sweep_and_a_resume_completes_it(tmp_path, monkeypatch):
    out = tmp_path / "s"
    real = np.savez
    calls = []

    def savez(fh, **arrays):
        calls.append(1)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fh, **arrays)

    monkeypatch.setattr(series_module.np, "savez", savez)
    r = _sweep(out, "--series", "netcdf")
    assert r.exit_code == 2, r.output
    assert "No space left on device" in r.output and f"{out}{os.sep}cases{os.sep}0001.npz" in r.output
    assert _ids(out) == ["0000"] and not (out / "series.nc").exists()
    monkeypatch.setattr(series_module.np, "savez", real)
    r = _sweep(out, "--series", "netcdf")
    assert r.exit_code == 0, r.output
    ds = load_sweep(out).series()
    assert ds["ok"].values.ravel().tolist() == [1, 1, 1, 1]


def _limited(limit):
    def pre():  # a file larger than ``limit`` bytes fails to write (EFBIG), as on a full disk
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return pre


def test_a_full_disk_writing_series_nc_is_exit_2_not_a_crash_and_a_resume_writes_it(tmp_path):
    """Each case's .npz fits (~70 kB), series.nc (~350 kB) does not: HDF5 failed the write and the
    interpreter crashed (segfault, exit 139) in h5py's clean-up."""
    out = tmp_path / "s"
    cmd = [sys.executable, "-m", "snoworm", "sweep", "tow6_uniform", *AXES, "--out", str(out)]
    cmd += ["--no-plot", "--save-cases", "--series", "netcdf"]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    r = subprocess.run(cmd, env=env, capture_output=True, text=True, preexec_fn=_limited(150_000), timeout=300)
    assert r.returncode == 2, r.stderr
    assert f"{out}{os.sep}series.nc: File too large" in r.stderr and "re-run the same command" in r.stderr
    assert sorted(os.listdir(out)) == sorted([MANIFEST, "cases", "summary.csv", "sweep.json"])  # no temp file
    assert _ids(out) == ["0000", "0001", "0002", "0003"]
    r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert load_sweep(out).series()["ok"].values.ravel().tolist() == [1, 1, 1, 1]
    assert not (out / "cases").exists()
