"""Uncertain inputs of ``snoworm odds``: distributions of scenario fields, a random X_t field along the
route and calibrated coefficients drawn jointly (docs/odds.md, section "The model of uncertainty").

Every input is a *group* of uniform coordinates: a scalar distribution takes one (mapped through its
inverse CDF, so quasi-Monte Carlo points keep their structure), the calibrated coefficients take one
per coefficient (standard normals correlated by the Cholesky factor of their covariance), and the X_t
field takes none: each draw has a seed of its own, and the field is white noise filtered by
:func:`snoworm.terrain.gaussian_field`.  A group is one input of the Sobol indices.

The ``uncertainty:`` section of a scenario file::

    uncertainty:
      vary:
        terrain.xt: normal:0.8:0.05          # the --vary grammar, or a mapping:
        tow.force_N: {dist: uniform, low: 100, high: 250}
      xt_field: {sd: 0.05, corr_m: 5}
      calibration: calib_out/                # a `snoworm calibrate` output folder
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import stats

from ...config.schema import ScenarioError, quote
from ...infra.files import read_regular_file

__all__ = [
    "DISTRIBUTIONS",
    "Distribution",
    "ScalarInput",
    "XtField",
    "CalibrationInput",
    "Uncertainty",
    "parse_vary",
    "parse_xt_field",
    "read_calibration",
    "uncertainty_from_section",
    "field_domain",
    "XT_FIELD_FLOOR",
]

#: Parameters of each distribution, in the order of the ``--vary`` grammar ``path=dist:p1:p2...``.
DISTRIBUTIONS = {
    "normal": ("mean", "sd"),
    "lognormal": ("mean", "sd"),
    "uniform": ("low", "high"),
    "triangular": ("low", "mode", "high"),
    "truncnormal": ("mean", "sd", "low", "high"),
}

#: Lowest X_t of a drawn field or a drawn X_t: the floor ``terrain.random`` clips its profile to
#: (``min_xt``'s default), so X_t stays in (0, 1] and the resistance X_t^-A finite.
XT_FIELD_FLOOR = 0.05

#: Uniform coordinates are kept this far inside (0, 1), so that no inverse CDF returns an infinity.
U_EPS = 1e-12


@dataclass(frozen=True)
class Distribution:
    """One scalar distribution (``kind`` of :data:`DISTRIBUTIONS`, ``params`` in that order)."""

    kind: str
    params: tuple

    def frozen(self):
        """The ``scipy.stats`` frozen distribution (lognormal: ``mean``/``sd`` of the value itself)."""
        p = self.params
        if self.kind == "normal":
            return stats.norm(p[0], p[1])
        if self.kind == "lognormal":
            s2 = math.log1p((p[1] / p[0]) ** 2)
            return stats.lognorm(math.sqrt(s2), scale=math.exp(math.log(p[0]) - s2 / 2))
        if self.kind == "uniform":
            return stats.uniform(p[0], p[1] - p[0])
        if self.kind == "triangular":
            return stats.triang((p[1] - p[0]) / (p[2] - p[0]), loc=p[0], scale=p[2] - p[0])
        return stats.truncnorm((p[2] - p[0]) / p[1], (p[3] - p[0]) / p[1], loc=p[0], scale=p[1])

    def ppf(self, u):
        return self.frozen().ppf(np.clip(u, U_EPS, 1 - U_EPS))

    def text(self) -> str:
        return f"{self.kind}:" + ":".join(f"{v:g}" for v in self.params)

    def to_dict(self) -> dict:
        return {"dist": self.kind, **dict(zip(DISTRIBUTIONS[self.kind], self.params))}


def _check_params(kind, params, where):  # noqa: C901 - one rule per distribution, a flat list
    names = DISTRIBUTIONS[kind]
    fix = f"write {kind}:" + ":".join(n.upper() for n in names)
    if len(params) != len(names):
        raise ScenarioError(f"{where}: {kind} takes {len(names)} parameters ({', '.join(names)}); {fix}.")
    if not all(math.isfinite(v) for v in params):
        raise ScenarioError(f"{where}: every parameter must be a finite number; {fix}.")
    d = dict(zip(names, params))
    if "sd" in d and not d["sd"] > 0:
        raise ScenarioError(
            f"{where}: sd must be > 0, got {d['sd']:g} (a fixed value is --set PATH=VALUE, not a distribution)."
        )
    if kind == "lognormal" and not d["mean"] > 0:
        raise ScenarioError(f"{where}: a lognormal value is positive, so its mean must be > 0; got {d['mean']:g}.")
    if "high" in d and not d["high"] > d["low"]:
        raise ScenarioError(f"{where}: high must be greater than low, got low {d['low']:g}, high {d['high']:g}.")
    if kind == "triangular" and not d["low"] <= d["mode"] <= d["high"]:
        raise ScenarioError(f"{where}: the mode must lie in [low, high], got {d['mode']:g}.")
    if kind == "truncnormal" and not (d["low"] <= d["mean"] + 8 * d["sd"] and d["high"] >= d["mean"] - 8 * d["sd"]):
        raise ScenarioError(
            f"{where}: the bounds [{d['low']:g}, {d['high']:g}] lie more than 8 sd from the mean {d['mean']:g}: "
            "almost no mass is left between them; move the bounds or the mean."
        )


def parse_distribution(text, where: str) -> Distribution:
    """``dist:p1:p2...`` or a mapping ``{dist: ..., <param>: ...}`` -> :class:`Distribution` (ScenarioError naming ``where``)."""
    if isinstance(text, dict):
        kind = text.get("dist")
        if kind not in DISTRIBUTIONS:
            raise ScenarioError(f"{where}.dist: expected one of {', '.join(DISTRIBUTIONS)}, got {quote(kind)}.")
        unknown = set(text) - {"dist", *DISTRIBUTIONS[kind]}
        missing = [n for n in DISTRIBUTIONS[kind] if n not in text]
        if unknown or missing:
            raise ScenarioError(
                f"{where}: {kind} takes the keys {', '.join(DISTRIBUTIONS[kind])}"
                + (f"; unknown {', '.join(sorted(map(str, unknown)))}" if unknown else "")
                + (f"; missing {', '.join(missing)}" if missing else "")
                + "."
            )
        params = [text[n] for n in DISTRIBUTIONS[kind]]
    elif isinstance(text, str):
        kind, *params = [p.strip() for p in text.split(":")]
        if kind not in DISTRIBUTIONS:
            raise ScenarioError(
                f"{where}: unknown distribution {quote(kind)}; expected one of {', '.join(DISTRIBUTIONS)}, "
                "e.g. normal:0.8:0.05."
            )
    else:
        raise ScenarioError(f"{where}: expected a distribution such as normal:0.8:0.05, got {quote(text)}.")
    try:
        values = tuple(float(p) for p in params)
    except (TypeError, ValueError):
        raise ScenarioError(f"{where}: the parameters of {kind} must be numbers, got {quote(params)}.") from None
    _check_params(kind, values, where)
    return Distribution(kind, values)


def field_domain(sc, path: str):
    """``(low, high, low_open, high_open, why)`` of the numeric scenario field at dotted ``path`` of the
    validated scenario ``sc`` (ScenarioError if the path is not a numeric field)."""
    node, parts = sc, path.split(".")
    for j, p in enumerate(parts):
        here = ".".join(parts[: j + 1])
        if not dataclasses.is_dataclass(node) or p not in {f.name for f in dataclasses.fields(node)}:
            raise ScenarioError(
                f"--vary {path}: {here} is not a field of the scenario; give the dotted path of a numeric "
                "field, e.g. terrain.xt or tow.force_N."
            )
        if j == len(parts) - 1:
            f = {f.name: f for f in dataclasses.fields(node)}[p]
            value = getattr(node, p)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ScenarioError(
                    f"--vary {path}: the field holds {quote(value)}, not a single number; only numeric fields "
                    "take a distribution (set it to a number in the scenario first)."
                )
            md = f.metadata
            lo = md.get("gt") if md.get("gt") is not None else md.get("ge")
            hi = md.get("lt") if md.get("lt") is not None else md.get("le")
            return lo, hi, md.get("gt") is not None, md.get("lt") is not None, md.get("why", "")
        node = getattr(node, p)
    raise AssertionError("unreachable")


@dataclass(frozen=True)
class ScalarInput:
    """A scenario field with a distribution (``--vary path=dist:...``)."""

    path: str
    dist: Distribution
    low: float | None = None  # the field's domain (draws outside are clipped to it, and counted)
    high: float | None = None

    name = property(lambda self: self.path)
    dim = 1

    def values(self, u) -> dict:
        v = self.dist.ppf(u[:, 0])
        lo = -np.inf if self.low is None else self.low
        hi = np.inf if self.high is None else self.high
        return {self.path: np.clip(v, lo, hi)}

    def describe(self) -> dict:
        return {**self.dist.to_dict(), "clipped_to": [self.low, self.high]}

    def bounded(self, sc) -> ScalarInput:
        """This input with its field's domain; ScenarioError if most of the distribution's mass lies outside."""
        lo, hi, lo_open, hi_open, why = field_domain(sc, self.path)
        if self.path == "terrain.xt":
            lo, lo_open = XT_FIELD_FLOOR, False
        d = self.dist.frozen()
        inside = float(d.cdf(np.inf if hi is None else hi) - d.cdf(-np.inf if lo is None else lo))
        if inside < 0.5:
            span = f"[{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}]"
            raise ScenarioError(
                f"--vary {self.path}={self.dist.text()}: only {100 * inside:.0f} % of the distribution lies in the "
                f"field's domain {span}{' (' + why.rstrip('.') + ')' if why else ''}; draws outside are clipped, "
                "so most draws would sit on the bound. Move the mean inside or reduce the spread."
            )
        if lo is not None and lo_open:
            lo = lo + 1e-9 * max(1.0, abs(lo))
        if hi is not None and hi_open:
            hi = hi - 1e-9 * max(1.0, abs(hi))
        return dataclasses.replace(self, low=lo, high=hi)


def parse_vary(item: str) -> ScalarInput:
    """``--vary PATH=DIST:P1:P2...`` -> :class:`ScalarInput` (domain not yet checked)."""
    if "=" not in item:
        raise ScenarioError(
            f"--vary {quote(item)}: expected PATH=DIST:PARAMS with a dotted scenario field, e.g. terrain.xt=normal:0.8:0.05."
        )
    path, _, spec = item.partition("=")
    path = path.strip()
    if not path or any(not p for p in path.split(".")):
        raise ScenarioError(f"--vary {quote(item)}: the path must be a dotted field such as tow.force_N.")
    return ScalarInput(path, parse_distribution(spec.strip(), f"--vary {path}"))


@dataclass(frozen=True)
class XtField:
    """A spatially random X_t field around the route's X_t: ``X_t(x) = clip(base(x) + sd g(x), floor, 1)``
    with ``g`` the unit Gaussian field of correlation length ``corr_m`` (:func:`snoworm.terrain.gaussian_field`)."""

    sd: float
    corr_m: float

    name = "xt_field"
    dim = 0

    def describe(self) -> dict:
        return {"dist": "gaussian_field", "sd": self.sd, "corr_m": self.corr_m, "floor": XT_FIELD_FLOOR, "ceiling": 1.0}

    def check_mean(self, base_xt_min: float, base_xt_max: float):
        """ScenarioError if the sd puts most of the field's mass outside (0, 1] around the route's X_t."""
        for xt in (base_xt_min, base_xt_max):
            inside = float(stats.norm(xt, self.sd).cdf(1.0) - stats.norm(xt, self.sd).cdf(XT_FIELD_FLOOR))
            if inside < 0.5:
                raise ScenarioError(
                    f"--xt-field sd={self.sd:g}: around the route's X_t {xt:g} only {100 * inside:.0f} % of the field "
                    f"lies in [{XT_FIELD_FLOOR:g}, 1] (X_t's domain is (0, 1]); the rest would be clipped. Reduce sd."
                )


def parse_xt_field(text) -> XtField:
    """``sd=0.05,corr=5`` (or a mapping ``{sd:, corr_m:}``) -> :class:`XtField`."""
    where = "--xt-field" if isinstance(text, str) else "uncertainty.xt_field"
    if isinstance(text, str):
        pairs = {}
        for part in text.split(","):
            k, eq, v = part.partition("=")
            if not eq:
                raise ScenarioError(f"--xt-field {quote(text)}: expected sd=SD,corr=METRES, e.g. sd=0.05,corr=5.")
            pairs[k.strip()] = v.strip()
        text = {("corr_m" if k in ("corr", "corr_m") else k): v for k, v in pairs.items()}
    if not isinstance(text, dict) or set(text) != {"sd", "corr_m"}:
        raise ScenarioError(f"{where}: expected exactly sd and corr (metres), e.g. sd=0.05,corr=5; got {quote(text)}.")
    try:
        sd, corr = float(text["sd"]), float(text["corr_m"])
    except (TypeError, ValueError):
        raise ScenarioError(f"{where}: sd and corr must be numbers, got {quote(text)}.") from None
    if not (math.isfinite(sd) and sd > 0):
        raise ScenarioError(f"{where}: sd must be > 0, got {sd:g} (no field: leave --xt-field out).")
    if not (math.isfinite(corr) and 1e-3 <= corr <= 1e5):
        raise ScenarioError(f"{where}: corr (the correlation length) must be in [0.001, 100000] m, got {corr:g}.")
    return XtField(sd, corr)


@dataclass(frozen=True)
class CalibrationInput:
    """Calibrated terrain-model coefficients drawn jointly: multivariate normal with the fitted values as
    mean and ``diag(stderr) C diag(stderr)`` as covariance (``calibration.json`` of ``snoworm calibrate``)."""

    folder: str
    names: tuple  # coefficient names (fields of terrain.model)
    mean: tuple
    cov: tuple  # rows

    name = "calibration"

    @property
    def dim(self) -> int:
        return len(self.names)

    def values(self, u) -> dict:
        z = stats.norm.ppf(np.clip(u, U_EPS, 1 - U_EPS))
        L = np.linalg.cholesky(np.asarray(self.cov, float))
        x = np.asarray(self.mean, float) + z @ L.T
        return {f"terrain.model.{n}": x[:, j] for j, n in enumerate(self.names)}

    def describe(self) -> dict:
        return {
            "dist": "multivariate_normal",
            "folder": self.folder,
            "names": list(self.names),
            "mean": list(self.mean),
            "cov": [list(r) for r in self.cov],
        }


def read_calibration(folder) -> CalibrationInput:
    """The coefficients and covariance of a ``snoworm calibrate`` output folder (its ``calibration.json``).

    The fitted X_t of each field case (``xt[case]``) is not a scenario coefficient and is left out
    (its standard error is what to give ``--vary terrain.xt=normal:...``, docs/odds.md)."""
    where = f"--calibration {quote(str(folder))}"
    path = Path(folder) / "calibration.json"
    try:
        doc = json.loads(read_regular_file(path, 16 * 2**20).decode("utf-8"))
    except (OSError, ValueError) as exc:
        raise ScenarioError(
            f"{where}: cannot read {path.name} ({exc}); give the output folder of `snoworm calibrate`."
        ) from None
    try:
        pars = doc["parameters"]
        corr = np.asarray(doc["correlation"], dtype=float)
        names = [p["name"] for p in pars]
        value = np.array([p["value"] for p in pars], dtype=float)
        se = np.array([np.nan if p["stderr"] is None else p["stderr"] for p in pars], dtype=float)
    except (KeyError, TypeError, ValueError):
        raise ScenarioError(
            f"{where}: calibration.json has no parameters with values, standard errors and a correlation matrix; "
            "re-run `snoworm calibrate` (it writes them)."
        ) from None
    keep = [j for j, n in enumerate(names) if not n.startswith("xt[")]
    if not keep:
        raise ScenarioError(f"{where}: no terrain-model coefficient was fitted (only X_t of the field cases).")
    if corr.shape != (len(names), len(names)) or not np.all(np.isfinite(corr[np.ix_(keep, keep)])):
        raise ScenarioError(
            f"{where}: calibration.json has no covariance of the fitted coefficients (correlation missing or not "
            "finite, e.g. a fit at a bound or with too few data); fit fewer coefficients or add field data."
        )
    if not np.all(np.isfinite(se[keep])) or not np.all(se[keep] > 0):
        raise ScenarioError(
            f"{where}: a fitted coefficient has no standard error ({', '.join(names[j] for j in keep)}); the "
            "covariance is unknown. Fit fewer coefficients or add field data."
        )
    C = corr[np.ix_(keep, keep)]
    cov = np.outer(se[keep], se[keep]) * C
    try:
        np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        raise ScenarioError(f"{where}: the covariance of the coefficients is not positive definite.") from None
    return CalibrationInput(
        str(folder), tuple(names[j] for j in keep), tuple(value[keep].tolist()), tuple(map(tuple, cov.tolist()))
    )


@dataclass(frozen=True)
class Uncertainty:
    """Every uncertain input of one odds study: scalar fields, an X_t field (or None), calibrated coefficients."""

    scalars: tuple = ()
    xt_field: XtField | None = None
    calibration: CalibrationInput | None = None

    @property
    def groups(self) -> list:
        """The inputs in Sobol order: scalars, calibration, field."""
        return [
            *self.scalars,
            *([self.calibration] if self.calibration else []),
            *([self.xt_field] if self.xt_field else []),
        ]

    @property
    def dim(self) -> int:
        return sum(g.dim for g in self.groups)

    def values(self, U) -> dict:
        """Dotted path -> array of values, one per row of the uniforms ``U`` (n, dim)."""
        out, j = {}, 0
        for g in self.groups:
            if g.dim:
                out.update(g.values(U[:, j : j + g.dim]))
                j += g.dim
        return out

    def describe(self) -> dict:
        return {g.name: g.describe() for g in self.groups}

    def is_empty(self) -> bool:
        return not self.groups


def uncertainty_from_section(section, base_dir=None) -> dict:
    """The ``uncertainty:`` section of a scenario file -> ``{"vary": [...], "xt_field": ..., "calibration": ...}``
    (ScenarioError naming the key)."""
    if section is None:
        return {"vary": [], "xt_field": None, "calibration": None}
    if not isinstance(section, dict):
        raise ScenarioError(
            f"uncertainty: expected a mapping with vary, xt_field or calibration; got {quote(section)}."
        )
    unknown = set(section) - {"vary", "xt_field", "calibration"}
    if unknown:
        raise ScenarioError(
            f"uncertainty.{sorted(map(str, unknown))[0]}: unknown key; known keys: vary, xt_field, calibration."
        )
    vary = section.get("vary") or {}
    if not isinstance(vary, dict):
        raise ScenarioError("uncertainty.vary: expected a mapping of dotted field -> distribution.")
    scalars = [ScalarInput(str(k), parse_distribution(v, f"uncertainty.vary.{k}")) for k, v in vary.items()]
    xf = section.get("xt_field")
    cal = section.get("calibration")
    if cal is not None and base_dir is not None:
        cal = str(Path(base_dir) / str(cal))
    return {"vary": scalars, "xt_field": parse_xt_field(xf) if xf is not None else None, "calibration": cal}
