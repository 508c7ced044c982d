"""Running a sweep: its plan (:func:`plan_sweep`), then :func:`run_sweep` and its steps.

The plan: :func:`plan_sweep` parses the axes, builds the cases (:mod:`.cases`) and validates every
case's scenario (an invalid case is recorded, not run; a controller that may not run refuses the
whole sweep); :class:`SweepPlan` holds the result, with the resume key of ``sweep.json``
(:func:`_definition`: the scenario, the axes, the version and the contents of the files they name).

Data flow: the axes -> :func:`~snoworm.studies.sweep.spec.build_cases` -> every case validated up front
(invalid ones are recorded, not run) -> tasks (:class:`~snoworm.studies.sweep.metrics.SweepTask`, small: the overridden scenario
mapping, never a big object) -> an executor running :func:`~snoworm.studies.sweep.metrics.run_case` ->
one row per case, appended to ``summary.csv`` as it finishes -> a :class:`SweepTable` sorted
by case id (and a plot).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import sys
from collections.abc import Callable, Iterable, Iterator
from contextlib import ExitStack
from dataclasses import dataclass, field as dc_field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Protocol, TextIO, cast

from ..._version import __version__
from ...config.scenario import Scenario, apply_overrides, read_scenario_yaml, scenario_from_dict
from ...config.schema import ScenarioError, short_key
from ...infra.commit import finish_commit
from ...infra.csvwriter import canonical_json
from ...infra.folders import OutputError, check_output_folder, folder_lock, os_error_message, write_manifest
from ...infra.progress import Progress
from ...modes.codeload import allowed_paths
from ...modes.controller import trust_problem_of
from ...results.frames import require_xarray
from ...results.result import LINK_COLUMNS, SEGMENT_COLUMNS
from .executors import BatchExecutor, DaskExecutor, ProcessExecutor, SerialExecutor, SweepExecutionError
from .inputs import input_hashes
from .metrics import METRIC_COLUMNS, SweepTask, case_metrics, one_line, run_case
from .series import SERIES_FORMATS, case_series_path, cases_with_series, combine_series, expected_dims
from .spec import as_axes, build_cases
from .summary import SweepTable, prepare_dir, summary_columns, write_plot

if TYPE_CHECKING:
    from ...infra.locks import FolderLease
    from ...results.result import FigureSize
    from .spec import Axis, SweepCase

    #: A sweep's base scenario: a YAML path or shipped name, a Scenario or a scenario mapping.
    ScenarioSource = str | os.PathLike[str] | Scenario | dict
    #: An axis: ``"KEY=SPEC"``, a ``(key, spec)`` pair or an :class:`Axis`.
    AxisSpec = str | tuple[str, Any] | Axis


class SweepExecutor(Protocol):
    """Where a sweep's cases run (:func:`run_sweep`'s ``executor``): ``fn(task)`` for every task,
    yielded in any order, and ``close()``."""

    def map_unordered(self, fn: Callable[[SweepTask], dict], tasks: Iterable[SweepTask]) -> Iterator[dict]: ...

    def close(self) -> None: ...


__all__ = ["run_sweep", "SweepPlan", "KEEP_VALIDATED_MAX", "plan_sweep"]


# ------------------------------------------------------------------------------------- the plan
def _base(scenario: ScenarioSource) -> tuple[dict, str, str | None]:
    """(raw mapping, source name, base_dir) of a path or a Scenario object."""
    if isinstance(scenario, Scenario):
        bd = scenario.origin.base_dir if scenario.origin is not None else None
        return scenario.to_dict(), scenario.name, (str(bd) if bd is not None else None)
    if isinstance(scenario, dict):
        return scenario, "scenario", None
    raw, path = read_scenario_yaml(scenario)
    return raw, str(path), str(path.resolve().parent)


def _definition(raw: dict, axes: list[Axis], zip_: bool, base_dir: str | None = None) -> dict:
    """The resume key: the scenario mapping, the axes, the snoworm version and the contents of
    every file they name (:mod:`snoworm.studies.sweep.inputs`)."""
    return json.loads(
        json.dumps(
            {
                "scenario_sha256": hashlib.sha256(canonical_json(raw).encode()).hexdigest(),
                "axes": [{"key": a.key, "values": list(a.values)} for a in axes],
                "zip": bool(zip_),
                "snoworm_version": __version__,
                "inputs": input_hashes(raw, axes, base_dir),
            },
            default=str,
        )
    )


@dataclass
class SweepPlan:
    """A sweep's cases, validated, and what its files record."""

    axes: list
    raw: dict
    source: str
    base_dir: str | None
    cases: list
    invalid: dict  # case index -> one-line error of the cases whose scenario is rejected
    n_links: int
    columns: list
    definition: dict
    #: case index -> its validated Scenario, kept for local executors (see _plan)
    scenarios: dict = dc_field(default_factory=dict)
    #: resolved paths whose controller code may run (run_sweep's allow_code), handed to every task
    allow_code: list = dc_field(default_factory=list)

    @property
    def keys(self) -> list[str]:
        return [a.key for a in self.axes]


#: Most validated scenarios a sweep keeps for its local executor (about 5 KiB each; a worker
#: process receives them pickled, ~0.05 ms against ~0.6 ms to validate again), so that a case is
#: not validated twice; larger sweeps validate again in the executor to bound memory.
KEEP_VALIDATED_MAX = 20_000


def plan_sweep(
    scenario: ScenarioSource,
    sets: Iterable[AxisSpec],
    zip_: bool,
    save_cases: bool,
    out_dir: str | os.PathLike[str] | None,
    jobs: int,
    keep: bool = False,
    allow_code: Iterable[str | os.PathLike[str]] = (),
) -> SweepPlan:
    """Parse the axes, build the cases and validate each one (about 2 ms a case).

    ``keep``: the cases run in this process or its own worker pool; keep their validated
    scenarios (up to :data:`KEEP_VALIDATED_MAX` cases) for the tasks.  ``allow_code``: see
    ``run_sweep`` (a controller that may not run refuses the whole sweep here)."""
    allow = list(allowed_paths(allow_code))  # ScenarioError for an empty path
    plan = _plan_cases(scenario, sets, zip_, save_cases, out_dir, jobs, keep, allow)
    plan.allow_code = allow
    return plan


def _plan_cases(
    scenario: ScenarioSource,
    sets: Iterable[AxisSpec],
    zip_: bool,
    save_cases: bool,
    out_dir: str | os.PathLike[str] | None,
    jobs: int,
    keep: bool,
    allow_code: list[str],
) -> SweepPlan:
    axes = as_axes(sets)
    raw, source, base_dir = _base(scenario)
    if not isinstance(raw, dict):
        raise ScenarioError(f"{source}: a scenario must be a YAML mapping.")
    cases = build_cases(axes, zip_)
    if save_cases and out_dir is None:
        raise ScenarioError("--save-cases needs --out: the time series are written under DIR/cases/.")
    if int(jobs) < 1:
        raise ScenarioError(f"-j/--jobs must be at least 1, got {jobs}.")
    invalid, n_links, kept = {}, 0, {}
    keep = keep and len(cases) <= KEEP_VALIDATED_MAX
    for c in cases:
        try:
            sc = scenario_from_dict(apply_overrides(raw, c.overrides(axes)), source, base_dir=base_dir)
        except ScenarioError as exc:
            invalid[c.index] = one_line(exc)
            continue
        why = trust_problem_of(sc, allow_code=allow_code) if sc.mode.type == "controller" else None
        if why is not None:  # refused for the whole sweep, before anything runs
            raise ScenarioError(f"case {c.case_id}: {why}")
        n_links = max(n_links, sc.vehicle.segments - 1)
        if keep:
            kept[c.index] = sc
    if len(invalid) == len(cases):
        first = invalid[cases[0].index]
        raise ScenarioError(
            f"every case of the sweep is invalid, e.g. case {cases[0].case_id} "
            f"({', '.join(f'{short_key(a.key)}={short_key(v)}' for a, v in zip(axes, cases[0].values))}): {first}"
        )
    return SweepPlan(
        axes,
        raw,
        source,
        base_dir,
        cases,
        invalid,
        n_links,
        summary_columns(axes, n_links),
        _definition(raw, axes, zip_, base_dir),
        kept,
    )


# ---------------------------------------------------------------------------------- progress
class _Progress:
    """Cases done, failures, time left: a bar on a terminal, a line per ~10 % otherwise
    (:class:`snoworm.infra.progress.Progress`)."""

    def __init__(self, total: int, already: int, stream: TextIO, enabled: bool) -> None:
        self.already, self.done, self.failed = already, 0, 0
        self.bar = Progress(total, "sweep", "cases", stream, mode="auto" if enabled else "off")
        self.bar.value = float(already)

    def _info(self) -> str:
        return f"{self.failed} failed" + (f", {self.already} resumed" if self.already else "")

    def update(self, failed: bool) -> None:
        self.done += 1
        self.failed += int(failed)
        self.bar.set(self.already + self.done, info=self._info())

    def show(self) -> None:
        self.bar.set(self.already + self.done, info=self._info())

    def close(self) -> None:
        self.bar.close(info=self._info())


# ---------------------------------------------------------------------------------- driver
def run_sweep(
    scenario: ScenarioSource,
    sets: Iterable[AxisSpec],
    out_dir: str | os.PathLike[str] | None = None,
    *,
    jobs: int = 1,
    scheduler: Any = None,
    zip_: bool = False,
    save_cases: bool = False,
    progress: bool | None = None,
    plot: bool = True,
    executor: SweepExecutor | None = None,
    batch: int = 0,
    series: str = "folders",
    plot_format: str = "png",
    overwrite: bool = False,
    allow_code: Iterable[str | os.PathLike[str]] = (),
    restart: bool = False,
    figure_size: FigureSize | None = None,
    command: str | None = None,
) -> SweepTable:
    """Run a scenario over a grid (or zip) of values and return the summary table.

    Parameters
    ----------
    scenario : str, Path, Scenario or dict
        The base scenario (a YAML path, as for ``snoworm run``, or a scenario object/mapping).
    sets : sequence
        Axes: ``"KEY=SPEC"`` strings (see :func:`parse_spec`), ``(key, spec)`` pairs or
        :class:`Axis` objects.  Several axes form a full grid (first axis slowest).
    out_dir : str or Path, optional
        Where ``sweep.json``, ``summary.csv`` and the plot go.  A re-run with the same
        definition resumes; with another definition it is refused (unless ``overwrite`` or
        ``restart``).  None: nothing is written.  The folder is locked while the sweep runs (a
        second sweep into it raises :class:`~snoworm.infra.folders.FolderLocked` naming the process
        holding it).
    jobs : int
        Local worker processes (1: run in this process).
    scheduler : str or distributed.Client, optional
        Address of a Dask scheduler (``tcp://host:port``); overrides ``jobs``.
    zip_ : bool
        Pair the axes element by element (equal lengths) instead of a grid.
    save_cases : bool
        Keep each case's time series (needs ``out_dir``), as ``series`` says.
    series : {"folders", "netcdf"}
        ``folders``: a run folder per case, ``out_dir/cases/<case_id>/``; ``netcdf``: every case in
        one file ``out_dir/series.nc`` (dims: swept keys x time x segment/link, see
        :mod:`snoworm.studies.sweep.series`; needs xarray).  ``netcdf`` implies ``save_cases``.
    progress : bool, optional
        Progress on stderr (default True): a bar on a terminal, one line per ~10 % otherwise.
    plot : bool
        Write ``sweep.png`` (one varying axis, or zipped axes) or ``heatmap.png`` (two).
    plot_format : {"png", "pdf", "svg"}
        File format of the plot.
    figure_size : str or (float, float), optional
        Print size of the plot: ``"column"``, ``"page"`` (default) or ``"WxH"`` inches
        (:func:`snoworm.plotting.style.parse_size`).
    executor : object, optional
        Anything with ``map_unordered(fn, tasks)`` and ``close()``; overrides jobs/scheduler.
    batch : int
        With ``batch > 1`` (and no scheduler or executor): integrate up to ``batch`` cases of the
        same structure as one stacked system (:class:`~snoworm.studies.sweep.executors.BatchExecutor`,
        ``jobs`` processes); other cases run one by one.  Same metrics within the solver tolerance.
    overwrite : bool
        Start afresh in a folder holding another sweep (its files are removed), or write into a
        non-empty folder snoworm did not write.
    allow_code : sequence of str or Path
        Paths whose controller code may run outside the scenario's folder (:func:`snoworm.simulate`).
    restart : bool
        Start afresh (removing its rows) over a sweep in ``out_dir`` run from other inputs.
    command : str, optional
        The command line recorded in the folder's manifest (default: this process's).

    Returns
    -------
    SweepTable
        Every case (resumed and new), sorted by case id.

    Raises
    ------
    ScenarioError
        A malformed SPEC, unequal zip lengths, every case invalid, or an output directory holding another sweep.
    """
    save_cases = _check_series(series) or save_cases
    local = executor is None and scheduler is None  # this process or its own pool: pass scenarios on
    plan = plan_sweep(scenario, sets, zip_, save_cases, out_dir, jobs, keep=local, allow_code=allow_code)
    out = _new_output_folder(out_dir, overwrite)
    opts = _Options(
        progress, plot, zip_, save_cases and series, overwrite or restart, plot_format, figure_size, command
    )
    return _on_executor(plan, out, executor, (scheduler, batch, jobs), opts)


def _on_executor(
    plan: SweepPlan, out: Path | None, executor: SweepExecutor | None, how: tuple[Any, int, int], opts: _Options
) -> SweepTable:
    """Run the planned sweep on ``executor`` (None: a new one for ``how`` = (scheduler, batch, jobs),
    closed at the end); an I/O failure becomes :class:`OutputError`."""
    own = executor is None
    if executor is None:  # before anything is written: an unreachable scheduler writes nothing
        executor = _make_executor(*how)
    try:
        return _in_folder(plan, out, executor, own, opts)
    except OSError as exc:  # writing sweep.json, the manifest or the plot
        raise OutputError(
            f"cannot write the sweep's files: {os_error_message(exc, out)}. Its finished cases (if any) are "
            "kept in summary.csv: free space (or fix the folder) and re-run the same command to resume."
        ) from None


def _new_output_folder(out_dir: str | os.PathLike[str] | None, overwrite: bool) -> Path | None:
    """``out_dir`` as a Path (None: nothing is written), checked before any case runs unless it holds
    a sweep already (resumed or refused later, by :func:`~snoworm.studies.sweep.summary.prepare_dir`)."""
    out = Path(os.path.abspath(out_dir)) if out_dir is not None else None  # once: a chdir does not move it
    if out is not None and not (out / "sweep.json").exists():
        check_output_folder(out, overwrite)
    return out


def _check_series(series: str) -> bool:
    """Check ``series`` (and that xarray is there for ``netcdf``, before any case runs); True if it
    implies saving the cases' series."""
    if series not in SERIES_FORMATS:
        raise ScenarioError(f"series: expected one of {', '.join(SERIES_FORMATS)}, got {series!r}.")
    if series == "netcdf":
        try:
            require_xarray()
            import h5netcdf  # noqa: F401  # lazy: optional dependency (snoworm[data]), checked before any case runs
        except ImportError:
            raise ScenarioError(
                "--series netcdf needs xarray and h5netcdf: pip install 'snoworm[data]' "
                "(or keep the default --series folders)."
            ) from None
        return True
    return False


@dataclass(frozen=True)
class _Options:
    """How a sweep reports and what it writes besides the table (:func:`run_sweep`'s options)."""

    progress: bool | None  # None/True: progress on stderr; False: none
    plot: bool
    zip_: bool
    keep_series: str | Literal[False]  # False, or the series format ("folders" or "netcdf")
    overwrite: bool
    plot_format: str
    figure_size: FigureSize | None  # print size of the plot (None: page width)
    command: str | None  # the command line the manifest records (None: this process's)


def _in_folder(plan: SweepPlan, out: Path | None, executor: SweepExecutor, own: bool, opts: _Options) -> SweepTable:
    """Run the sweep with ``out`` (or None) locked and prepared."""
    with ExitStack() as stack:
        done, lease = {}, None
        if out is not None:
            try:
                _mkdir(out)
                lease = stack.enter_context(folder_lock(out))
                finish_commit(out)  # a commit in place interrupted between its renames: completed first
                done = prepare_dir(
                    out, plan.definition, plan.columns, plan.cases, plan.axes, plan.source, overwrite=opts.overwrite
                )
                done = _rerun_without_series(plan, done, out, opts)
                write_manifest(out, opts.command, status="running")
            except BaseException:
                if own:
                    executor.close()
                raise
        table = _run(plan, done, out, executor, own, opts, lease)
        if lease is not None:
            lease.check("running a sweep in")  # the folder is still the one locked: else no manifest
            write_manifest(out, opts.command, status="complete")
        return table


def _rerun_without_series(plan: SweepPlan, done: dict[int, dict], out: Path, opts: _Options) -> dict[int, dict]:
    """``done`` without the finished ``ok`` cases whose time series are missing when this sweep
    keeps them (a resume adding ``--series netcdf`` or ``--save-cases``): those cases run again
    (their rows removed from ``summary.csv`` first), and a warning says how many."""
    if not opts.keep_series or not done:
        return done
    have = cases_with_series(out, plan.cases, opts.keep_series, expected_dims(plan.axes, opts.zip_))
    missing = [i for i, r in done.items() if r.get("status") == "ok" and i not in have]
    if not missing:
        return done
    keep = {i: r for i, r in done.items() if i not in missing}
    SweepTable(plan.columns, list(keep.values()), plan.keys).to_csv(out / "summary.csv")
    ids = ", ".join(plan.cases[i].case_id for i in sorted(missing)[:5]) + (", ..." if len(missing) > 5 else "")
    logging.getLogger("snoworm").warning(
        "%s: %d finished case(s) (%s) have no saved time series (the sweep ran without keeping them); "
        "they are run again so that every case has its series.",
        out,
        len(missing),
        ids,
    )
    return keep


def _mkdir(out: Path) -> None:
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot write results: {os_error_message(exc, out)}") from None


def _run(
    plan: SweepPlan,
    done: dict[int, dict],
    out: Path | None,
    executor: SweepExecutor,
    own: bool,
    opts: _Options,
    lease: FolderLease | None = None,
) -> SweepTable:
    """Run the cases still to do, then write ``series.nc`` and the plot (``lease``: the folder's
    lock, checked before each write: a folder replaced meanwhile gets nothing)."""
    bar = _Progress(len(plan.cases), len(done), sys.stderr, opts.progress is None or bool(opts.progress))
    keep_series = opts.keep_series
    rows = dict(done)
    todo = [c for c in plan.cases if c.index not in done]
    token = lease.token if lease is not None else None
    _execute(plan, todo, executor, _Recorder(plan, rows, out, bar, lease), own, out, (keep_series, token))
    table = SweepTable(plan.columns, [rows[c.index] for c in plan.cases], plan.keys, out_dir=out)
    if lease is not None:
        lease.check("running a sweep in")
    if keep_series == "netcdf":
        combine_series(
            out,
            plan.axes,
            plan.cases,
            opts.zip_,
            {"segments": SEGMENT_COLUMNS, "links": LINK_COLUMNS},
            {"scenario": plan.source, "sweep_definition": json.dumps(plan.definition)},
        )
    if out is not None and opts.plot:
        write_plot(table, out, opts.plot_format, opts.figure_size)
    return table


def _make_executor(scheduler: Any, batch: int, jobs: int) -> SweepExecutor:
    """The executor of ``scheduler`` / ``batch`` / ``jobs`` (see :func:`run_sweep`)."""
    if scheduler is not None:
        return DaskExecutor(scheduler)
    if int(batch) > 1:
        return BatchExecutor(
            int(batch), int(jobs), ProcessExecutor(int(jobs)) if int(jobs) > 1 else None, metrics=case_metrics
        )
    if int(jobs) > 1:
        return ProcessExecutor(int(jobs))
    return SerialExecutor()


class _Recorder:
    """Turns each case's result into a row: kept in ``rows``, appended to ``summary.csv`` (one
    ``write`` and ``fsync`` per case) and counted on the progress line."""

    def __init__(
        self, plan: SweepPlan, rows: dict, out: Path | None, bar: _Progress, lease: FolderLease | None = None
    ) -> None:
        self.plan, self.rows, self.bar, self.lease = plan, rows, bar, lease
        self.table = SweepTable(plan.columns, [], plan.keys)
        self.path = out / "summary.csv" if out is not None else None
        self.fd: int | None = None

    def open(self) -> None:
        if self.path is not None:
            self.fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | getattr(os, "O_NOFOLLOW", 0))

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None

    def record(self, c: SweepCase, result: dict) -> None:
        if result.get("output_error"):  # the case's series could not be saved: stop, not recorded
            raise OutputError(self._unsaved(c, result["output_error"]))
        row = {"case_id": c.case_id, "case_key": c.key, **dict(zip(self.plan.keys, c.values))}
        row.update(status=result["status"], error=result["error"])
        for m in list(METRIC_COLUMNS)[:7] + ["energy_per_m_J", "immobilised", "verdict", "immobilised_at_m"]:
            row[m] = result.get(m)
        links = result.get("final_link_forces_N") or []
        for j in range(self.plan.n_links):
            row[f"final_link_force_{j}_N"] = links[j] if j < len(links) else None
        row["wall_time_s"] = result.get("wall_time_s")
        if self.lease is not None:
            self.lease.check("running a sweep in")  # never a row into a file no longer in the folder
        if self.fd is not None:
            try:
                os.write(self.fd, self.table.csv_line(row).encode("utf-8"))
                os.fsync(self.fd)
            except OSError as exc:
                raise OutputError(
                    f"cannot append to the summary: {os_error_message(exc, self.path)}; the "
                    f"{len(self.rows)} finished cases are kept, re-run the same command to "
                    "resume."
                ) from None
        self.rows[c.index] = row
        self.bar.update(row["status"] != "ok")

    def _unsaved(self, c: SweepCase, why: object) -> str:
        where = self.path.parent if self.path is not None else "memory"
        return (
            f"cannot save the series of case {c.case_id}: {str(why).rstrip('.')}. The sweep stopped; its "
            f"{len(self.rows)} finished cases are kept in {where} and case {c.case_id} is not recorded: free "
            "space (or fix the folder) and re-run the same command to resume."
        )


def _tasks(
    plan: SweepPlan,
    todo: Iterable[SweepCase],
    out: Path | None,
    keep_series: str | Literal[False],
    token: str | None = None,
) -> Iterator[SweepTask]:
    """The tasks of the cases still to run (:class:`SweepTask`, made one at a time).

    ``keep_series``: False, or where the cases' series go ("folders" or "netcdf"); ``token``: the
    folder lock's (:attr:`~snoworm.infra.locks.FolderLease.token`), checked before a series is saved."""
    for c in todo:
        if c.index in plan.invalid:
            continue
        save = case_series_path(cast(Path, out), c.case_id, keep_series) if keep_series else None  # kept: out given
        sc = plan.scenarios.pop(c.index, None)  # validated by _plan: not again
        raw = apply_overrides(plan.raw, c.overrides(plan.axes)) if sc is None else None
        yield SweepTask(
            c.index,
            raw=raw,
            scenario=sc,
            source=plan.source,
            base_dir=plan.base_dir,
            save_dir=save,
            allow_code=tuple(plan.allow_code),
            lock_token=token if save else None,
        )


def _execute(
    plan: SweepPlan,
    todo: list[SweepCase],
    executor: SweepExecutor,
    rec: _Recorder,
    own: bool,
    out: Path | None,
    series: tuple[str | Literal[False], str | None],
) -> None:
    """Record the invalid cases, run the others on ``executor``, record each as it finishes; then
    close the progress line, the executor (if the sweep made it) and ``summary.csv``.  ``series``:
    (the series format or False, the lock's token or None), see :func:`_tasks`."""
    try:
        rec.open()
        rec.bar.show()
        _run_cases(plan, todo, executor, rec, out, series)
    finally:
        rec.bar.close()
        if own:
            executor.close()
        rec.close()


def _run_cases(
    plan: SweepPlan,
    todo: list[SweepCase],
    executor: SweepExecutor,
    rec: _Recorder,
    out: Path | None,
    series: tuple[str | Literal[False], str | None],
) -> None:
    by_index = {c.index: c for c in plan.cases}
    try:
        for c in todo:
            if c.index in plan.invalid:
                rec.record(c, {"status": "invalid", "error": plan.invalid[c.index], "wall_time_s": 0.0})
        for result in executor.map_unordered(run_case, _tasks(plan, todo, out, *series)):
            rec.record(by_index[result["index"]], result)
    except (KeyboardInterrupt, ScenarioError, OutputError):
        raise
    except Exception as exc:  # the executor itself failed (a worker died, the cluster went away)
        n = len(rec.rows)
        where = f"; the {n} finished cases are in {out / 'summary.csv'}, re-run to resume" if out is not None else ""
        raise SweepExecutionError(
            f"the sweep's executor failed ({type(exc).__name__}: {one_line(exc)}){where}."
        ) from exc
