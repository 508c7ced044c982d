"""The hostile-input battery's cases, one generator per surface (benchmarks/hostile.py)."""

from __future__ import annotations

import os
import textwrap
from pathlib import Path

from hostile_core import Case, check_map, check_run, check_sweep
from hostile_system import SYSTEM_SURFACES

SHORT = ["--set", "simulation.duration_s=0.5"]
RR = ("refused",)
OK = ("ok",)
EITHER = ("ok", "refused")

SCENARIO = """\
name: hostile
vehicle: {{parameter_set: frostyboy, segments: 3, links: {{type: fixed}}}}
terrain: {terrain}
tow: {{force_N: 0}}
mode: {{type: uniform, speed_mps: 1.0, start_time_s: 0.0}}
simulation: {{duration_s: 0.5, output_dt_s: 0.05}}
"""

GOOD_ROUTE = "distance_m,elevation_m,xt\n-20,0,0.9\n0,0,0.9\n50,2,0.8\n100,2,0.8\n"


def write_scenario(ctx, terrain="{route: route.csv}", name="sc.yaml", folder=None):
    d = folder or ctx.cwd
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_text(SCENARIO.format(terrain=terrain))


# ------------------------------------------------------------------------------------------ routes


def _route_variants():
    big = "distance_m,elevation_m,xt\n" + "".join(f"{i * 0.01:.2f},0,0.9\n" for i in range(-2000, 98000))
    v = {
        "good": (GOOD_ROUTE, OK),
        "bom": ("\ufeff" + GOOD_ROUTE, EITHER),
        "crlf": (GOOD_ROUTE.replace("\n", "\r\n"), EITHER),
        "cr_only": (GOOD_ROUTE.replace("\n", "\r"), EITHER),
        "comment_first": ("# a comment\n" + GOOD_ROUTE, OK),
        "header_only": ("distance_m,elevation_m,xt\n", RR),
        "empty": ("", RR),
        "blank_lines": ("\n\n" + GOOD_ROUTE + "\n\n", EITHER),
        "one_row": ("distance_m,elevation_m,xt\n0,0,0.9\n", EITHER),
        "no_distance": ("elevation_m,xt\n0,0.9\n1,0.9\n", RR),
        "no_elevation": ("distance_m,xt\n-20,0.9\n100,0.9\n", EITHER),
        "no_xt": ("distance_m,elevation_m\n-20,0\n100,2\n", EITHER),
        "extra_column": ("distance_m,elevation_m,xt,note\n-20,0,0.9,a\n100,2,0.9,b\n", EITHER),
        "dup_column": ("distance_m,distance_m,xt\n-20,0,0.9\n100,2,0.9\n", RR),
        "short_row": ("distance_m,elevation_m,xt\n-20,0,0.9\n100,2\n", RR),
        "long_row": ("distance_m,elevation_m,xt\n-20,0,0.9,5\n100,2,0.9\n", RR),
        "nan_elev": ("distance_m,elevation_m,xt\n-20,nan,0.9\n100,2,0.9\n", RR),
        "inf_elev": ("distance_m,elevation_m,xt\n-20,inf,0.9\n100,2,0.9\n", RR),
        "nan_dist": ("distance_m,elevation_m,xt\nnan,0,0.9\n100,2,0.9\n", RR),
        "ninf_dist": ("distance_m,elevation_m,xt\n-inf,0,0.9\n100,2,0.9\n", RR),
        "nan_xt": ("distance_m,elevation_m,xt\n-20,0,nan\n100,2,0.9\n", RR),
        "xt_zero": ("distance_m,elevation_m,xt\n-20,0,0\n100,2,0.9\n", RR),
        "xt_over_one": ("distance_m,elevation_m,xt\n-20,0,1.5\n100,2,0.9\n", RR),
        "xt_negative": ("distance_m,elevation_m,xt\n-20,0,-0.5\n100,2,0.9\n", RR),
        "huge_value": ("distance_m,elevation_m,xt\n-20,0,0.9\n1e308,2,0.9\n", RR),
        "tiny_step": ("distance_m,elevation_m,xt\n-20,0,0.9\n-19.9999999999,0,0.9\n100,0,0.9\n", EITHER),
        "non_monotonic": ("distance_m,elevation_m,xt\n-20,0,0.9\n50,1,0.9\n10,2,0.9\n100,2,0.9\n", RR),
        "duplicate_distance": ("distance_m,elevation_m,xt\n-20,0,0.9\n10,0,0.9\n10,5,0.9\n100,5,0.9\n", RR),
        "cliff": ("distance_m,elevation_m,xt\n-20,0,0.9\n0,0,0.9\n0.01,50,0.9\n100,50,0.9\n", RR),
        "steep_60deg": ("distance_m,elevation_m,xt\n-20,0,0.9\n0,0,0.9\n10,17.3,0.9\n100,17.3,0.9\n", RR),
        "text_cell": ("distance_m,elevation_m,xt\n-20,abc,0.9\n100,2,0.9\n", RR),
        "empty_cell": ("distance_m,elevation_m,xt\n-20,,0.9\n100,2,0.9\n", RR),
        "semicolons": ("distance_m;elevation_m;xt\n-20;0;0.9\n100;2;0.9\n", RR),
        "tabs": ("distance_m\televation_m\txt\n-20\t0\t0.9\n100\t2\t0.9\n", RR),
        "quoted": ('"distance_m","elevation_m","xt"\n"-20","0","0.9"\n"100","2","0.9"\n', EITHER),
        "spaces": ("distance_m, elevation_m, xt\n-20, 0, 0.9\n100, 2, 0.9\n", EITHER),
        "hex_float": ("distance_m,elevation_m,xt\n-20,0x1p3,0.9\n100,2,0.9\n", RR),
        "underscore_num": ("distance_m,elevation_m,xt\n-20,1_0,0.9\n100,2,0.9\n", EITHER),  # Python's float()
        "huge_cell": ("distance_m,elevation_m,xt\n-20,0," + "9" * 200_000 + "\n100,2,0.9\n", RR),
        "huge_header": ("x" * 300_000 + "\n-20,0,0.9\n", RR),
        "nul_byte": ("distance_m,elevation_m,xt\n-20,0\x00,0.9\n100,2,0.9\n", RR),
        "latin1": (b"# caf\xe9\ndistance_m,elevation_m,xt\n-20,0,0.9\n100,2,0.9\n", EITHER),
        "utf16": (GOOD_ROUTE.encode("utf-16"), RR),
        "binary": (bytes(range(256)) * 40, RR),
        "rows_100k": (big, EITHER),
    }
    return v


def _write(path: Path, content):
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8", newline="")


def _route_setup(content):
    def setup(ctx):
        write_scenario(ctx)
        _write(ctx.cwd / "route.csv", content)

    return setup


# setups of the route-path cases (module-level: one small function each, listed by _route_path_setups)
def _rp_symlink_good(ctx):
    write_scenario(ctx)
    _write(ctx.base / "real.csv", GOOD_ROUTE)
    os.symlink(ctx.base / "real.csv", ctx.cwd / "route.csv")


def _rp_symlink_loop(ctx):
    write_scenario(ctx)
    os.symlink(ctx.cwd / "route.csv", ctx.cwd / "route.csv")


def _rp_symlink_loop2(ctx):
    write_scenario(ctx)
    os.symlink(ctx.cwd / "b.csv", ctx.cwd / "route.csv")
    os.symlink(ctx.cwd / "route.csv", ctx.cwd / "b.csv")


def _rp_dangling(ctx):
    write_scenario(ctx)
    os.symlink(ctx.base / "nowhere.csv", ctx.cwd / "route.csv")


def _rp_fifo(ctx):
    write_scenario(ctx)
    os.mkfifo(ctx.cwd / "route.csv")


def _rp_devzero(ctx):
    write_scenario(ctx)
    os.symlink("/dev/zero", ctx.cwd / "route.csv")


def _rp_devurandom(ctx):
    write_scenario(ctx)
    os.symlink("/dev/urandom", ctx.cwd / "route.csv")


def _rp_directory(ctx):
    write_scenario(ctx)
    (ctx.cwd / "route.csv").mkdir()


def _rp_missing(ctx):
    write_scenario(ctx)


def _rp_nul_in_path(ctx):
    write_scenario(ctx, terrain='{route: "rou\\0te.csv"}')


def _rp_long_path(ctx):
    write_scenario(ctx, terrain="{route: " + "a" * 10_000 + ".csv}")


def _rp_deep_path(ctx):
    write_scenario(ctx, terrain="{route: " + "d/" * 3000 + "r.csv}")


def _rp_victim_route(ctx):
    write_scenario(ctx, terrain="{route: ../victim.txt}")


def _rp_outside_route(ctx):
    write_scenario(ctx, terrain="{route: ../real.csv}")
    _write(ctx.base / "real.csv", GOOD_ROUTE)


def _rp_unreadable_perm(ctx):
    write_scenario(ctx)
    _write(ctx.cwd / "route.csv", GOOD_ROUTE)
    os.chmod(ctx.cwd / "route.csv", 0)


def _rp_route_number(ctx):
    write_scenario(ctx, terrain="{route: 12}")


def _rp_route_list(ctx):
    write_scenario(ctx, terrain="{route: [a, b]}")


def _rp_route_empty(ctx):
    write_scenario(ctx, terrain="{route: ''}")


def _rp_route_dot(ctx):
    write_scenario(ctx, terrain="{route: .}")


def _rp_route_and_xt(ctx):
    write_scenario(ctx, terrain="{route: route.csv, xt: 0.5}")
    _write(ctx.cwd / "route.csv", GOOD_ROUTE)


def _route_path_setups():
    return {
        "symlink_to_good": (_rp_symlink_good, EITHER),
        "symlink_loop": (_rp_symlink_loop, RR),
        "symlink_loop2": (_rp_symlink_loop2, RR),
        "dangling_symlink": (_rp_dangling, RR),
        "fifo": (_rp_fifo, RR),
        "dev_zero": (_rp_devzero, RR),
        "dev_urandom": (_rp_devurandom, RR),
        "directory": (_rp_directory, RR),
        "missing": (_rp_missing, RR),
        "nul_in_path": (_rp_nul_in_path, RR),
        "long_path": (_rp_long_path, RR),
        "deep_path": (_rp_deep_path, RR),
        "victim_as_route": (_rp_victim_route, RR),
        "outside_folder": (_rp_outside_route, EITHER),
        "mode_000": (_rp_unreadable_perm, EITHER),
        "route_number": (_rp_route_number, RR),
        "route_list": (_rp_route_list, RR),
        "route_empty": (_rp_route_empty, RR),
        "route_dot": (_rp_route_dot, RR),
        "route_and_xt": (_rp_route_and_xt, RR),
    }


def routes():
    cases = []
    for name, (content, expect) in _route_variants().items():
        setup = _route_setup(content)
        cases.append(
            Case(
                "routes",
                f"run/{name}",
                ["run", "sc.yaml", "--out", "{out}", "--no-plot"],
                setup=setup,
                expect=expect,
                check=check_run,
            )
        )
    for name, (setup, expect) in _route_path_setups().items():
        cases.append(
            Case(
                "routes",
                f"run/{name}",
                ["run", "sc.yaml", "--out", "{out}", "--no-plot"],
                setup=setup,
                expect=expect,
                check=check_run,
            )
        )
        cases.append(Case("routes", f"validate/{name}", ["validate", "sc.yaml"], setup=setup, expect=expect))

    # results folders are self-contained: the route file edited after the run
    def edited_after(ctx):
        _route_setup(GOOD_ROUTE)(ctx)

    body = textwrap.dedent("""\
        import subprocess, sys, snoworm
        subprocess.run([sys.executable, '-m', 'snoworm', 'run', 'sc.yaml', '--out', '{out}', '--no-plot'], check=True,
                       capture_output=True)
        a = snoworm.load_result('{out}').scenario.terrain.route_data().elevation_profile()
        open('route.csv', 'w').write('distance_m,elevation_m,xt\\n-20,0,0.3\\n100,9,0.3\\n')
        b = snoworm.load_result('{out}').scenario.terrain.route_data().elevation_profile()
        if a != b: nonsense('load_result gives another route after the original was edited')
        """)
    cases.append(
        Case("routes", "api/edited_after_run", code=body, setup=edited_after, expect=OK, may_touch=("work/route.csv",))
    )
    return cases


# ------------------------------------------------------------------------------------------ grades


def grades():
    cases = []
    consts = [
        "0",
        "5",
        "-5",
        "39.9",
        "40",
        "40.1",
        "-40.1",
        "90",
        "1e308",
        ".nan",
        ".inf",
        "-.inf",
        "'5'",
        "abc",
        "[5]",
        "true",
        "null",
        "1e-320",
    ]
    exp = {"'5'": EITHER, "0": OK, "5": OK, "-5": OK, "39.9": EITHER, "40": EITHER, "1e-320": EITHER, "null": EITHER}
    for v in consts:
        cases.append(
            Case(
                "grades",
                f"grade_deg={v}",
                ["run", "tow6_uniform", *SHORT, "--set", f"terrain.grade_deg={v}", "--out", "{out}", "--no-plot"],
                expect=exp.get(v, RR),
                check=check_run,
            )
        )
    tables = {
        "ok": ("[[-100,0],[3,0],[600,52.03]]", OK),
        "one_point": ("[[0,0]]", EITHER),
        "empty": ("[]", RR),
        "nan": ("[[-100,.nan],[600,5]]", RR),
        "inf_dist": ("[[-.inf,0],[600,5]]", RR),
        "unsorted": ("[[600,5],[-100,0]]", RR),
        "duplicate": ("[[-100,0],[0,0],[0,5],[600,5]]", RR),
        "three_columns": ("[[-100,0,1],[600,5,1]]", RR),
        "one_column": ("[[-100],[600]]", RR),
        "strings": ("[[a,b],[c,d]]", RR),
        "nested": ("[[[1]],[[2]]]", RR),
        "cliff": ("[[-100,0],[0,0],[0.001,10],[600,10]]", RR),
        "huge": ("[[-1e300,0],[1e300,1e300]]", RR),
        "not_list": ("5", RR),
        "mapping": ("{a: 1}", RR),
    }
    for name, (v, e) in tables.items():
        cases.append(
            Case(
                "grades",
                f"elevation/{name}",
                ["run", "tow6_uniform", *SHORT, "--set", f"terrain.elevation={v}", "--out", "{out}", "--no-plot"],
                expect=e,
                check=check_run,
            )
        )
    big = "[" + ",".join(f"[{i},{i * 0.01:.2f}]" for i in range(-100, 100_000)) + "]"
    cases.append(
        Case(
            "grades",
            "elevation/100k_inline",
            ["validate", "sc.yaml"],
            setup=lambda ctx: write_scenario(ctx, terrain="{elevation: " + big + "}"),
            expect=RR,
        )
    )
    patches = {
        "ok": ("[{start_m: 0, end_m: 5, grade_deg: 5}]", OK),
        "overlap": ("[{start_m: 0, end_m: 5, grade_deg: 5}, {start_m: 3, end_m: 8, grade_deg: 2}]", RR),
        "reversed": ("[{start_m: 5, end_m: 0, grade_deg: 5}]", RR),
        "zero_length": ("[{start_m: 5, end_m: 5, grade_deg: 5}]", RR),
        "nan": ("[{start_m: 0, end_m: 5, grade_deg: .nan}]", RR),
        "steep": ("[{start_m: 0, end_m: 5, grade_deg: 80}]", RR),
        "inf_end": ("[{start_m: 0, end_m: .inf, grade_deg: 5}]", RR),
        "missing_key": ("[{start_m: 0, grade_deg: 5}]", RR),
        "unknown_key": ("[{start_m: 0, end_m: 5, grade: 5}]", RR),
        "negative_ramp": ("[{start_m: 0, end_m: 5, grade_deg: 5, ramp_m: -1}]", RR),
        "nan_ramp": ("[{start_m: 0, end_m: 5, grade_deg: 5, ramp_m: .nan}]", RR),
        "many": (
            "[" + ",".join(f"{{start_m: {i}, end_m: {i + 0.5}, grade_deg: 1}}" for i in range(2000)) + "]",
            EITHER,
        ),
        "not_list": ("5", RR),
        "empty": ("[]", EITHER),
    }
    for name, (v, e) in patches.items():
        cases.append(
            Case(
                "grades",
                f"grade_patches/{name}",
                [
                    "run",
                    "tow6_uniform",
                    *SHORT,
                    "--set",
                    "terrain.grade_deg=0",
                    "--set",
                    f"terrain.grade_patches={v}",
                    "--out",
                    "{out}",
                    "--no-plot",
                ],
                expect=e,
                check=check_run,
            )
        )
    cases.append(
        Case(
            "grades",
            "grade_patches/without_grade_deg",
            ["validate", "tow6_uniform", "--set", "terrain.grade_patches=[{start_m: 0, end_m: 5, grade_deg: 5}]"],
            expect=EITHER,
        )
    )
    cases.append(
        Case(
            "grades",
            "grade_and_elevation",
            ["validate", "tow6_uniform", "--set", "terrain.grade_deg=5", "--set", "terrain.elevation=[[0,0],[10,1]]"],
            expect=RR,
        )
    )
    xtp = {
        "overlap": "[{start_m: 0, end_m: 5, xt: 0.3}, {start_m: 4, end_m: 8, xt: 0.5}]",
        "xt_zero": "[{start_m: 0, end_m: 5, xt: 0}]",
        "xt_nan": "[{start_m: 0, end_m: 5, xt: .nan}]",
        "reversed": "[{start_m: 5, end_m: 0, xt: 0.3}]",
    }
    for name, v in xtp.items():
        cases.append(
            Case(
                "grades", f"xt_patches/{name}", ["validate", "tow6_uniform", "--set", f"terrain.patches={v}"], expect=RR
            )
        )
    # sweeps over grades: every row present and finite
    for spec in ("0:10:3", "-5,0,5", "0,.nan", "0:50:3"):
        e = OK  # an invalid case is recorded as such (status invalid) and the sweep goes on
        cases.append(
            Case(
                "grades",
                f"sweep/grade_deg={spec}",
                ["sweep", "tow6_uniform", *SHORT, "--set", f"terrain.grade_deg={spec}", "--out", "{out}", "--no-plot"],
                expect=e,
                check=check_sweep,
            )
        )
    return cases


# ---------------------------------------------------------------------------------- mobility-map


def mobility():
    cases = []
    base = ["mobility-map", "tow6_uniform", "--no-inching", "--no-plot", "--out", "{out}"]
    xts = {
        "0.2:1.0:5": OK,
        "0.5": OK,
        "0.3,0.6,0.9": OK,
        "0:1:5": RR,
        "0.2:1.0:0": RR,
        "0.2:1.0:-3": RR,
        "0.2:1.0:2.5": RR,
        "0.2:1.0:1e9": RR,
        "0.2:1.0:100000": EITHER,
        "nan": RR,
        "inf": RR,
        ".nan": RR,
        "": RR,
        "a": RR,
        "0.5,,0.6": RR,
        ":::": RR,
        "0.2:1.0": RR,
        "0.2:1.0:3:4": RR,
        "1e-300": EITHER,
        "1.0000001": RR,
        "0.5:0.5:1": EITHER,
        "0.9:0.2:3": EITHER,
        "0x1p-1": RR,
        "0.5," * 2000 + "0.5": EITHER,
        "9" * 5000: RR,
        " 0.5 ": EITHER,
    }
    for v, e in xts.items():
        cases.append(Case("mobility", f"xt={v[:40]}", [*base, "--xt", v], expect=e, check=check_map))
    grades_ = {
        "0:10:3": OK,
        "41": RR,
        "-41": RR,
        "nan": RR,
        "0:10:1e6": RR,
        "0:10:100000": RR,
        "": RR,
        "0,5,inf": RR,
        "0:10:0": RR,
    }
    for v, e in grades_.items():
        cases.append(
            Case("mobility", f"grade={v}", [*base, "--xt", "0.5,0.9", "--grade", v], expect=e, check=check_map)
        )
    tows = {
        "0,100": OK,
        "1e7": RR,
        "-1e7": RR,
        "nan": RR,
        "inf": RR,
        "abc": RR,
        "": RR,
        "0,0,0": EITHER,
        "0:100:3": EITHER,
        "1e-320": EITHER,
    }
    for v, e in tows.items():
        cases.append(Case("mobility", f"tow={v}", [*base, "--xt", "0.5,0.9", "--tow", v], expect=e, check=check_map))
    cases.append(
        Case(
            "mobility",
            "cells=1e5x3x3",
            [*base, "--xt", "0.2:1.0:100000", "--grade", "0:5:3", "--tow", "0,1,2"],
            expect=RR,
        )
    )
    inch = ["mobility-map", "traverse_patch", "--inch-duration", "0.5", "--no-plot", "--out", "{out}", "--xt", "0.3"]
    cases.append(Case("mobility", "gait=garbage", [*inch, "--gait", "[[0],[9]]"], expect=RR))
    cases.append(Case("mobility", "gait=yaml_bomb", [*inch, "--gait", "&a [*a]"], expect=RR))
    cases.append(Case("mobility", "gait=empty_phase", [*inch, "--gait", "[[0],[]]"], expect=RR))
    cases.append(Case("mobility", "gait=named", [*inch, "--gait", "six_segment"], expect=OK, check=check_map))
    cases.append(Case("mobility", "gait=huge", [*inch, "--gait", "[" + "[0]," * 20000 + "[1]]"], expect=RR))
    cases.append(Case("mobility", "rolling_speed=nan", [*base, "--xt", "0.5", "--rolling-speed", "nan"], expect=RR))
    cases.append(Case("mobility", "rolling_speed=1e9", [*base, "--xt", "0.5", "--rolling-speed", "1e9"], expect=RR))
    cases.append(
        Case(
            "mobility",
            "inch_duration=1e9",
            [
                "mobility-map",
                "inchworm6",
                "--xt",
                "0.25",
                "--inch-duration",
                "1e9",
                "--rolling-speed",
                "1.0",
                "--no-plot",
                "--out",
                "{out}",
            ],
            expect=RR,
            timeout=60,
        )
    )
    cases.append(
        Case(
            "mobility",
            "inch_duration=nan",
            [
                "mobility-map",
                "inchworm6",
                "--xt",
                "0.25",
                "--inch-duration",
                "nan",
                "--rolling-speed",
                "1.0",
                "--no-plot",
                "--out",
                "{out}",
            ],
            expect=RR,
        )
    )
    cases.append(
        Case(
            "mobility",
            "inching_short",
            [
                "mobility-map",
                "inchworm6",
                "--xt",
                "0.25,0.9",
                "--inch-duration",
                "0.5",
                "--rolling-speed",
                "1.0",
                "--no-plot",
                "--out",
                "{out}",
            ],
            expect=OK,
            check=check_map,
        )
    )
    return cases


# ---------------------------------------------------------------------------------- figure sizes


def figures():
    cases = []
    sizes = {
        "column": OK,
        "page": OK,
        "3.5x2.5": OK,
        "COLUMN": EITHER,
        "3.5X2.5": EITHER,
        " 3.5x2.5 ": EITHER,
        "0x0": RR,
        "-1x2": RR,
        "nanxnan": RR,
        "infx2": RR,
        "1e6x1e6": RR,
        "0.1x0.1": RR,
        "100x100": RR,
        "3.5": RR,
        "x": RR,
        "3.5x": RR,
        "3,5x2": RR,
        "3.5x2.5x1": RR,
        "1e-300x2": RR,
        "\u0663x\u0662": EITHER,
        "": RR,
        "3.5x2.5" * 2000: RR,
        "0x1p2x2": RR,
        "7.16x1": EITHER,
    }
    for v, e in sizes.items():
        cases.append(
            Case(
                "figures",
                f"run/{v[:30]!r}",
                ["run", "tow6_uniform", *SHORT, "--figure-size", v, "--out", "{out}"],
                expect=e,
                check=check_run,
            )
        )
    for v in ("column", "nanxnan", "0x0"):
        cases.append(
            Case(
                "figures",
                f"sweep/{v}",
                ["sweep", "tow6_uniform", *SHORT, "--set", "tow.force_N=0,100", "--figure-size", v, "--out", "{out}"],
                expect=OK if v == "column" else RR,
                check=check_sweep,
            )
        )
    api = {
        "True": RR,
        "(3.5,)": RR,
        "('3','2')": RR,
        "(float('nan'), 2)": RR,
        "(3.5, 2.5)": OK,
        "[3.5, 2.5]": EITHER,
        "'column'": EITHER,
        "None": OK,
        "__import__('numpy').array([3.5, 2.5])": EITHER,
        "(3.5+0j, 2)": RR,
        "(1e9, 1e9)": RR,
        "(0, 0)": RR,
        "(-3, 2)": RR,
        "'3.5x2.5'": EITHER,
        "b'column'": RR,
        "{}": RR,
    }
    for v, e in api.items():
        body = textwrap.dedent(f"""\
            import snoworm
            sc = snoworm.load_scenario('tow6_uniform').with_({{'simulation.duration_s': 0.5}})
            res = snoworm.simulate(sc)
            res.write('{{out}}', figure_size={v})
            """)
        cases.append(
            Case(
                "figures", f"api/figure_size={v[:30]}", code=body, expect=e, check=lambda ctx, run: check_run(ctx, run)
            )
        )
    return cases


SURFACES = {"routes": routes, "grades": grades, "mobility": mobility, "figures": figures, **SYSTEM_SURFACES}
