"""Grade inputs of a scenario and route files (docs/model.md section 7, beyond the paper).

A scenario's ``terrain`` section gives the elevation along the track in one of three ways:

* ``grade_deg: 8`` -- a constant grade, optionally with ``grade_patches`` of other grade on it;
* ``elevation: [[distance_m, elevation_m], ...]`` -- a piecewise-linear table;
* ``route: FILE`` -- a CSV route file (:func:`read_route`) that gives the elevation *and* X_t
  along the track, as a field survey or a GPS track resampled to distance along the track gives.

All compile to one :class:`~snoworm.slope.ElevationProfile`.  Validation (one-line messages,
exit status 2 at the command line): finite numbers, strictly increasing distances and
``|grade| <= MAX_GRADE_DEG`` (40 deg).
"""

from __future__ import annotations

import csv
import errno
import math
from dataclasses import dataclass, field as dc_field
from pathlib import Path

from ..infra.files import FileProblem, read_regular_file
from ..slope import MAX_GRADE_DEG, ElevationProfile
from .schema import Config, ScenarioError, field, quote, short_path

__all__ = [
    "check_grade_inputs",
    "resolve_route",
    "GRADE_DOMAIN",
    "ROUTE_COLUMNS",
    "GradePatchConfig",
    "Route",
    "read_route",
    "check_elevation_table",
    "check_vehicle_on_grade",
    "route_end_warning",
]

#: Domain of every grade angle a scenario or a study gives [deg].
GRADE_DOMAIN = dict(
    ge=-MAX_GRADE_DEG,
    le=MAX_GRADE_DEG,
    why=f"|grade| <= {MAX_GRADE_DEG:g} deg: no snow slope stands beyond its angle of repose "
    "(30-40 deg), and the 1-D chain assumes gentle curvature (docs/model.md section 7).",
)

#: Columns a route file must have (units in the names); others are ignored.
ROUTE_COLUMNS = ("distance_m", "elevation_m", "xt")
#: Largest route file read (bytes): a survey of a million points is ~30 MB.
MAX_ROUTE_BYTES = 64 * 2**20

_FAR_M = 1e7


@dataclass(frozen=True)
class GradePatchConfig(Config):
    """A stretch of other grade on the base ``grade_deg`` (``terrain.grade_patches``)."""

    _section = "terrain.grade_patches[]"
    start_m: float = field(
        ge=-_FAR_M,
        le=_FAR_M,
        unit="m",
        doc="distance where the patch's grade is reached",
        why="A finite distance along the track.",
    )
    end_m: float = field(
        ge=-_FAR_M,
        le=_FAR_M,
        unit="m",
        doc="distance where the patch's grade ends",
        why="A finite distance along the track.",
    )
    grade_deg: float = field(**GRADE_DOMAIN, unit="deg", doc="grade inside the patch, positive uphill")
    ramp_m: float = field(
        0.0,
        ge=0,
        le=_FAR_M,
        unit="m",
        why="A finite length.",
        doc="length over which the grade changes back to the base outside each edge (0: a kink)",
    )

    def _check(self, path):
        if not self.end_m > self.start_m:
            raise ScenarioError(
                f"{path}.end_m: must be greater than start_m ({self.start_m} m), got {self.end_m} m. "
                "A grade patch covers [start_m, end_m]."
            )


def check_grade_inputs(terrain, path: str) -> None:
    """The grade inputs of a ``terrain`` section (:class:`~snoworm.config.sections.TerrainConfig`):
    at most one of ``grade_deg``, ``elevation``, ``route``; grade patches on a base grade, in order
    without overlap; the elevation table; the route file, read (once) and checked."""
    grades = [k for k in ("grade_deg", "elevation", "route") if getattr(terrain, k) is not None]
    if len(grades) > 1:
        raise ScenarioError(
            f"{path}: give at most one of 'grade_deg', 'elevation' and 'route' (a route file "
            f"carries its elevation); got {' and '.join(repr(g) for g in grades)}."
        )
    if terrain.grade_patches is not None and terrain.grade_deg is None:
        raise ScenarioError(
            f"{path}.grade_patches: grade patches lie on a base grade; give 'grade_deg' "
            "(the grade outside the patches, 0 for level)."
        )
    prev_end, prev_j = -math.inf, None
    for j, pt in enumerate(terrain.grade_patches or ()):
        if pt.start_m - pt.ramp_m < prev_end:
            raise ScenarioError(
                f"{path}.grade_patches[{j}]: overlaps grade_patches[{prev_j}] (with its ramps); "
                "list grade patches in order along the route, without overlap."
            )
        prev_end, prev_j = pt.end_m + pt.ramp_m, j
    if terrain.elevation is not None:
        check_elevation_table(terrain.elevation, f"{path}.elevation")
    if terrain.route is not None:
        terrain.route_data()  # read (and checked) once, at validation


def resolve_route(terrain_raw: dict, base_dir) -> dict:
    """The ``terrain`` mapping with a relative ``route`` file taken from ``base_dir`` (the scenario
    file's folder) and made absolute, before validation (called by
    :func:`~snoworm.config.scenario.scenario_from_dict`; a route given directly in Python is read
    from the working directory)."""
    route = terrain_raw.get("route")
    if isinstance(route, str) and route:
        p = Path(route)
        try:
            return {**terrain_raw, "route": str((p if p.is_absolute() else Path(base_dir) / p).resolve())}
        except (OSError, RuntimeError, ValueError) as exc:  # a symlink loop, a NUL byte, a name too long
            raise ScenarioError(
                f"terrain.route: {quote(route, 200)} cannot be used as a path ({_why(exc)}); "
                "give a CSV route file relative to the scenario's folder."
            ) from None
    return terrain_raw


def _why(exc) -> str:
    """What is wrong with a path, from the exception a path operation raised."""
    if isinstance(exc, ValueError):
        return "it holds a NUL byte" if "null" in str(exc) else quote(str(exc), 100)
    if isinstance(exc, RuntimeError) or getattr(exc, "errno", None) == errno.ELOOP:
        return "a symbolic link loop"
    return getattr(exc, "strerror", None) or quote(str(exc), 100)


def check_elevation_table(pairs, where: str) -> None:
    """Check ``[[distance_m, elevation_m], ...]``: finite, strictly increasing, |grade| within the limit."""
    if len(pairs) < 2:
        raise ScenarioError(f"{where}: needs at least two [distance_m, elevation_m] pairs (a level track needs none).")
    prev = None
    for j, pair in enumerate(pairs):
        if len(pair) != 2:
            raise ScenarioError(f"{where}[{j}]: expected a pair [distance_m, elevation_m], got {list(pair)!r}.")
        _check_step(prev, pair, f"{where}[{j}]")
        prev = pair


def _check_step(prev, pair, where):
    s, z = pair
    for v, name in ((s, "distance_m"), (z, "elevation_m")):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or abs(v) > _FAR_M:
            raise ScenarioError(f"{where}: {name} must be a finite number within +-{_FAR_M:g} m, got {v!r}.")
    if prev is None:
        return
    if not s > prev[0]:
        raise ScenarioError(f"{where}: distances must increase strictly; {s:g} m follows {prev[0]:g} m.")
    rise = (z - prev[1]) / (s - prev[0])
    lim = math.sin(math.radians(MAX_GRADE_DEG))
    if abs(rise) > lim:
        grade = math.degrees(math.asin(min(abs(rise), 1.0)))
        raise ScenarioError(
            f"{where}: the grade from {prev[0]:g} m to {s:g} m is {grade:.1f} deg (rise {rise:.3f} per "
            f"metre along the track), over the {MAX_GRADE_DEG:g} deg limit; check the units and the "
            "distances (along the track, in metres)."
        )


@dataclass(frozen=True)
class Route:
    """A route read from a file: distances along the track [m], elevations [m] and X_t, one per row;
    ``data``: the file's bytes as read (what a results folder keeps a copy of, issue 30)."""

    path: str
    distance_m: tuple
    elevation_m: tuple
    xt: tuple
    data: bytes = dc_field(default=b"", repr=False, compare=False)

    def elevation_profile(self) -> ElevationProfile:
        return ElevationProfile(self.distance_m, self.elevation_m)


def _number(text, where):
    try:
        v = float(text)
    except ValueError:
        raise ScenarioError(f"{where}: expected a number, got {quote(text.strip(), 60)}.") from None
    if not math.isfinite(v):
        raise ScenarioError(f"{where}: expected a finite number, got {quote(text.strip(), 60)}.")
    return v


#: Longest cell of a route file (characters): csv's own field limit, stated here.
MAX_ROUTE_CELL = 131_072


def _csv_rows(text: str, where: str) -> list:
    """(line number, cells) of the rows of a route file's text that are not empty or comments."""
    rows, reader = [], csv.reader(text.splitlines())
    while True:
        try:
            r = next(reader)
        except StopIteration:
            return rows
        except csv.Error as exc:  # a cell over the field limit, a NUL byte
            detail = (
                f"a cell is longer than {MAX_ROUTE_CELL} characters"
                if "field larger" in str(exc)
                else quote(str(exc), 100)
            )
            raise ScenarioError(
                f"{where}, line {reader.line_num}: not a CSV row ({detail}); a route file holds short numbers."
            ) from None
        if r and not r[0].lstrip().startswith("#"):
            rows.append((reader.line_num, r))


def _route_row(row, n, header, col, where) -> dict:
    """The numbers of route line ``n`` (its cells ``row``) by column name, checked: one cell per
    header column, each a finite number, X_t in (0, 1] (ScenarioError naming the line and column)."""
    if any(c.strip() for c in row[len(header) :]):
        raise ScenarioError(
            f"{where}, line {n}: {len(row)} cells, but the header names {len(header)} columns; a cell "
            "without a column (a decimal comma? a missing header name?) would be dropped. Give each row "
            "one cell per header column, with decimal points."
        )
    vals = {}
    for c in ROUTE_COLUMNS:
        j = col[c]
        cell = f"{where}, line {n}, column {j + 1} ({c})"
        if j >= len(row):
            raise ScenarioError(f"{cell}: missing; the row has {len(row)} columns, the header {len(header)}.")
        vals[c] = _number(row[j], cell)
    if not 0 < vals["xt"] <= 1:
        raise ScenarioError(
            f"{where}, line {n}, column {col['xt'] + 1} (xt): X_t must be in (0, 1] "
            f"(paper section 3), got {vals['xt']:g}."
        )
    return vals


def read_route(path) -> Route:
    """Read a route CSV: a header with ``distance_m``, ``elevation_m`` and ``xt`` (other columns ignored),
    then one row per survey point; lines starting with ``#`` are comments (e.g. the provenance).

    ``distance_m`` is the distance along the track (strictly increasing), ``elevation_m`` the
    elevation, ``xt`` the terrain coefficient in (0, 1].  Errors name the file, line and column.

    Raises
    ------
    ScenarioError
        ``terrain.route: FILE, line L, column C (name): ...``.
    """
    p = Path(path)
    where = f"terrain.route: {short_path(p)}"
    try:
        data = read_regular_file(p, MAX_ROUTE_BYTES)
        # utf-8-sig: a spreadsheet's UTF-8 byte-order mark is not part of the first column's name
        text = data.decode("utf-8-sig")
    except FileNotFoundError:
        raise ScenarioError(
            f"{where}: no such file; give a CSV route file relative to the scenario's folder."
        ) from None
    except FileProblem as exc:
        raise ScenarioError(f"{where}: the route file is {exc}; give a CSV file.") from None
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{where}: not UTF-8 text (byte {exc.start}); save the route as UTF-8 CSV.") from None
    except (OSError, RuntimeError, ValueError) as exc:
        raise ScenarioError(f"{where}: cannot read it ({_why(exc)}).") from None
    rows = _csv_rows(text, where)
    if not rows:
        raise ScenarioError(f"{where}: empty; expected a header {','.join(ROUTE_COLUMNS)} and rows of numbers.")
    hline, header = rows[0]
    header = [h.strip() for h in header]
    missing = [c for c in ROUTE_COLUMNS if c not in header]
    if missing:
        raise ScenarioError(
            f"{where}, line {hline}: the header lacks {', '.join(missing)}; expected the columns "
            f"{','.join(ROUTE_COLUMNS)} (units in the names: metres, metres, X_t)."
        )
    col = {c: header.index(c) for c in ROUTE_COLUMNS}
    dist, elev, xts, prev = [], [], [], None
    for n, row in rows[1:]:
        vals = _route_row(row, n, header, col, where)
        pair = (vals["distance_m"], vals["elevation_m"])
        _check_step(prev, pair, f"{where}, line {n}")
        prev = pair
        dist.append(pair[0])
        elev.append(pair[1])
        xts.append(vals["xt"])
    if len(dist) < 2:
        raise ScenarioError(f"{where}: needs at least two rows of numbers after the header.")
    return Route(str(p), tuple(dist), tuple(elev), tuple(xts), data)


def check_vehicle_on_grade(vehicle, elevation: ElevationProfile | None, path: str = "vehicle.segment") -> None:
    """Every wheel keeps a positive normal load on the steepest grade (the pitch load transfer of
    :func:`snoworm.terrain.normal_load_N` must not lift an axle: ``2 h / b tan(theta) < 1``)."""
    if elevation is None or elevation.is_level:
        return
    theta = math.radians(elevation.max_abs_grade_deg())
    for k, seg in enumerate(vehicle.segment_params()):
        h, b = seg.com_height_m, seg.wheelbase_m
        if h > 0 and (b <= 0 or 2.0 * h * math.tan(theta) >= b):
            raise ScenarioError(
                f"{path}.com_height_m: segment {k} tips (an axle lifts off) on the steepest grade "
                f"{math.degrees(theta):.1f} deg: needs 2 h tan(theta) < wheelbase ({b:g} m), h = {h:g} m. "
                "Lower the centre of mass or the grade."
            )


def route_end_warning(route: Route, t_s, front_m) -> str | None:
    """One line when a run drove past the end of its route file, else None.

    ``t_s``: the output times [s]; ``front_m``: the position of the leader's front axle at those times
    [m] (the chain's foremost contact).  Beyond the last row the terrain is not extrapolated: the
    elevation is held (level ground, :class:`~snoworm.slope.ElevationProfile`) and so is X_t
    (:class:`~snoworm.terrain.TerrainProfile`), at the last row's values.
    """
    end = route.distance_m[-1]
    past = [j for j, x in enumerate(front_m) if x > end]
    if not past:
        return None
    return (
        f"warning: the chain drove past the end of the route file {short_path(route.path, 120)} at "
        f"t = {float(t_s[past[0]]):.1f} s (its front axle reached {max(front_m):.1f} m; the file ends at {end:g} m). "
        f"Beyond it the run went on over level ground at the last row's elevation ({route.elevation_m[-1]:g} m) "
        f"and X_t ({route.xt[-1]:g}), held, not extrapolated; give a longer route or a shorter simulation.duration_s."
    )
