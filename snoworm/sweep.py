"""Parameter sweeps: run one scenario over a grid (or a zip) of dotted-key values.

A sweep is defined by a base scenario and one or more *axes*, each a dotted scenario key with a
list of values (``--set terrain.xt=0.6:1.0:9 --set tow.force_N=0,100,200``).  Every case is the
base scenario with one value per axis applied exactly as ``snoworm run --set KEY=VALUE`` would,
so a case re-runs on its own with ``snoworm run``.

Data flow
---------
``parse_spec`` -> :class:`Axis` -> :func:`build_cases` (grid or zip, deterministic case ids)
-> every case validated up front (invalid ones are recorded, not run) -> tasks (small plain
dicts: the overridden scenario mapping, never a big object) -> an executor (serial, local
processes or a Dask cluster) running :func:`run_case` -> one row per case, appended to
``summary.csv`` as it finishes -> :class:`SweepTable` sorted by case id.

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

Metrics
-------
See :func:`case_metrics`.  The ``immobilised`` flag: the chain's mean forward ground speed over
the last 25 % of the run is below ``max(0.05 m/s, 5 * terrain.model.sign_eps_mps)``.  The smooth
sign of the terrain resistance (``tanh(V / sign_eps_mps)``) lets a stuck vehicle creep: with the
default ``sign_eps_mps = 0.01 m/s`` a free-rolling FrostyBoy creeps at 0.006 m/s at X_t = 0.5 and
0.032 m/s at X_t = 0.586, while at X_t = 0.59 it already rolls at 0.2 m/s.  Below the threshold
``tanh(V / sign_eps_mps) > tanh(5) = 0.9999``: the terrain resistance is saturated, so the motion
is the regularisation's creep, not rolling.

Extending
---------
An executor is any object with ``map_unordered(fn, tasks)`` yielding ``fn(task)`` results in any
order (and ``close()``); a batched executor (several cases stacked in one solve) can be passed
to :func:`run_sweep` as ``executor=`` without changing anything else.
"""
from __future__ import annotations

import csv
import hashlib
import io
import itertools
import json
import math
import os
import re
import sys
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from ._version import __version__
from .driver import SolverError, simulate
from .fileio import atomic_write_text
from .scenario import Scenario, apply_overrides, read_yaml, scenario_from_dict
from .schema import ScenarioError

__all__ = ["Axis", "Case", "SweepTable", "SweepExecutionError", "parse_spec", "parse_sweep_option", "build_cases",
           "case_metrics", "run_case", "run_sweep", "SerialExecutor", "ProcessExecutor", "DaskExecutor",
           "IMMOBILISED_SPEED_MPS", "IMMOBILISED_SIGN_FACTOR", "LATE_FRACTION", "SLIP_FRACTION",
           "METRIC_COLUMNS", "STATUSES"]

#: Absolute floor of the immobilised speed threshold [m/s].
IMMOBILISED_SPEED_MPS = 0.05
#: The threshold is at least this multiple of ``terrain.model.sign_eps_mps``.
IMMOBILISED_SIGN_FACTOR = 5.0
#: Fraction of the run (at its end) over which the immobilised speed is measured.
LATE_FRACTION = 0.25
#: Fraction of the run (at its end) over which slip is averaged.
SLIP_FRACTION = 0.5

#: Case statuses: ``ok``; ``solver_failure`` (SolverError); ``invalid`` (the case's scenario is
#: rejected, ScenarioError); ``error`` (any other exception in the case, a bug: please report it).
STATUSES = ("ok", "solver_failure", "invalid", "error")

#: Metric columns of ``summary.csv`` (the final link forces come between ``max_link_force_N``
#: and ``energy_per_m_J``, one column ``final_link_force_<j>_N`` per link).
METRIC_COLUMNS = {
    "n_segments": "number of segments N",
    "distance_m": "distance travelled, mean over the segments [m]",
    "mean_speed_mps": "distance_m / duration [m/s]",
    "late_speed_mps": "mean forward ground speed over the segments and the last 25 % of the run [m/s]",
    "mean_slip": "slip (Eq. 1, signed) averaged over the segments and the second half of the run",
    "max_slip": "largest slip (signed) over the segments and the second half of the run",
    "max_link_force_N": "largest |link force| over the links and the whole run (0 for one segment) [N]",
    "energy_per_m_J": "energy used (electrical motor + joint work) per metre travelled [J/m] (empty if no distance)",
    "immobilised": "late_speed_mps < max(0.05 m/s, 5 sign_eps_mps): only smooth-sign creep is left",
}

_MAX_ERROR_CHARS = 500


class SweepExecutionError(RuntimeError):
    """The executor failed (not a case): e.g. a worker process died or the Dask cluster was lost."""


# ---------------------------------------------------------------------------------- specs
@dataclass(frozen=True)
class Axis:
    """One swept key and its values (in the order given)."""

    key: str
    values: tuple
    spec: str = ""


def _parse_scalar(text: str):
    """A number if ``text`` is one (``1e-3`` included), else the YAML value."""
    t = text.strip()
    for conv in (int, float):
        try:
            v = conv(t)
        except ValueError:
            continue
        return v
    return yaml.safe_load(t)


def _split_top_level(text: str):
    """Split at commas outside brackets (so ``[1.8, 1.5],[1.0, 1.0]`` gives two values)."""
    parts, depth, cur = [], 0, []
    for ch in text:
        if ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    parts.append("".join(cur))
    return parts


_RANGE = re.compile(r"^[^,\[\]{}]*:[^,\[\]{}]*:[^,\[\]{}]*$")


def _clean_float(v: float):
    """Round away linspace noise (0.7000000000000001 -> 0.7): 12 significant digits."""
    return float(f"{v:.12g}")


def parse_spec(key: str, spec) -> tuple:
    """Values of one sweep axis from its SPEC.

    Parameters
    ----------
    key : str
        Dotted scenario key (only used in messages).
    spec : str or sequence
        ``"a,b,c"`` (a list; each item a number or a YAML value, brackets allowed for list
        values), ``"start:stop:count"`` (``count`` values from ``start`` to ``stop`` inclusive,
        evenly spaced; whole numbers stay whole when the spacing is whole), a single value, or
        an already-parsed sequence of values.

    Raises
    ------
    ScenarioError
        Empty item, malformed range, non-positive count, duplicate value.
    """
    opt = f"--set {key}={spec}"
    if isinstance(spec, (list, tuple)):
        values = tuple(spec)
    else:
        text = str(spec).strip()
        if not text:
            raise ScenarioError(f"{opt}: no values. Give a list (0,100,200) or a range START:STOP:COUNT (0.3:1.0:15).")
        if _RANGE.match(text):
            values = _parse_range(opt, text)
        else:
            items = _split_top_level(text)
            for it in items:
                if ":" in it and "[" not in it and "{" not in it and _looks_numeric(it.split(":")):
                    raise ScenarioError(f"{opt}: {it.strip()!r} is not a range: a range is START:STOP:COUNT "
                                        "(two colons, no commas; a range cannot be mixed with a list), e.g. 0.3:1.0:15 for 15 values "
                                        "from 0.3 to 1.0.")
            if any(not it.strip() for it in items):
                raise ScenarioError(f"{opt}: empty item in the list. Separate values by single commas, "
                                    "e.g. 0,100,200, with no trailing comma.")
            try:
                values = tuple(_parse_scalar(it) for it in items)
            except yaml.YAMLError as exc:
                raise ScenarioError(f"{opt}: a value is not valid YAML ({getattr(exc, 'problem', exc)}).") from None
    if not values:
        raise ScenarioError(f"{opt}: no values.")
    seen = set()
    for v in values:
        k = _canon(v)
        if k in seen:
            raise ScenarioError(f"{opt}: the value {v!r} appears twice. Give each value once.")
        seen.add(k)
    return values


def _parse_range(opt, text):
    a, b, c = (p.strip() for p in text.split(":"))
    hint = "A range is START:STOP:COUNT, inclusive, e.g. 0.3:1.0:15 for 15 values from 0.3 to 1.0."
    try:
        start, stop = _number(a), _number(b)
    except ValueError:
        raise ScenarioError(f"{opt}: START and STOP must be numbers, got {a!r} and {b!r}. {hint}") from None
    try:
        count = int(c)
    except ValueError:
        raise ScenarioError(f"{opt}: COUNT must be a whole number of values, got {c!r}. {hint}") from None
    if count < 1:
        raise ScenarioError(f"{opt}: COUNT must be at least 1, got {count}. {hint}")
    if count == 1:
        if start != stop:
            raise ScenarioError(f"{opt}: COUNT 1 needs START = STOP; give {start} alone or COUNT >= 2. {hint}")
        return (start,)
    if start == stop:
        raise ScenarioError(f"{opt}: START = STOP with COUNT {count} repeats one value. {hint}")
    if isinstance(start, int) and isinstance(stop, int) and (stop - start) % (count - 1) == 0:
        step = (stop - start) // (count - 1)
        return tuple(start + j * step for j in range(count))
    return tuple(_clean_float(v) for v in np.linspace(float(start), float(stop), count))


def _looks_numeric(parts):
    for p in parts:
        if p.strip():
            try:
                float(p)
            except ValueError:
                return False
    return True


def _number(text):
    try:
        return int(text)
    except ValueError:
        v = float(text)
        if not math.isfinite(v):
            raise ValueError(text)
        return v


def parse_sweep_option(item: str) -> Axis:
    """Split one ``KEY=SPEC`` option into an :class:`Axis`."""
    if not isinstance(item, str) or "=" not in item:
        raise ScenarioError(f"--set {item!r}: expected KEY=SPEC with a dotted scenario key, e.g. "
                            "terrain.xt=0.6:1.0:9 or tow.force_N=0,100,200.")
    key, _, spec = item.partition("=")
    key = key.strip()
    if not key or any(not p.strip() for p in key.split(".")):
        raise ScenarioError(f"--set {item!r}: the key must be a dotted scenario path such as tow.force_N.")
    return Axis(key, parse_spec(key, spec), spec.strip())


def _as_axes(sets) -> list:
    if isinstance(sets, (str, Axis)):
        sets = [sets]
    axes = []
    for s in sets:
        if isinstance(s, Axis):
            axes.append(s)
        elif isinstance(s, str):
            axes.append(parse_sweep_option(s))
        else:
            key, spec = s
            axes.append(Axis(str(key), parse_spec(str(key), spec), spec if isinstance(spec, str) else ""))
    if not axes:
        raise ScenarioError("no --set KEY=SPEC given: a sweep needs at least one key to vary, "
                            "e.g. --set terrain.xt=0.6:1.0:9.")
    keys = [a.key for a in axes]
    for k in keys:
        if keys.count(k) > 1:
            raise ScenarioError(f"--set {k}: the key is given more than once. Put all its values in one SPEC.")
    return axes


# ---------------------------------------------------------------------------------- cases
def _canon(v) -> str:
    """Canonical JSON text of a value (the stable identity of swept values)."""
    return json.dumps(v, sort_keys=True, separators=(",", ":"), default=str)


@dataclass(frozen=True)
class Case:
    """One case: its index in the grid order and one value per axis."""

    index: int
    values: tuple
    case_id: str
    key: str

    def overrides(self, axes):
        return [(a.key, v) for a, v in zip(axes, self.values)]


def build_cases(axes, zip_: bool = False) -> list:
    """All cases of a sweep, in a deterministic order.

    A grid (``itertools.product``, the first axis varying slowest) or, with ``zip_``, the
    element-wise pairing of axes of equal length.  ``case_id`` is the zero-padded index in that
    order; ``key`` is a digest of the keys and values, the identity used for resumption.
    """
    if zip_:
        lens = {a.key: len(a.values) for a in axes}
        if len(set(lens.values())) > 1:
            detail = ", ".join(f"{k} has {n}" for k, n in lens.items())
            raise ScenarioError(f"--zip pairs the values of every --set element by element, so each needs the "
                                f"same number of values; {detail}. Make the lengths equal or drop --zip for a grid.")
        combos = list(zip(*(a.values for a in axes)))
    else:
        combos = list(itertools.product(*(a.values for a in axes)))
    width = max(4, len(str(len(combos) - 1)))
    cases = []
    for j, vals in enumerate(combos):
        digest = hashlib.sha1(_canon([[a.key, v] for a, v in zip(axes, vals)]).encode()).hexdigest()[:12]
        cases.append(Case(j, tuple(vals), f"{j:0{width}d}", digest))
    return cases


# ---------------------------------------------------------------------------------- metrics
def case_metrics(result) -> dict:
    """Scalar metrics of one finished run (the numeric columns of ``summary.csv``).

    Parameters
    ----------
    result : Result
        A finished simulation.

    Returns
    -------
    dict
        ``n_segments``, ``distance_m`` and ``mean_speed_mps`` (as in ``Result.summary()``),
        ``late_speed_mps`` (mean forward ground speed over the segments and the last 25 % of
        the run, from the displacement), ``mean_slip`` and ``max_slip`` (signed slip, mean and
        maximum over the segments and the output samples of the second half of the run),
        ``max_link_force_N`` (largest absolute link force over the whole run, 0 without links),
        ``final_link_forces_N`` (list, tension positive), ``energy_per_m_J`` (total energy of
        ``Result.energy()`` per metre, None if the distance is below 1 micrometre),
        ``immobilised`` (``late_speed_mps`` below ``max(0.05 m/s, 5 sign_eps_mps)``, see the
        module docstring) and ``immobilised_threshold_mps``.
    """
    t = np.asarray(result.t, float)
    x = result.segments["x_m"]
    t0, t1 = float(t[0]), float(t[-1])
    dur = t1 - t0
    dist = float(np.mean(x[-1] - x[0]))
    # late window: displacement-based mean speed (independent of output sampling)
    j_late = int(np.searchsorted(t, t1 - LATE_FRACTION * dur - 1e-9))
    j_late = min(j_late, max(len(t) - 2, 0))
    dt_late = t1 - float(t[j_late])
    late = float(np.mean(x[-1] - x[j_late])) / dt_late if dt_late > 0 else 0.0
    half = t >= t1 - SLIP_FRACTION * dur - 1e-9
    slip = result.segments["slip"][half]
    F = result.links["force_N"]
    e = result.energy()
    eps = result.scenario.terrain.model.sign_eps_mps
    thr = max(IMMOBILISED_SPEED_MPS, IMMOBILISED_SIGN_FACTOR * eps)
    return {
        "n_segments": int(x.shape[1]),
        "distance_m": dist,
        "mean_speed_mps": dist / dur if dur > 0 else 0.0,
        "late_speed_mps": late,
        "mean_slip": float(np.mean(slip)),
        "max_slip": float(np.max(slip)),
        "max_link_force_N": float(np.max(np.abs(F))) if F.size else 0.0,
        "final_link_forces_N": [float(f) for f in F[-1]] if F.size else [],
        "energy_per_m_J": float(e["total_J"] / dist) if dist > 1e-6 else None,
        "immobilised": bool(late < thr),
        "immobilised_threshold_mps": thr,
    }


def _one_line(text: str) -> str:
    text = " | ".join(s.strip() for s in str(text).splitlines() if s.strip())
    return text if len(text) <= _MAX_ERROR_CHARS else text[:_MAX_ERROR_CHARS - 3] + "..."


def run_case(task: dict) -> dict:
    """Run one case (the function executors call; top-level so it pickles).

    Parameters
    ----------
    task : dict
        ``index``, ``raw`` (the scenario mapping with the case's overrides applied),
        ``source``, ``base_dir`` and ``save_dir`` (None, or where to write the time series).

    Returns
    -------
    dict
        ``index``, ``status``, ``error`` and, for ``ok``, the :func:`case_metrics` and
        ``wall_time_s``.  Never raises for a failing case; the time series stay in the worker.
    """
    wall0 = time.perf_counter()
    out = {"index": task["index"], "status": "ok", "error": ""}
    try:
        sc = scenario_from_dict(task["raw"], task.get("source", "scenario"), base_dir=task.get("base_dir"))
        res = simulate(sc)
        out.update(case_metrics(res))
        if task.get("save_dir"):
            res.write(task["save_dir"], plot=False)
        del res
    except ScenarioError as exc:
        out.update(status="invalid", error=_one_line(exc))
    except SolverError as exc:
        out.update(status="solver_failure", error=_one_line(exc))
    except Exception as exc:  # noqa: BLE001 - a case must never stop the sweep
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
        out.update(status="error", error=_one_line(f"{type(exc).__name__}: {exc}{where}"))
    out["wall_time_s"] = time.perf_counter() - wall0
    return out


# ---------------------------------------------------------------------------------- table
def _fmt(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, str):
        return v
    return _canon(v)


def _columns(axes, n_links):
    return (["case_id", "case_key"] + [a.key for a in axes] + ["status", "error"]
            + list(METRIC_COLUMNS)[:7] + [f"final_link_force_{j}_N" for j in range(n_links)]
            + ["energy_per_m_J", "immobilised", "wall_time_s"])


def _parse_cell(col, text, swept):
    if col in ("case_id", "case_key", "status", "error"):
        return text
    if text == "":
        return None
    if col in swept:
        return _parse_scalar(text)
    if col == "n_segments":
        return int(text)
    if col == "immobilised":
        return text == "true"
    return float(text)


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
    """

    def __init__(self, columns, rows, keys=()):
        self.columns = list(columns)
        self.keys = list(keys)
        self.rows = sorted(rows, key=lambda r: r["case_id"])

    def __len__(self):
        return len(self.rows)

    def __iter__(self):
        return iter(self.rows)

    def __getitem__(self, name):
        """A column as a list (``table["mean_speed_mps"]``)."""
        return self.column(name)

    def column(self, name) -> list:
        if name not in self.columns:
            raise KeyError(f"no column {name!r}; columns: {', '.join(self.columns)}")
        return [r.get(name) for r in self.rows]

    def failures(self) -> list:
        """Rows whose status is not ``ok``."""
        return [r for r in self.rows if r["status"] != "ok"]

    def csv_line(self, row) -> str:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow([_fmt(row.get(c)) for c in self.columns])
        return buf.getvalue()

    def to_csv(self, path=None) -> str:
        """The table as CSV text (sorted by case id); written atomically to ``path`` if given."""
        text = ",".join(self.columns) + "\n" + "".join(self.csv_line(r) for r in self.rows)
        if path is not None:
            atomic_write_text(path, text)
        return text

    @classmethod
    def from_csv(cls, path, keys=None):
        """Read a ``summary.csv`` (a truncated last line is ignored)."""
        header, rows, _ = _read_summary(Path(path), keys)
        return cls(header, rows, keys or _keys_from_header(header))

    def __repr__(self):
        ok = sum(r["status"] == "ok" for r in self.rows)
        return f"SweepTable({len(self.rows)} cases, {ok} ok, keys={self.keys})"


def _keys_from_header(header):
    try:
        return header[2:header.index("status")]
    except ValueError:
        return []


def _read_summary(path: Path, keys=None):
    """(header, complete rows, number of dropped lines) of a summary.csv."""
    data = path.read_bytes().decode("utf-8", errors="replace")
    lines = data.split("\n")
    complete, dropped = lines[:-1], (1 if lines[-1] else 0)   # no final newline: truncated
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


# ---------------------------------------------------------------------------------- executors
class SerialExecutor:
    """Run the cases one after the other in this process."""

    def map_unordered(self, fn, tasks):
        for task in tasks:
            yield fn(task)

    def close(self):
        pass


#: Thread-pool variables set to 1 in worker processes (unless the user set them), as Dask does:
#: one multi-threaded OpenBLAS per worker oversubscribes the cores and halved the speed here.
_THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def _exit_with_parent(ppid: int, poll_s: float = 1.0):
    """Worker initializer: one BLAS/OpenMP thread per worker, and exit when the sweep process is
    gone (killed), instead of lingering.

    A forked worker inherits the parent's already started BLAS thread pool, which the
    ``*_NUM_THREADS`` variables no longer reach; ``threadpoolctl`` limits it at run time
    (measured: 2 forked processes at 1.6x serial with the pool as inherited, 1.8-2.0x with one
    thread each).
    """
    import threading

    from threadpoolctl import threadpool_limits
    threadpool_limits(limits=1)

    def watch():
        while True:
            time.sleep(poll_s)
            if os.getppid() != ppid:
                os._exit(1)

    threading.Thread(target=watch, name="snoworm-parent-watch", daemon=True).start()


def _start_method() -> str:
    """How worker processes start: ``fork`` on Linux with Python < 3.12, else ``spawn``.

    A forked worker inherits the imported modules, so it starts in milliseconds instead of the
    ~1 s a spawned one spends importing NumPy/SciPy (measured: 2 processes gave 1.9x the serial
    throughput with fork, 1.6x with spawn, on a 200-case sweep).  Python 3.12 deprecates fork in
    a process with threads (NumPy's BLAS pool counts), and other platforms fork unsafely, so
    those spawn.
    """
    import multiprocessing
    if sys.platform.startswith("linux") and sys.version_info < (3, 12) \
            and "fork" in multiprocessing.get_all_start_methods():
        return "fork"
    return "spawn"


class ProcessExecutor:
    """Run the cases in ``jobs`` local processes (forked or spawned, see :func:`_start_method`).

    At most ``2 * jobs`` cases are in flight, so memory stays flat for any number of cases.
    Workers run with one BLAS/OpenMP thread each (``OMP_NUM_THREADS`` etc. default to 1 while
    the pool lives, unless already set; forked workers also limit the inherited pool).  A script
    calling :func:`run_sweep` with ``jobs > 1`` where workers are spawned needs the usual
    ``if __name__ == "__main__":`` guard.
    """

    def __init__(self, jobs: int):
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor
        self.jobs = int(jobs)
        self._env = {k: os.environ.get(k) for k in _THREAD_ENV}
        for k, v in self._env.items():
            if v is None:
                os.environ[k] = "1"
        self.pool = ProcessPoolExecutor(self.jobs, mp_context=multiprocessing.get_context(_start_method()),
                                        initializer=_exit_with_parent, initargs=(os.getpid(),))

    def map_unordered(self, fn, tasks):
        from concurrent.futures import FIRST_COMPLETED, wait
        it = iter(tasks)
        pending = set()
        for task in itertools.islice(it, 2 * self.jobs):
            pending.add(self.pool.submit(fn, task))
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                nxt = next(it, None)
                if nxt is not None:
                    pending.add(self.pool.submit(fn, nxt))
                yield fut.result()

    def close(self):
        try:
            self.pool.shutdown(wait=True, cancel_futures=True)
        finally:
            for k, v in self._env.items():
                if v is None:
                    os.environ.pop(k, None)


class DaskExecutor:
    """Run the cases on a Dask distributed cluster at ``address`` (``tcp://host:port``).

    The workers need snoworm installed; ``save_cases`` and a relative ``terrain.model_file``
    need a file system shared with the workers.  At most ``4 * workers`` cases are in flight.
    """

    def __init__(self, address):
        try:
            from distributed import Client
        except ImportError:
            raise ScenarioError(f"--scheduler {address}: Dask is not installed. Install it with "
                                "pip install 'snoworm[dask]' (or pip install 'dask[distributed]').") from None
        self.address = address
        try:
            self.client = address if hasattr(address, "submit") else Client(address, timeout="20s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ScenarioError(f"--scheduler {address}: cannot connect to the Dask scheduler ({exc}). "
                                "Check the address (tcp://host:port) and that the scheduler is running.") from None
        self._own = not hasattr(address, "submit")

    def map_unordered(self, fn, tasks):
        from distributed import as_completed
        n_workers = max(len(self.client.scheduler_info().get("workers", {})), 1)
        window = 4 * n_workers
        it = iter(tasks)
        first = [self.client.submit(fn, t, pure=False) for t in itertools.islice(it, window)]
        if not first:
            return
        ac = as_completed(first)
        for fut in ac:
            nxt = next(it, None)
            if nxt is not None:
                ac.add(self.client.submit(fn, nxt, pure=False))
            result = fut.result()
            fut.release()
            yield result

    def close(self):
        if self._own:
            self.client.close()


# ---------------------------------------------------------------------------------- progress
class _Progress:
    """A one-line progress report on a terminal: cases done, failures, time left."""

    def __init__(self, total, already, stream, enabled):
        self.total, self.already, self.stream, self.enabled = total, already, stream, enabled
        self.done = self.failed = 0
        self.t0 = time.perf_counter()
        self._last = 0.0

    def update(self, failed: bool, force=False):
        self.done += 1
        self.failed += int(failed)
        self.show(force)

    def show(self, force=False):
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self._last < 0.1 and self.done + self.already < self.total:
            return
        self._last = now
        n = self.already + self.done
        width = 24
        fill = int(width * n / max(self.total, 1))
        el = now - self.t0
        left = self.total - n
        eta = f"~{_hms(el / self.done * left)} left" if self.done and left else ("done" if not left else "")
        skip = f", {self.already} resumed" if self.already else ""
        self.stream.write(f"\rsweep [{'#' * fill}{'.' * (width - fill)}] {n}/{self.total} cases{skip}, "
                          f"{self.failed} failed, {_hms(el)} elapsed, {eta}   ")
        self.stream.flush()

    def close(self):
        if self.enabled:
            self.show(force=True)
            self.stream.write("\n")
            self.stream.flush()


def _hms(s):
    s = int(round(s))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


# ---------------------------------------------------------------------------------- driver
def _base(scenario):
    """(raw mapping, source name, base_dir) of a path or a Scenario object."""
    if isinstance(scenario, Scenario):
        return scenario.to_dict(), scenario.name, None
    if isinstance(scenario, dict):
        return scenario, "scenario", None
    path = Path(scenario)
    raw = read_yaml(path)
    return raw, str(path), str(path.resolve().parent)


def _definition(raw, axes, zip_):
    return json.loads(json.dumps({
        "scenario_sha256": hashlib.sha256(_canon(raw).encode()).hexdigest(),
        "axes": [{"key": a.key, "values": list(a.values)} for a in axes],
        "zip": bool(zip_),
    }, default=str))


def run_sweep(scenario, sets, out_dir=None, jobs: int = 1, scheduler=None, zip_: bool = False,
              save_cases: bool = False, progress=None, plot: bool = True, executor=None,
              batch: int = 0) -> SweepTable:
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
        definition resumes; with another definition it is refused.  None: nothing is written.
    jobs : int
        Local worker processes (1: run in this process).
    scheduler : str or distributed.Client, optional
        Address of a Dask scheduler (``tcp://host:port``); overrides ``jobs``.
    zip_ : bool
        Pair the axes element by element (equal lengths) instead of a grid.
    save_cases : bool
        Write each case's time series to ``out_dir/cases/<case_id>/`` (needs ``out_dir``).
    progress : bool, optional
        Progress line on stderr; default: only when stderr is a terminal.
    plot : bool
        Write ``sweep.png`` (one varying axis, or zipped axes) or ``heatmap.png`` (two).
    executor : object, optional
        Anything with ``map_unordered(fn, tasks)`` and ``close()``; overrides jobs/scheduler.
    batch : int
        With ``batch > 1`` (and no scheduler or executor): integrate up to ``batch`` cases of the
        same structure as one stacked system (:class:`snoworm.batch.BatchExecutor`, ``jobs``
        processes); other cases run one by one.  Same metrics within the solver tolerance.

    Returns
    -------
    SweepTable
        Every case (resumed and new), sorted by case id.

    Raises
    ------
    ScenarioError
        A malformed SPEC, unequal zip lengths, every case invalid, or an output directory
        holding another sweep.
    """
    axes = _as_axes(sets)
    raw, source, base_dir = _base(scenario)
    if not isinstance(raw, dict):
        raise ScenarioError(f"{source}: a scenario must be a YAML mapping.")
    cases = build_cases(axes, zip_)
    if save_cases and out_dir is None:
        raise ScenarioError("--save-cases needs --out: the time series are written under DIR/cases/.")
    if int(jobs) < 1:
        raise ScenarioError(f"-j/--jobs must be at least 1, got {jobs}.")

    # validate every case up front (about 2 ms each); keep only its link count or its error
    invalid, n_links = {}, 0
    for c in cases:
        try:
            sc = scenario_from_dict(apply_overrides(raw, c.overrides(axes)), source, base_dir=base_dir)
            n_links = max(n_links, sc.vehicle.segments - 1)
        except ScenarioError as exc:
            invalid[c.index] = _one_line(exc)
    if len(invalid) == len(cases):
        first = invalid[cases[0].index]
        raise ScenarioError(f"every case of the sweep is invalid, e.g. case {cases[0].case_id} "
                            f"({', '.join(f'{a.key}={v}' for a, v in zip(axes, cases[0].values))}): {first}")
    columns = _columns(axes, n_links)
    table = SweepTable(columns, [], [a.key for a in axes])
    definition = _definition(raw, axes, zip_)

    out = Path(out_dir) if out_dir is not None else None
    done = {}
    if out is not None:
        done = _prepare_dir(out, definition, columns, cases, axes, source)
    if progress is None:
        progress = sys.stderr.isatty()
    bar = _Progress(len(cases), len(done), sys.stderr, bool(progress))

    rows = dict(done)
    fd = os.open(out / "summary.csv", os.O_WRONLY | os.O_APPEND) if out is not None else None

    def record(c, result):
        row = {"case_id": c.case_id, "case_key": c.key, **dict(zip(table.keys, c.values))}
        row.update(status=result["status"], error=result["error"])
        for m in list(METRIC_COLUMNS)[:7] + ["energy_per_m_J", "immobilised"]:
            row[m] = result.get(m)
        links = result.get("final_link_forces_N") or []
        for j in range(n_links):
            row[f"final_link_force_{j}_N"] = links[j] if j < len(links) else None
        row["wall_time_s"] = result.get("wall_time_s")
        if fd is not None:
            os.write(fd, table.csv_line(row).encode("utf-8"))
            os.fsync(fd)
        rows[c.index] = row
        bar.update(row["status"] != "ok")

    todo = [c for c in cases if c.index not in done]

    def tasks():
        for c in todo:
            if c.index in invalid:
                continue
            save = str(out / "cases" / c.case_id) if save_cases else None
            yield {"index": c.index, "raw": apply_overrides(raw, c.overrides(axes)), "source": source,
                   "base_dir": base_dir, "save_dir": save}

    own = executor is None
    if own:
        if scheduler is not None:
            executor = DaskExecutor(scheduler)
        elif int(batch) > 1:
            from .sweep_batch import BatchExecutor
            executor = BatchExecutor(int(batch), int(jobs), ProcessExecutor(int(jobs)) if int(jobs) > 1 else None,
                                     metrics=case_metrics)
        elif int(jobs) > 1:
            executor = ProcessExecutor(int(jobs))
        else:
            executor = SerialExecutor()
    by_index = {c.index: c for c in cases}
    bar.show(force=True)
    try:
        for c in todo:
            if c.index in invalid:
                record(c, {"status": "invalid", "error": invalid[c.index], "wall_time_s": 0.0})
        for result in executor.map_unordered(run_case, tasks()):
            record(by_index[result["index"]], result)
    except (KeyboardInterrupt, ScenarioError):
        raise
    except Exception as exc:  # the executor itself failed (a worker died, the cluster went away)
        n = len(rows)
        where = f"; the {n} finished cases are in {out / 'summary.csv'}, re-run to resume" if out is not None else ""
        raise SweepExecutionError(f"the sweep's executor failed ({type(exc).__name__}: {_one_line(exc)}){where}.") from exc
    finally:
        bar.close()
        if own:
            executor.close()
        if fd is not None:
            os.close(fd)

    table = SweepTable(columns, [rows[c.index] for c in cases], table.keys)
    if out is not None and plot:
        _plot(table, axes, zip_, out)
    return table


def _prepare_dir(out: Path, definition, columns, cases, axes, source) -> dict:
    """Create or check ``out``; return the rows already finished, by case index."""
    out.mkdir(parents=True, exist_ok=True)
    spath, dpath = out / "summary.csv", out / "sweep.json"
    if dpath.exists():
        try:
            old = json.loads(dpath.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ScenarioError(f"{dpath}: unreadable ({exc}). Use another --out or delete the directory.") from None
        if old.get("definition") != definition:
            what = [k for k in definition if old.get("definition", {}).get(k) != definition[k]]
            raise ScenarioError(f"{out} holds another sweep (its {', '.join(what) or 'definition'} differs from "
                                f"this one, see {dpath}). Re-run the original command to resume it, or give a "
                                "new --out directory.")
    elif spath.exists():
        raise ScenarioError(f"{spath} exists but {dpath} does not, so the sweep it belongs to is unknown. "
                            "Give a new --out directory (or delete the old one).")
    atomic_write_text(dpath, json.dumps({
        "snoworm_version": __version__, "scenario": source, "definition": definition,
        "n_cases": len(cases), "columns": columns,
        "immobilised": METRIC_COLUMNS["immobilised"]}, indent=2) + "\n")
    if not spath.exists():
        atomic_write_text(spath, ",".join(columns) + "\n")
        return {}
    keys = [a.key for a in axes]
    header, rows, dropped = _read_summary(spath, keys)
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
    if dropped:   # rewrite without the truncated or foreign lines, so appends start on a fresh line
        keep = SweepTable(columns, list(done.values()), keys)
        keep.to_csv(spath)
    return done


def _plot_positions(values):
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return [float(v) for v in values], None
    return list(range(len(values))), [_fmt(v) for v in values]


def _plot(table, axes, zip_, out):
    from . import plotting
    varying = [a for a in axes if len(a.values) > 1]
    ok = [r["status"] == "ok" for r in table.rows]
    if zip_ or len(varying) == 1:
        ax = varying[0] if varying else axes[0]
        x, labels = _plot_positions(table.column(ax.key))
        metrics = {m: table.column(m) for m in ("mean_speed_mps", "mean_slip", "max_link_force_N", "energy_per_m_J")}
        plotting.plot_sweep(x, metrics, ax.key, out / "sweep.png", immobilised=table.column("immobilised"),
                            ok=ok, tick_labels=labels)
    elif len(varying) == 2:
        ax_x, ax_y = varying
        xi = {_canon(v): j for j, v in enumerate(ax_x.values)}
        yi = {_canon(v): j for j, v in enumerate(ax_y.values)}
        grid = np.full((len(ax_y.values), len(ax_x.values)), np.nan)
        imm = np.zeros(grid.shape, bool)
        fail = np.zeros(grid.shape, bool)
        for r in table.rows:
            j, k = yi[_canon(r[ax_y.key])], xi[_canon(r[ax_x.key])]
            if r["status"] == "ok":
                grid[j, k] = r["mean_speed_mps"]
                imm[j, k] = bool(r["immobilised"])
            else:
                fail[j, k] = True
        plotting.plot_sweep_heatmap([_fmt(v) for v in ax_x.values], [_fmt(v) for v in ax_y.values], grid,
                                    ax_x.key, ax_y.key, "mean speed [m/s]", out / "heatmap.png",
                                    immobilised=imm, failed=fail)
