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


def test_repr_is_short_and_says_what_ran(res):
    text = repr(res)
    assert len(text) <= 500
    for part in ("tow6_uniform", "6 segments", "mode uniform", "2 s", "distance", "solver"):
        assert part in text, part
    assert f"{res.summary()['distance_m']:.3f} m" in text


def test_units_read_from_the_descriptions():
    u = units_of(SEGMENT_COLUMNS)
    assert u["v_mps"] == "m/s" and u["traction_N"] == "N" and u["motor_torque_Nm"] == "N m"
    assert u["slip"] == "1" and u["xt"] == "1"
    assert units_of(LINK_COLUMNS)["force_N"] == "N"


def test_to_pandas_is_one_frame_with_a_column_multiindex(res):
    df = res.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert df.index.name == "t_s" and len(df) == res.t.size
    np.testing.assert_array_equal(df.index.to_numpy(), res.t)
    assert df.columns.names == ["kind", "quantity", "index"]
    assert df.shape[1] == 6 * len(SEGMENT_COLUMNS) + 5 * len(LINK_COLUMNS)
    np.testing.assert_array_equal(df["segment", "v_mps"].to_numpy(), res.segments["v_mps"])
    np.testing.assert_array_equal(df["link", "force_N"].to_numpy(), res.links["force_N"])
    seg2 = df.xs(2, axis=1, level="index")["segment"]
    np.testing.assert_array_equal(seg2["slip"].to_numpy(), res.segments["slip"][:, 2])
    assert df.attrs["units"]["segment"]["v_mps"] == "m/s" and df.attrs["units"]["link"]["force_N"] == "N"
    assert len(df.head()) == 5


def test_tidy_tables_a_call_away(res):
    seg, lk = res.segments_frame(), res.links_frame()
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
    df = res.segments_frame()
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
