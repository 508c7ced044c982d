"""The summary of a sweep: :class:`SweepTable`, ``summary.csv`` and ``sweep.json``, resumption,
and the table's figures.

``summary.csv`` holds one line per finished case (appended as cases finish, in completion
order; cells formatted by :mod:`snoworm.infra.csvwriter` at full precision).  ``sweep.json`` holds the
sweep's definition and columns: :func:`prepare_dir` refuses an output directory holding another
sweep and returns the cases already finished there, dropping a truncated last line.

Figures of the table (:func:`plot_table`, :func:`write_plot`): metrics against the swept value
(one varying key, or a zip) or a heat map of one metric (two keys on a grid).  Used by
:meth:`SweepTable.plot` and by :func:`~snoworm.studies.sweep.run.run_sweep` for ``sweep.<fmt>`` /
``heatmap.<fmt>``.
"""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import warnings
from collections.abc import Collection, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import yaml

from ..._version import __version__
from ...config.schema import ScenarioError, quote
from ...infra.commit import unfinished_commit
from ...infra.csvwriter import FULL, canonical_json, csv_line, csv_text, format_cell, write_csv
from ...infra.folders import MANIFEST, atomic_write_text, folder_state, remove_listed
from ...infra.manifest import STAGE, ManifestProblem, read_small_file
from ...results.frames import require_pandas
from ...results.result import ResultFileError, read_back
from .inputs import changed_inputs
from .metrics import METRIC_COLUMNS
from .series import SERIES_FILE, expected_dims, load_series
from .spec import parse_scalar

if TYPE_CHECKING:
    import pandas
    import xarray
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ...results.result import FigureSize
    from .spec import Axis, SweepCase

__all__ = [
    "SweepTable",
    "summary_columns",
    "read_summary",
    "prepare_dir",
    "load_sweep",
    "plot_table",
    "write_plot",
    "SWEEP_METRICS",
]


#: Largest sweep.json read (bytes): the definition lists every axis value.
MAX_SWEEP_JSON = 64 * 2**20
#: Largest summary.csv read (bytes): 10 kB a row for the most cases a sweep has (100 000).
MAX_SUMMARY_BYTES = 2**30


def summary_columns(axes: Sequence[Axis], n_links: int) -> list[str]:
    """Columns of ``summary.csv``: ids, swept keys, status, metrics, link forces, wall time."""
    return (
        ["case_id", "case_key"]
        + [a.key for a in axes]
        + ["status", "error"]
        + list(METRIC_COLUMNS)[:7]
        + [f"final_link_force_{j}_N" for j in range(n_links)]
        + ["energy_per_m_J", "immobilised", "verdict", "immobilised_at_m", "wall_time_s"]
    )


def _parse_cell(col: str, text: str, swept: Collection[str]) -> Any:
    if col in ("case_id", "case_key", "status", "error"):
        return text
    if col == "verdict":
        return text or None
    if text == "":
        return None
    if col in swept:
        return parse_scalar(text)
    if col == "n_segments":
        return int(text)
    if col == "immobilised":
        return text == "true"
    value = float(text)
    if not math.isfinite(value):  # metrics are finite or empty (None): a NaN or inf is a tampered line
        raise ValueError(f"{col}: non-finite value {text!r}")
    return value


class SweepTable:
    """The summary of a sweep: one row (a dict) per case, sorted by case id.

    Attributes
    ----------
    columns : list of str
        Column names, in ``summary.csv`` order.
    rows : list of dict
        One mapping column -> value per case (None where empty).
    keys : list of str
        The swept keys (columns after ``case_key``).
    out_dir : Path or None
        The sweep's output directory (None for a sweep run without one).
    """

    #: the swept dimensions series.nc must have (set by load_sweep; checked when it is read)
    series_dims: dict[str, int] | None

    def __init__(
        self,
        columns: Iterable[str],
        rows: Iterable[dict[str, Any]],
        keys: Iterable[str] = (),
        out_dir: str | os.PathLike[str] | None = None,
    ) -> None:
        self.columns = list(columns)
        self.keys = list(keys)
        self.rows = sorted(rows, key=lambda r: r["case_id"])
        self.out_dir = Path(out_dir) if out_dir is not None else None
        self.dropped = 0  #: lines of summary.csv dropped when read back (load_sweep)

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return iter(self.rows)

    def __getitem__(self, name: str) -> list:
        """A column as a list (``table["mean_speed_mps"]``)."""
        return self.column(name)

    def column(self, name: str) -> list:
        if name not in self.columns:
            raise KeyError(f"no column {name!r}; columns: {', '.join(self.columns)}")
        return [r.get(name) for r in self.rows]

    def to_pandas(self) -> pandas.DataFrame:
        """The table as a :class:`pandas.DataFrame`, one row per case (sorted by case id), the
        columns of ``summary.csv`` (the swept keys under their dotted names).  Needs pandas
        (``pip install 'snoworm[data]'``)."""
        pd = require_pandas()
        df = pd.DataFrame([[r.get(c) for c in self.columns] for r in self.rows], columns=self.columns)
        df.attrs["keys"] = list(self.keys)
        return df

    def series(self) -> xarray.Dataset:
        """Every case's time series as an :class:`xarray.Dataset` (the sweep's ``series.nc``,
        written by ``run_sweep(..., series="netcdf")``; see :mod:`snoworm.studies.sweep.series`)."""
        path = self.out_dir / SERIES_FILE if self.out_dir is not None else None
        if path is None or not os.path.lexists(path):  # a symlink loop or dangling link: read_series says so
            raise FileNotFoundError(
                f"no {SERIES_FILE} in {self.out_dir}: run the sweep with --save-cases "
                "--series netcdf (series='netcdf') to keep every case's series in one file"
            )
        return load_series(path, getattr(self, "series_dims", None))

    def plot(
        self,
        metric: str | None = None,
        *,
        size: FigureSize | None = None,
        ax: Axes | Sequence[Axes] | None = None,
        fig: Figure | None = None,
    ) -> Figure:
        """The sweep's standard figure (:func:`snoworm.studies.sweep.summary.plot_table`): ``metric``
        (default: speed, slip, link force, energy) against the swept value of a one-key sweep or a
        zip, or a heat map of ``metric`` (default mean speed) over a two-key grid.  ``size``:
        ``"column"``, ``"page"`` or ``"WxH"``; ``ax``/``fig``: yours.  Returns the Figure."""
        return plot_table(self, metric, size=size, ax=ax, fig=fig)

    def failures(self) -> list[dict[str, Any]]:
        """Rows whose status is not ``ok``."""
        return [r for r in self.rows if r["status"] != "ok"]

    def csv_line(self, row: Mapping[str, Any]) -> str:
        """One ``summary.csv`` line (with its newline) of a row."""
        return csv_line([row.get(c) for c in self.columns], FULL)

    def to_csv(self, path: str | os.PathLike[str] | None = None) -> str:
        """The table as CSV text (sorted by case id); written atomically to ``path`` if given."""
        text = csv_text(self.columns, self.rows, FULL)
        if path is not None:
            atomic_write_text(path, text)
        return text

    @classmethod
    def from_csv(cls, path: str | os.PathLike[str], keys: Sequence[str] | None = None) -> SweepTable:
        """Read a ``summary.csv`` (a truncated last line is ignored)."""
        header, rows, _ = read_summary(Path(path), keys)
        return cls(header, rows, keys or _keys_from_header(header))

    def __repr__(self) -> str:
        ok = sum(r["status"] == "ok" for r in self.rows)
        return f"SweepTable({len(self.rows)} cases, {ok} ok, keys={self.keys})"


def load_sweep(out_dir: str | os.PathLike[str]) -> SweepTable:
    """Read a sweep's output directory (``sweep.json`` and ``summary.csv``) back into a :class:`SweepTable`.

    The swept values are parsed as in ``--set`` (numbers stay numbers); a truncated last line of
    an interrupted sweep is ignored.  Lines that do not parse are dropped and reported: a
    :class:`UserWarning` and ``table.dropped`` (their count).  ``table.series()`` opens
    ``series.nc`` when the sweep kept its series there.

    Raises
    ------
    snoworm.results.ResultFileError
        A file missing, not a regular file, malformed, or the two files disagreeing; the message
        names the file.  Or the folder holds an unfinished commit (:mod:`snoworm.infra.commit`).
    """
    out = Path(out_dir)
    spath, dpath = out / "summary.csv", out / "sweep.json"
    if unfinished_commit(out):
        raise ResultFileError(unfinished_commit(out))
    if not spath.is_file() or not dpath.is_file():
        raise ResultFileError(f"{out} is not a sweep's output directory (it needs sweep.json and summary.csv)")
    try:
        doc = json.loads(read_back(dpath, MAX_SWEEP_JSON))
        definition = doc.get("definition", {})
        keys = [a["key"] for a in definition.get("axes", [])] or None
        if keys is not None and not all(isinstance(k, str) for k in keys):
            raise TypeError("axis keys are not text")
        axes = [(a["key"], len(a["values"])) for a in definition.get("axes", [])]
        dims = expected_dims(axes, bool(definition.get("zip"))) if axes else None
    except ResultFileError:
        raise
    except (ValueError, RecursionError, AttributeError, TypeError, KeyError):
        raise ResultFileError(f"{dpath}: not a sweep definition (a JSON object with definition.axes[].key)") from None
    header, rows, dropped = read_summary(spath, keys)
    if header[:2] != ["case_id", "case_key"] or "status" not in header or (keys and header[2 : 2 + len(keys)] != keys):
        raise ResultFileError(f"{spath}: its columns {quote(header)} are not those of the sweep in {dpath}")
    rows, twice = _first_of_each_case(rows)
    table = SweepTable(header, rows, keys or _keys_from_header(header), out_dir=out)
    table.series_dims = dims  # the swept dimensions series.nc must have (checked when it is read)
    table.dropped = dropped + len(twice)
    if dropped:
        warnings.warn(
            f"{spath}: {dropped} line(s) dropped (truncated or malformed); the table holds the {len(rows)} others",
            stacklevel=2,
        )
    if twice:
        warnings.warn(
            f"{spath}: {len(twice)} line(s) repeat a case already listed ({', '.join(twice[:5])}"
            f"{', ...' if len(twice) > 5 else ''}); the first line of each case is kept, the repeats dropped "
            "(as a resume does)",
            stacklevel=2,
        )
    return table


def _first_of_each_case(rows: Iterable[dict[str, Any]]) -> tuple[list[dict[str, Any]], list[str]]:
    """(the first row of each case id, the case ids of the repeated rows dropped)."""
    seen: set = set()
    kept: list[dict[str, Any]] = []
    twice: list[str] = []
    for r in rows:
        if r["case_id"] in seen:
            twice.append(str(r["case_id"]))
        else:
            seen.add(r["case_id"])
            kept.append(r)
    return kept, twice


def _keys_from_header(header: list[str]) -> list[str]:
    try:
        return header[2 : header.index("status")]
    except ValueError:
        return []


def read_summary(path: Path, keys: Sequence[str] | None = None) -> tuple[list[str], list[dict[str, Any]], int]:
    """(header, complete rows, number of dropped lines) of a summary.csv of at most
    :data:`MAX_SUMMARY_BYTES` (ResultFileError naming it otherwise)."""
    try:
        data = read_small_file(path, MAX_SUMMARY_BYTES).decode("utf-8", errors="replace")
    except FileNotFoundError:
        raise ResultFileError(f"{path}: missing") from None
    except ManifestProblem as exc:
        raise ResultFileError(str(exc)) from None
    except MemoryError:
        raise ResultFileError(f"{path}: too large to read in this machine's free memory") from None
    lines = data.split("\n")
    complete, dropped = lines[:-1], (1 if lines[-1] else 0)  # no final newline: truncated
    if not complete:
        return [], [], dropped
    header = next(csv.reader([complete[0]]))
    swept = set(keys if keys is not None else _keys_from_header(header))
    rows = []
    for line in complete[1:]:
        try:
            cells = next(csv.reader([line]))
            if len(cells) != len(header):
                raise ValueError("wrong number of fields")
            rows.append({c: _parse_cell(c, t, swept) for c, t in zip(header, cells)})
        except (ValueError, StopIteration, yaml.YAMLError, csv.Error):
            dropped += 1
    return header, rows, dropped


#: The files a sweep writes at the top of its folder (besides the manifest).
SWEEP_FILES = (
    "summary.csv",
    "sweep.json",
    "sweep.png",
    "heatmap.png",
    "sweep.pdf",
    "heatmap.pdf",
    "sweep.svg",
    "heatmap.svg",
    SERIES_FILE,
)


def _case_entries(out: Path) -> list:
    """The entries of ``out/cases`` a sweep wrote (case folders snoworm wrote, ``.npz`` series);
    raises ScenarioError naming the first other entry (nothing is removed then)."""
    cases = out / "cases"
    if not os.path.lexists(cases):
        return []
    if cases.is_symlink() or not cases.is_dir():
        raise ScenarioError(
            f"{cases} is not a folder snoworm wrote (a symbolic link or a file); nothing was "
            "touched. Move it away or give a new --out directory."
        )
    found = []
    for e in sorted(os.listdir(cases)):
        p = cases / e
        if STAGE in e or ".snoworm-old-" in e:  # a killed writer's staging folder: cleaned when rewritten
            continue
        if p.is_symlink():
            ok = False
        elif p.is_dir():
            ok = folder_state(p) in ("snoworm", "empty")
        else:
            ok = p.is_file() and e.endswith(".npz")
        if not ok:
            raise ScenarioError(
                f"{p} was not written by this sweep (a symbolic link, or a file or folder without "
                f"snoworm's {MANIFEST}); nothing was touched. Move it away or give a new --out "
                "directory."
            )
        found.append(p)
    return found


def _clear(out: Path) -> None:
    """Remove an earlier snoworm folder's files: its manifest's (checked, see :mod:`snoworm.infra.manifest`),
    a sweep's own files and case folders; an entry snoworm did not write stops it before anything
    is removed (ScenarioError)."""
    cases = _case_entries(out)
    remove_listed(out)
    for name in SWEEP_FILES + (MANIFEST,):
        p = out / name
        if p.is_symlink() or p.is_file():
            p.unlink()
    for p in cases:
        if p.is_dir():
            shutil.rmtree(p)
        else:
            p.unlink()
    try:
        os.rmdir(out / "cases")
    except OSError:  # missing, or a killed writer's staging folder is left in it
        pass


def check_resumable(out: Path) -> None:
    """Refuse (ScenarioError) a sweep folder whose files or case folders snoworm would write
    through: a symlink, FIFO or device at ``summary.csv``, ``sweep.json`` or the manifest, or a
    symlink at ``cases/`` or a case folder."""
    for name in ("summary.csv", "sweep.json", MANIFEST):
        p = out / name
        if os.path.lexists(p) and (p.is_symlink() or not p.is_file()):
            raise ScenarioError(
                f"{p} is not a regular file (a symbolic link, a folder, a FIFO or a device); "
                "snoworm will not read or write through it. Give a new --out directory."
            )
    _case_entries(out)


def _other_sweep(out: Path, dpath: Path, old: Any, new: dict[str, Any]) -> str:
    """Why ``out``'s sweep (definition ``old``) cannot be resumed by this one (``new``)."""
    old = old if isinstance(old, dict) else {}
    if all(old.get(k) == new[k] for k in new if k not in ("inputs", "snoworm_version")):
        changed = changed_inputs(old.get("inputs"), new.get("inputs"))
        why = (
            f"{quote(changed[0], 200)} changed since it ran"
            + (f" (and {len(changed) - 1} more file(s))" if len(changed) > 1 else "")
            if changed
            else f"it was run by snoworm {quote(old.get('snoworm_version'), 40)}, this is {new.get('snoworm_version')}"
        )
        return (
            f"{out} holds this sweep run from other inputs: {why}, so its rows would mix old and new results. "
            "Pass --restart (restart=True in Python) to run it afresh (its rows are removed), or give a new "
            "--out directory."
        )
    what = [k for k in new if old.get(k) != new[k]]
    return (
        f"{out} holds another sweep (its {', '.join(what) or 'definition'} differs from this one, see {dpath}). "
        "Re-run the original command to resume it, give a new --out directory, or pass --overwrite to replace it."
    )


def prepare_dir(
    out: Path,
    definition: dict[str, Any],
    columns: Sequence[str],
    cases: Sequence[SweepCase],
    axes: Sequence[Axis],
    source: str,
    overwrite: bool = False,
) -> dict[int, dict[str, Any]]:
    """Create or check ``out``; return the rows already finished, by case index.

    A folder written by another snoworm command is cleared first; one holding another sweep is
    refused, or cleared if ``overwrite``.
    """
    out.mkdir(parents=True, exist_ok=True)
    spath, dpath = out / "summary.csv", out / "sweep.json"
    check_resumable(out)
    if not dpath.exists() and folder_state(out) == "snoworm":
        _clear(out)
    if dpath.exists() and overwrite:
        try:
            same = json.loads(read_small_file(dpath, MAX_SWEEP_JSON)).get("definition") == definition
        except (OSError, ValueError, AttributeError, RecursionError):
            same = False
        if not same:
            _clear(out)
    if dpath.exists():
        try:
            old = json.loads(read_small_file(dpath, MAX_SWEEP_JSON))
            if not isinstance(old, dict):
                raise ValueError("not a JSON object")
        except (OSError, ValueError, RecursionError) as exc:
            raise ScenarioError(f"{dpath}: unreadable ({exc}). Use another --out or delete the directory.") from None
        if old.get("definition") != definition:
            raise ScenarioError(_other_sweep(out, dpath, old.get("definition"), definition))
    elif spath.exists():
        raise ScenarioError(
            f"{spath} exists but {dpath} does not, so the sweep it belongs to is unknown. "
            "Give a new --out directory (or delete the old one)."
        )
    atomic_write_text(
        dpath,
        json.dumps(
            {
                "snoworm_version": __version__,
                "scenario": source,
                "definition": definition,
                "n_cases": len(cases),
                "columns": columns,
                "immobilised": METRIC_COLUMNS["immobilised"],
            },
            indent=2,
        )
        + "\n",
    )
    if not spath.exists():
        write_csv(spath, columns, [], FULL)
        return {}
    keys = [a.key for a in axes]
    header, rows, dropped = read_summary(spath, keys)
    if header != columns:
        raise ScenarioError(f"{spath}: its columns differ from this sweep's. Give a new --out directory.")
    by_id = {c.case_id: c for c in cases}
    done = {}
    for r in rows:
        c = by_id.get(r["case_id"])
        if c is None or c.key != r["case_key"] or c.index in done:
            dropped += 1
            continue
        r.update(dict(zip(keys, c.values)))
        done[c.index] = r
    if dropped:  # rewrite without the truncated or foreign lines, so appends start on a fresh line
        keep = SweepTable(columns, list(done.values()), keys)
        keep.to_csv(spath)
    return done


# ------------------------------------------------------------------------- figures of the table
#: The metrics drawn against a one-axis (or zip) sweep, a panel each.
SWEEP_METRICS = ("mean_speed_mps", "mean_slip", "max_link_force_N", "energy_per_m_J")


def _distinct(values: Iterable[Any]) -> list:
    """Distinct values in order of first appearance (the rows are in case-id order, so a grid's
    values come back in the order of the sweep's definition)."""
    seen: set[str] = set()
    out: list = []
    for v in values:
        key = canonical_json(v)
        if key not in seen:
            seen.add(key)
            out.append(v)
    return out


def _positions(values: Sequence[Any]) -> tuple[list[float], list[str] | None]:
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return [float(v) for v in values], None
    return list(range(len(values))), [format_cell(v, FULL) for v in values]


def _layout(table: SweepTable) -> tuple[str, Any]:
    """("line", key) for one varying key or a zip; ("heatmap", (key_x, key_y)) for a two-key grid."""
    varying = [k for k in table.keys if len(_distinct(table.column(k))) > 1] or list(table.keys[:1])
    counts = [len(_distinct(table.column(k))) for k in varying]
    grid = len(varying) == 2 and counts[0] * counts[1] == len(table.rows)
    if grid:
        return "heatmap", tuple(varying)
    if len(varying) > 2 and int(np.prod(counts)) == len(table.rows):
        raise ValueError(
            f"a sweep over {len(varying)} keys on a grid has no standard figure; "
            "pick two keys with table.to_pandas() and plotting.plot_sweep_heatmap"
        )
    return "line", varying[0]


def plot_table(
    table: SweepTable,
    metric: str | None = None,
    *,
    size: FigureSize | None = None,
    ax: Axes | Sequence[Axes] | None = None,
    fig: Figure | None = None,
) -> Figure:
    """The standard figure of a sweep: ``metric`` (default: the four of :data:`SWEEP_METRICS`)
    against the swept value for one varying key or a zip (immobilised cases crossed, failed ones
    dotted), or a heat map of ``metric`` (default ``mean_speed_mps``) over a two-key grid.
    ``size``, ``ax``, ``fig``: as for every plotting function.  Returns the Figure."""
    from ... import plotting  # lazy: matplotlib costs ~0.5 s to import; sweeps without plots never pay it

    kind, keys = _layout(table)
    ok = [r["status"] == "ok" for r in table.rows]
    if kind == "line":
        x, labels = _positions(table.column(keys))
        names = [metric] if isinstance(metric, str) else list(metric or SWEEP_METRICS)
        return plotting.plot_sweep(
            x,
            {m: table.column(m) for m in names},
            keys,
            immobilised=table.column("immobilised"),
            ok=ok,
            tick_labels=labels,
            size=size,
            ax=ax,
            fig=fig,
        )
    metric = metric or "mean_speed_mps"
    kx, ky = keys
    xs, ys = _distinct(table.column(kx)), _distinct(table.column(ky))
    xi = {canonical_json(v): j for j, v in enumerate(xs)}
    yi = {canonical_json(v): j for j, v in enumerate(ys)}
    grid = np.full((len(ys), len(xs)), np.nan)
    imm = np.zeros(grid.shape, bool)
    fail = np.zeros(grid.shape, bool)
    for r in table.rows:
        j, k = yi[canonical_json(r[ky])], xi[canonical_json(r[kx])]
        if r["status"] == "ok":
            grid[j, k] = np.nan if r.get(metric) is None else r[metric]
            imm[j, k] = bool(r["immobilised"])
        else:
            fail[j, k] = True
    return plotting.plot_sweep_heatmap(
        [format_cell(v, FULL) for v in xs],
        [format_cell(v, FULL) for v in ys],
        grid,
        kx,
        ky,
        plotting.quantity_label(metric),
        immobilised=imm,
        failed=fail,
        size=size,
        ax=ax,
        fig=fig,
    )


def write_plot(table: SweepTable, out: Path, plot_format: str = "png", size: FigureSize | None = None) -> Path | None:
    """Write the sweep's standard figure (headless) as ``sweep.<fmt>`` (line) or
    ``heatmap.<fmt>`` (grid of two keys) in ``out``; nothing for a grid of more keys.
    Returns the path or None."""
    from ... import plotting  # lazy: matplotlib costs ~0.5 s to import; sweeps without plots never pay it

    try:
        kind, _ = _layout(table)
    except ValueError:
        return None
    name = "sweep" if kind == "line" else "heatmap"
    return plotting.write_figure(
        out / f"{name}.{plot_format}", lambda size=None: plot_table(table, size=size), fmt=plot_format, size=size
    )
