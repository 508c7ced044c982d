"""Ground truth: the model against FrostyBoy's field data (paper Table 2) and Figure 3.

Three pieces, each a pure function of a parameter set plus a thin writer:

* :func:`~snoworm.studies.field_data.read_field_data` (:mod:`snoworm.studies.field_data`) reads
  a field-data CSV (``#`` comment lines allowed) such as the shipped ``frostyboy_2020.csv``
  (paper Table 2) and validates it.
* :func:`compare_table2` runs the steady-state model (:func:`snoworm.steady.steady_state`) on
  every case at its measured wheel speed ``R_w*omega``, drawbar and assigned ``X_t``, and lists
  measured against modelled ground speed, slip and torque (docs/model.md section 3).
* :func:`terrain_curves` evaluates the terrain laws (Eqs. 2 and 3) against slip at given
  ``X_t`` (paper Figure 3), with the zero crossing of the net longitudinal force.

The terrain laws themselves live only in :mod:`snoworm.terrain`; nothing here re-implements them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from .. import steady, terrain
from ..config.params import PARAMETER_SETS, parameter_set, read_model_file
from ..config.scenario import SegmentConfig, TerrainConfig, TerrainModelConfig
from ..config.schema import ScenarioError, build, check_field, dump, quote, suggest
from ..infra.csvwriter import csv_text, write_csv
from ..infra.folders import output_folder, relocate
from ..results.copies import write_copies
from ..terrain import TerrainParams
from .field_data import FieldData, read_field_data

__all__ = [
    "vehicle_model",
    "compare_table2",
    "table2_csv",
    "format_table2",
    "TerrainCurves",
    "terrain_curves",
    "terrain_curves_csv",
    "format_zero_crossings",
    "run_groundtruth",
    "run_terrain_curves",
]


def vehicle_model(parameter_set_name: str = "frostyboy", model_file=None):
    """Segment and terrain-model parameters of a named set, optionally with a terrain-model file.

    Parameters
    ----------
    parameter_set_name : str
        Name of a set in :data:`snoworm.config.params.PARAMETER_SETS`.
    model_file : str or Path, optional
        YAML of terrain-model coefficients (e.g. ``terrain_model.yaml`` written by
        ``snoworm calibrate``), mapping optionally under ``terrain_model:``; its values replace
        the set's.

    Returns
    -------
    (SegmentConfig, TerrainParams)
    """
    if parameter_set_name not in PARAMETER_SETS:
        raise ScenarioError(
            f"parameter set {parameter_set_name!r} is unknown.{suggest(parameter_set_name, PARAMETER_SETS)} "
            f"Known sets: {', '.join(PARAMETER_SETS)}."
        )
    ps = parameter_set(parameter_set_name)
    seg = build(SegmentConfig, ps["segment"], "segment")
    model = dict(ps["terrain_model"])
    if model_file is not None:
        model.update(read_model_file(str(model_file), None))
    cfg = build(TerrainModelConfig, model, "terrain_model")
    return seg, TerrainParams(**dump(cfg))


# ---------------------------------------------------------------------------------- Table 2


def model_cases(data: FieldData, seg, tp: TerrainParams, xt=None):
    """Steady state of the model at every case's measured wheel speed and drawbar.

    Parameters
    ----------
    data : FieldData
    seg : SegmentConfig
    tp : TerrainParams
    xt : array_like, optional
        X_t per case (default: the file's ``xt`` column).

    Returns
    -------
    list of SteadyState or None
        ``None`` where the segment cannot pull the drawbar (immobilised).
    """
    xt = data.xt if xt is None else np.asarray(xt, float)
    out = []
    for k in range(len(data)):
        try:
            out.append(
                steady.steady_state(
                    float(xt[k]),
                    seg,
                    tp,
                    drawbar_N=float(data.drawbar_N[k]),
                    wheel_speed_mps=float(data.wheel_speed_mps[k]),
                )
            )
        except steady.Immobilised:
            out.append(None)
    return out


#: Columns of ``table2.csv``.
TABLE2_COLUMNS = (
    "case",
    "xt",
    "drawbar_N",
    "wheel_speed_mps",
    "speed_measured_mps",
    "speed_model_mps",
    "speed_residual_mps",
    "slip_measured",
    "slip_model",
    "slip_residual",
    "torque_measured_Nm",
    "torque_model_Nm",
    "torque_residual_Nm",
)


def compare_table2(data: FieldData, seg, tp: TerrainParams) -> list:
    """Measured against modelled steady state for every case (paper Table 2, docs/model.md section 3).

    The model runs at the case's measured wheel speed ``R_w*omega`` and drawbar with the
    case's X_t.  Residuals are model minus measured.  An immobilised case has NaN model values.

    Returns
    -------
    list of dict
        One row per case with the keys :data:`TABLE2_COLUMNS` (slip as a fraction).
    """
    rows = []
    for k, st in enumerate(model_cases(data, seg, tp)):
        v, s, T = (st.ground_speed_mps, st.slip, st.torque_Nm) if st is not None else (math.nan,) * 3
        rows.append(
            {
                "case": data.case[k],
                "xt": float(data.xt[k]),
                "drawbar_N": float(data.drawbar_N[k]),
                "wheel_speed_mps": float(data.wheel_speed_mps[k]),
                "speed_measured_mps": float(data.speed_mps[k]),
                "speed_model_mps": v,
                "speed_residual_mps": v - float(data.speed_mps[k]),
                "slip_measured": float(data.slip[k]),
                "slip_model": s,
                "slip_residual": s - float(data.slip[k]),
                "torque_measured_Nm": float(data.torque_Nm[k]),
                "torque_model_Nm": T,
                "torque_residual_Nm": T - float(data.torque_Nm[k]),
            }
        )
    return rows


def table2_csv(rows) -> str:
    """CSV text of :func:`compare_table2` rows (6 significant digits, slip as a fraction)."""
    return csv_text(TABLE2_COLUMNS, rows)


def format_table2(rows) -> str:
    """Plain-text table of :func:`compare_table2` rows: speeds in m/s, slip in %, torque in N m."""
    head = (
        f"{'case':>4} {'X_t':>5} {'drawbar':>7} {'R_w*w':>6} | {'V meas':>6} {'V model':>7} | "
        f"{'slip meas':>9} {'slip model':>10} {'d slip':>6} | {'T meas':>6} {'T model':>7} {'d T':>5}"
    )
    units = (
        f"{'':>4} {'':>5} {'[N]':>7} {'[m/s]':>6} | {'[m/s]':>6} {'[m/s]':>7} | "
        f"{'[%]':>9} {'[%]':>10} {'[pt]':>6} | {'[N m]':>6} {'[N m]':>7} {'[N m]':>5}"
    )
    lines = [head, units, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r['case']:>4} {r['xt']:5.2f} {r['drawbar_N']:7.1f} {r['wheel_speed_mps']:6.2f} | "
            f"{r['speed_measured_mps']:6.2f} {r['speed_model_mps']:7.3f} | "
            f"{100 * r['slip_measured']:9.1f} {100 * r['slip_model']:10.2f} {100 * r['slip_residual']:+6.2f} | "
            f"{r['torque_measured_Nm']:6.1f} {r['torque_model_Nm']:7.2f} {r['torque_residual_Nm']:+5.2f}"
        )
    if any(math.isnan(r["slip_model"]) for r in rows):
        lines.append("nan: the model segment is immobilised (cannot pull the drawbar) on that case's X_t")
    return "\n".join(lines)


def run_groundtruth(
    out_dir,
    data_path=None,
    parameter_set_name: str = "frostyboy",
    model_file=None,
    plot: bool = True,
    plot_format: str = "png",
    overwrite: bool = False,
    figure_size=None,
    *,
    command: str | None = None,
):
    """Compare the model with field data and write ``table2.csv`` (and ``table2.png``, or the
    ``plot_format``: png, pdf, svg; at print ``figure_size``: column, page or WxH), with a copy of
    the field data as read (``inputs/<file>``, its SHA-256 in the folder's manifest).

    Everything is computed and validated before anything is written; each file is written
    atomically.  ``command`` is the command line the folder's manifest records (default: this
    process's).

    Returns
    -------
    (rows, text, paths)
        The rows of :func:`compare_table2`, the printed table and the files written.
    """
    data = read_field_data(data_path)
    seg, tp = vehicle_model(parameter_set_name, model_file)
    rows = compare_table2(data, seg, tp)
    text = (
        f"field data: {data.source}\nmodel: parameter set {parameter_set_name}"
        + (f" with terrain model {model_file}" if model_file else "")
        + f" (d = {tp.peak_exponent_d:g}, torque balance '{tp.torque_balance}')\n"
        + format_table2(rows)
    )
    with output_folder(out_dir, overwrite, command) as out:
        paths = [write_csv(out / "table2.csv", TABLE2_COLUMNS, rows)]
        if plot:
            from .. import plotting  # lazy: matplotlib costs ~0.5 s to import; --no-plot never pays it

            paths.append(
                plotting.write_figure(out / "table2.png", plotting.plot_table2, rows, fmt=plot_format, size=figure_size)
            )
        copies = write_copies(out, {"data": (Path(data.source).name, data.data)})  # the data compared, as read
        paths += [out / rel for rel in copies.values()]
    return rows, text, relocate(paths, out, out_dir)


# ---------------------------------------------------------------------------------- Figure 3


@dataclass(frozen=True)
class TerrainCurves:
    """Terrain forces per wheel against slip (paper Figure 3).

    Attributes
    ----------
    slip : ndarray (n,)
        Slip grid, 0..1.
    xt : ndarray (m,)
        Terrain coefficients.
    normal_load_N : float
        Normal load per wheel (a quarter of the segment weight for FrostyBoy).
    traction_N, resistance_N, net_N : ndarray (m, n)
        Tractive force (Eq. 2), resistance of forward motion (Eq. 3, sgn = +1) and their
        difference, per wheel [N].
    zero_crossing_slip : ndarray (m,)
        Smallest slip at which the net force changes from negative to non-negative; NaN where
        the net force stays negative on [0, 1] (no steady forward motion without help).
    """

    slip: np.ndarray
    xt: np.ndarray
    normal_load_N: float
    traction_N: np.ndarray
    resistance_N: np.ndarray
    net_N: np.ndarray
    zero_crossing_slip: np.ndarray


def _net_per_wheel_N(i, X, F_n, tp):
    # forward motion: sgn(V) = +1, reached by V -> +inf in the smooth sign tanh(V / v_s)
    return terrain.traction_force(i, F_n, X, tp) - terrain.resistance_force(np.inf, F_n, X, tp)


#: Most slip values of the terrain curves (``--points``) and most rows (X_t values x slip values).
MAX_CURVE_POINTS = 100_001
MAX_CURVE_ROWS = 2_000_000


def terrain_curves(xts, seg, tp: TerrainParams, n_points: int = 1001) -> TerrainCurves:
    """Tractive, resistive and net longitudinal force per wheel against slip (paper Figure 3).

    The normal load is the static load per wheel, ``m g / n_wheels`` (a quarter of the segment
    weight for FrostyBoy's four wheels).  The resistance is that of forward motion, Eq. 3 with
    ``sgn(V) = +1``, independent of slip.

    Parameters
    ----------
    xts : sequence of float
        Terrain coefficients X_t (> 0).
    seg : SegmentConfig
    tp : TerrainParams
    n_points : int
        Number of slip values on [0, 1].
    """
    if len(list(xts)) == 0:
        raise ScenarioError("--xt: give one or more terrain coefficients X_t in (0, 1].")
    if (
        isinstance(n_points, bool)
        or not isinstance(n_points, (int, np.integer))
        or not 3 <= n_points <= MAX_CURVE_POINTS
    ):
        raise ScenarioError(
            f"--points: expected a whole number of slip values from 3 to {MAX_CURVE_POINTS} (a slip step of "
            f"1e-5 resolves every curve), got {quote(n_points, 40)}."
        )
    if len(list(xts)) * n_points > MAX_CURVE_ROWS:
        raise ScenarioError(
            f"--points: {len(list(xts))} X_t values x {n_points} slip values give "
            f"{len(list(xts)) * n_points} rows, over the {MAX_CURVE_ROWS} allowed; use fewer --points or --xt."
        )
    xt = np.asarray([check_field(TerrainConfig, "xt", x, "--xt") for x in xts], float)
    _, F_n, _ = steady.segment_geometry(seg)
    i = np.linspace(0.0, 1.0, int(n_points))
    X = xt[:, None]
    Ft = terrain.traction_force(i[None, :], F_n, X, tp)
    Ftr = np.broadcast_to(terrain.resistance_force(np.inf, F_n, X, tp), Ft.shape).copy()
    net = Ft - Ftr
    zc = np.full(xt.size, math.nan)
    for m in range(xt.size):
        up = np.nonzero((net[m, :-1] < 0) & (net[m, 1:] >= 0))[0]
        if up.size:
            j = int(up[0])
            zc[m] = brentq(lambda s, x=xt[m]: float(_net_per_wheel_N(s, x, F_n, tp)), i[j], i[j + 1], xtol=1e-12)
    return TerrainCurves(i, xt, float(F_n), Ft, Ftr, net, zc)


#: Columns of ``terrain_curves.csv`` (long format, per wheel).
CURVE_COLUMNS = ("xt", "slip", "traction_N", "resistance_N", "net_N")


def _curve_rows(c: TerrainCurves):
    for m, x in enumerate(c.xt):
        yield from zip(np.full(c.slip.size, x), c.slip, c.traction_N[m], c.resistance_N[m], c.net_N[m])


def terrain_curves_csv(c: TerrainCurves) -> str:
    """Long-format CSV: ``xt, slip, traction_N, resistance_N, net_N`` (per wheel)."""
    return csv_text(CURVE_COLUMNS, _curve_rows(c))


def format_zero_crossings(c: TerrainCurves) -> str:
    """One line per X_t: the zero crossing of the net force, or its maximum if there is none."""
    lines = [f"normal load per wheel {c.normal_load_N:.1f} N; resistance of forward motion (sgn = +1)"]
    for m, x in enumerate(c.xt):
        if math.isnan(c.zero_crossing_slip[m]):
            lines.append(
                f"X_t = {x:g}: net force negative for every slip in [0, 1] "
                f"(max {c.net_N[m].max():.1f} N/wheel at slip {100 * c.slip[np.argmax(c.net_N[m])]:.1f} %)"
            )
        else:
            lines.append(
                f"X_t = {x:g}: net force crosses zero at slip {100 * c.zero_crossing_slip[m]:.2f} % "
                f"(max {c.net_N[m].max():.1f} N/wheel)"
            )
    return "\n".join(lines)


def run_terrain_curves(
    xts,
    out_dir,
    *,
    parameter_set_name: str = "frostyboy",
    model_file=None,
    plot: bool = True,
    n_points: int = 1001,
    plot_format: str = "png",
    overwrite: bool = False,
    figure_size=None,
    command: str | None = None,
):
    """Compute Figure 3's curves and write ``terrain_curves.csv`` (and ``terrain_curves.png``, or
    the ``plot_format``: png, pdf, svg; at print ``figure_size``: column, page or WxH); ``command``:
    the command line the folder's manifest records (default: this process's).

    Returns
    -------
    (TerrainCurves, text, paths)
    """
    seg, tp = vehicle_model(parameter_set_name, model_file)
    c = terrain_curves(xts, seg, tp, n_points)
    with output_folder(out_dir, overwrite, command) as out:
        paths = [write_csv(out / "terrain_curves.csv", CURVE_COLUMNS, _curve_rows(c))]
        if plot:
            from .. import plotting  # lazy: matplotlib costs ~0.5 s to import; --no-plot never pays it

            paths.append(
                plotting.write_figure(
                    out / "terrain_curves.png", plotting.plot_terrain_curves, c, fmt=plot_format, size=figure_size
                )
            )
    return c, format_zero_crossings(c), relocate(paths, out, out_dir)
