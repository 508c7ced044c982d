"""Results as tables and datasets for the researcher's own tools: pandas and xarray.

pandas and xarray are optional (``pip install 'snoworm[data]'``) and imported only when one of
these functions is called.  The functions take any object with a :class:`~snoworm.results.result.Result`'s
``t``, ``segments``, ``links``, ``columns`` and ``scenario``; :class:`Result` exposes them as
``Result.to_pandas`` and ``Result.to_xarray``.

Tables are *tidy* (long): one row per time and segment (or link), the columns ``t_s``,
``segment`` (or ``link``) and one column per quantity, named with its unit suffix (the columns
of ``segments.csv`` and ``links.csv``; ``slip`` and ``xt`` are dimensionless).
"""
from __future__ import annotations

import re
from importlib import metadata

import numpy as np

from .._version import __version__
from ..config.scenario import dump_scenario

__all__ = ["versions", "to_pandas", "to_xarray", "units_of", "require_pandas", "require_xarray"]

_EXTRA = "pip install 'snoworm[data]'"


def require_pandas():
    """The pandas module, or an ImportError saying how to install it."""
    try:
        import pandas  # lazy: optional dependency (snoworm[data])
    except ImportError as exc:
        raise ImportError(f"this needs pandas, which is not installed: {_EXTRA}") from exc
    return pandas


def require_xarray():
    """The xarray module, or an ImportError saying how to install it."""
    try:
        import xarray  # lazy: optional dependency (snoworm[data])
    except ImportError as exc:
        raise ImportError(f"this needs xarray, which is not installed: {_EXTRA}") from exc
    return xarray


def units_of(columns: dict) -> dict:
    """Column -> unit, read from the ``[unit]`` at the end of each description ("1": dimensionless)."""
    out = {}
    for name, doc in columns.items():
        m = re.search(r"\[([^\]]+)\]\s*$", doc)
        out[name] = m.group(1) if m else "1"
    return out


def _columns(result):
    """(segment, link) column descriptions of a result (``Result.columns``)."""
    cols = result.columns
    return cols["segments"], cols["links"]


def versions() -> dict:
    """Versions of snoworm and of the numerical packages behind a result (for provenance attrs)."""
    out = {"snoworm": __version__}
    for pkg in ("numpy", "scipy", "pandas", "xarray"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            pass
    return out


def _long(t, series: dict, index_name: str) -> dict:
    """Tidy columns of per-time, per-entity arrays (n_t, n): t_s, index, one column per series."""
    n_t = t.size
    n = next(iter(series.values())).shape[1] if series else 0
    cols = {"t_s": np.repeat(t, n), index_name: np.tile(np.arange(n), n_t)}
    cols.update({k: np.asarray(v, float).reshape(-1) for k, v in series.items()})
    return cols


def to_pandas(result) -> dict:
    """``{"segments": DataFrame, "links": DataFrame}``: the run's tidy tables.

    ``segments`` has the columns ``t_s, segment`` and those of ``segments.csv``; ``links`` the
    columns ``t_s, link`` and those of ``links.csv``; one row per output time and segment (link),
    in the CSV files' order.  Units in ``DataFrame.attrs["units"]``; the scenario name in
    ``attrs["scenario"]``.
    """
    pd = require_pandas()
    seg_cols, link_cols = _columns(result)
    seg_units, link_units = units_of(seg_cols), units_of(link_cols)
    frames = {}
    for name, series, idx, units in (("segments", result.segments, "segment", seg_units),
                                     ("links", result.links, "link", link_units)):
        df = pd.DataFrame(_long(np.asarray(result.t, float), series, idx))
        df.attrs["units"] = {"t_s": "s", idx: "1", **units}
        df.attrs["scenario"] = result.scenario.name
        frames[name] = df
    return frames


def to_xarray(result):
    """The run as an :class:`xarray.Dataset` (dims ``time x segment`` and ``time x link``).

    Coordinates: ``time`` [s], ``segment`` (0 = leader), ``link`` (link ``j`` joins segments
    ``j`` and ``j+1``).  Every variable has ``units`` and ``long_name`` attrs; the Dataset's attrs
    hold the resolved scenario as YAML text (``scenario_yaml``), its name and the package
    versions (``version_<package>``), so a saved file records how it was made.
    """
    xr = require_xarray()
    seg_cols, link_cols = _columns(result)
    data = {}
    for cols, series, dims in ((seg_cols, result.segments, ("time", "segment")),
                               (link_cols, result.links, ("time", "link"))):
        units = units_of(cols)
        for k, v in series.items():
            data[k if k not in data else f"link_{k}"] = xr.Variable(
                dims, np.asarray(v, float), {"units": units[k], "long_name": cols[k]})
    n = result.segments["x_m"].shape[1]
    coords = {"time": ("time", np.asarray(result.t, float), {"units": "s", "long_name": "output time"}),
              "segment": ("segment", np.arange(n), {"long_name": "segment index, 0 = leader"}),
              "link": ("link", np.arange(max(n - 1, 0)), {"long_name": "link index, link j joins segments j and j+1"})}
    attrs = {"scenario": result.scenario.name, "scenario_yaml": dump_scenario(result.scenario),
             **{f"version_{k}": v for k, v in versions().items()}}
    return xr.Dataset(data, coords=coords, attrs=attrs)
