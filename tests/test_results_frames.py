"""Results as pandas tables and xarray Datasets (snoworm.results.frames, Result.to_pandas/to_xarray)."""
import io

import numpy as np
import pandas as pd
import pytest
import xarray as xr
import yaml

from snoworm import load_scenario, scenario_from_dict, simulate
from snoworm.results.frames import units_of, versions
from snoworm.results.result import LINK_COLUMNS, SEGMENT_COLUMNS
from tests.conftest import SCENARIOS


@pytest.fixture(scope="module")
def res():
    return simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml", ["simulation.duration_s=2"]))


def test_units_read_from_the_descriptions():
    u = units_of(SEGMENT_COLUMNS)
    assert u["v_mps"] == "m/s" and u["traction_N"] == "N" and u["motor_torque_Nm"] == "N m"
    assert u["slip"] == "1" and u["xt"] == "1"
    assert units_of(LINK_COLUMNS)["force_N"] == "N"


def test_to_pandas_tidy_tables(res):
    frames = res.to_pandas()
    seg, lk = frames["segments"], frames["links"]
    n_t = res.t.size
    assert list(seg.columns) == ["t_s", "segment", *SEGMENT_COLUMNS]
    assert list(lk.columns) == ["t_s", "link", *LINK_COLUMNS]
    assert len(seg) == n_t * 6 and len(lk) == n_t * 5
    for k in (0, 3, 5):
        rows = seg[seg["segment"] == k]
        np.testing.assert_array_equal(rows["t_s"].to_numpy(), res.t)
        np.testing.assert_array_equal(rows["v_mps"].to_numpy(), res.segments["v_mps"][:, k])
    wide = lk.pivot(index="t_s", columns="link", values="force_N")
    np.testing.assert_array_equal(wide.to_numpy(), res.links["force_N"])
    assert seg.attrs["units"]["v_mps"] == "m/s" and seg.attrs["scenario"] == "tow6_uniform"


def test_to_pandas_matches_the_csv(res):
    """The CSV is the same table, at its printed precision (times 4 decimals, values 6 significant digits)."""
    csv = pd.read_csv(io.StringIO(res.segments_csv()))
    df = res.to_pandas()["segments"]
    assert list(csv.columns) == list(df.columns)
    np.testing.assert_allclose(csv["t_s"], df["t_s"], rtol=0, atol=5e-5)
    np.testing.assert_allclose(csv.iloc[:, 1:].to_numpy(float), df.iloc[:, 1:].to_numpy(float), rtol=5e-6, atol=0)


def test_to_xarray_dims_units_and_provenance(res, tmp_path):
    ds = res.to_xarray()
    assert ds["v_mps"].dims == ("time", "segment") and ds["force_N"].dims == ("time", "link")
    assert ds.sizes == {"time": res.t.size, "segment": 6, "link": 5}
    np.testing.assert_array_equal(ds["time"].to_numpy(), res.t)
    np.testing.assert_array_equal(ds["net_force_N"].to_numpy(), res.segments["net_force_N"])
    assert ds["traction_N"].attrs["units"] == "N" and ds["time"].attrs["units"] == "s"
    assert ds.attrs["version_numpy"] == np.__version__ and ds.attrs["version_snoworm"] == versions()["snoworm"]
    again = scenario_from_dict(yaml.safe_load(ds.attrs["scenario_yaml"]))
    assert again == res.scenario
    path = tmp_path / "run.nc"
    ds.to_netcdf(path, engine="scipy")
    with xr.open_dataset(path, engine="scipy") as back:
        xr.testing.assert_identical(back.load(), ds)


def test_missing_pandas_says_how_to_install(res, monkeypatch):
    monkeypatch.setitem(__import__("sys").modules, "pandas", None)
    with pytest.raises(ImportError, match=r"needs pandas, which is not installed: pip install 'snoworm\[data\]'"):
        res.to_pandas()
