"""Results as tables and datasets for the researcher's own tools: pandas and xarray.

pandas and xarray are optional (``pip install 'snoworm[data]'``) and imported only when one of
these functions is called.  The functions take any object with a :class:`~snoworm.results.result.Result`'s
``t``, ``segments``, ``links``, ``columns`` and ``scenario``; :class:`Result` exposes them as
``Result.to_pandas`` and ``Result.to_xarray``.

:func:`to_pandas` gives ONE DataFrame: a row per output time, a column MultiIndex ``(kind,
quantity, index)`` (kind ``segment`` or ``link``).  :func:`frames` gives the two *tidy* (long)
tables of the CSV files: one row per time and segment (or link), the columns ``t_s``,
``segment`` (or ``link``) and one column per quantity, named with its unit suffix (``slip``
and ``xt`` are dimensionless).
"""

from __future__ import annotations

import re
from importlib import metadata

import numpy as np

from .._version import __version__
from ..config.scenario import dump_scenario

__all__ = [
    "versions",
    "to_pandas",
    "frames",
    "to_xarray",
    "units_of",
    "require_pandas",
    "require_xarray",
    "short_repr",
    "long_name_of",
]

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


def long_name_of(doc: str) -> str:
    """A column description without its trailing ``[unit]`` (the unit goes in the ``units``
    attribute; xarray's labels then read ``ground speed [m/s]``, not ``... [m/s] [m/s]``)."""
    return re.sub(r"\s*\[[^\]]+\]\s*$", "", doc)


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


def short_repr(result) -> str:
    """A few lines about a result (<= 500 characters): scenario, duration, segments, mode,
    distance, solver status."""
    t = np.asarray(result.t, float)
    dur = float(t[-1] - t[0]) if t.size > 1 else 0.0
    x = result.segments["x_m"]
    dist = float(np.mean(x[-1] - x[0])) if len(x) else 0.0
    st = result.stats or {}
    solver = ", ".join(f"{k} {st[k]}" for k in ("nfev", "njev", "intervals") if k in st)
    status = st.get("status", "ok")
    name = str(result.scenario.name)[:60]
    mode = str(getattr(result.scenario.mode, "type", "?"))[:40]
    return (
        f"<snoworm Result {name!r}: {result.segments['x_m'].shape[1]} segments, mode {mode}, {dur:g} s "
        f"({t.size} samples), distance {dist:.3f} m; solver {status}{': ' + solver if solver else ''}; "
        f"{len(result.events)} events.  Detail: .summary(), .segments, .links, .stats, .scenario>"
    )


def to_pandas(result):
    """The run as one DataFrame: index ``t_s`` (output times), columns a MultiIndex
    ``(kind, quantity, index)``: every per-segment quantity (kind ``segment``, index 0 = leader)
    and every per-link quantity (kind ``link``, link ``j`` joins segments ``j`` and ``j+1``).
    Units in ``DataFrame.attrs["units"]`` (quantity -> unit, per kind); the scenario name in
    ``attrs["scenario"]``.
    """
    pd = require_pandas()
    seg_cols, link_cols = _columns(result)
    blocks, codes = [], ([], [], [])
    kinds, quantities = ["segment", "link"], []
    for kind, series in (("segment", result.segments), ("link", result.links)):
        for q, v in series.items():
            v = np.asarray(v, float)
            blocks.append(v)
            quantities.append(q)
            for j in range(v.shape[1]):  # levels in the documented order: codes sorted, fast lookups
                for level, code in zip(codes, (kinds.index(kind), len(quantities) - 1, j)):
                    level.append(code)
    data = np.concatenate(blocks, axis=1) if blocks else np.zeros((len(result.t), 0))
    width = max((b.shape[1] for b in blocks), default=0)
    cols = pd.MultiIndex(
        levels=[kinds, quantities, list(range(width))], codes=list(codes), names=["kind", "quantity", "index"]
    )
    df = pd.DataFrame(data, index=pd.Index(np.asarray(result.t, float), name="t_s"), columns=cols)
    df.attrs["units"] = {"segment": units_of(seg_cols), "link": units_of(link_cols)}
    df.attrs["scenario"] = result.scenario.name
    return df


def frames(result) -> dict:
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
    for name, series, idx, units in (
        ("segments", result.segments, "segment", seg_units),
        ("links", result.links, "link", link_units),
    ):
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
    for cols, series, dims in (
        (seg_cols, result.segments, ("time", "segment")),
        (link_cols, result.links, ("time", "link")),
    ):
        units = units_of(cols)
        for k, v in series.items():
            data[k if k not in data else f"link_{k}"] = xr.Variable(
                dims, np.asarray(v, float), {"units": units[k], "long_name": long_name_of(cols[k])}
            )
    n = result.segments["x_m"].shape[1]
    coords = {
        "time": ("time", np.asarray(result.t, float), {"units": "s", "long_name": "output time"}),
        "segment": ("segment", np.arange(n), {"units": "1", "long_name": "segment index, 0 = leader"}),
        "link": (
            "link",
            np.arange(max(n - 1, 0)),
            {"units": "1", "long_name": "link index, link j joins segments j and j+1"},
        ),
    }
    attrs = {
        "scenario": result.scenario.name,
        "scenario_yaml": dump_scenario(result.scenario),
        **{f"version_{k}": v for k, v in versions().items()},
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)
