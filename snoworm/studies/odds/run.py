"""``snoworm.odds``: the odds of getting through (docs/odds.md).

Data flow: the scenario (its ``uncertainty:`` section, ``--vary``, ``--xt-field``, ``--calibration``,
``--set``) -> :class:`~snoworm.studies.odds.inputs.Uncertainty` -> the draws
(:mod:`~snoworm.studies.odds.sampling`) -> per draw and strategy a task, run on the sweep's executors
(serial, ``-j`` processes, Dask; :mod:`snoworm.studies.sweep.executors`) with ``transient`` fidelity,
or the steady screen (:mod:`~snoworm.studies.odds.screen`) -> one row per draw and strategy, appended
to ``samples.csv`` as it finishes (resumable: a re-run of the same study skips the rows there) ->
``odds.json`` (P(go) with Wilson intervals, percentiles, Sobol indices) and the figures.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import sys
from collections.abc import Iterable, Sequence
from contextlib import ExitStack
from dataclasses import dataclass, field as dc_field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import pandas
    from numpy.typing import NDArray

    from ...config.scenario import Scenario
    from ..sweep.run import SweepExecutor

from ..._version import __version__
from ...config.scenario import apply_overrides, parse_set_option, scenario_from_dict
from ...config.schema import ScenarioError, quote
from ...infra.commit import finish_commit
from ...infra.csvwriter import FULL, canonical_json, csv_line, write_csv
from ...infra.files import read_regular_file
from ...infra.folders import (
    OutputError,
    atomic_write_text,
    check_output_folder,
    folder_lock,
    os_error_message,
    remove_listed,
    write_manifest,
)
from ...infra.progress import Progress
from ...modes.codeload import allowed_paths
from ...modes.controller import trust_problem_of
from ..sweep.executors import DaskExecutor, ProcessExecutor, SerialExecutor, SweepExecutionError
from ..sweep.metrics import one_line
from ..sweep.run import _base
from . import screen
from .inputs import Uncertainty, parse_vary, parse_xt_field, read_calibration, uncertainty_from_section
from .outcome import OUTCOME_COLUMNS, STRATEGIES, OddsTask, goal_of, run_draw, strategy_raw
from .sampling import Design, design
from .stats import PERCENTILES, percentiles, sobol, wilson

__all__ = ["odds", "OddsResult", "FIDELITIES", "MAX_DRAWS", "DEFINITION_FILE", "summary_text", "load_odds"]

#: ``--fidelity``: simulate every draw, or screen it with the steady states (docs/odds.md).
FIDELITIES = ("transient", "steady")

#: Most draws times strategies of one study (as many as the cases of one sweep).
MAX_DRAWS = 1_000_000

#: The study's definition in its folder: a re-run with the same one resumes.
DEFINITION_FILE = "odds_definition.json"

#: Outputs whose Sobol indices ``--sensitivity`` computes.
SOBOL_OUTPUTS = ("go", "speed_made_good_mps")


@dataclass
class OddsResult:
    """An odds study: ``rows`` (one per draw and strategy, the columns of ``samples.csv``), ``summary``
    (the contents of ``odds.json``) and ``text`` (the printed summary, in field terms)."""

    rows: list
    summary: dict
    text: str
    columns: list
    out_dir: Path | None = None
    figures: list = dc_field(default_factory=list)

    def to_pandas(self) -> pandas.DataFrame:
        """``samples.csv`` as a pandas DataFrame."""
        import pandas as pd  # lazy: optional at import time (results.frames does the same)

        return pd.DataFrame(self.rows, columns=self.columns)

    def p_go(self, strategy: str) -> float:
        return self.summary["strategies"][strategy]["p_go"]

    def __repr__(self) -> str:
        return f"OddsResult({self.text!r})"


# ------------------------------------------------------------------------------------- the plan
@dataclass
class _Plan:
    raw: dict
    source: str
    base_dir: str | None
    sc: Scenario
    unc: Uncertainty
    strategies: list
    strategy_raws: dict
    goal_m: float | None
    dsg: Design
    values: dict  # path -> array over draws
    columns: list
    definition: dict
    method: str = "random"
    seed: int = 0
    fidelity: str = "transient"
    sensitivity: bool = False
    allow_code: tuple = ()


def _scenario_and_section(scenario, sets):
    raw, source, base_dir = _base(scenario)
    if not isinstance(raw, dict):
        raise ScenarioError(f"{source}: a scenario must be a YAML mapping.")
    raw = dict(raw)
    section = raw.pop("uncertainty", None)
    ov = [parse_set_option(s) if isinstance(s, str) else tuple(s) for s in sets]
    if ov:
        raw = apply_overrides(raw, ov)
    sc = scenario_from_dict(raw, source, base_dir=base_dir)
    return raw, source, base_dir, sc, section, {k for k, _ in ov}


def _uncertainty(sc, section, base_dir, vary, xt_field, calibration, fixed) -> Uncertainty:
    sec = uncertainty_from_section(section, base_dir)
    scalars = {s.path: s for s in sec["vary"]}
    for item in vary:
        s = parse_vary(item) if isinstance(item, str) else item
        scalars[s.path] = s
    scalars = [s.bounded(sc) for p, s in scalars.items() if p not in fixed]  # --set fixes an input
    fld = parse_xt_field(xt_field) if isinstance(xt_field, (str, dict)) else (xt_field or sec["xt_field"])
    if fld is not None:
        prof = sc.terrain.compile()
        vals = np.asarray(prof.values if hasattr(prof, "values") else [prof(np.zeros(1))[0]], float)
        fld.check_mean(float(np.min(vals)), float(np.max(vals)))
    cal = calibration if calibration is not None else sec["calibration"]
    cal = read_calibration(cal) if isinstance(cal, (str, os.PathLike)) else cal
    clash = sorted(f"terrain.model.{n}" for n in (cal.names if cal else ()) if f"terrain.model.{n}" in fixed)
    if clash:  # fixing one of jointly drawn coefficients would change the others' distribution too
        raise ScenarioError(
            f"--set {clash[0]}: --calibration draws this coefficient jointly with {', '.join(cal.names)}; fixing it "
            "alone is not the calibration's distribution. Leave it out of --set, or calibrate without fitting it."
        )
    unc = Uncertainty(tuple(scalars), fld, cal)
    if unc.is_empty():
        raise ScenarioError(
            "odds: no uncertain input. Give at least one of --vary PATH=DIST:PARAMS (e.g. terrain.xt=normal:0.8:0.05), "
            "--xt-field sd=SD,corr=METRES, --calibration FOLDER, or an 'uncertainty:' section in the scenario."
        )
    return unc


def _columns(unc, strategies) -> list:
    inputs = [f"{k}" for g in unc.groups if g.dim for k in g.values(np.full((1, g.dim), 0.5))]
    return ["draw", "strategy", *inputs, *(["xt_field_seed"] if unc.xt_field else []), *OUTCOME_COLUMNS]


def _plan(
    scenario,
    sets,
    vary,
    xt_field,
    calibration,
    samples,
    method,
    seed,
    strategies,
    sensitivity,
    fidelity,
    goal_m,
    rolling_speed,
) -> _Plan:  # noqa: PLR0913
    raw, source, base_dir, sc, section, fixed = _scenario_and_section(scenario, sets)
    unc = _uncertainty(sc, section, base_dir, vary, xt_field, calibration, fixed)
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 1:
        raise ScenarioError(f"--samples: must be a whole number of draws >= 1, got {quote(samples)}.")
    if fidelity not in FIDELITIES:
        raise ScenarioError(f"--fidelity: expected one of {', '.join(FIDELITIES)}, got {quote(fidelity)}.")
    strategies = list(strategies or ["scenario"])
    for s in strategies:
        if s not in STRATEGIES:
            raise ScenarioError(f"--strategy: unknown strategy {quote(s)}; expected one of {', '.join(STRATEGIES)}.")
    if len(set(strategies)) != len(strategies):
        raise ScenarioError(f"--strategy: a strategy is named twice ({', '.join(strategies)}).")
    sraw = {s: strategy_raw(raw, sc, s, rolling_speed) for s in strategies}
    for s, r in sraw.items():  # every strategy's scenario valid before anything runs
        scenario_from_dict(r, f"{source} ({s})", base_dir=base_dir)
    dsg = design(unc, int(samples), method, int(seed), sensitivity)
    if dsg.n_draws * len(strategies) > MAX_DRAWS:
        raise ScenarioError(
            f"--samples: {dsg.n_draws} draws x {len(strategies)} strategies is over the {MAX_DRAWS} of one study; "
            "use fewer draws."
        )
    goal = goal_of(sc, goal_m)
    if goal is not None and not goal > 0:
        raise ScenarioError(f"--goal-m: the end of the route must lie ahead of the start (> 0 m), got {goal:g} m.")
    definition = json.loads(
        json.dumps(
            {
                "scenario_sha256": hashlib.sha256(canonical_json(raw).encode()).hexdigest(),
                "inputs": unc.describe(),
                "samples": int(samples),
                "method": method,
                "seed": int(seed),
                "strategies": strategies,
                "sensitivity": bool(sensitivity),
                "fidelity": fidelity,
                "goal_m": goal,
                "rolling_speed": rolling_speed,
                "snoworm_version": __version__,
            },
            default=str,
        )
    )
    return _Plan(
        raw,
        source,
        base_dir,
        sc,
        unc,
        strategies,
        sraw,
        goal,
        dsg,
        unc.values(dsg.U),
        _columns(unc, strategies),
        definition,
        method,
        int(seed),
        fidelity,
        bool(sensitivity),
    )


# ------------------------------------------------------------------------------------- the files
def _read_rows(path: Path, columns) -> dict:
    """Rows already in ``samples.csv`` by index (draw * strategies + strategy); a truncated last line is dropped."""
    text = read_regular_file(path, 2**31).decode("utf-8")
    lines = text.splitlines(keepends=True)
    if lines and not lines[-1].endswith("\n"):
        lines = lines[:-1]
    reader = csv.reader(io.StringIO("".join(lines)))
    header = next(reader, None)
    if header != columns:
        raise ScenarioError(f"{path}: its columns differ from this study's. Give a new --out directory.")
    rows = {}
    for cells in reader:
        if len(cells) != len(columns):
            continue
        rows[(int(cells[0]), cells[1])] = {c: _cell(c, v) for c, v in zip(columns, cells)}
    return rows


def _cell(col, text):
    if col in ("strategy", "status", "verdict", "error"):
        return text
    if text == "":
        return None
    v = float(text)
    return int(v) if col in ("draw", "go", "xt_field_seed") else v


def _prepare(out: Path, plan: _Plan, overwrite: bool) -> dict:
    """Create or check ``out``; return the rows already there (resume)."""
    dpath, spath = out / DEFINITION_FILE, out / "samples.csv"
    same = False
    if dpath.exists():
        try:
            same = json.loads(read_regular_file(dpath, 2**24)).get("definition") == plan.definition
        except (OSError, ValueError, AttributeError):
            same = False
        if not same and not overwrite:
            raise ScenarioError(
                f"{out} holds another odds study (other scenario, inputs, draws or strategies): give another --out, "
                "or --overwrite to replace it."
            )
    if not same:
        remove_listed(out)
        for p in (dpath, spath):
            if p.exists():
                p.unlink()
    atomic_write_text(
        dpath, json.dumps({"snoworm_version": __version__, "definition": plan.definition}, indent=2) + "\n"
    )
    if not spath.exists():
        write_csv(spath, plan.columns, [], FULL)
        return {}
    done = _read_rows(spath, plan.columns)
    write_csv(spath, plan.columns, list(done.values()), FULL)  # without a truncated line: appends start fresh
    return done


class _Recorder:
    """Each finished draw: a row kept, appended to ``samples.csv`` (one write and fsync), counted on the progress line."""

    def __init__(self, plan, rows, out, bar, lease):
        self.plan, self.rows, self.bar, self.lease = plan, rows, bar, lease
        self.fd = None
        if out is not None:
            self.fd = os.open(out / "samples.csv", os.O_WRONLY | os.O_APPEND | getattr(os, "O_NOFOLLOW", 0))

    def record(self, key, row):
        if self.lease is not None:
            self.lease.check("running an odds study in")
        if self.fd is not None:
            try:
                os.write(self.fd, csv_line([row.get(c) for c in self.plan.columns], FULL).encode("utf-8"))
                os.fsync(self.fd)
            except OSError as exc:
                raise OutputError(
                    f"cannot append to samples.csv: {os_error_message(exc)}; the finished draws are kept, re-run the "
                    "same command to resume."
                ) from None
        self.rows[key] = row
        self.bar.set(len(self.rows), info=f"{sum(r['status'] != 'ok' for r in self.rows.values())} failed")

    def close(self):
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


def _row(plan: _Plan, k: int, strategy: str, result: dict) -> dict:
    row = {"draw": k, "strategy": strategy}
    row.update({p: float(v[k]) for p, v in plan.values.items()})
    if plan.unc.xt_field:
        row["xt_field_seed"] = int(plan.dsg.field_seeds[k])
    row.update({c: result.get(c) for c in OUTCOME_COLUMNS})
    return row


def _tasks(plan: _Plan, todo):
    n_s = len(plan.strategies)
    for k, s in todo:
        yield OddsTask(
            k * n_s + plan.strategies.index(s),
            plan.strategy_raws[s],
            {p: float(v[k]) for p, v in plan.values.items()},
            plan.unc.xt_field,
            int(plan.dsg.field_seeds[k]),
            plan.goal_m,
            plan.source,
            plan.base_dir,
            plan.allow_code,
        )


def _make_executor(jobs, scheduler):
    if scheduler is not None:
        return DaskExecutor(scheduler)
    if int(jobs) > 1:
        return ProcessExecutor(int(jobs))
    return SerialExecutor()


def _execute(plan: _Plan, todo, rec: _Recorder, executor, out):
    n_s = len(plan.strategies)
    if plan.fidelity == "steady":
        for (k, s), res in screen.screen_draws(plan, todo, executor, out):
            rec.record((k, s), _row(plan, k, s, res))
        return
    try:
        for res in executor.map_unordered(run_draw, _tasks(plan, todo)):
            k, s = divmod(res["index"], n_s)
            rec.record((k, plan.strategies[s]), _row(plan, k, plan.strategies[s], res))
    except (KeyboardInterrupt, ScenarioError, OutputError):
        raise
    except Exception as exc:  # the executor itself failed (a worker died, the cluster went away)
        raise SweepExecutionError(
            f"the odds study's executor failed ({type(exc).__name__}: {one_line(exc)}); the {len(rec.rows)} finished "
            "draws are in samples.csv, re-run to resume."
        ) from exc


# ------------------------------------------------------------------------------------- the summary
def _strategy_summary(plan: _Plan, rows: list) -> dict:
    ok = [r for r in rows if r["status"] == "ok"]
    k = sum(int(r["go"]) for r in ok)
    n = len(ok)
    lo, hi = wilson(k, n)
    stuck = [r for r in ok if not r["go"] and r["verdict"] == "immobilised"]
    return {
        "p_go": k / n if n else None,
        "p_go_ci": [lo, hi],
        "n": n,
        "n_go": k,
        "n_failed": len(rows) - n,
        "time_s": percentiles(r["time_s"] for r in ok if r["go"]),
        "speed_made_good_mps": percentiles(r["speed_made_good_mps"] for r in ok),
        "energy_per_m_J": percentiles(r["energy_per_m_J"] for r in ok if r["go"]),
        "n_immobilised": len(stuck),
        "n_out_of_time": sum(1 for r in ok if not r["go"] and r["verdict"] != "immobilised"),
        "stop_m": percentiles(r["stop_m"] for r in stuck),
        "stop_xt": percentiles(r["stop_xt"] for r in stuck),
        "stop_grade_deg": percentiles(r["stop_grade_deg"] for r in stuck),
    }


def _sobol_summary(plan: _Plan, by_strategy: dict, seed: int) -> dict:
    out = {}
    for s, rows in by_strategy.items():
        rows = sorted(rows, key=lambda r: r["draw"])
        if len(rows) != plan.dsg.n_draws or any(r["status"] != "ok" for r in rows):
            out[s] = {"note": "not computed: some draws have no outcome (see samples.csv's status)"}
            continue
        per = {}
        for o in SOBOL_OUTPUTS:
            f = np.array([float(r[o]) if r[o] is not None else np.nan for r in rows])
            per[o] = sobol(f, plan.dsg, seed=seed)
        out[s] = per
    return out


def _pct(v: float) -> str:
    """A proportion in per cent, with a decimal where whole per cents would round it to 0 or 100."""
    return f"{100 * v:.1f}" if (0 < v < 0.005 or 0.995 < v < 1) else f"{100 * v:.0f}"


def summary_text(summary: dict) -> str:
    """The printed summary, in field terms (docs/odds.md)."""
    parts, n_all = [], None
    for s, st in summary["strategies"].items():
        if st["p_go"] is None:
            parts.append(f"{s}: no draw has an outcome")
            continue
        lo, hi = st["p_go_ci"]
        n_all = st["n"]
        parts.append(f"{s} gets through in {_pct(st['p_go'])} % of {st['n']:,} draws ({_pct(lo)}-{_pct(hi)} %)")
    lines = ["; ".join(parts) + "."]
    for s, st in summary["strategies"].items():
        if st.get("stop_m"):
            where = f"{s}: most stops between {st['stop_m']['p5']:.0f} and {st['stop_m']['p95']:.0f} m"
            g, x = st.get("stop_grade_deg"), st.get("stop_xt")
            if g and x:
                where += f" (grade {g['p50']:.0f} deg, X_t {x['p5']:.2f}-{x['p95']:.2f})"
            lines.append(where + ".")
        if st.get("n_out_of_time"):
            lines.append(
                f"{s}: {st['n_out_of_time']} draws were still moving at the end of the run, short of the end of the "
                "route (counted as not getting through; lengthen simulation.duration_s)."
            )
    for s, per in (summary.get("sobol") or {}).items():
        go = per.get("go") if isinstance(per, dict) else None
        if go and any(v["total"] for v in go.values()):  # no variance (all go or all stop): nothing to apportion
            top = max(go, key=lambda g: go[g]["total"] if go[g]["total"] is not None else -1)
            if go[top]["first"] is not None:
                lines.append(
                    f"{s}: {top} explains {100 * go[top]['first']:.0f} %{_ci_text(go[top]['first_ci'])} of the "
                    f"variance of getting through alone, {100 * go[top]['total']:.0f} % with its interactions."
                )
    if n_all is not None and summary.get("goal_m") is None:
        lines.append("(no end of route: 'gets through' means not immobilised by the end of the run)")
    return "\n".join(lines)


def _ci_text(ci) -> str:
    if ci is None or any(v is None for v in ci):
        return ""
    return f" ({100 * ci[0]:.0f}-{100 * ci[1]:.0f} %)"


def _summary(plan: _Plan, rows: dict) -> dict:
    method, seed, fidelity, sensitivity = plan.method, plan.seed, plan.fidelity, plan.sensitivity
    indep = plan.dsg.independent
    by_s = {s: [r for (k, s2), r in rows.items() if s2 == s] for s in plan.strategies}
    strategies = {s: _strategy_summary(plan, [r for r in by_s[s] if indep[r["draw"]]]) for s in plan.strategies}
    doc = {
        "snoworm_version": __version__,
        "scenario": plan.sc.name,
        "goal_m": plan.goal_m,
        "fidelity": fidelity,
        "method": method,
        "seed": int(seed),
        "n_draws": int(plan.dsg.n_draws),
        "n_independent": int(indep.sum()),
        "percentiles": list(PERCENTILES),
        "inputs": plan.unc.describe(),
        "strategies": strategies,
        "model_error": "not sampled: P(go) is the probability under the model, given these input distributions",
    }
    if sensitivity:
        doc["sobol"] = _sobol_summary(plan, by_s, seed)
    return doc


# ------------------------------------------------------------------------------------- the entry
def odds(  # noqa: PLR0913 - the options of `snoworm odds`, one keyword each
    scenario: str | os.PathLike[str] | Scenario | dict[str, Any],
    *,
    vary: str | Sequence[str] = (),
    xt_field: str | None = None,
    calibration: str | os.PathLike[str] | None = None,
    sets: str | Sequence[str] = (),
    samples: int = 1000,
    method: str = "random",
    seed: int = 0,
    strategies: str | Sequence[str] | None = None,
    sensitivity: bool = False,
    fidelity: str = "transient",
    goal_m: float | None = None,
    rolling_speed: float | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
    executor: SweepExecutor | None = None,
    overwrite: bool = False,
    plot: bool = True,
    plot_format: str = "png",
    progress: bool | None = None,
    allow_code: Iterable[str | os.PathLike[str]] = (),
    command: str | None = None,
) -> OddsResult:
    """The odds of getting through: sample the uncertain inputs, run each draw for each strategy, estimate P(go).

    Parameters
    ----------
    scenario : str, Path, Scenario or dict
        The scenario (a YAML path or a shipped scenario's name; its ``uncertainty:`` section is read).
    vary : sequence of str
        ``PATH=DIST:PARAMS`` (``terrain.xt=normal:0.8:0.05``; distributions in
        :data:`~snoworm.studies.odds.inputs.DISTRIBUTIONS`), added to (or replacing) the section's.
    xt_field : str, optional
        ``sd=SD,corr=METRES``: a random X_t field around the route's X_t (docs/odds.md).
    calibration : str or Path, optional
        A ``snoworm calibrate`` output folder: its coefficients drawn jointly (multivariate normal).
    sets : sequence of str
        ``KEY=VALUE`` fixed for every draw (a fixed key is no longer uncertain).
    samples : int
        Draws (with ``sensitivity``: the base size ``n`` of Saltelli's design, ``n (k + 2)`` draws).
    method : {"random", "sobol", "lhs"}
        Monte Carlo or quasi-Monte Carlo points (:mod:`~snoworm.studies.odds.sampling`).
    seed : int
        Seed of the points and of the X_t fields: the same seed gives the same draws.
    strategies : sequence of str, or a comma-separated str
        Of ``scenario`` (default), ``rolling``, ``inching``, ``supervisor``: the same draws for each.
    sensitivity : bool
        Also first-order and total Sobol indices of the go indicator and of the speed made good.
    fidelity : {"transient", "steady"}
        Simulate every draw, or screen it with the steady states (:mod:`~snoworm.studies.odds.screen`).
    goal_m : float, optional
        The leader's distance that counts as the end of the route (default: the route's last point).
    rolling_speed : float, optional
        The wheel speed of ``rolling`` when the scenario's mode does not roll [m/s].
    out_dir : str or Path, optional
        Where ``odds.json``, ``samples.csv`` and the figures go (None: nothing is written).  A re-run of
        the same study resumes; another study there is refused unless ``overwrite``.
    jobs, scheduler, executor :
        Where the draws run, as for :func:`snoworm.run_sweep`.

    Returns
    -------
    OddsResult
    """
    vary, sets = _listed(vary), _listed(sets)  # one string is one item, as on the command line
    if isinstance(strategies, str):
        strategies = [t.strip() for t in strategies.split(",") if t.strip()]
    plan = _plan(
        scenario,
        sets,
        vary,
        xt_field,
        calibration,
        samples,
        method,
        seed,
        strategies,
        sensitivity,
        fidelity,
        goal_m,
        rolling_speed,
    )
    plan.allow_code = tuple(str(p) for p in allowed_paths(allow_code))  # ScenarioError for an empty path
    if plan.sc.mode.type == "controller" and "scenario" in plan.strategies:  # refused before anything runs
        why = trust_problem_of(plan.sc, allow_code=plan.allow_code)
        if why is not None:
            raise ScenarioError(why)
    out = Path(os.path.abspath(out_dir)) if out_dir is not None else None
    if out is not None and not (out / DEFINITION_FILE).exists():
        check_output_folder(out, overwrite)
    own = executor is None
    if own:  # before anything is written: an unreachable scheduler writes nothing
        executor = _make_executor(jobs, scheduler)
    try:
        with ExitStack() as stack:
            done, lease = {}, None
            if out is not None:
                lease = _open_folder(out, plan, overwrite, command, stack)
                done = _prepare(out, plan, overwrite)
                write_manifest(out, command, status="running")
            rows = _run_draws(plan, done, out, executor, progress, lease)
            return _finish(plan, rows, out, lease, (plot, plot_format, command))
    finally:
        if own:
            executor.close()


def _open_folder(out: Path, plan: _Plan, overwrite: bool, command, stack):
    """Create ``out``, take its lock (held until ``stack`` closes) and complete an interrupted commit."""
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot write results: {os_error_message(exc, out)}") from None
    lease = stack.enter_context(folder_lock(out))
    finish_commit(out)
    return lease


def _run_draws(plan: _Plan, done: dict, out, executor, progress, lease) -> dict:
    """Every (draw, strategy) not in ``done``, recorded as it finishes; returns all rows by (draw, strategy)."""
    rows = dict(done)
    todo = [(k, s) for k in range(plan.dsg.n_draws) for s in plan.strategies if (k, s) not in done]
    total = plan.dsg.n_draws * len(plan.strategies)
    bar = Progress(total, "odds", "draws", sys.stderr, mode="auto" if progress is None or progress else "off")
    bar.value = float(len(done))
    rec = _Recorder(plan, rows, out, bar, lease)
    try:
        _execute(plan, todo, rec, executor, out)
    finally:
        rec.close()
        bar.close()
    return rows


def _finish(plan: _Plan, rows: dict, out, lease, opts) -> OddsResult:
    """The summary, ``odds.json``, the figures and the manifest (``opts``: plot, plot format, command)."""
    plot, plot_format, command = opts
    summary = _summary(plan, rows)
    ordered = [rows[(k, s)] for k in range(plan.dsg.n_draws) for s in plan.strategies]
    res = OddsResult(ordered, summary, summary_text(summary), plan.columns, out)
    if out is not None:
        lease.check("running an odds study in")
        atomic_write_text(out / "odds.json", json.dumps(summary, indent=2, default=_json) + "\n")
        if plot:
            res.figures = _write_figures(res, plan, out, plot_format)
        write_manifest(out, command, status="complete")
    return res


def _listed(items) -> list:
    return [items] if isinstance(items, str) else list(items or ())


def _json(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    raise TypeError(f"not JSON: {type(v).__name__}")


def route_data(sc: Scenario, goal_m: float | None, rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The route for the stops figure: leader positions from the start to the end (or the farthest
    stop), the elevation and the nominal X_t there."""
    far = max([goal_m or 0.0] + [r["stop_m"] for r in rows if r.get("stop_m") is not None] + [1.0])
    x = np.linspace(0.0, far, 400)
    el = sc.terrain.elevation_profile()
    z = np.zeros_like(x) if el is None else np.asarray(el.elevation(x), float)
    return {"x_m": x, "elevation_m": z, "xt": np.asarray(sc.terrain.compile()(x), float), "goal_m": goal_m}


def convergence(
    rows: Sequence[dict[str, Any]], strategies: Sequence[str], independent: NDArray[np.bool_]
) -> dict[str, dict[str, NDArray[np.float64]]]:
    """P(go) and its Wilson interval after the first n independent draws, per strategy (n on a log grid)."""
    out = {}
    for s in strategies:
        go = np.array(
            [r["go"] for r in rows if r["strategy"] == s and r["status"] == "ok" and independent[r["draw"]]], float
        )
        if go.size == 0:
            continue
        ns = np.unique(np.geomspace(1, go.size, min(go.size, 60)).astype(int))
        k = np.cumsum(go)[ns - 1]
        ci = np.array([wilson(int(kk), int(n)) for kk, n in zip(k, ns)])
        out[s] = {"n": ns, "p": k / ns, "low": ci[:, 0], "high": ci[:, 1]}
    return out


def _write_figures(res: OddsResult, plan: _Plan, out: Path, plot_format: str) -> list:
    from ...plotting import odds as odds_plots  # lazy: matplotlib is imported only when figures are drawn

    indep = plan.dsg.independent
    rows = [r for r in res.rows if indep[r["draw"]]]  # Saltelli's AB blocks are not independent draws
    route = route_data(plan.sc, plan.goal_m, rows)
    curves = convergence(rows, plan.strategies, indep)
    return odds_plots.write_odds_figures(rows, res.summary, route, curves, out, plot_format)


def load_odds(out_dir: str | os.PathLike[str]) -> dict[str, Any]:
    """The ``odds.json`` of an odds study's folder."""
    path = Path(out_dir) / "odds.json"
    try:
        return json.loads(read_regular_file(path, 2**26))
    except (OSError, ValueError) as exc:
        raise ScenarioError(f"{path}: cannot read it ({exc}); is {out_dir} the folder of `snoworm odds`?") from None
