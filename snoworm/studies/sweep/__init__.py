"""Parameter sweeps: run one scenario over a grid (or a zip) of dotted-key values.

A sweep is defined by a base scenario and one or more *axes*, each a dotted scenario key with a
list of values (``--set terrain.xt=0.6:1.0:9 --set tow.force_N=0,100,200``).  Every case is the
base scenario with one value per axis applied exactly as ``snoworm run --set KEY=VALUE`` would,
so a case re-runs on its own with ``snoworm run``.

Modules, in data-flow order
---------------------------
:mod:`.spec`
    ``KEY=SPEC`` -> :class:`Axis` (lists and ``START:STOP:COUNT`` ranges); :func:`build_cases`:
    grid or zip, deterministic case ids and keys.
:mod:`.inputs`
    The files a sweep's scenario names, hashed into its resume key.
:mod:`.metrics`
    :func:`run_case` (one case, never raising for a failing case) and :func:`case_metrics`.
:mod:`.executors`
    Where the cases run: serial, local processes (:class:`snoworm.infra.pool.ProcessExecutor`),
    a Dask cluster, or stacked in batched solves.
:mod:`.summary`
    :class:`SweepTable` (``to_pandas``, ``series``, ``plot``), ``summary.csv`` and ``sweep.json``,
    resumption, :func:`load_sweep`, the table's figures.
:mod:`.series`
    Every case's time series in one netCDF file (``series="netcdf"``).
:mod:`.run`
    The plan (every case validated up front; invalid ones are recorded, not run) and
    :func:`run_sweep`: tasks (:class:`SweepTask`, small: the overridden scenario mapping, never a
    big object) -> an executor -> one row per case, appended to ``summary.csv`` as it finishes ->
    the table, sorted by case id, and a plot.

Files in the output directory
-----------------------------
``sweep.json``
    The sweep definition (scenario digest, axes, zip flag) and the column list; a re-run with
    another definition is refused.
``summary.csv``
    One line per finished case, appended with a single ``write`` and ``fsync`` as each case
    finishes, in completion order.  A re-run resumes: cases already there are skipped, a
    truncated last line is dropped and recomputed.
``sweep.png`` / ``heatmap.png``
    Metrics against the value of a one-axis sweep; a heat map of the mean speed for two axes.
``cases/<case_id>/``
    With ``save_cases``: each case's full time series (``Result.write(..., plot=False)``).
``series.nc``
    With ``series="netcdf"`` instead: every case's series in one file (dims: swept keys x time
    x segment/link), see :mod:`.series`.

Metrics
-------
See :func:`case_metrics`; the ``immobilised`` flag is explained in :mod:`.metrics`.

Extending
---------
An executor is any object with ``map_unordered(fn, tasks)`` yielding ``fn(task)`` results in any
order (and ``close()``); pass it to :func:`run_sweep` as ``executor=``.
"""

from ...infra.pool import ProcessExecutor
from .executors import BatchExecutor, DaskExecutor, SerialExecutor, SweepExecutionError, run_chunk
from .metrics import (
    IMMOBILISED_SIGN_FACTOR,
    IMMOBILISED_SPEED_MPS,
    LATE_FRACTION,
    METRIC_COLUMNS,
    SLIP_FRACTION,
    STATUSES,
    SweepTask,
    case_metrics,
    run_case,
)
from .run import run_sweep
from .series import SERIES_FORMATS, combine_series, load_series
from .spec import Axis, SweepCase, build_cases, parse_spec, parse_sweep_option
from .summary import SweepTable, load_sweep

__all__ = [
    "Axis",
    "SweepCase",
    "SweepTask",
    "SweepTable",
    "SweepExecutionError",
    "parse_spec",
    "parse_sweep_option",
    "build_cases",
    "case_metrics",
    "run_case",
    "run_sweep",
    "SerialExecutor",
    "ProcessExecutor",
    "DaskExecutor",
    "BatchExecutor",
    "run_chunk",
    "IMMOBILISED_SPEED_MPS",
    "IMMOBILISED_SIGN_FACTOR",
    "LATE_FRACTION",
    "SLIP_FRACTION",
    "METRIC_COLUMNS",
    "STATUSES",
    "load_sweep",
    "load_series",
    "combine_series",
    "SERIES_FORMATS",
]
