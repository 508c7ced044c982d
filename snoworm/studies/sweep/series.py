"""Every case's time series in one netCDF file (``series.nc``) instead of a folder per case.

With ``run_sweep(..., save_cases=True, series="netcdf")`` (CLI ``--save-cases --series
netcdf``) each worker writes its case's arrays to ``cases/<case_id>.npz`` (numpy only, no
xarray in the workers) and, once the cases have run, :func:`combine_series` gathers them into
``series.nc`` and removes the ``.npz`` files.  A resumed sweep keeps the series of the cases
already in ``series.nc``.

Layout of ``series.nc`` (netCDF4/HDF5, written with h5netcdf, zlib-compressed)
------------------------------------------------------------------------------
Dimensions: one per swept key, named by the key as an identifier (``terrain.xt`` ->
``terrain_xt``, so ``ds.sel(terrain_xt=0.8)`` works; the dotted key is the coordinate's ``key``
attribute), its coordinate the swept values; with ``zip`` a single ``case`` dimension with each
key as a coordinate along it.  Then ``time`` (the output sample; its coordinate is the output
time [s] when every case has the same times), ``segment`` and ``link``.  Variables: ``t_s``
(swept x time), every column of ``segments.csv`` (swept x time x segment) and of ``links.csv``
(swept x time x link); ``ok`` (1 where the case has a series), ``case_index``, ``n_time``,
``n_segments``.  Every variable and coordinate carries CF ``units`` (``"1"`` for dimensionless
ones) and a ``long_name`` without the unit (so xarray's labels read ``ground speed [m/s]``).
Cases with fewer samples or segments, and failed cases, are padded with NaN.  Attrs: the base
scenario, the sweep definition (JSON) and the package versions.  :func:`load_series` also reads
the netCDF3 files of earlier versions.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import gc
import json
import os
import re
import stat
import sys
import typing
from pathlib import Path

import numpy as np

from ...config.scenario import Scenario
from ...config.schema import quote, short_path, split_unit
from ...config.sections import MAX_SEGMENTS
from ...infra.folders import OutputError, atomic_path
from ...results.frames import long_name_of, require_xarray, units_of, versions
from ...results.result import ResultFileError

__all__ = [
    "SERIES_FORMATS",
    "SERIES_FILE",
    "save_series",
    "case_series_path",
    "combine_series",
    "load_series",
    "read_series",
    "cases_with_series",
    "expected_dims",
    "MAX_SERIES_BYTES",
    "dim_names",
    "key_attrs",
    "COMPRESSION",
]

#: Where a sweep keeps its cases' time series: a folder per case, or one netCDF file.
SERIES_FORMATS = ("folders", "netcdf")
#: Name of the combined file in the sweep's output directory.
SERIES_FILE = "series.nc"


#: Encoding of every variable of ``series.nc`` (zlib, level 4: about as small as level 9, faster).
COMPRESSION = {"zlib": True, "complevel": 4}


def dim_names(keys) -> dict:
    """Dotted key -> a dimension name that is a Python identifier (``terrain.xt`` -> ``terrain_xt``),
    distinct from one another and from ``time``, ``segment``, ``link``, ``case``."""
    taken, out = {"time", "segment", "link", "case"}, {}
    for key in keys:
        name = re.sub(r"\W", "_", str(key))
        name = name if name and not name[0].isdigit() else "k_" + name
        base, n = name, 2
        while name in taken:
            name, n = f"{base}_{n}", n + 1
        taken.add(name)
        out[key] = name
    return out


def _field_meta(key):
    """(unit, doc) declared for a scenario key (``schema.field``), or ("", "") if not found."""
    cls, md = Scenario, {}
    try:
        for part in key.split("."):
            md = {f.name: f for f in dataclasses.fields(cls)}[part].metadata
            cls = typing.get_type_hints(cls).get(part)
    except (KeyError, TypeError, NameError):
        return "", ""
    return md.get("unit", ""), md.get("doc", "")


def key_attrs(key) -> dict:
    """CF attributes of a swept key's coordinate: ``units`` (the field's declared unit, else its
    name's unit suffix, else ``"1"``), ``long_name`` (the field's description, else the key in
    words) and ``key`` (the dotted key)."""
    unit, doc = _field_meta(key)
    stem, suffix_unit = split_unit(key.rsplit(".", 1)[-1])
    words = " ".join(re.sub(r"[_\-]+", " ", p) for p in [*key.split(".")[:-1][-1:], stem] if p)
    return {"units": unit or suffix_unit or "1", "long_name": doc or words, "key": key}


def case_series_path(out: Path, case_id: str, series: str) -> str:
    """Where a case's series go: ``cases/<case_id>/`` (folders) or ``cases/<case_id>.npz`` (netcdf)."""
    return str(out / "cases" / (case_id + (".npz" if series == "netcdf" else "")))


def save_series(result, save_dir) -> None:
    """Write a case's time series: a run folder (:meth:`Result.write`, no plots) or, for a
    ``.npz`` path, the arrays (``t_s``, ``segments/<column>``, ``links/<column>``) atomically."""
    path = Path(save_dir)
    for p in (path.parent, path):
        if p.is_symlink():
            raise OutputError(
                f"{p} is a symbolic link: a sweep's case series are never written through one. "
                "Give a new --out directory."
            )
    if path.suffix != ".npz":
        result.write(path, plot=False)
        return
    arrays = {"t_s": np.asarray(result.t, float)}
    arrays.update({f"segments/{k}": np.asarray(v, float) for k, v in result.segments.items()})
    arrays.update({f"links/{k}": np.asarray(v, float) for k, v in result.links.items()})
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **arrays)


def _from_old(path: Path, n_cases: int, expected=None) -> dict:
    """Case index -> arrays of the cases already in an earlier ``series.nc`` (padding trimmed);
    ResultFileError naming the file if it is not as a sweep writes it (:func:`read_series`)."""
    ds = read_series(path, expected)
    try:

        def flat(v):
            return np.asarray(ds[v].values).reshape((n_cases,) + ds[v].shape[ds["ok"].ndim :])

        ok, nt, ns = flat("ok"), flat("n_time"), flat("n_segments")
        T, S = ds.sizes["time"], ds.sizes["segment"]
        if not (np.isin(ok, (0, 1)).all() and ((nt >= 0) & (nt <= T)).all() and ((ns >= 1) & (ns <= S)).all()):
            raise ValueError(f"ok, n_time or n_segments outside 0/1, 0..{T}, 1..{S}")
        names = [v for v in ds.data_vars if "time" in ds[v].dims and v != "t_s"]
        out = {}
        for i in np.nonzero(ok)[0]:
            a = {"t_s": flat("t_s")[i, : nt[i]]}
            for v in names:
                kind = "segments" if "segment" in ds[v].dims else "links"
                a[f"{kind}/{ds[v].attrs['column']}"] = flat(v)[i, : nt[i], : ns[i] - (kind == "links")]
            out[int(i)] = a
        if out and any("segments/x_m" not in a for a in out.values()):
            raise ValueError("no x_m variable")
    except (KeyError, ValueError, TypeError, IndexError) as exc:
        raise ResultFileError(f"{short_path(path)}: not a series file snoworm wrote ({quote(str(exc), 160)})") from None
    return out


def _gather(out: Path, cases, expected=None) -> dict:
    """Case index -> arrays, from the ``.npz`` files and an earlier ``series.nc``."""
    old = out / SERIES_FILE
    per_case = _from_old(old, len(cases), expected) if os.path.lexists(old) else {}
    for c in cases:
        f = out / "cases" / f"{c.case_id}.npz"
        if f.exists():
            with np.load(f) as z:
                per_case[c.index] = {k: z[k] for k in z.files}
    return per_case


def _coord(values):
    if all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool) for v in values):
        return np.asarray(values, float)
    return np.asarray([json.dumps(v) if not isinstance(v, str) else v for v in values])


def _stack(per_case, n_cases, columns):
    """(t_s, {variable: (array (n_cases, n_t, n), dim, column)}, n_time, n_segments), NaN-padded."""
    nt = np.zeros(n_cases, np.int32)
    ns = np.zeros(n_cases, np.int32)
    for i, a in per_case.items():
        nt[i], ns[i] = a["t_s"].size, a["segments/x_m"].shape[1]
    T, S = max(int(nt.max()), 1), max(int(ns.max()), 1)
    t = np.full((n_cases, T), np.nan)
    data = {}
    for kind, cols, dim, width in (
        ("segments", columns["segments"], "segment", S),
        ("links", columns["links"], "link", S - 1),
    ):
        for col in cols:
            name = col if kind == "segments" or col not in columns["segments"] else f"link_{col}"
            data[name] = (np.full((n_cases, T, width), np.nan), dim, col, kind)
    for i, a in per_case.items():
        t[i, : nt[i]] = a["t_s"]
        for arr, _, col, kind in data.values():
            v = a[f"{kind}/{col}"]
            arr[i, : v.shape[0], : v.shape[1]] = v
    return t, data, nt, ns


def combine_series(out, axes, cases, zip_, columns, attrs) -> Path:
    """Gather every case's series into ``out/series.nc`` (see the module's docstring) and remove
    the per-case ``.npz`` files.  ``columns``: ``Result.columns`` (descriptions with units)."""
    xr = require_xarray()
    out = Path(out)
    n = len(cases)
    per_case = _gather(out, cases, expected_dims(axes, zip_))
    t, data, nt, ns = _stack(per_case, n, columns)
    names = dim_names([a.key for a in axes])
    if zip_:
        shape, dims = (n,), ("case",)
        coords = {names[a.key]: ("case", _coord(a.values), key_attrs(a.key)) for a in axes}
    else:
        shape, dims = tuple(len(a.values) for a in axes), tuple(names[a.key] for a in axes)
        coords = {names[a.key]: (names[a.key], _coord(a.values), key_attrs(a.key)) for a in axes}
    units = {**units_of(columns["segments"]), **units_of(columns["links"])}
    ok = np.zeros(n, np.int8)
    ok[list(per_case)] = 1
    one = {"units": "1"}
    variables = {
        "t_s": (dims + ("time",), t.reshape(shape + t.shape[1:]), {"units": "s", "long_name": "output time"}),
        "ok": (dims, ok.reshape(shape), {**one, "long_name": "1 where the case has a time series"}),
        "case_index": (
            dims,
            np.arange(n, dtype=np.int32).reshape(shape),
            {**one, "long_name": "case id as an integer"},
        ),
        "n_time": (
            dims,
            nt.reshape(shape),
            {**one, "long_name": "output samples of the case (the rest is NaN padding)"},
        ),
        "n_segments": (dims, ns.reshape(shape), {**one, "long_name": "segments of the case (the rest is NaN padding)"}),
    }
    for name, (arr, dim, col, kind) in data.items():
        variables[name] = (
            dims + ("time", dim),
            arr.reshape(shape + arr.shape[1:]),
            {"units": units[col], "long_name": long_name_of(columns[kind][col]), "column": col},
        )
    rows = [t[i, : nt[i]] for i in per_case]
    if (
        rows
        and all(r.shape == rows[0].shape and np.array_equal(r, rows[0]) for r in rows)
        and rows[0].size == t.shape[1]
    ):
        coords["time"] = ("time", rows[0], {"units": "s", "long_name": "output time (the same for every case)"})
    S = data["x_m"][0].shape[2]
    coords.update(
        segment=("segment", np.arange(S, dtype=np.int32), {**one, "long_name": "segment index, 0 = leader"}),
        link=(
            "link",
            np.arange(S - 1, dtype=np.int32),
            {**one, "long_name": "link index, link j joins segments j and j+1"},
        ),
    )
    ds = xr.Dataset(variables, coords=coords, attrs={**attrs, **{f"version_{k}": v for k, v in versions().items()}})
    path = out / SERIES_FILE
    write_netcdf(ds, path, {v: dict(COMPRESSION) for v in ds.data_vars})
    for c in cases:
        (out / "cases" / f"{c.case_id}.npz").unlink(missing_ok=True)
    try:
        (out / "cases").rmdir()
    except OSError:
        pass
    return path


def write_netcdf(ds, path, encoding) -> None:
    """Write ``ds`` to ``path`` (netCDF4 via h5netcdf) atomically, so that a full disk is a plain
    ``OSError`` and never a crash.

    HDF5 failing a write (``ENOSPC``) leaves h5py's objects in a state whose clean-up crashed the
    interpreter (segfault, exit 139).  So the file is built in memory (xarray >= 2025: ``to_netcdf()``
    returns the bytes) and written with ``os.write``; with an older xarray, which writes netCDF4
    only to a path, the free space is checked first against the uncompressed size (an upper bound).
    """
    try:
        data = ds.to_netcdf(engine="h5netcdf", encoding=encoding)
    except (ValueError, TypeError):  # an older xarray: only scipy (netCDF3) writes to memory
        data = None
    try:
        _write_atomically(ds, path, encoding, data)
    except OSError as exc:  # name the file, not the temporary one (or none)
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None


def _write_atomically(ds, path, encoding, data):
    with atomic_path(path) as tmp:
        if data is None:
            _check_space(path.parent, ds.nbytes + 2**20)
            ds.to_netcdf(tmp, engine="h5netcdf", encoding=encoding)
            return
        with open(tmp, "wb") as fh:
            fh.write(memoryview(data))
            fh.flush()
            os.fsync(fh.fileno())


def _check_space(folder: Path, need: int) -> None:
    """Raise ``OSError(ENOSPC)`` naming ``folder`` if it has less than ``need`` bytes free."""
    st = os.statvfs(folder)
    if st.f_bavail * st.f_frsize < need:
        raise OSError(errno.ENOSPC, f"No space left on device (series.nc needs up to {need} bytes)", str(folder))


def expected_dims(axes, zip_) -> dict:
    """The sizes of the swept dimensions of a sweep's ``series.nc``: ``{name: size}``.  ``axes``:
    objects with ``key`` and ``values``, or ``(key, number of values)`` pairs."""
    pairs = [(a.key, len(a.values)) if hasattr(a, "key") else (a[0], int(a[1])) for a in axes]
    if zip_:
        return {"case": pairs[0][1] if pairs else 0}
    names = dim_names([k for k, _ in pairs])
    return {names[k]: n for k, n in pairs}


#: Largest ``series.nc`` opened (bytes).
MAX_SERIES_BYTES = 64 * 2**30
#: Most bytes a ``series.nc`` may expand to per byte of file (zlib's ceiling is about 1032; a
#: larger claim is a tampered header: an array of unwritten chunks, a dimension of 10**12).
MAX_EXPANSION = 1100
#: Variables every ``series.nc`` holds, with the dimensions after the swept ones.
_REQUIRED = {"t_s": ("time",), "ok": (), "n_time": (), "n_segments": ()}


def _engine(fh) -> str:
    """``scipy`` for a netCDF3 file (``CDF`` magic, earlier versions), ``h5netcdf`` otherwise."""
    magic = fh.read(3)
    fh.seek(0)
    return "scipy" if magic == b"CDF" else "h5netcdf"


def _check_layout(ds, size: int, expected) -> str | None:
    """What is wrong with the dimensions and variables of an opened ``series.nc`` (None: nothing),
    checked before any array is read."""
    sizes = dict(ds.sizes)
    swept = [d for d in sizes if d not in ("time", "segment", "link")]
    if expected is not None and {d: sizes[d] for d in swept} != dict(expected):
        return f"its swept dimensions {quote({d: sizes[d] for d in swept}, 160)} are not the sweep's {quote(dict(expected), 160)}"
    S = sizes.get("segment", 0)
    if not 1 <= S <= MAX_SEGMENTS or sizes.get("link") != S - 1:
        return f"segment/link dimensions {sizes.get('segment')}/{sizes.get('link')} (expected 1..{MAX_SEGMENTS} segments, one link fewer)"
    total = 0
    for name, var in ds.variables.items():
        if var.dtype.kind not in "biuf" and name not in ds.coords:
            return f"variable {quote(name, 60)} is not numeric ({var.dtype})"
        total += int(np.prod([sizes[d] for d in var.dims], dtype=float)) * var.dtype.itemsize
    for name, tail in _REQUIRED.items():
        if name not in ds.variables or tuple(ds[name].dims) != tuple(swept) + tail:
            return f"no variable {name} over the dimensions {quote(tuple(swept) + tail, 120)}"
    if total > MAX_EXPANSION * size + 2**26:
        return f"its arrays would take {total:.3g} bytes, more than a {size}-byte compressed file can hold"
    return None


def read_series(path, expected=None, only=None):
    """A sweep's ``series.nc`` as an :class:`xarray.Dataset`, loaded into memory and the file closed.

    Opened as the other readers open a user's file: a regular file (a FIFO or a device is refused
    unopened, never waited on) of at most :data:`MAX_SERIES_BYTES`; its dimensions are checked
    (``expected``: the swept dimensions' sizes, :func:`expected_dims`; at most ``MAX_SEGMENTS``
    segments) and its arrays' size against what the file can hold before a value is read.
    ``only``: the names of the variables to load (default: all).

    Raises
    ------
    snoworm.results.ResultFileError
        Naming the file and what is wrong with it (any error of the netCDF libraries included).
    """
    xr = require_xarray()
    where = short_path(path)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise ResultFileError(f"{where}: missing") from None
    except (OSError, ValueError) as exc:
        raise ResultFileError(f"{where}: cannot be opened ({getattr(exc, 'strerror', None) or exc})") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):  # checked before fdopen, which refuses a folder with IsADirectoryError
        os.close(fd)
        raise ResultFileError(f"{where}: not a regular file (a FIFO, a device or a folder)")
    with os.fdopen(fd, "rb") as fh:
        if st.st_size > MAX_SERIES_BYTES:
            raise ResultFileError(f"{where}: {st.st_size} bytes, more than the {MAX_SERIES_BYTES} accepted")
        with _quiet_half_open_files():
            try:
                with xr.open_dataset(fh, engine=_engine(fh)) as ds:
                    problem = _check_layout(ds, st.st_size, expected)
                    if problem is None:
                        return (ds[list(only)] if only else ds).load()
            except ResultFileError:
                raise
            except Exception as exc:  # noqa: BLE001 - h5py/h5netcdf/scipy/xarray on a tampered file: bad input
                problem = f"not a netCDF file snoworm wrote ({type(exc).__name__}: {quote(str(exc), 160)})"
    raise ResultFileError(f"{where}: {problem}")


@contextlib.contextmanager
def _quiet_half_open_files():
    """Drop the 'Exception ignored in File.close' tracebacks that h5netcdf prints (through
    :func:`sys.unraisablehook`) when it closes a file whose opening failed half-way (a tampered
    ``series.nc``): :func:`read_series` reports that file as one ResultFileError instead.  Every
    other unraisable exception goes to the hook as before."""
    previous = sys.unraisablehook

    def hook(u):
        if not type(u.object).__module__.startswith("h5netcdf") and not getattr(u.object, "__module__", "").startswith(
            "h5netcdf"
        ):
            previous(u)

    sys.unraisablehook = hook
    try:
        yield
    finally:
        gc.collect()  # the half-open file's finaliser runs now, under the hook
        sys.unraisablehook = previous


def cases_with_series(out, cases, keep_series, expected=None) -> set:
    """The indices of ``cases`` whose time series ``out`` holds already: in ``series.nc`` or as a
    ``cases/<case_id>.npz`` (``netcdf``), or as a ``cases/<case_id>/`` folder (``folders``)."""
    out = Path(out)
    if keep_series == "netcdf":
        have = set()
        if os.path.lexists(out / SERIES_FILE):
            ok = np.asarray(read_series(out / SERIES_FILE, expected, only=("ok",))["ok"].values).reshape(-1)
            have = {i for i in range(min(ok.size, len(cases))) if ok[i] == 1}
        return have | {c.index for c in cases if (out / "cases" / f"{c.case_id}.npz").is_file()}
    return {c.index for c in cases if (out / "cases" / c.case_id).is_dir()}


def load_series(path, expected=None):
    """The ``series.nc`` of a sweep as an :class:`xarray.Dataset` (loaded into memory, file closed;
    netCDF4 via h5netcdf, or the netCDF3 of earlier versions); see :func:`read_series`."""
    return read_series(path, expected)
