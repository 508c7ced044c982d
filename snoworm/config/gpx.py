"""Routes from the field: a GPS track (GPX) turned into a route file (``snoworm route import``).

A GPX file's track points (``<trkpt lat= lon=><ele>``; a route's ``<rtept>`` when the file has no
track), in the file's order (several tracks or track segments are joined end to end), become the
rows of a route file (:func:`snoworm.config.routes.read_route`):

* ``distance_m``: the distance along the track, summed over consecutive points from the
  **geodesic** on the WGS84 ellipsoid (:func:`geodesic_m`, Vincenty's inverse formula: accurate to
  ~0.5 mm on the ellipsoid, Vincenty 1975; it converges except for nearly antipodal points, which
  consecutive track points never are).  The haversine on a sphere would err by up to 0.5 % (the
  ellipsoid's flattening), 5 m a kilometre; Karney's algorithm (``geographiclib``, ``pyproj``) is
  as exact here and needs a dependency.  The track is taken as a curve on the ellipsoid: the
  elevation's change adds ``1 - cos(theta)`` to the length (0.4 % at 5 deg, 1.5 % at 10 deg), which
  is left out, as GPS tracks' lengths usually are.  Points less than :data:`MIN_SPACING_M` after the
  previous one (a receiver standing still) are dropped (the route's distances must increase).
* ``elevation_m``: the points' ``<ele>`` smoothed along the track by a triangular window of full
  width ``smooth_m`` (:func:`smooth_elevation`; default :data:`DEFAULT_SMOOTH_M`).  GPS elevations
  scatter by metres from fix to fix; a route's grade is their slope, and unsmoothed, a 1 m
  scatter over 2 m between points is a 30 deg grade.  The triangular window (a moving average of
  width ``smooth_m / 2`` applied twice) makes the grade at a point the mean over the window
  instead of the difference of two raw points; what is shorter than about ``smooth_m / 2`` is
  smoothed away.  ``smooth_m = 0`` keeps the raw elevations.
* ``xt``: a constant (``xt=0.8``) or, per point, the number in the element named ``xt_tag``
  inside the point's ``<extensions>`` (any namespace, e.g. ``<extensions><sw:xt>0.6</sw:xt>``).

The file also gets the columns ``latitude_deg``, ``longitude_deg`` and ``gpx_elevation_m`` (the raw
elevation), which the route reader ignores, and comment lines saying where it came from.  Bad GPX:
:class:`~snoworm.config.schema.ScenarioError` naming the file, the line and the fix.
"""

from __future__ import annotations

import math
import os
import xml.parsers.expat
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._version import __version__
from ..infra.files import FileProblem, read_regular_file
from ..slope import MAX_GRADE_DEG, ElevationProfile
from .routes import MAX_ROUTE_BYTES, ROUTE_COLUMNS
from .schema import ScenarioError, quote, short_path

__all__ = [
    "WGS84_A_M",
    "WGS84_F",
    "DEFAULT_SMOOTH_M",
    "MIN_SPACING_M",
    "GpxTrack",
    "geodesic_m",
    "read_gpx",
    "smooth_elevation",
    "route_from_track",
    "route_csv",
]

#: WGS84 ellipsoid: semi-major axis [m] and flattening (NIMA TR8350.2), the datum of GPS.
WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
#: Default full width of the elevation's triangular smoothing window [m]: longer than the scatter
#: of GPS elevations between a few fixes, shorter than the hills a chain of ~10 m climbs (assumed).
DEFAULT_SMOOTH_M = 20.0
#: Smallest step between kept points [m]: closer points (a receiver standing still) are dropped,
#: so distances written to the millimetre still increase strictly.
MIN_SPACING_M = 0.01
_ITERATIONS = 200


def geodesic_m(
    lat1_deg: np.ndarray,
    lon1_deg: np.ndarray,
    lat2_deg: np.ndarray,
    lon2_deg: np.ndarray,
    a_m: float = WGS84_A_M,
    f: float = WGS84_F,
) -> np.ndarray:
    """Geodesic distance [m] between points 1 and 2 on the ellipsoid ``(a_m, f)`` (any shapes that
    broadcast): Vincenty's inverse formula (T. Vincenty, "Direct and inverse solutions of geodesics on
    the ellipsoid with application of nested equations", Survey Review 23(176), 1975, Eqs. 3-6 and
    the iteration on lambda), iterated to 1e-12 rad, all pairs at once.

    Raises
    ------
    ValueError
        The iteration does not converge (nearly antipodal points).
    """
    b_m = (1.0 - f) * a_m
    L = np.radians(np.asarray(lon2_deg, float) - np.asarray(lon1_deg, float))
    U1 = np.arctan((1.0 - f) * np.tan(np.radians(np.asarray(lat1_deg, float))))
    U2 = np.arctan((1.0 - f) * np.tan(np.radians(np.asarray(lat2_deg, float))))
    L, U1, U2 = np.broadcast_arrays(L, U1, U2)
    sU1, cU1, sU2, cU2 = np.sin(U1), np.cos(U1), np.sin(U2), np.cos(U2)
    lam = L.copy()
    for _ in range(_ITERATIONS):
        sl, cl = np.sin(lam), np.cos(lam)
        s_sig = np.hypot(cU2 * sl, cU1 * sU2 - sU1 * cU2 * cl)
        c_sig = sU1 * sU2 + cU1 * cU2 * cl
        sig = np.arctan2(s_sig, c_sig)
        s_alpha = np.where(s_sig > 0, cU1 * cU2 * sl / np.where(s_sig > 0, s_sig, 1.0), 0.0)
        c2_alpha = 1.0 - s_alpha**2
        # on the equator (cos^2 alpha = 0) the term vanishes
        c2sm = np.where(c2_alpha > 0, c_sig - 2.0 * sU1 * sU2 / np.where(c2_alpha > 0, c2_alpha, 1.0), 0.0)
        C = f / 16.0 * c2_alpha * (4.0 + f * (4.0 - 3.0 * c2_alpha))
        lam_new = L + (1.0 - C) * f * s_alpha * (sig + C * s_sig * (c2sm + C * c_sig * (-1.0 + 2.0 * c2sm**2)))
        done = np.abs(lam_new - lam) <= 1e-12
        lam = lam_new
        if np.all(done):
            break
    else:
        raise ValueError("Vincenty's inverse formula did not converge (nearly antipodal points)")
    u2 = c2_alpha * (a_m**2 - b_m**2) / b_m**2
    A = 1.0 + u2 / 16384.0 * (4096.0 + u2 * (-768.0 + u2 * (320.0 - 175.0 * u2)))
    B = u2 / 1024.0 * (256.0 + u2 * (-128.0 + u2 * (74.0 - 47.0 * u2)))
    d_sig = (
        B
        * s_sig
        * (
            c2sm
            + B
            / 4.0
            * (c_sig * (-1.0 + 2.0 * c2sm**2) - B / 6.0 * c2sm * (-3.0 + 4.0 * s_sig**2) * (-3.0 + 4.0 * c2sm**2))
        )
    )
    return np.asarray(b_m * A * (sig - d_sig), float)


@dataclass(frozen=True)
class GpxTrack:
    """The points of a GPX file, in order: latitude and longitude [deg], elevation [m], X_t from the
    extension tag (NaN without one) and the line of each point in the file."""

    path: str
    lat_deg: np.ndarray
    lon_deg: np.ndarray
    ele_m: np.ndarray
    xt: np.ndarray
    line: np.ndarray


class _Reader:
    """Collects the track (or route) points of a GPX document from expat's events, with their lines."""

    def __init__(self, parser: xml.parsers.expat.XMLParserType, where: str, xt_tag: str | None) -> None:
        self.parser, self.where, self.xt_tag = parser, where, xt_tag
        self.points: dict[str, list[dict]] = {"trkpt": [], "rtept": []}
        self.stack: list[str] = []
        self.point: dict | None = None
        self.text: list[str] = []

    def start(self, name: str, attrs: dict[str, str]) -> None:
        local = name.rsplit(" ", 1)[-1]  # namespace_separator " ": "URI local"
        self.stack.append(local)
        self.text = []
        if local in ("trkpt", "rtept") and self.point is None:
            self.point = {"kind": local, "line": self.parser.CurrentLineNumber, "attrs": dict(attrs)}

    def end(self, name: str) -> None:
        local = self.stack.pop()
        p = self.point
        if p is not None:
            text = "".join(self.text).strip()
            if local == "ele" and "ele" not in p:
                p["ele"] = (text, self.parser.CurrentLineNumber)
            elif self.xt_tag is not None and local == self.xt_tag and "extensions" in self.stack and "xt" not in p:
                p["xt"] = (text, self.parser.CurrentLineNumber)
            elif local == p["kind"]:
                self.points[local].append(p)
                self.point = None
        self.text = []

    def chars(self, data: str) -> None:
        self.text.append(data)

    def no_entities(self, *args: object) -> None:
        raise ScenarioError(
            f"{self.where}, line {self.parser.CurrentLineNumber}: declares an entity; a GPX file needs "
            "none, and snoworm reads none (export the track again from the GPS software)."
        )


def _parse(data: bytes, where: str, xt_tag: str | None) -> list[dict]:
    parser = xml.parsers.expat.ParserCreate(namespace_separator=" ")
    reader = _Reader(parser, where, xt_tag)
    parser.StartElementHandler = reader.start
    parser.EndElementHandler = reader.end
    parser.CharacterDataHandler = reader.chars
    parser.EntityDeclHandler = reader.no_entities
    parser.SetParamEntityParsing(xml.parsers.expat.XML_PARAM_ENTITY_PARSING_NEVER)
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError as exc:
        raise ScenarioError(
            f"{where}, line {exc.lineno}, column {exc.offset + 1}: not well-formed XML "
            f"({xml.parsers.expat.ErrorString(exc.code)}); a GPX file is XML: export the track again "
            "as GPX 1.1 from the GPS software."
        ) from None
    pts = reader.points["trkpt"] or reader.points["rtept"]
    if not pts:
        raise ScenarioError(
            f"{where}: holds no track points (<trk><trkseg><trkpt lat=.. lon=..>) nor route points "
            "(<rtept>); give the GPX file of a recorded track."
        )
    return pts


def _coordinate(p: dict, key: str, limit: float, where: str) -> float:
    text = p["attrs"].get(key)
    tag = f"{where}, line {p['line']}: <{p['kind']}>"
    if text is None:
        raise ScenarioError(f"{tag} has no '{key}' attribute; every point needs lat and lon in degrees (WGS84).")
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and -limit <= v <= limit):
        raise ScenarioError(
            f"{tag} '{key}' must be a number of degrees in [-{limit:g}, {limit:g}], got {quote(text, 40)}."
        )
    return v


def _number(p: dict, key: str, what: str, fix: str, where: str) -> float:
    if key not in p:
        raise ScenarioError(f"{where}, line {p['line']}: <{p['kind']}> has no {what}; {fix}")
    text, line = p[key]
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not math.isfinite(v):
        raise ScenarioError(f"{where}, line {line}: {what} must be a finite number, got {quote(text, 40)}.")
    return v


def read_gpx(path: str | os.PathLike[str], xt_tag: str | None = None) -> GpxTrack:
    """The points of the GPX file at ``path`` (see the module docstring); ``xt_tag``: the local name
    of the element in each point's ``<extensions>`` that holds X_t.

    Raises
    ------
    ScenarioError
        Not a readable GPX file, a point without lat, lon or ele (or X_t, with ``xt_tag``), a value
        out of range; the message names the file, the line and the fix.
    """
    where = f"route import: {short_path(path)}"
    try:
        data = read_regular_file(Path(path), MAX_ROUTE_BYTES * 4)
    except FileNotFoundError:
        raise ScenarioError(f"{where}: no such file; give the path of a GPX file.") from None
    except FileProblem as exc:
        raise ScenarioError(f"{where}: the file is {exc}; give a GPX file.") from None
    except OSError as exc:
        raise ScenarioError(f"{where}: cannot read it ({exc.strerror or exc}).") from None
    pts = _parse(data, where, xt_tag)
    lat = [_coordinate(p, "lat", 90.0, where) for p in pts]
    lon = [_coordinate(p, "lon", 180.0, where) for p in pts]
    fix = "the route needs the elevation of every point: record or export the track with elevations."
    ele = [_number(p, "ele", "<ele> (elevation)", fix, where) for p in pts]
    xts = [math.nan] * len(pts)
    if xt_tag is not None:
        fix = f"give every point an <extensions><{xt_tag}> with its X_t, or a constant X_t (--xt)."
        xts = [_number(p, "xt", f"<{xt_tag}> in its <extensions>", fix, where) for p in pts]
        for p, v in zip(pts, xts):
            if not 0 < v <= 1:
                raise ScenarioError(
                    f"{where}, line {p['xt'][1]}: X_t (<{xt_tag}>) must be in (0, 1] (paper section 3), got {v:g}."
                )
    arr = lambda v: np.asarray(v, float)  # noqa: E731
    return GpxTrack(str(path), arr(lat), arr(lon), arr(ele), arr(xts), np.array([p["line"] for p in pts]))


def smooth_elevation(s_m: np.ndarray, z_m: np.ndarray, smooth_m: float) -> np.ndarray:
    """Elevations ``z_m`` at distances ``s_m`` smoothed by a triangular window of full width
    ``smooth_m`` [m]: the moving average of width ``smooth_m / 2`` of the piecewise-linear
    elevation (exact, :meth:`~snoworm.slope.ElevationProfile.mean_elevation`), applied twice.  Near
    the ends the window holds the end's elevation beyond them.  ``smooth_m = 0``: unchanged."""
    z = np.asarray(z_m, float)
    if smooth_m <= 0 or len(s_m) < 2:
        return z.copy()
    pos = tuple(float(v) for v in s_m)
    for _ in range(2):
        z = np.asarray(
            ElevationProfile(pos, tuple(float(v) for v in z)).mean_elevation(np.asarray(s_m), smooth_m / 4.0)
        )
    return z


@dataclass(frozen=True)
class ImportedRoute:
    """A route made from a track: rows of ``distance_m``, ``elevation_m`` and ``xt`` with the kept
    points' latitude, longitude, raw elevation and line; ``dropped``: points closer than
    :data:`MIN_SPACING_M` to the previous one."""

    distance_m: np.ndarray
    elevation_m: np.ndarray
    xt: np.ndarray
    lat_deg: np.ndarray
    lon_deg: np.ndarray
    gpx_elevation_m: np.ndarray
    line: np.ndarray
    dropped: int
    smooth_m: float


def route_from_track(track: GpxTrack, smooth_m: float = DEFAULT_SMOOTH_M, xt: float | None = None) -> ImportedRoute:
    """The route of ``track`` (see the module docstring); ``xt``: a constant X_t (else the track's own).

    Raises
    ------
    ScenarioError
        Fewer than two distinct points, no X_t, or a grade over the route's limit after smoothing.
    """
    where = f"route import: {short_path(track.path)}"
    if xt is None and np.isnan(track.xt).any():
        raise ScenarioError(f"{where}: no X_t; give a constant (--xt 0.8) or the points' extension tag (--xt-tag).")
    if xt is not None and not (math.isfinite(xt) and 0 < xt <= 1):
        raise ScenarioError(f"--xt: X_t must be in (0, 1] (paper section 3), got {xt!r}.")
    if not (math.isfinite(smooth_m) and 0 <= smooth_m <= 1e5):
        raise ScenarioError(f"--smooth-m: the smoothing window must be from 0 to 100 km, got {smooth_m!r} m.")
    step = geodesic_m(track.lat_deg[:-1], track.lon_deg[:-1], track.lat_deg[1:], track.lon_deg[1:])
    keep, s, acc = [0], [0.0], 0.0
    for j, d in enumerate(step, start=1):
        acc += float(d)
        if acc >= MIN_SPACING_M:  # the distance from the last kept point
            keep.append(j)
            s.append(s[-1] + acc)
            acc = 0.0
    if len(keep) < 2:
        raise ScenarioError(
            f"{where}: the track's points lie within {MIN_SPACING_M:g} m of each other; a route needs a track "
            "that goes somewhere."
        )
    k = np.array(keep)
    dist = np.array(s)
    z = smooth_elevation(dist, track.ele_m[k], smooth_m)
    rise = np.abs(np.diff(z) / np.diff(dist))
    j = int(np.argmax(rise))
    if rise[j] > math.sin(math.radians(MAX_GRADE_DEG)):
        grade = math.degrees(math.asin(min(rise[j], 1.0)))
        raise ScenarioError(
            f"{where}, line {track.line[k[j + 1]]}: after smoothing over {smooth_m:g} m the elevation changes by "
            f"{z[j + 1] - z[j]:.2f} m from {dist[j]:.1f} m to {dist[j + 1]:.1f} m along the track, a grade of "
            f"{grade:.1f} deg, over a route's {MAX_GRADE_DEG:g} deg limit; smooth over a longer window "
            "(--smooth-m) or check the elevations."
        )
    xts = np.full(k.size, float(xt)) if xt is not None else track.xt[k]
    return ImportedRoute(
        dist,
        z,
        xts,
        track.lat_deg[k],
        track.lon_deg[k],
        track.ele_m[k],
        track.line[k],
        len(step) + 1 - k.size,
        smooth_m,
    )


def route_csv(route: ImportedRoute, source: str) -> str:
    """The text of the route file (:func:`snoworm.config.routes.read_route` reads it): comment lines
    with the provenance, the header, a row per kept point (distances and elevations to the mm)."""
    head = [
        f"# route imported from {source} by snoworm {__version__} (snoworm route import)",
        f"# {route.distance_m.size} points ({route.dropped} dropped within {MIN_SPACING_M:g} m of the previous), "
        f"{route.distance_m[-1]:.1f} m along the track",
        "# distance_m: geodesic on the WGS84 ellipsoid (Vincenty's inverse) summed over the points",
        f"# elevation_m: the GPX <ele> smoothed by a triangular window of {route.smooth_m:g} m (gpx_elevation_m: raw)",
        ",".join([*ROUTE_COLUMNS, "latitude_deg", "longitude_deg", "gpx_elevation_m"]),
    ]
    cols = (route.distance_m, route.elevation_m, route.xt, route.lat_deg, route.lon_deg, route.gpx_elevation_m)
    rows = [
        f"{s:.3f},{z:.3f},{x:.6g},{la:.8f},{lo:.8f},{e:.3f}" for s, z, x, la, lo, e in zip(*(c.tolist() for c in cols))
    ]
    return "\n".join(head + rows) + "\n"
