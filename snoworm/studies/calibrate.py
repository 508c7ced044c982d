"""Calibration of terrain-model coefficients to steady-state field data (paper section 4).

The paper set its coefficients "by trial and error until simulation and data converge"; here the
same match is a weighted least-squares problem solved by :func:`scipy.optimize.least_squares`.

Model
    For every case of a field-data file (:func:`snoworm.studies.field_data.read_field_data`), the
    steady state of one segment (:func:`snoworm.steady.steady_state`) at the case's measured
    wheel speed ``R_w*omega`` and drawbar gives a model slip (Eq. 1) and motor torque per wheel.

Residuals (two per case, dimensionless)
    ``(T_model - T_measured) / torque_scale_Nm`` and ``(i_model - i_measured) / slip_scale``.
    The defaults ``torque_scale_Nm = 1`` and ``slip_scale = 0.01`` weigh an error of 1 N m in
    torque like an error of 1 percentage point in slip.  A case where the model segment is
    immobilised (cannot pull the drawbar) is scored at slip 1 (its torque taken at slip 1), a
    large but finite residual that steers the fit back to mobile coefficients.

Parameters that can be fitted (``--fit NAME``)
    ``b_tF, b_trF, A, peak_exponent_d, tau0, tau1`` (:class:`snoworm.terrain.TerrainParams`) and
    ``xt``, which fits every case's X_t (one parameter per case, reported as ``xt[<case>]``).
    Parameters not fitted keep their starting values (the parameter set, or a model file).

Uncertainty
    Standard errors from the Jacobian at the solution: ``cov = s^2 (J^T J)^-1`` with
    ``s^2 = sum(r^2) / (n_residuals - n_params)``.  They are NaN when ``J^T J`` is singular
    (a parameter the data cannot determine, e.g. ``tau0`` and ``tau1`` from cases all at one X_t).
    Slip does not depend on ``tau0, tau1`` (docs/model.md section 2), so slip residuals that no
    fitted parameter can reduce inflate ``s`` and hence every standard error; fit a slip
    parameter too, or read the errors as conservative.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import yaml
from scipy.optimize import least_squares

from .. import steady
from ..config.schema import ScenarioError, suggest
from ..config.sections import TerrainConfig, TerrainModelConfig
from ..infra.folders import atomic_write_text, check_output_folder, output_folder, relocate
from ..results.copies import write_copies
from ..terrain import TerrainParams
from .field_data import FieldData, read_field_data
from .groundtruth import compare_table2, format_table2, vehicle_model

__all__ = [
    "FIT_NAMES",
    "BOUNDS",
    "CalibrationResult",
    "model_predictions",
    "calibrate",
    "run_calibration",
    "format_report",
    "terrain_model_yaml",
]

#: Coefficients that can be fitted, with bounds kept physically meaningful during the search: every
#: terrain-model field declaring ``search`` bounds (snoworm.config.sections.TerrainModelConfig), and X_t.
BOUNDS = {
    **{f.name: f.metadata["search"] for f in dataclasses.fields(TerrainModelConfig) if f.metadata.get("search")},
    "xt": next(f.metadata["search"] for f in dataclasses.fields(TerrainConfig) if f.name == "xt"),
}
#: Names accepted by ``--fit``; ``xt`` fits the X_t of every case.
FIT_NAMES = tuple(BOUNDS)

#: Terrain-model keys written to ``terrain_model.yaml`` (those of ``terrain.model`` in a scenario).
_MODEL_KEYS = tuple(TerrainParams.__dataclass_fields__)


def _check_fit(fit, n_cases):
    names = []
    for f in fit:
        if f not in FIT_NAMES:
            raise ScenarioError(
                f"--fit {f!r}: unknown parameter.{suggest(f, FIT_NAMES)} "
                f"Fittable: {', '.join(FIT_NAMES)} ('xt' fits every case's X_t)."
            )
        if f not in names:
            names.append(f)
    if not names:
        raise ScenarioError(f"--fit: name at least one parameter to fit, from {', '.join(FIT_NAMES)}.")
    n_par = sum(n_cases if f == "xt" else 1 for f in names)
    n_res = 2 * n_cases
    if n_res <= n_par:
        raise ScenarioError(
            f"--fit {' '.join(names)}: {n_par} parameter(s) to fit but only {n_res} residuals "
            f"({n_cases} case(s) x torque and slip). Least squares with standard errors needs more "
            "residuals than parameters: add cases or fit fewer parameters."
        )
    return names


def _unpack(theta, names, tp: TerrainParams, xt0, n_cases):
    kw, xt, j = {}, np.array(xt0, float), 0
    for f in names:
        if f == "xt":
            xt = np.array(theta[j : j + n_cases], float)
            j += n_cases
        else:
            kw[f] = float(theta[j])
            j += 1
    return replace(tp, **kw), xt


def _param_labels(names, data):
    out = []
    for f in names:
        out += [f"xt[{c}]" for c in data.case] if f == "xt" else [f]
    return out


def model_predictions(data: FieldData, seg, tp: TerrainParams, xt=None):
    """Model slip and torque per wheel at every case (immobilised cases scored at slip 1).

    Returns
    -------
    slip, torque_Nm : ndarray
    immobilised : ndarray of bool
    """
    xt = data.xt if xt is None else np.asarray(xt, float)
    s, T, imm = np.empty(len(data)), np.empty(len(data)), np.zeros(len(data), bool)
    for k in range(len(data)):
        w = float(data.wheel_speed_mps[k])
        try:
            st = steady.steady_state(float(xt[k]), seg, tp, drawbar_N=float(data.drawbar_N[k]), wheel_speed_mps=w)
        except steady.Immobilised:
            st = steady.state_at_slip(1.0, float(xt[k]), w, seg, tp)
            imm[k] = True
        s[k], T[k] = st.slip, st.torque_Nm
    return s, T, imm


@dataclass(frozen=True)
class CalibrationResult:
    """Outcome of :func:`calibrate`.

    Attributes
    ----------
    names : tuple of str
        Fitted parameter labels (``xt[<case>]`` for per-case X_t).
    start, value, stderr : ndarray
        Starting values, fitted values and standard errors (NaN if not identifiable).
    correlation : ndarray
        Correlation matrix of the estimates (NaN if not identifiable).
    terrain_params : TerrainParams
        Fitted terrain model (unfitted coefficients at their starting values).
    xt : ndarray
        X_t per case after the fit (unchanged unless ``xt`` was fitted).
    rows_before, rows_after : list of dict
        Residual tables (:func:`snoworm.studies.groundtruth.compare_table2` rows) before and after.
    n_residuals, dof : int
    sigma : float
        Root-mean-square weighted residual per degree of freedom, ``s``.
    cost_before, cost_after : float
        ``0.5 * sum(r^2)`` of the weighted residuals.
    torque_scale_Nm, slip_scale : float
        Residual scales (weights are their inverses).
    success : bool
    message : str
    nfev : int
    immobilised_after : tuple of str
        Cases where the fitted model segment is immobilised (should be empty).
    """

    names: tuple
    start: np.ndarray
    value: np.ndarray
    stderr: np.ndarray
    correlation: np.ndarray
    terrain_params: TerrainParams
    xt: np.ndarray
    rows_before: list
    rows_after: list
    n_residuals: int
    dof: int
    sigma: float
    cost_before: float
    cost_after: float
    torque_scale_Nm: float
    slip_scale: float
    success: bool
    message: str
    nfev: int
    immobilised_after: tuple


def _start(names, data: FieldData, tp: TerrainParams):
    """Starting point and bounds of the fit: the current values (every case's X_t for ``xt``),
    moved just inside the bounds ``BOUNDS``."""
    x0 = []
    lo, hi = [], []
    for f in names:
        vals = list(data.xt) if f == "xt" else [getattr(tp, f)]
        x0 += vals
        lo += [BOUNDS[f][0]] * len(vals)
        hi += [BOUNDS[f][1]] * len(vals)
    x0 = np.clip(np.array(x0, float), np.nextafter(np.array(lo), np.inf), np.nextafter(np.array(hi), -np.inf))
    return x0, lo, hi


def _uncertainty(J, s2):
    """Standard errors and correlations of the fitted values from the Jacobian ``J`` at the solution
    and the residual variance ``s2`` (``s2 (J^T J)^-1``; NaN where ``J^T J`` is near singular)."""
    n_par = J.shape[1]
    with np.errstate(all="ignore"):
        JTJ = J.T @ J
        try:
            ok = np.linalg.cond(JTJ) < 1e12
            cov = np.linalg.inv(JTJ) * s2 if ok else np.full((n_par, n_par), np.nan)
        except np.linalg.LinAlgError:
            cov = np.full((n_par, n_par), np.nan)
        se = np.sqrt(np.where(np.diag(cov) >= 0, np.diag(cov), np.nan))
        corr = cov / np.outer(se, se)
    return se, corr


def _result(
    data: FieldData, names, seg, tp: TerrainParams, x0, r0, sol, *, torque_scale_Nm, slip_scale
) -> CalibrationResult:
    """The calibration's result from the solver's solution ``sol`` (started at ``x0`` with residuals
    ``r0``): fitted values with standard errors and correlations, Table 2 before and after, costs,
    and the cases the fitted model leaves immobilised."""
    n = len(data)
    tp_fit, xt_fit = _unpack(sol.x, names, tp, data.xt, n)
    n_res, n_par = r0.size, sol.x.size
    dof = n_res - n_par
    s2 = float(sol.fun @ sol.fun) / dof
    se, corr = _uncertainty(sol.jac, s2)
    _, _, imm = model_predictions(data, seg, tp_fit, xt_fit)
    data_fit = replace(data, xt=np.asarray(xt_fit, float))
    return CalibrationResult(
        names=tuple(_param_labels(names, data)),
        start=np.array(x0),
        value=np.array(sol.x),
        stderr=se,
        correlation=corr,
        terrain_params=tp_fit,
        xt=np.asarray(xt_fit, float),
        rows_before=compare_table2(data, seg, tp),
        rows_after=compare_table2(data_fit, seg, tp_fit),
        n_residuals=n_res,
        dof=dof,
        sigma=math.sqrt(s2),
        cost_before=0.5 * float(r0 @ r0),
        cost_after=float(sol.cost),
        torque_scale_Nm=float(torque_scale_Nm),
        slip_scale=float(slip_scale),
        success=bool(sol.success),
        message=str(sol.message),
        nfev=int(sol.nfev),
        immobilised_after=tuple(c for c, m in zip(data.case, imm) if m),
    )


def calibrate(
    data: FieldData,
    fit,
    seg,
    tp: TerrainParams,
    *,
    torque_scale_Nm: float = 1.0,
    slip_scale: float = 0.01,
    progress=None,
) -> CalibrationResult:
    """Fit terrain-model coefficients (and optionally every case's X_t) to steady field data.

    Parameters
    ----------
    data : FieldData
        Steady-state cases (measured wheel speed, drawbar, slip, torque, X_t).
    fit : sequence of str
        Names from :data:`FIT_NAMES`.
    seg : SegmentConfig
        Segment parameters (mass, wheel radius, wheels).
    tp : TerrainParams
        Starting terrain model; unfitted coefficients stay at these values.
    torque_scale_Nm, slip_scale : float
        Residual scales: torque error in units of ``torque_scale_Nm``, slip error in units of
        ``slip_scale`` (default 1 N m and 1 percentage point).
    progress : callable, optional
        ``progress(evaluations, budget)`` after each model evaluation (budget: ``max_nfev``), and
        ``progress(n, n)`` when the fit ends after ``n`` (usually well within the budget).

    Raises
    ------
    ScenarioError
        Unknown ``fit`` name, or not more residuals than fitted parameters.
    """
    if not (0 < torque_scale_Nm < math.inf and 0 < slip_scale < math.inf):
        raise ScenarioError(
            f"residual scales must be finite and greater than 0, got torque {torque_scale_Nm} N m "
            f"and slip {slip_scale}."
        )
    n = len(data)
    names = _check_fit(fit, n)
    x0, lo, hi = _start(names, data, tp)
    meas = np.concatenate([data.torque_Nm / torque_scale_Nm, data.slip / slip_scale])

    budget = 200 * (len(x0) + 1)
    count = [0]

    def resid(theta):
        tpk, xt = _unpack(theta, names, tp, data.xt, n)
        s, T, _ = model_predictions(data, seg, tpk, xt)
        count[0] += 1
        if progress is not None:
            progress(count[0], budget)
        return np.concatenate([T / torque_scale_Nm, s / slip_scale]) - meas

    r0 = resid(x0)
    sol = least_squares(
        resid,
        x0,
        bounds=(lo, hi),
        method="trf",
        jac="3-point",
        x_scale="jac",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=budget,
    )
    if progress is not None:  # the fit has ended (usually well within its budget): all of its work is done
        progress(count[0], count[0])
    return _result(data, names, seg, tp, x0, r0, sol, torque_scale_Nm=torque_scale_Nm, slip_scale=slip_scale)


def format_report(res: CalibrationResult) -> str:
    """Plain-text report: fitted values with standard errors, residual tables before and after."""
    lines = [
        f"least squares: {res.message} ({res.nfev} evaluations); {res.n_residuals} residuals, "
        f"{len(res.names)} parameters, dof {res.dof}",
        f"residual scales: torque {res.torque_scale_Nm:g} N m, slip {100 * res.slip_scale:g} percentage point(s); "
        f"cost {res.cost_before:.4g} -> {res.cost_after:.4g}, s = {res.sigma:.4g}",
        "",
        f"{'parameter':>16} {'start':>10} {'fitted':>10} {'std err':>10}",
    ]
    for n, a, b, e in zip(res.names, res.start, res.value, res.stderr):
        lines.append(f"{n:>16} {a:10.4f} {b:10.4f} {e:10.4f}")
    if np.any(~np.isfinite(res.stderr)):
        lines.append("std err nan: J^T J is singular; the data cannot determine these parameters separately.")
    if res.immobilised_after:
        lines.append(f"warning: the fitted model is immobilised on case(s) {', '.join(res.immobilised_after)}.")
    for n, v in zip(res.names, res.value):
        lo, hi = BOUNDS["xt" if n.startswith("xt[") else n]
        if min(abs(v - lo), abs(v - hi)) <= 1e-3 * (hi - lo):  # least_squares stays strictly inside
            lines.append(
                f"note: {n} = {v:.6g} sits at a bound of its search range [{lo:g}, {hi:g}] (its physical "
                "domain); the data push it beyond: check the data or the fitted set."
            )
    lines += ["", "before:", format_table2(res.rows_before), "", "after:", format_table2(res.rows_after)]
    return "\n".join(lines)


def terrain_model_yaml(res: CalibrationResult, source: str = "") -> str:
    """``terrain_model.yaml`` text: every terrain-model coefficient under ``terrain_model:``.

    A scenario uses it with ``terrain: {model_file: terrain_model.yaml, xt: ...}``.  Fitted X_t
    values are listed in the comment header (they belong to the cases, not to the model).
    """
    tp = res.terrain_params
    model = {k: (v if isinstance(v := getattr(tp, k), str) else float(v)) for k in _MODEL_KEYS}
    head = [
        "# Terrain-model coefficients written by `snoworm calibrate`.",
        f"# Data: {source}" if source else "# Data: (in memory)",
        "# Fitted: " + ", ".join(f"{n} = {v:.6g} +- {e:.2g}" for n, v, e in zip(res.names, res.value, res.stderr)),
        "# Use in a scenario:  terrain: {model_file: <this file>, xt: ...}",
    ]
    return "\n".join(head) + "\n" + yaml.safe_dump({"terrain_model": model}, sort_keys=False)


def _json_float(v):
    v = float(v)
    return v if math.isfinite(v) else None


def calibration_json(res: CalibrationResult, source: str = "", parameter_set_name: str = "") -> str:
    """``calibration.json`` text: everything in :class:`CalibrationResult`, NaN written as null."""

    def rows(rs):
        return [{k: (_json_float(v) if isinstance(v, float) else v) for k, v in r.items()} for r in rs]

    doc = {
        "data": source,
        "parameter_set": parameter_set_name,
        "parameters": [
            {"name": n, "start": _json_float(a), "value": _json_float(b), "stderr": _json_float(e)}
            for n, a, b, e in zip(res.names, res.start, res.value, res.stderr)
        ],
        "correlation": [[_json_float(c) for c in row] for row in res.correlation],
        "xt": {str(c): _json_float(x) for c, x in zip([r["case"] for r in res.rows_after], res.xt)},
        "terrain_model": {
            k: (v if isinstance(v := getattr(res.terrain_params, k), str) else float(v)) for k in _MODEL_KEYS
        },
        "residual_scales": {"torque_Nm": res.torque_scale_Nm, "slip": res.slip_scale},
        "n_residuals": res.n_residuals,
        "dof": res.dof,
        "sigma": res.sigma,
        "cost_before": res.cost_before,
        "cost_after": res.cost_after,
        "success": res.success,
        "message": res.message,
        "nfev": res.nfev,
        "immobilised_after": list(res.immobilised_after),
        "residuals_before": rows(res.rows_before),
        "residuals_after": rows(res.rows_after),
    }
    return json.dumps(doc, indent=2) + "\n"


def run_calibration(
    field_path,
    fit,
    out_dir,
    *,
    parameter_set_name: str = "frostyboy",
    model_file=None,
    torque_scale_Nm: float = 1.0,
    slip_scale: float = 0.01,
    overwrite: bool = False,
    progress=None,
    command: str | None = None,
):
    """Read, validate, fit, then write ``terrain_model.yaml``, ``calibration.json`` and a copy of the
    field data as read (``inputs/<file>``, its SHA-256 in the folder's manifest) to ``out_dir``.

    Nothing is written if the input is invalid (every check runs before the first write).
    ``command`` is the command line the folder's manifest records (default: this process's).

    Returns
    -------
    (CalibrationResult, report text, paths)
    """
    data = read_field_data(field_path)
    seg, tp = vehicle_model(parameter_set_name, model_file)
    _check_fit(fit, len(data))
    check_output_folder(out_dir, overwrite)  # before the fit, not after
    res = calibrate(data, fit, seg, tp, torque_scale_Nm=torque_scale_Nm, slip_scale=slip_scale, progress=progress)
    with output_folder(out_dir, overwrite, command) as out:
        copies = write_copies(out, {"data": (Path(data.source).name, data.data)})  # the data fitted, as read
        paths = [
            atomic_write_text(out / "terrain_model.yaml", terrain_model_yaml(res, data.source)),
            atomic_write_text(out / "calibration.json", calibration_json(res, data.source, parameter_set_name)),
            *(out / rel for rel in copies.values()),
        ]
    return res, format_report(res), relocate(paths, out, out_dir)
