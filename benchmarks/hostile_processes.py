"""The hostile-input battery's cases on processes and file systems: concurrency, signals, full disk, read-only."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path

from hostile_core import ROOT, Case, api_argv, check_map, check_run, check_sweep, snoworm_argv, spawn

RR = ("refused",)
OK = ("ok",)
EITHER = ("ok", "refused")

LONG_SWEEP = [
    "sweep",
    "inchworm6",
    "--set",
    "tow.force_N=0:100:40",
    "--set",
    "simulation.duration_s=20",
    "--no-plot",
    "--out",
    "{out}",
]
SHORT_RUN = ["run", "tow6_uniform", "--set", "simulation.duration_s=0.5", "--no-plot", "--out", "{out}"]
LONG_RUN = ["run", "inchworm6", "--set", "simulation.duration_s=400", "--no-plot", "--out", "{out}"]


def _env():
    return {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONDONTWRITEBYTECODE": "1", "MPLBACKEND": "Agg"}


def _start(ctx, args):
    return subprocess.Popen(
        snoworm_argv(ctx, args),
        cwd=ctx.cwd,
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )


def _finish(proc, timeout=120):
    try:
        out, err = proc.communicate(timeout=timeout)
        return proc.returncode, out.decode(errors="replace"), err.decode(errors="replace"), False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        return proc.returncode, out.decode(errors="replace"), err.decode(errors="replace"), True


def _wait_for(path: Path, seconds=30.0, rows=0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        if path.exists():
            if not rows:
                return True
            try:
                if len(path.read_text().splitlines()) > rows:
                    return True
            except OSError:
                pass
        time.sleep(0.05)
    return False


# ------------------------------------------------------------------------------------- concurrency


def _second_into_held(second, first=LONG_SWEEP, first_check=check_sweep, api=False):
    """``first`` holds --out (a running sweep); ``second`` must be refused and ``first`` end whole."""

    def runner(ctx):
        a = _start(ctx, first)
        if not _wait_for(ctx.out / ".snoworm-lock", 40):
            rc, o, e, t = _finish(a)
            return {"rc": rc, "stderr": e, "timed_out": t, "note": "the first command never locked --out"}
        b = spawn(ctx, api_argv(ctx, second) if api else snoworm_argv(ctx, second), timeout=60)
        rc, o, e, t = _finish(a)
        res = {
            "rc": rc,
            "stdout": o,
            "stderr": e + "\n--- second command ---\n" + b["stderr"],
            "timed_out": t or b["timed_out"],
            "note": f"second command exit {b['rc']}",
        }
        if b["rc"] == 0:
            res["nonsense"] = "the second command succeeded into a folder another process held"
        elif b["rc"] != 2:
            res["nonsense"] = f"the second command ended with exit {b['rc']}, not 2"
        elif "in use" not in b["stderr"]:
            res["nonsense"] = "the refusal does not say the folder is in use"
        elif rc == 0:
            res["nonsense"] = first_check(ctx, res)
        return res

    return runner


def _runs_race(ctx):
    a = _start(ctx, ["run", "inchworm6", "--set", "simulation.duration_s=30", "--no-plot", "--out", "{out}"])
    time.sleep(0.8)
    b = _start(ctx, ["run", "tow6_uniform", "--set", "simulation.duration_s=30", "--no-plot", "--out", "{out}"])
    ra, rb = _finish(a), _finish(b)
    res = {
        "rc": 0 if 0 in (ra[0], rb[0]) else ra[0],
        "stderr": ra[2] + "\n---\n" + rb[2],
        "timed_out": ra[3] or rb[3],
        "note": f"exits {ra[0]}, {rb[0]}",
    }
    if any(r[0] not in (0, 2) for r in (ra, rb)):
        res["nonsense"] = f"exits {ra[0]} and {rb[0]}"
    elif res["rc"] == 0:
        res["nonsense"] = check_run(ctx, res)
    return res


def concurrency():
    c = []
    for tag, extra in (("", []), ("_overwrite", ["--overwrite"])):
        c.append(
            Case(
                "concurrency",
                f"run_into_running_sweep{tag}",
                runner=_second_into_held([*SHORT_RUN, *extra]),
                expect=OK,
                serial=True,
                timeout=150,
            )
        )
        c.append(
            Case(
                "concurrency",
                f"same_sweep_twice{tag}",
                runner=_second_into_held([*LONG_SWEEP, *extra]),
                expect=OK,
                serial=True,
            )
        )
        c.append(
            Case(
                "concurrency",
                f"other_sweep{tag}",
                runner=_second_into_held(
                    [
                        "sweep",
                        "tow6_uniform",
                        "--set",
                        "tow.force_N=0,1",
                        "--set",
                        "simulation.duration_s=0.5",
                        "--no-plot",
                        "--out",
                        "{out}",
                        *extra,
                    ]
                ),
                expect=OK,
                serial=True,
            )
        )
    c.append(
        Case(
            "concurrency",
            "mobility_map_into_running_sweep",
            runner=_second_into_held(
                ["mobility-map", "tow6_uniform", "--xt", "0.5", "--no-inching", "--no-plot", "--out", "{out}"]
            ),
            expect=OK,
            serial=True,
        )
    )
    c.append(
        Case(
            "concurrency",
            "result_write_into_running_sweep",
            runner=_second_into_held(
                "import snoworm\nr = snoworm.simulate(snoworm.load_scenario('tow6_uniform').with_({'simulation.duration_s': 0.5}))"
                "\nr.write('{out}', plot=False)",
                api=True,
            ),
            expect=OK,
            serial=True,
        )
    )
    c.append(Case("concurrency", "two_runs_race", runner=_runs_race, expect=OK, serial=True))
    return c


# ------------------------------------------------------------------------------------------ signals


def _interrupt(args, sig, after_rows=0, delay=2.0, resume=None, check=None, twice=False):
    def runner(ctx):
        p = _start(ctx, args)
        if after_rows:  # a few cases finished: the lock is taken, then ~1 s per case
            _wait_for(ctx.out / ".snoworm-lock", 60)
            time.sleep(1.5 * after_rows)
        else:
            time.sleep(delay)
        os.killpg(p.pid, sig)
        if twice:
            time.sleep(0.05)
            try:
                os.killpg(p.pid, sig)
            except ProcessLookupError:
                pass
        rc, o, e, t = _finish(p)
        want = 128 + sig
        if rc == -sig:  # died by the signal itself (Python's own exit on an uncaught KeyboardInterrupt)
            rc = want
        res = {"rc": 0 if rc == want else rc, "stderr": e, "timed_out": t, "note": f"interrupted: exit {rc}"}
        if rc != want:
            res["nonsense"] = f"exit {rc} after signal {sig}, not {want}"
            return res
        if resume:
            r = spawn(ctx, snoworm_argv(ctx, resume), timeout=120)
            res.update(rc=r["rc"], stderr=e + "\n--- resume ---\n" + r["stderr"], timed_out=r["timed_out"])
            res["note"] += f"; resume exit {r['rc']}"
        if check and res["rc"] == 0:
            res["nonsense"] = check(ctx, res)
        return res

    return runner


def _nothing_written(ctx, res):
    if ctx.out.exists() and any(ctx.out.iterdir()):
        return f"an interrupted run left {sorted(p.name for p in ctx.out.iterdir())} in --out"
    return None


def _old_kept(ctx, res):
    summary = json.loads((ctx.out / "summary.json").read_text())
    if (
        summary.get("scenario", summary.get("name", "")) not in ("", "tow6_uniform")
        and "tow6" not in json.dumps(summary)[:4000]
    ):
        return "the earlier result was replaced by an interrupted run"
    return check_run(ctx, res)


def _earlier_run(ctx):
    r = spawn(ctx, snoworm_argv(ctx, SHORT_RUN))
    assert r["rc"] == 0, r["stderr"]


def _series_complete(ctx, res):
    bad = check_sweep(ctx, res)
    if bad:
        return bad
    code = "import snoworm\nt = snoworm.load_sweep('{out}')\nds = t.series()\nprint(len(t.to_pandas()), ds.sizes)"
    r = spawn(ctx, api_argv(ctx, code))
    if r["rc"] != 0:
        return "series() after the resume fails: " + r["stderr"][-300:]
    return None


def signals():
    c = []
    sweep_nc = [*LONG_SWEEP, "--save-cases", "--series", "netcdf"]
    for name, sig in (("sigint", signal.SIGINT), ("sigterm", signal.SIGTERM)):
        c.append(
            Case(
                "signals",
                f"run/{name}",
                runner=_interrupt(LONG_RUN, sig, check=_nothing_written),
                expect=OK,
                serial=True,
                ok_rcs=(0, 1, 2),
            )
        )
        c.append(
            Case(
                "signals",
                f"run_over_earlier/{name}",
                setup=_earlier_run,
                runner=_interrupt([*LONG_RUN], sig, check=_old_kept),
                expect=OK,
                serial=True,
            )
        )
        c.append(
            Case(
                "signals",
                f"sweep/{name}",
                runner=_interrupt(LONG_SWEEP, sig, after_rows=3, resume=LONG_SWEEP, check=check_sweep),
                expect=OK,
                serial=True,
                timeout=200,
            )
        )
        c.append(
            Case(
                "signals",
                f"sweep_j2/{name}",
                runner=_interrupt(
                    [*LONG_SWEEP, "-j", "2"], sig, after_rows=3, resume=[*LONG_SWEEP, "-j", "2"], check=check_sweep
                ),
                expect=OK,
                serial=True,
            )
        )
        c.append(
            Case(
                "signals",
                f"sweep_netcdf/{name}",
                runner=_interrupt(sweep_nc, sig, after_rows=3, resume=sweep_nc, check=_series_complete),
                expect=OK,
                serial=True,
            )
        )
    c.append(
        Case(
            "signals",
            "sweep/sigint_twice",
            runner=_interrupt(
                LONG_SWEEP, signal.SIGINT, after_rows=2, resume=LONG_SWEEP, check=check_sweep, twice=True
            ),
            expect=OK,
            serial=True,
        )
    )
    c.append(
        Case(
            "signals",
            "sweep/sigint_at_start",
            runner=_interrupt(LONG_SWEEP, signal.SIGINT, delay=0.6, resume=LONG_SWEEP, check=check_sweep),
            expect=OK,
            serial=True,
            ok_rcs=(0, 1, 2),
        )
    )
    return c


# --------------------------------------------------------------------------------- full disk, read-only


def _mount_tmpfs(ctx, name, size="2m"):
    m = ctx.base / name
    m.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(m)], check=True, capture_output=True)
    ctx.mounts.append(m)
    return m


def _disk_setup(free_bytes, prefill=None):
    def setup(ctx):
        m = _mount_tmpfs(ctx, "disk")
        ctx.out = m / "out"
        if prefill:
            prefill(ctx)
        st = os.statvfs(m)
        avail = st.f_bavail * st.f_frsize
        with open(m / "filler", "wb") as f:
            f.write(b"\0" * max(0, avail - free_bytes))

    return setup


def _grow_and_resume(args, check):
    """Run on the full disk; if refused, grow the tmpfs and run the same command again (a resume)."""

    def runner(ctx):
        r = spawn(ctx, snoworm_argv(ctx, args), timeout=90)
        res = dict(r, note=f"on the full disk: exit {r['rc']}")
        if r["rc"] == 2:
            if "Traceback" in r["stderr"]:
                return res
            subprocess.run(["mount", "-o", "remount,size=256m", str(ctx.mounts[0])], check=True)
            r2 = spawn(ctx, snoworm_argv(ctx, args), timeout=90)
            res.update(
                rc=r2["rc"],
                stderr=r["stderr"] + "\n--- after freeing space ---\n" + r2["stderr"],
                timed_out=r2["timed_out"],
            )
            res["note"] += f"; with space: exit {r2['rc']}"
        elif r["rc"] == 0:
            res["note"] += " (fitted)"
        if res["rc"] == 0:
            res["nonsense"] = check(ctx, res)
        return res

    return runner


def disk():
    c = []
    sweep = [
        "sweep",
        "tow6_uniform",
        "--set",
        "tow.force_N=0:100:6",
        "--set",
        "simulation.duration_s=2",
        "--out",
        "{out}",
    ]
    for free in (0, 4096, 40_000, 150_000, 600_000):
        c.append(
            Case(
                "disk",
                f"run_plots/free={free}",
                setup=_disk_setup(free),
                runner=_grow_and_resume(
                    ["run", "tow6_uniform", "--set", "simulation.duration_s=2", "--out", "{out}"], check_run
                ),
                expect=OK,
            )
        )
        c.append(
            Case(
                "disk",
                f"sweep_save_cases/free={free}",
                setup=_disk_setup(free),
                runner=_grow_and_resume([*sweep, "--no-plot", "--save-cases"], check_sweep),
                expect=OK,
            )
        )
        c.append(
            Case(
                "disk",
                f"sweep_netcdf/free={free}",
                setup=_disk_setup(free),
                runner=_grow_and_resume([*sweep, "--no-plot", "--save-cases", "--series", "netcdf"], _series_complete),
                expect=OK,
            )
        )
    c.append(
        Case(
            "disk",
            "mobility_map/free=0",
            setup=_disk_setup(0),
            runner=_grow_and_resume(
                ["mobility-map", "tow6_uniform", "--xt", "0.3:1:5", "--no-inching", "--out", "{out}"], check_map
            ),
            expect=OK,
        )
    )
    c.append(
        Case(
            "disk",
            "api_write/free=0",
            setup=_disk_setup(0),
            code=(
                "import snoworm\nr = snoworm.simulate(snoworm.load_scenario('tow6_uniform').with_({'simulation.duration_s': 2}))"
                "\nr.write('{out}')"
            ),
            expect=RR,
        )
    )
    return c


def _ro_setup(prefill=None, out="out"):
    def setup(ctx):
        m = _mount_tmpfs(ctx, "ro", "64m")
        ctx.out = m / out if out else m
        if prefill:
            r = spawn(ctx, snoworm_argv(ctx, prefill))
            assert r["rc"] == 0, r["stderr"]
        subprocess.run(["mount", "-o", "remount,ro", str(m)], check=True, capture_output=True)

    return setup


def readonly():
    c = []
    sw = [
        "sweep",
        "tow6_uniform",
        "--set",
        "tow.force_N=0,100",
        "--set",
        "simulation.duration_s=0.5",
        "--no-plot",
        "--out",
        "{out}",
    ]
    c.append(Case("readonly", "run", SHORT_RUN, setup=_ro_setup(), expect=RR))
    c.append(Case("readonly", "run_into_mount_point", SHORT_RUN, setup=_ro_setup(out=""), expect=RR))
    c.append(Case("readonly", "run_over_earlier", SHORT_RUN, setup=_ro_setup(SHORT_RUN), expect=RR))
    c.append(Case("readonly", "sweep", sw, setup=_ro_setup(), expect=RR))
    c.append(Case("readonly", "sweep_resume_complete", sw, setup=_ro_setup(sw), expect=EITHER, check=check_sweep))
    c.append(
        Case("readonly", "sweep_extend", [*sw[:3], "tow.force_N=0,100,200", *sw[4:]], setup=_ro_setup(sw), expect=RR)
    )
    c.append(
        Case(
            "readonly",
            "mobility_map",
            ["mobility-map", "tow6_uniform", "--xt", "0.5", "--no-inching", "--out", "{out}"],
            setup=_ro_setup(),
            expect=RR,
        )
    )
    c.append(
        Case(
            "readonly",
            "terrain_curves",
            ["terrain-curves", "--xt", "1", "--out", "{out}"],
            setup=_ro_setup(),
            expect=RR,
        )
    )
    c.append(Case("readonly", "groundtruth", ["groundtruth", "--out", "{out}"], setup=_ro_setup(), expect=RR))
    c.append(
        Case(
            "readonly",
            "api_write",
            code=(
                "import snoworm\nr = snoworm.simulate(snoworm.load_scenario('tow6_uniform').with_({'simulation.duration_s': 0.5}))"
                "\nr.write('{out}')"
            ),
            setup=_ro_setup(),
            expect=RR,
        )
    )
    c.append(
        Case(
            "readonly",
            "load_result",
            code="import snoworm\nr = snoworm.load_result('{out}')\nprint(r.summary)",
            setup=_ro_setup(SHORT_RUN),
            expect=OK,
        )
    )
    c.append(
        Case(
            "readonly",
            "load_sweep",
            code="import snoworm\nprint(len(snoworm.load_sweep('{out}').to_pandas()))",
            setup=_ro_setup(sw),
            expect=OK,
        )
    )
    return c


PROCESS_SURFACES = {"concurrency": concurrency, "signals": signals, "disk": disk, "readonly": readonly}
