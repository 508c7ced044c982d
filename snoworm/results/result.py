"""Results of a simulation: time series per segment and per link, summary, files on disk.

Every output quantity is recomputed from the solved states after the solve, in one vectorised
pass of the same force kernel the right-hand side uses (:meth:`ChainModel.evaluate`).
"""

from __future__ import annotations

import io
import json
import math
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._version import __version__
from ..config.scenario import dump_scenario, load_scenario
from ..config.schema import ScenarioError, quote
from ..infra.commit import unfinished_commit
from ..infra.folders import atomic_write_text, output_folder, relocate
from ..infra.manifest import ManifestProblem, read_small_file
from ..model.quantities import output_series
from . import frames
from .copies import copy_inputs, input_problem
from .energy import energy_along, energy_metrics
from .step import step_responses
from .verdict import verdict as judge

if TYPE_CHECKING:
    import pandas
    import xarray
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from numpy.typing import NDArray

    from ..config.scenario import Scenario
    from ..model.chain import ChainModel
    from ..model.inputs import Controls
    from ..modes.base import Mode
    from .verdict import Verdict

#: A figure size: "column", "page", "WxH" in inches or a (width, height) pair.
FigureSize = str | tuple[float, float]

__all__ = ["Result", "ResultFileError", "SEGMENT_COLUMNS", "LINK_COLUMNS", "load_result", "read_back"]

#: Columns of ``segments.csv`` (after ``t_s, segment``): name -> description.
SEGMENT_COLUMNS = {
    "x_m": "position of the segment's reference point [m]",
    "v_mps": "ground speed [m/s]",
    "wheel_speed_mps": "wheel circumferential speed R_w*omega, mean of the axles [m/s]",
    "slip": "slip (Eq. 1 regularised, or clip(j / K) of the shear law: docs/model.md section 2), mean of the axles",
    "traction_N": "tractive force F_t summed over the segment's wheels [N]",
    "resistance_N": "terrain resistance force F_tr summed over the segment's wheels [N]",
    "net_force_N": "traction - resistance, summed over the wheels [N]",
    "motor_torque_Nm": "motor torque per wheel at the wheel, mean of the axles [N m]",
    "speed_setpoint_mps": "wheel-speed set-point R_w*omega_ref [m/s]",
    "connector_net_N": "net force of the links (and tow) on the segment, forward positive [N]",
    "xt": "terrain coefficient X_t under the segment, mean of the axles",
    "motor_power_W": "mechanical motor power at the wheels, summed over the wheels [W]",
    "terrain_dissipation_W": "power dissipated at the wheel-terrain contacts of the segment [W]",
    "motor_electrical_power_W": "electrical power drawn by the segment's motors: motoring power / drivetrain "
    "efficiency, braking not recovered [W]",
    "grade_deg": "grade under the segment (the chord between its axles), positive uphill [deg]",
    "elevation_m": "elevation of the segment, the mean over its wheelbase (its potential-energy height) [m]",
    "gravity_N": "gravity along the track on the segment, -m g sin(grade), forward positive [N]",
    "sinkage_m": "slip-sinkage of the wheels, mean of the axles (terrain.model.sinkage: slip; 0 without it) [m]",
}

#: The segment columns of a run on a grade (docs/model.md section 7); zeros on level ground.
GRADE_COLUMNS = ("grade_deg", "elevation_m", "gravity_N")

#: Segment columns a folder written before them may lack (read back as zeros): the grade columns
#: (a run before them was on level ground) and the sinkage (a run before it had none).
OPTIONAL_COLUMNS = (*GRADE_COLUMNS, "sinkage_m")

#: Columns of ``links.csv`` (after ``t_s, link``).
LINK_COLUMNS = {
    "force_N": "link force, tension positive [N]",
    "length_m": "centre-to-centre distance of the two segments [m]",
    "extension_m": "prismatic joint extension (0 for a fixed link) [m]",
    "joint_power_W": "mechanical power delivered by the prismatic joint actuator [W]",
    "spring_force_N": "force of the link spring (in series with the damper and the actuator), tension positive [N]",
    "damper_power_W": "power dissipated in the link damper [W]",
}


@dataclass
class Result:
    """A finished simulation.

    Attributes
    ----------
    scenario : Scenario
        The resolved scenario.
    t : ndarray (n_t,)
        Output times [s].
    segments : dict of str -> ndarray (n_t, N)
        Per-segment series, exactly the keys of :data:`SEGMENT_COLUMNS`.
    links : dict of str -> ndarray (n_t, N-1)
        Per-link series, exactly the keys of :data:`LINK_COLUMNS`.
    phases : list of dict
        Integration intervals (start, end, label).
    events : list of dict
        Mode events (gait phase changes, switches), with time and cause.
    stats : dict
        Solver statistics (nfev, njev, nlu, intervals, wall_time_s).
    mode_summary : dict
        Mode-specific metrics.
    """

    scenario: Scenario
    t: np.ndarray
    segments: dict
    links: dict
    phases: list
    events: list
    stats: dict
    mode_summary: dict = field(default_factory=dict)

    @classmethod
    def from_pieces(
        cls,
        sc: Scenario,
        model: ChainModel,
        mode: Mode,
        pieces: Sequence[tuple[NDArray[np.float64], NDArray[np.float64], Controls]],
        phases: list[dict[str, Any]],
        stats: dict[str, Any],
    ) -> Result:
        seg_parts, link_parts, ts = [], [], []
        for t, ys, ctl in pieces:
            seg, lk = output_series(model, ys, ctl)
            seg_parts.append(seg)
            link_parts.append(lk)
            ts.append(t)
        t = np.concatenate(ts)
        segments = {k: np.concatenate([p[k] for p in seg_parts]) for k in seg_parts[0]}
        links = {k: np.concatenate([p[k] for p in link_parts]) for k in link_parts[0]}
        segments = {k: segments[k] for k in SEGMENT_COLUMNS}  # the documented columns, in order
        links = {k: links[k] for k in LINK_COLUMNS}
        res = cls(sc, t, segments, links, phases, list(mode.log), stats)
        res.mode_summary = mode.summary(res)
        return res

    # ------------------------------------------------------------------ metrics
    @property
    def n_segments(self) -> int:
        return self.segments["x_m"].shape[1]

    def energy(self, metrics: dict | None = None) -> dict:
        """Energy used [J]: motors (mechanical and electrical, with the drivetrain loss) and joints.

        Electrical energy counts only motoring power (``T w > 0``) divided by the drivetrain
        efficiency; braking and holding power are not recovered.  Joint energy counts the
        positive mechanical work of the prismatic actuators, and its electrical energy that work
        divided by ``vehicle.links.joint_efficiency``.  ``total_J`` is the electrical total
        (definitions in :mod:`snoworm.results.energy`).  ``metrics``: an already computed
        :func:`snoworm.results.energy.energy_metrics` of this result, to select from.
        """
        e = energy_metrics(self) if metrics is None else metrics
        return {
            "motor_electrical_J": e["motor_electrical_J"],
            "motor_mechanical_J": e["motor_mechanical_J"],
            "joint_work_J": e["joint_mechanical_J"],
            "joint_electrical_J": e["joint_electrical_J"],
            "total_J": e["total_electrical_J"],
        }

    def energy_along(self) -> dict:
        """Electrical energy as it accumulates over the run (:func:`snoworm.results.energy.energy_along`):
        ``t_s``, ``distance_m``, ``motor_electrical_J``, ``joint_electrical_J``, ``total_electrical_J``."""
        return energy_along(self)

    def verdict(self, criteria: Mapping[str, float] | None = None) -> Verdict:
        """Where the run ended up (:func:`snoworm.results.verdict.verdict`): a
        :class:`~snoworm.results.verdict.Verdict` with ``status`` (``moving``, ``reached_end`` or
        ``immobilised``), ``t_s``, ``x_m`` (the leader's position), ``reason`` (the line ``snoworm
        run`` prints) and, immobilised, the X_t, grade and slip there.  ``criteria``: a mapping
        changing the scenario's (``simulation.immobilised``: ``speed_mps``, ``window_s``, ``slip``,
        ``sinkage_m``; and ``goal_m``), e.g. ``res.verdict({"window_s": 10})``."""
        return judge(self, criteria)

    def summary(self) -> dict:
        """The metrics written to ``summary.json`` (with the verdict: ``status``,
        ``immobilised_at_m``, ``status_reason``, :meth:`verdict`)."""
        x = self.segments["x_m"]
        dist = float(np.mean(x[-1] - x[0]))
        dur = float(self.t[-1] - self.t[0]) if self.t.size > 1 else 0.0
        metrics = energy_metrics(self)
        e = self.energy(metrics)
        v = self.verdict()
        s = {
            "scenario": self.scenario.name,
            "snoworm_version": __version__,
            "segments": self.n_segments,
            "duration_s": dur,
            "distance_m": dist,
            "mean_speed_mps": dist / dur if dur > 0 else 0.0,
            "status": v.status,
            "immobilised_at_m": v.immobilised_at_m,
            "status_reason": v.reason,
            "final_link_forces_N": self.links["force_N"][-1].tolist(),
            "final_net_forces_N": self.segments["net_force_N"][-1].tolist(),
            "final_slip": self.segments["slip"][-1].tolist(),
            "final_speed_mps": self.segments["v_mps"][-1].tolist(),
            "max_abs_link_force_N": float(np.max(np.abs(self.links["force_N"]))) if self.links["force_N"].size else 0.0,
            "energy": e,
            "energy_per_metre_J_per_m": e["total_J"] / dist if dist > 1e-9 else None,
            "energy_metrics": metrics,
            "solver": dict(self.stats),
            "events": self.events,
            "sources": self.scenario.sources,
        }
        s.update(self.mode_summary)
        steps = step_responses(self)
        if steps is not None:
            s["step_response"] = steps
        return s

    def step_info(self) -> list | None:
        """Step-response metrics of a controlled run (:func:`snoworm.results.step.step_responses`,
        python-control's ``step_info`` conventions): rise time (10-90 %), settling time (2 %),
        overshoot and undershoot [%], peak, steady-state error, one dict per response (the chain's
        speed against its set-point; in force control each controlled link's force against its
        reference).  None for a gait.  Also in ``summary.json`` as ``step_response``."""
        return step_responses(self)

    # ------------------------------------------------------------------ data and figures
    @property
    def columns(self) -> dict:
        """``{"segments": SEGMENT_COLUMNS, "links": LINK_COLUMNS}``: quantity -> description [unit]."""
        return {"segments": SEGMENT_COLUMNS, "links": LINK_COLUMNS}

    def __repr__(self) -> str:
        """A few lines (``Result.summary()``, ``.segments``, ``.scenario`` hold the detail)."""
        return frames.short_repr(self)

    def to_pandas(self) -> pandas.DataFrame:
        """The run as ONE :class:`pandas.DataFrame`: a row per output time (index ``t_s``), and a
        column MultiIndex ``(kind, quantity, index)``: ``("segment", "v_mps", 0)``, ...,
        ``("link", "force_N", 0)``, ...  ``df["segment", "v_mps"]`` is a time x segment table,
        ``df.xs(2, axis=1, level="index")`` everything about segment 2 (and link 2).

        The tidy (long) tables of the CSV files are a call away: :meth:`segments_frame` and
        :meth:`links_frame`.
        Needs pandas (``pip install 'snoworm[data]'``); see :func:`snoworm.results.frames.to_pandas`.
        """
        return frames.to_pandas(self)

    def segments_frame(self) -> pandas.DataFrame:
        """The ``segments.csv`` table as a DataFrame (``t_s``, ``segment``, one column per quantity)."""
        return frames.frames(self)["segments"]

    def links_frame(self) -> pandas.DataFrame:
        """The ``links.csv`` table as a DataFrame (``t_s``, ``link``, one column per quantity)."""
        return frames.frames(self)["links"]

    def to_xarray(self) -> xarray.Dataset:
        """The run as an :class:`xarray.Dataset`: dims ``time x segment`` and ``time x link``, units
        in each variable's attrs, the resolved scenario (YAML) and package versions in the
        Dataset's attrs.  Needs xarray (``pip install 'snoworm[data]'``); see
        :func:`snoworm.results.frames.to_xarray`.
        """
        return frames.to_xarray(self)

    def plot(
        self,
        kind: str = "speeds",
        ax: Axes | Sequence[Axes] | None = None,
        fig: Figure | None = None,
        size: FigureSize | None = None,
        **kwargs: Any,
    ) -> Figure:
        """Draw one of the run's figures and return the :class:`~matplotlib.figure.Figure`.

        ``kind``: ``forces``, ``speeds``, ``positions``, ``force_diagram``, ``groups``, ``slip``,
        ``motor`` or ``energy`` (see :mod:`snoworm.plotting`).  ``ax``: your own axes (as many as
        the figure has panels), or ``fig``: a figure to draw in; neither: a new figure from
        pyplot's figure manager (shown inline in Jupyter, by ``plt.show()`` in a script).
        ``size``: ``"column"`` (3.5 in), ``"page"`` (7.16 in, default) or ``"WxH"`` inches.  The
        matplotlib backend is never selected or changed.
        """
        from .. import plotting  # lazy: matplotlib costs ~0.5 s to import; runs without plots never pay it

        if kind not in plotting.PLOT_KINDS:
            raise ValueError(f"unknown plot kind {kind!r}; kinds: {', '.join(plotting.PLOT_KINDS)}")
        return plotting.PLOT_KINDS[kind](self, ax=ax, fig=fig, size=size, **kwargs)

    def animate(
        self,
        path: str | os.PathLike[str],
        fps: int = 20,
        speed_up: float | None = None,
        fmt: str | None = None,
        progress: Callable[[int, int], None] | None = None,
        force_scale_N: float | None = None,
    ) -> Path:
        """Write an animation of the run to ``path`` (GIF, or MP4 where ffmpeg is installed) and
        return its path: the chain moving along its route, to scale, the links coloured by their
        force, the terrain's elevation and X_t under it, the time and gait phase in a corner
        (:func:`snoworm.plotting.animation.animate_result`; ``snoworm animate`` at the command line).

        ``fps``: frames per second (a whole number, 1 to 60); ``speed_up``: simulated seconds per video second
        (default: the run in at most 20 s of video, never faster than real time); ``fmt``: ``"gif"``
        or ``"mp4"`` (default from the suffix of ``path``); ``progress(done, total)``: called after
        each frame; ``force_scale_N``: the force at the ends of the colour map (default: the run's
        largest |force|).  Written atomically; into a snoworm results folder under its lock and
        listed in its manifest.

        Raises
        ------
        ValueError
            A bad option, MP4 without ffmpeg, or too many frames (the message says the fix).
        snoworm.infra.folders.OutputError
            The file cannot be written (nothing is written).
        """
        from ..plotting import animation  # lazy: matplotlib costs ~0.5 s to import

        return animation.animate_result(self, path, fps, speed_up, fmt, progress, force_scale_N)

    # ------------------------------------------------------------------ tables
    def segments_csv(self) -> str:
        n_t, n = self.segments["x_m"].shape
        cols = ["t_s", "segment"] + list(SEGMENT_COLUMNS)
        data = np.column_stack(
            [np.repeat(self.t, n), np.tile(np.arange(n), n_t)] + [self.segments[c].reshape(-1) for c in SEGMENT_COLUMNS]
        )
        return _csv(cols, data, int_cols=(1,), t_decimals=time_decimals(self.scenario.simulation.output_dt_s))

    def links_csv(self) -> str:
        n_t, n = self.links["force_N"].shape
        cols = ["t_s", "link"] + list(LINK_COLUMNS)
        data = np.column_stack(
            [np.repeat(self.t, n), np.tile(np.arange(n), n_t)] + [self.links[c].reshape(-1) for c in LINK_COLUMNS]
        )
        return _csv(cols, data, int_cols=(1,), t_decimals=time_decimals(self.scenario.simulation.output_dt_s))

    def write(
        self,
        out_dir: str | os.PathLike[str],
        plot: bool = True,
        plot_format: str = "png",
        overwrite: bool = False,
        figure_size: FigureSize | None = None,
        *,
        command: str | None = None,
    ) -> list:
        """Write ``segments.csv``, ``links.csv``, ``summary.json``, ``scenario.yaml`` (and plots,
        ``plot_format`` files: png at 200 dpi, pdf or svg, at print ``figure_size``: column,
        page or WxH), and under ``inputs/`` a copy of every file the scenario read (a route, a
        parameter-set file; :mod:`snoworm.results.copies`), which ``scenario.yaml`` names relative
        to the folder: the folder reads back and re-runs wherever it is moved.

        All or nothing (:func:`snoworm.infra.folders.output_folder`): the files are written into a
        temporary sibling folder that replaces ``out_dir`` at the end, with a manifest; an earlier
        snoworm folder there is replaced as a whole, a non-empty folder snoworm did not write is
        refused unless ``overwrite``.  Returns the paths.  :func:`load_result` reads the folder back.
        ``command`` is the command line recorded in the manifest (default: this process's).

        Raises
        ------
        snoworm.infra.folders.OutputError
            Unusable ``out_dir`` or an I/O failure (nothing is written then).
        ValueError
            A ``figure_size`` that is not column, page, 'WxH' or a (width, height) pair (checked
            before anything is written).
        """
        if plot and figure_size is not None:
            from .. import plotting  # lazy: matplotlib costs ~0.5 s to import; only when plotting

            plotting.parse_size(figure_size)
        with output_folder(out_dir, overwrite, command) as stage:
            copies = copy_inputs(self.scenario, stage)  # the folder holds what the run read
            paths = [
                atomic_write_text(stage / "segments.csv", self.segments_csv()),
                atomic_write_text(stage / "links.csv", self.links_csv()),
                atomic_write_text(stage / "summary.json", json.dumps(self.summary(), indent=2) + "\n"),
                atomic_write_text(stage / "scenario.yaml", dump_scenario(self.scenario, copies)),
            ]
            if plot:
                from .. import plotting  # lazy: matplotlib costs ~0.5 s to import; runs without plots never pay it

                paths += plotting.plot_result(self, stage, plot_format, size=figure_size)
            paths += [stage / rel for rel in copies.values()]
        return relocate(paths, stage, out_dir)


def time_decimals(output_dt_s: float) -> int:
    """Decimals of ``t_s`` in the CSVs: 4, or enough that times ``output_dt_s`` apart print apart
    (one digit below the sampling interval's leading digit; at most 12)."""
    return int(min(12, max(4, 1 - math.floor(math.log10(output_dt_s)))))


#: Keys of ``summary.json`` that are not the mode's own (the rest is ``Result.mode_summary``).
_SUMMARY_KEYS = (
    "scenario",
    "snoworm_version",
    "segments",
    "duration_s",
    "distance_m",
    "mean_speed_mps",
    "status",
    "immobilised_at_m",
    "status_reason",
    "final_link_forces_N",
    "final_net_forces_N",
    "final_slip",
    "final_speed_mps",
    "max_abs_link_force_N",
    "energy",
    "energy_per_metre_J_per_m",
    "energy_metrics",
    "solver",
    "events",
    "sources",
    "step_response",
)


class ResultFileError(ValueError):
    """A folder read back (:func:`load_result`, :func:`snoworm.studies.sweep.load_sweep`) is not as snoworm
    wrote it: a file missing, unreadable, malformed, non-finite or inconsistent with the others.
    The message names the file and the problem."""


#: Largest file read back from a results folder (bytes): the output-sample cap in CSV text.
MAX_READ_BYTES = 2**31


def read_back(path: str | os.PathLike[str], limit: int = MAX_READ_BYTES) -> str:
    """The text of ``path``, a regular file (a FIFO or a device refused unread; ResultFileError)."""
    try:
        return read_small_file(path, limit).decode("utf-8")
    except FileNotFoundError:
        raise ResultFileError(f"{path}: missing") from None
    except ManifestProblem as exc:
        raise ResultFileError(str(exc)) from None
    except UnicodeDecodeError:
        raise ResultFileError(f"{path}: not UTF-8 text") from None


def _read_table(
    path: Path, index: str, columns: Iterable[str], n_rows: int
) -> tuple[NDArray[np.float64] | None, dict[str, NDArray[np.float64]]]:
    """(t, {column: ndarray (n_t, n_rows)}) of a ``segments.csv`` / ``links.csv`` with ``n_rows``
    segments or links, every shape and value checked (ResultFileError naming the file)."""
    text = read_back(path)
    header = text.split("\n", 1)[0].strip().split(",")
    expected = ["t_s", index] + list(columns)
    # a run written before the grade columns (docs/model.md section 7) was on level ground, one
    # written before the sinkage column had none: zeros
    older = ["t_s", index] + [c for c in columns if c in header[2:]]
    if header != expected and not (header == older and set(columns) - set(header) <= set(OPTIONAL_COLUMNS)):
        raise ResultFileError(f"{path}: unexpected columns {quote(header)}; expected {', '.join(expected)}")
    body = text.split("\n", 1)[1] if "\n" in text else ""
    if not body.strip():
        return None, {c: np.zeros((0, n_rows)) for c in columns}
    try:
        data = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2)
    except ValueError as exc:
        raise ResultFileError(f"{path}: not a table of numbers ({quote(str(exc))})") from None
    if data.shape[0] == 0 or n_rows == 0:
        if data.shape[0] and n_rows == 0:
            raise ResultFileError(f"{path}: holds rows, but the scenario has no {index}s")
        return None, {c: np.zeros((0, n_rows)) for c in columns}
    if data.shape[1] != len(header) or not np.isfinite(data).all():
        raise ResultFileError(f"{path}: rows with missing, NaN or infinite values")
    if data.shape[0] % n_rows or not np.array_equal(data[:, 1], np.tile(np.arange(n_rows), data.shape[0] // n_rows)):
        raise ResultFileError(
            f"{path}: the {index} column does not run 0..{n_rows - 1} at every time "
            f"(the scenario has {n_rows} {index}s)"
        )
    t = data[::n_rows, 0]
    if np.any(data[:, 0] != np.repeat(t, n_rows)) or np.any(np.diff(t) < 0):
        raise ResultFileError(f"{path}: the times t_s are not the same within a sample or go backwards")
    got = {c: data[:, 2 + j].reshape(t.size, n_rows) for j, c in enumerate(header[2:])}
    return t, {c: got[c] if c in got else np.zeros((t.size, n_rows)) for c in columns}


def _read_summary_json(path: Path) -> dict:
    try:
        summary = json.loads(read_back(path, 2**26))
    except (ValueError, RecursionError) as exc:
        if isinstance(exc, ResultFileError):
            raise
        raise ResultFileError(f"{path}: not valid JSON") from None
    if (
        not isinstance(summary, dict)
        or not isinstance(summary.get("events", []), list)
        or not isinstance(summary.get("solver", {}), dict)
    ):
        raise ResultFileError(f"{path}: not a run summary (a JSON object with an 'events' list and a 'solver' mapping)")
    return summary


def load_result(run_dir: str | os.PathLike[str]) -> Result:
    """Read a run folder written by :meth:`Result.write` (or ``snoworm run``) back into a Result.

    The series come from ``segments.csv`` and ``links.csv``, so they carry the files' precision:
    6 significant digits (times: 4 decimals, more for an ``output_dt_s`` below 1e-3).  The scenario is ``scenario.yaml`` (validated
    again, and never run: its controller, if any, is checked statically and trusts no folder, see
    docs/controllers.md), reading the folder's copies of its files (``inputs/``: a route, a
    parameter-set file), each checked first against the SHA-256 the folder's manifest recorded;
    ``stats``, ``events`` and the mode's metrics come from ``summary.json``.
    The integration intervals (``phases``) are not written to disk and come back empty.

    Raises
    ------
    ResultFileError
        A file missing, unreadable (a FIFO, a device), malformed, with NaN values, or whose shape
        disagrees with the scenario or the other files; a copy in ``inputs/`` changed since the
        run was written (or not recorded in the manifest); the message names the file.  Or the
        folder holds an unfinished commit (a command interrupted while moving its files into
        place, :mod:`snoworm.infra.commit`): its files may mix two runs.
    """
    d = Path(run_dir)
    unfinished = unfinished_commit(d)
    if unfinished:
        raise ResultFileError(unfinished)
    missing = [f for f in ("segments.csv", "links.csv", "summary.json", "scenario.yaml") if not (d / f).is_file()]
    if missing:
        raise ResultFileError(f"{d} is not a snoworm run folder: {', '.join(missing)} missing")
    why = input_problem(d)  # the copies of the run's input files, checked before they are read
    if why is not None:
        raise ResultFileError(why)
    try:
        sc = load_scenario(d / "scenario.yaml", trust_folder=False)  # its controller, if any, runs from nowhere
    except (ScenarioError, RecursionError) as exc:
        raise ResultFileError(f"{d / 'scenario.yaml'}: {quote(str(exc), 300)}") from None
    n = sc.vehicle.segments
    t, segments = _read_table(d / "segments.csv", "segment", SEGMENT_COLUMNS, n)
    t_links, links = _read_table(d / "links.csv", "link", LINK_COLUMNS, n - 1)
    if t is None:
        raise ResultFileError(f"{d / 'segments.csv'}: no samples")
    if t_links is not None and not np.array_equal(t_links, t):
        raise ResultFileError(
            f"{d / 'links.csv'}: its times differ from segments.csv's ({t_links.size} vs {t.size} samples)"
        )
    if t_links is None and n > 1:
        raise ResultFileError(f"{d / 'links.csv'}: no samples, but the scenario has {n - 1} links")
    if t_links is None:
        links = {c: np.zeros((t.size, 0)) for c in LINK_COLUMNS}
    summary = _read_summary_json(d / "summary.json")
    mode_summary = {k: v for k, v in summary.items() if k not in _SUMMARY_KEYS}
    return Result(
        sc, t, segments, links, [], list(summary.get("events", [])), dict(summary.get("solver", {})), mode_summary
    )


def _csv(cols: Sequence[str], data: NDArray[np.float64], int_cols: Sequence[int] = (), t_decimals: int = 4) -> str:
    """CSV text of ``data`` (rows of samples) under header ``cols``: time with ``t_decimals``
    decimals, ``int_cols`` as integers, the rest to 6 significant digits (as ``np.savetxt`` with
    these formats would write, in one formatting operation instead of one per row)."""
    fmt = ["%.6g"] * data.shape[1]
    fmt[0] = f"%.{t_decimals}f"
    for c in int_cols:
        fmt[c] = "%d"
    row = ",".join(fmt) + "\n"
    return ",".join(cols) + "\n" + (row * data.shape[0]) % tuple(data.ravel().tolist())
