"""GPS tracks to route files (issue 34): the geodesic, the smoothing, the file and its errors."""

import math

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.integrate import quad

from snoworm import load_scenario
from snoworm.cli import main
from snoworm.config import gpx
from snoworm.config.gpx import geodesic_m, read_gpx, route_csv, route_from_track, smooth_elevation
from snoworm.config.routes import read_route
from snoworm.config.schema import ScenarioError
from tests.conftest import SCENARIOS


def dms(d, m, s, sign=1):
    return sign * (d + m / 60 + s / 3600)


# ------------------------------------------------------------------ the geodesic
@pytest.mark.parametrize(
    "ellipsoid, p1, p2, s_m",
    [
        # T. Vincenty (1975), Survey Review 23(176), the test lines (a)-(c) of its table
        ((6377397.155, 1 / 299.1528128), (dms(55, 45, 0), 0.0), (dms(33, 26, 0, -1), dms(108, 13, 0)), 14110526.170),
        (
            (6378388.0, 1 / 297.0),
            (dms(37, 19, 54.95367), 0.0),
            (dms(26, 7, 42.83946), dms(41, 28, 35.50729)),
            4085966.703,
        ),
        (
            (6378388.0, 1 / 297.0),
            (dms(35, 16, 11.24862), 0.0),
            (dms(67, 22, 14.77638), dms(137, 47, 28.31435)),
            8084823.839,
        ),
        # Geoscience Australia's worked example on GRS80: Flinders Peak to Buninyong
        (
            (6378137.0, 1 / 298.257222101),
            (dms(37, 57, 3.72030, -1), dms(144, 25, 29.52440)),
            (dms(37, 39, 10.15610, -1), dms(143, 55, 35.38390)),
            54972.271,
        ),
    ],
)
def test_geodesic_matches_the_literature(ellipsoid, p1, p2, s_m):
    # the published distances are rounded to the millimetre; Vincenty's formula is good to ~0.1 mm
    assert geodesic_m(*p1, *p2, *ellipsoid) == pytest.approx(s_m, abs=1e-3)


def test_geodesic_on_the_equator_and_along_a_meridian():
    a, f = gpx.WGS84_A_M, gpx.WGS84_F
    # the equator is a circle of radius a (a geodesic for arcs up to (1 - f) pi)
    assert geodesic_m(0.0, 10.0, 0.0, 10.5) == pytest.approx(a * math.radians(0.5), rel=1e-12)
    # a meridian arc: the integral of the meridian's radius of curvature M = a (1 - e2) / (1 - e2 sin^2)^1.5
    e2 = f * (2 - f)
    arc, _ = quad(lambda p: a * (1 - e2) / (1 - e2 * math.sin(p) ** 2) ** 1.5, math.radians(45.0), math.radians(45.2))
    assert geodesic_m(45.0, 7.0, 45.2, 7.0) == pytest.approx(arc, abs=1e-6)
    assert geodesic_m(45.0, 7.0, 45.0, 7.0) == 0.0


# ------------------------------------------------------------------ GPX files
def gpx_text(points, xt_tag=None, ns=True):
    """A GPX 1.1 document of track points (lat, lon, ele[, xt]), one per line after the header."""
    ext_ns = ' xmlns:sw="https://example.org/snoworm"' if ns else ""
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<gpx version="1.1" creator="test" xmlns="http://www.topografix.com/GPX/1/1"{ext_ns}>',
        "<trk><name>t</name><trkseg>",
    ]
    for p in points:
        ext = f"<extensions><sw:{xt_tag}>{p[3]}</sw:{xt_tag}></extensions>" if xt_tag else ""
        lines.append(f'<trkpt lat="{p[0]}" lon="{p[1]}"><ele>{p[2]}</ele>{ext}</trkpt>')
    lines.append("</trkseg></trk></gpx>")
    return "\n".join(lines) + "\n"


def meridian_track(n=40, step_deg=2e-5, grade=0.05):
    """Points northwards along the meridian 11 E from 46 N, elevations on a ramp of ``grade``."""
    lat = 46.0 + step_deg * np.arange(n)
    s = np.concatenate([[0.0], np.cumsum(geodesic_m(lat[:-1], 11.0, lat[1:], 11.0))])
    return lat, s, 1500.0 + grade * s


def test_round_trip_through_the_route_reader(tmp_path):
    lat, s, z = meridian_track()
    xt = np.linspace(0.4, 0.9, lat.size)
    track = tmp_path / "t.gpx"
    track.write_text(gpx_text([(la, 11.0, f"{e:.4f}", f"{x:.4f}") for la, e, x in zip(lat, z, xt)], xt_tag="xt"))
    out = tmp_path / "route.csv"
    r = CliRunner().invoke(
        main, ["route", "import", str(track), "--out", str(out), "--xt-tag", "xt", "--smooth-m", "0"]
    )
    assert r.exit_code == 0, r.output
    route = read_route(out)
    np.testing.assert_allclose(route.distance_m, s, atol=5e-4)  # written to the mm
    np.testing.assert_allclose(route.elevation_m, z, atol=5e-4)  # raw: not smoothed
    np.testing.assert_allclose(route.xt, xt, atol=1e-4)
    assert "40 points" in r.output
    # a scenario reads it as its route (the grade of the ramp: asin(0.05))
    sc = load_scenario(SCENARIOS / "tow6_uniform.yaml", [f"terrain={{route: {out}}}", "simulation.duration_s=1"])
    # rounding: elevations to 0.1 mm in the GPX, then distances and elevations to the mm in the file,
    # over steps of min(diff(s)): the rise per metre is off by at most (2 x 0.5 mm + 0.05 x 2 x 0.5 mm) / step
    tol = math.degrees((1e-3 + 0.05e-3 + 1e-4) / np.min(np.diff(s)))
    grade = sc.terrain.elevation_profile().max_abs_grade_deg()
    assert grade == pytest.approx(math.degrees(math.asin(0.05)), abs=tol)
    # an existing file is not replaced without --overwrite
    r = CliRunner().invoke(main, ["route", "import", str(track), "--out", str(out), "--xt", "0.5"])
    assert r.exit_code == 2 and "--overwrite" in r.output
    r = CliRunner().invoke(main, ["route", "import", str(track), "--out", str(out), "--xt", "0.5", "--overwrite"])
    assert r.exit_code == 0 and set(read_route(out).xt) == {0.5}


def test_smoothing_keeps_a_ramp_and_damps_the_scatter():
    s = np.arange(0.0, 200.0, 2.0)
    ramp = 100.0 + 0.1 * s
    # a triangular window is exact on a straight line (away from the ends, where the end is held)
    inner = (s >= 20.0) & (s <= 180.0)
    np.testing.assert_allclose(smooth_elevation(s, ramp, 20.0)[inner], ramp[inner], atol=1e-9)
    np.testing.assert_array_equal(smooth_elevation(s, ramp, 0.0), ramp)
    # +-1 m of zigzag every 2 m: over a 10 m box only a part-period is left, whose integral is at most
    # 1 m x 2 m / 2, so each box average is within 0.1 m, and so is the second pass
    zig = ramp + np.where(np.arange(s.size) % 2 == 0, 1.0, -1.0)
    assert np.max(np.abs(smooth_elevation(s, zig, 20.0) - ramp)[inner]) <= 0.1 + 1e-9


def test_points_standing_still_are_dropped_and_the_defaults_hold(tmp_path):
    lat, s, z = meridian_track(n=10)
    pts = [(la, 11.0, e) for la, e in zip(lat, z)]
    pts.insert(3, pts[2])  # the receiver stood still
    track = tmp_path / "t.gpx"
    track.write_text(gpx_text(pts))
    rt = route_from_track(read_gpx(track), xt=0.7)
    assert rt.dropped == 1 and rt.distance_m.size == 10 and rt.smooth_m == gpx.DEFAULT_SMOOTH_M
    assert np.all(np.diff(rt.distance_m) > gpx.MIN_SPACING_M)
    text = route_csv(rt, "t.gpx")
    assert text.startswith("# route imported from t.gpx") and "triangular window of 20 m" in text
    # the command line states the same default as the module
    opt = next(p for p in main.commands["route"].commands["import"].params if p.name == "smooth_m")
    assert opt.default == gpx.DEFAULT_SMOOTH_M


@pytest.mark.parametrize(
    "text, match",
    [
        (
            '<gpx><trk><trkseg>\n<trkpt lat="46" lon="11"><ele>1</ele>\n</trkseg></trk></gpx>',
            r"line 3, column \d+: not well-formed",
        ),
        ("<gpx><trk></trk></gpx>", "holds no track points"),
        ('<gpx><trk><trkseg>\n<trkpt lat="46" lon="11"></trkpt></trkseg></trk></gpx>', r"line 2: <trkpt> has no <ele>"),
        (
            '<gpx><trk><trkseg>\n\n<trkpt lat="96" lon="11"><ele>1</ele></trkpt></trkseg></trk></gpx>',
            r"line 3: <trkpt> 'lat'",
        ),
        (
            '<gpx><trk><trkseg>\n<trkpt lon="11"><ele>1</ele></trkpt></trkseg></trk></gpx>',
            r"line 2: <trkpt> has no 'lat'",
        ),
        (
            '<gpx><trk><trkseg>\n<trkpt lat="46" lon="11"><ele>high</ele></trkpt></trkseg></trk></gpx>',
            r"line 2: .*finite",
        ),
        (
            '<?xml version="1.0"?>\n<!DOCTYPE gpx [\n<!ENTITY a "aaaaaaaaaa">\n<!ENTITY b "&a;&a;&a;&a;">\n]>\n<gpx/>',
            "line 3: declares an entity",
        ),
    ],
)
def test_bad_gpx_names_the_line_and_the_fix(tmp_path, text, match):
    track = tmp_path / "bad.gpx"
    track.write_text(text)
    with pytest.raises(ScenarioError, match=match):
        read_gpx(track)
    r = CliRunner().invoke(main, ["route", "import", str(track), "--out", str(tmp_path / "r.csv"), "--xt", "0.5"])
    assert r.exit_code == 2 and "bad.gpx" in r.output and "Traceback" not in r.output
    assert not (tmp_path / "r.csv").exists()


def test_xt_and_grade_problems_are_input_errors(tmp_path):
    lat, s, z = meridian_track(n=12)
    track = tmp_path / "t.gpx"
    track.write_text(gpx_text([(la, 11.0, e, 0.5) for la, e in zip(lat, z)], xt_tag="xt"))
    with pytest.raises(ScenarioError, match=r"no <snow> in its <extensions>.*--xt"):
        read_gpx(track, xt_tag="snow")
    with pytest.raises(ScenarioError, match="no X_t"):
        route_from_track(read_gpx(track))
    r = CliRunner().invoke(main, ["route", "import", str(track), "--out", str(tmp_path / "r.csv")])
    assert r.exit_code == 2 and "--xt-tag" in r.output
    r = CliRunner().invoke(main, ["route", "import", str(track), "--out", str(tmp_path / "r.csv"), "--xt", "1.5"])
    assert r.exit_code == 2 and "(0, 1]" in r.output
    cliff = [(la, 11.0, 0.0 if k < 6 else 30.0) for k, la in enumerate(lat)]  # 30 m up within ~2 m
    track.write_text(gpx_text(cliff))  # points from line 4: the 7th (the first at 30 m) on line 10
    with pytest.raises(
        ScenarioError, match=r"line 10: after smoothing over 0 m the elevation changes by 30.00 m .*\(--smooth-m\)"
    ):
        route_from_track(read_gpx(track), smooth_m=0.0, xt=0.5)


# ------------------------------------------------------------------ a run past the end of its route
def test_a_run_past_the_route_end_warns_once_and_the_terrain_is_held(tmp_path):
    route = tmp_path / "short.csv"
    route.write_text("distance_m,elevation_m,xt\n-12,0,0.9\n-2,0.5,0.9\n2.0,0.7,0.8\n")
    raw = [f"terrain={{route: {route}}}", "simulation.duration_s=4", "simulation.output_dt_s=0.1", "tow.force_N=0"]
    out = tmp_path / "run"
    args = ["run", str(SCENARIOS / "tow6_uniform.yaml"), "--out", str(out), "--no-plot"]
    r = CliRunner().invoke(main, args + [a for kv in raw for a in ("--set", kv)])
    assert r.exit_code == 0, r.output
    warnings = [line for line in r.stderr.splitlines() if "past the end of the route file" in line]
    assert len(warnings) == 1
    from snoworm.results.result import load_result

    res = load_result(out)
    b = res.scenario.vehicle.segment.wheelbase_m
    front = res.segments["x_m"][:, 0] + b / 2
    first = res.t[np.argmax(front > 2.0)]  # the first output time the leader's front axle is past 2 m
    assert f"at t = {first:.1f} s" in warnings[0] and "ends at 2 m" in warnings[0]
    # beyond the end: level ground (grade 0) at the last row's elevation, the last row's X_t
    beyond = res.segments["x_m"] - b / 2 > 2.0  # both axles past the end
    assert beyond.any()
    np.testing.assert_allclose(res.segments["grade_deg"][beyond], 0.0, atol=1e-9)
    np.testing.assert_allclose(res.segments["elevation_m"][beyond], 0.7, atol=1e-6)
    np.testing.assert_allclose(res.segments["xt"][beyond], 0.8, atol=1e-6)
    # a route long enough: no warning
    route.write_text("distance_m,elevation_m,xt\n-12,0,0.9\n-2,0.5,0.9\n40,0.7,0.8\n")
    r = CliRunner().invoke(main, args + ["--overwrite"] + [a for kv in raw for a in ("--set", kv)])
    assert r.exit_code == 0 and "past the end" not in r.stderr


def test_the_shipped_example_track_imports_and_drives(tmp_path):
    track = SCENARIOS.parent / "examples" / "tracks" / "drift_traverse.gpx"
    out = tmp_path / "route.csv"
    r = CliRunner().invoke(main, ["route", "import", str(track), "--out", str(out), "--xt-tag", "xt"])
    assert r.exit_code == 0, r.output
    route = read_route(out)
    s, z, xt = (np.array(v) for v in (route.distance_m, route.elevation_m, route.xt))
    # its header: 6 deg up from 40 to 140 m, scatter of at most 0.9 m; the smoothing is exact on the
    # straight ramp, so over 60..120 m the mean grade is off by at most 2 x 0.9 m / 60 m in sin(grade)
    j0, j1 = np.searchsorted(s, 60.0), np.searchsorted(s, 120.0)
    rise = (z[j1] - z[j0]) / (s[j1] - s[j0])
    assert abs(rise - math.sin(math.radians(6.0))) <= 1.8 / (s[j1] - s[j0])
    assert set(xt[(s > 155) & (s < 195)]) == {0.6} and set(xt[s < 140]) == {0.9}
    sc = load_scenario(
        SCENARIOS / "tow6_uniform.yaml", [f"terrain={{route: {out}}}", "simulation.duration_s=2", "tow.force_N=0"]
    )
    from snoworm import simulate

    res = simulate(sc)
    assert res.segments["x_m"][-1, 0] > res.segments["x_m"][0, 0] + 0.5  # it drives on the imported route


def test_track_segments_are_joined_and_route_points_read_without_a_track(tmp_path):
    lat, s, z = meridian_track(n=8)
    pts = [f'<trkpt lat="{la}" lon="11.0"><ele>{e}</ele></trkpt>' for la, e in zip(lat, z)]
    track = tmp_path / "two.gpx"
    track.write_text(
        '<gpx xmlns="http://www.topografix.com/GPX/1/1"><trk><trkseg>\n'
        + "\n".join(pts[:4])
        + "\n</trkseg><trkseg>\n"
        + "\n".join(pts[4:])
        + "\n</trkseg></trk></gpx>\n"
    )
    rt = route_from_track(read_gpx(track), smooth_m=0.0, xt=0.5)
    np.testing.assert_allclose(rt.distance_m, s, atol=1e-9)  # the gap between segments counted once
    rte = tmp_path / "route.gpx"
    rte.write_text(
        '<gpx xmlns="http://www.topografix.com/GPX/1/1"><rte>\n'
        + "\n".join(p.replace("trkpt", "rtept") for p in pts)
        + "\n</rte></gpx>\n"
    )
    np.testing.assert_allclose(route_from_track(read_gpx(rte), smooth_m=0.0, xt=0.5).distance_m, s, atol=1e-9)
