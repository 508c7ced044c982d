"""snoworm benchmark suite (issue 7): speed, scaling, sweep throughput, memory and accuracy.

Usage (from the repository root)::

    python benchmarks/run.py                 # full run, ~6-8 minutes on 2 cores
    python benchmarks/run.py --quick         # smaller sweeps, fewer repeats, whole processes once: ~2 minutes
    python benchmarks/run.py --out benchmarks/results.json
    python benchmarks/run.py --only baseline startup     # some sections (names: SECTIONS)

Prints a table with every measurement and PASS/MISS against the targets, and writes the same
numbers as JSON.  Wall-clock numbers depend on the machine and its load (the core count is
recorded); ratios measured within one run are the meaningful part.  Timings are the best of a
few repeats.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from benchmarks.baseline import baseline_section, compare_envs, export_tree  # noqa: E402
from snoworm import Simulator, load_scenario, simulate  # noqa: E402
from snoworm.model import floatkernel  # noqa: E402
from snoworm.simulation.driver import assemble, chain_model  # noqa: E402
from snoworm.studies.sweep import run_sweep  # noqa: E402
from tests.reference_quantities import compared, is_gait, quantities, scaled_error  # noqa: E402

TIGHT = json.loads((ROOT / "tests" / "data" / "tight_reference.json").read_text())

SC = ROOT / "scenarios"
TARGETS = {
    "tow6_uniform_rtf": (">=", 700.0, "tow6_uniform real-time factor"),
    "inchworm6_rtf": (">=", 60.0, "inchworm6 real-time factor"),
    "inchworm6_tight_err": ("<=", 5e-4, "inchworm6 worst quantity vs rtol 1e-9 reference (of scale)"),
    "steady_rel_err": ("<=", 1e-3, "steady states vs tight reference (max rel. error)"),
    "rhs_n48_over_n6": ("<=", 2.0, "NumPy kernel cost N=48 / N=6"),
    "sweep_2proc_speedup": (">=", 1.8, "2 processes / serial cases/s"),
    "sweep_batched_speedup": (">=", 10.0, "batched, one process / serial cases/s"),
    "sweep_batched_2proc_speedup": (">=", 18.0, "batched, 2 processes / serial cases/s"),
    "batched_rel_err": ("<=", 1e-3, "batched vs one-by-one metrics (max rel. error)"),
    "sweep10k_peak_MB": ("<", 500.0, "10,000-case sweep peak memory [MB]"),
    "controller_tow6_rtf": (">=", 20.0, "tow6 20 s, 50 Hz Python controller real-time factor"),
    "simulator_step_rtf": (">=", 10.0, "Simulator.step dt = 10 ms (tow6, 20 s) real-time factor"),
    "traverse_patch_speedup": (">=", 2.0, "traverse_patch: baseline wall / current wall (interleaved)"),
    "inching_sweep_speedup": (">=", 4.0, "inchworm6 sweep 100 x 30 s: current -j 2 / baseline serial cases/s"),
    "paper_s": ("<=", 8.0, "`snoworm paper` whole process [s]"),
    "mobility_map_s": ("<=", 8.0, "`snoworm mobility-map` traverse_patch 9 x 3, -j 2, whole process [s]"),
    "odds_steady_1000_s": ("<=", 60.0, "odds --fidelity steady, 1 km X_t field, 1,000 draws x 2 gaits, -j 2 [s]"),
    "odds_transient_throughput": (">=", 0.9, "odds --fidelity transient / plain sweep of the same cases (cases/s)"),
}

#: Whole-process commands timed by :func:`bench_processes` (``{out}``: a fresh temporary directory).
PROCESSES = {
    "paper_s": ["paper", "--out", "{out}"],
    "mobility_map_s": [
        "mobility-map",
        str(SC / "traverse_patch.yaml"),
        "--xt",
        "0.2:1.0:9",
        "--tow",
        "0,100,200",
        "-j",
        "2",
        "--out",
        "{out}",
    ],
}


def rhs_cost_us(sc, repeats=5, calls=1000, numpy_kernel=False):
    """Best-of-``repeats`` cost of one bare ``model.rhs`` call [us], at the state of t = 2 s controls
    (``numpy_kernel``: of the NumPy kernel, ``model.evaluate``, whatever ``rhs`` runs on)."""
    case = assemble(sc)
    m, mode = case.model, case.mode
    y = mode.initial_state()
    ctl = mode.interval(max(2.0, 0.0), y).controls
    fn = (lambda: m.evaluate(y.reshape(m.layout.shape), ctl)) if numpy_kernel else (lambda: m.rhs(0.0, y, ctl))
    fn()
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - t0) / calls * 1e6)
    return best


def run_timed(sc, repeats):
    best, res = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = simulate(sc)
        best = min(best, time.perf_counter() - t0)
    return res, best


def rel_err(a, b):
    """Max |a - b| / max |reference| over a vector (relative to the vector's scale)."""
    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    if a.size == 0:
        return 0.0
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-12))


def steady_quantities(res):
    s = res.summary()
    return {
        "final_link_forces_N": s["final_link_forces_N"],
        "final_speed_mps": s["final_speed_mps"],
        "mean_speed_mps": s["mean_speed_mps"],
    }


def bench_scenarios(repeats, report):
    """Real-time factors (best of ``repeats`` runs; of ``5 * repeats`` for the runs of ~0.05 s,
    whose single timings scatter most on a shared machine) and errors against a tight reference."""
    rows = {}
    for name in ("tow6_uniform", "inchworm6", "frostyboy_case3"):
        sc = load_scenario(SC / f"{name}.yaml")
        res, wall = run_timed(sc, 5 * repeats if name != "inchworm6" else max(1, repeats - 1))
        ref = simulate(
            load_scenario(
                SC / f"{name}.yaml",
                [("simulation.rtol", 1e-9), ("simulation.atol_scale", 1e-3), ("simulation.method", "LSODA")],
            )
        )
        q, qr = steady_quantities(res), steady_quantities(ref)
        errs = {k: rel_err(q[k], qr[k]) for k in q}
        qt = quantities(res)
        tight = max(scaled_error(qt, TIGHT[name], k) for k in compared(is_gait(sc)))
        rows[name] = {
            "duration_s": sc.simulation.duration_s,
            "wall_s": wall,
            "rtf": sc.simulation.duration_s / wall,
            "nfev": res.stats["nfev"],
            "njev": res.stats["njev"],
            "rhs_us": rhs_cost_us(sc),
            "rel_err_vs_tight": errs,
            "reference_nfev": ref.stats["nfev"],
            "tight_scaled_err": tight,
        }
        report(
            f"  {name:16s} RTF {rows[name]['rtf']:7.1f}x  wall {wall:6.3f} s  nfev {res.stats['nfev']:6d}  "
            f"njev {res.stats['njev']:5d}  RHS {rows[name]['rhs_us']:6.1f} us  "
            f"max rel. err vs rtol 1e-9: {max(errs.values()):.2e} ({', '.join(f'{k} {v:.1e}' for k, v in errs.items())}); "
            f"worst quantity of tests/reference_quantities.py vs tests/data/tight_reference.json: {tight:.2e} of scale"
        )
    # tow6 on a constant 5 deg grade and along an elevation table (docs/model.md section 7), against the
    # level run of this session: a constant grade keeps the precomputed terrain factors, a table does not
    for label, sets in (
        ("tow6_uniform 5 deg", [("terrain.grade_deg", 5.0)]),
        ("tow6_uniform elevation table", [("terrain.elevation", [[-20, 0], [0, 0], [20, 1], [40, 1.5]])]),
    ):
        sc = load_scenario(SC / "tow6_uniform.yaml", sets)
        res, wall = run_timed(sc, 5 * repeats)
        rhs = rhs_cost_us(sc)
        rows[label] = {
            "duration_s": sc.simulation.duration_s,
            "wall_s": wall,
            "rtf": sc.simulation.duration_s / wall,
            "nfev": res.stats["nfev"],
            "rhs_us": rhs,
            "rhs_ratio_to_level": rhs / rows["tow6_uniform"]["rhs_us"],
        }
        report(
            f"  {label:28s} RTF {rows[label]['rtf']:7.1f}x  wall {wall:6.3f} s  nfev {res.stats['nfev']:6d}  "
            f"RHS {rhs:6.1f} us ({rows[label]['rhs_ratio_to_level']:.2f}x the level RHS)"
        )
    # the same run on the previous solver settings (LSODA, rtol 1e-4, atol_scale 10), for the ratio
    sc = load_scenario(
        SC / "inchworm6.yaml",
        [("simulation.method", "LSODA"), ("simulation.rtol", 1e-4), ("simulation.atol_scale", 10)],
    )
    res, wall = run_timed(sc, max(1, repeats - 1))
    rows["inchworm6 (LSODA)"] = {
        "duration_s": sc.simulation.duration_s,
        "wall_s": wall,
        "rtf": sc.simulation.duration_s / wall,
        "nfev": res.stats["nfev"],
        "njev": res.stats["njev"],
    }
    report(
        f"  inchworm6 on LSODA (rtol 1e-4, atol_scale 10, the previous settings): RTF {sc.simulation.duration_s / wall:.1f}x  "
        f"wall {wall:6.3f} s  nfev {res.stats['nfev']}  njev {res.stats['njev']}  -> VODE is "
        f"{wall / rows['inchworm6']['wall_s']:.2f}x faster in this run"
    )
    return rows


_FLOAT_LIMIT_CHILD = """
import sys, time
import snoworm
from snoworm.model import floatkernel
n, kernel, mode = int(sys.argv[1]), sys.argv[2], sys.argv[3]
floatkernel.MAX_SEGMENTS = 10**6 if kernel == "float" else 0
if mode == "inching":
    ov = [("vehicle.segments", n), ("mode.gait", [list(range(p, n, 3)) for p in range(3)]), ("simulation.duration_s", 15.0)]
    sc = snoworm.load_scenario("inchworm6", ov)
else:
    sc = snoworm.load_scenario("tow6_uniform", [("vehicle.segments", n), ("tow.force_N", 20.0 * n)])
t0 = time.process_time()
res = snoworm.simulate(sc)
print(time.process_time() - t0, res.summary()["distance_m"])
"""


def bench_float_limit(report, repeats):
    """Where the float kernel stops paying: whole runs (code generation included, each in a fresh
    child process, CPU time) on the float kernel and on the NumPy kernel, alternating, best of
    ``repeats``; rolling (tow6_uniform, 20 s) and inching (the six-segment gait's pattern, 15 s)."""
    rows = {}
    for n in (6, 8, 10, 12, 16, 24):
        for mode in ("rolling", "inching"):
            best = {"float": np.inf, "numpy": np.inf}
            for _ in range(repeats):
                for kernel in best:
                    out = subprocess.run(
                        [sys.executable, "-c", _FLOAT_LIMIT_CHILD, str(n), kernel, mode],
                        capture_output=True,
                        text=True,
                        check=True,
                        cwd=ROOT,
                    )
                    best[kernel] = min(best[kernel], float(out.stdout.split()[0]))
            rows[f"{mode} N={n}"] = r = {**best, "gain": best["numpy"] / best["float"]}
            report(
                f"  {mode:8s} N = {n:2d}: float kernel {r['float']:6.2f} s, NumPy kernel {r['numpy']:6.2f} s CPU: gain {r['gain']:.2f}x"
            )
    report(f"  (snoworm.model.floatkernel.MAX_SEGMENTS = {floatkernel.MAX_SEGMENTS})")
    return rows


def bench_scaling(report, repeats):
    rows = {}
    for n in (2, 6, 12, 24, 48):
        sc = load_scenario(SC / "tow6_uniform.yaml", [("vehicle.segments", n), ("tow.force_N", 200.0 * n / 6)])
        res, wall = run_timed(sc, repeats)
        rows[n] = {
            "rhs_us": rhs_cost_us(sc),
            "rtf": sc.simulation.duration_s / wall,
            "nfev": res.stats["nfev"],
            "njev": res.stats["njev"],
            "numpy_rhs_us": rhs_cost_us(sc, numpy_kernel=True),
            "float_kernel": chain_model(sc).float_kernel is not None,
        }
        report(
            f"  N = {n:3d}: RHS {rows[n]['rhs_us']:7.1f} us  ({rows[n]['rhs_us'] / n:6.2f} us/segment, "
            f"{'float' if rows[n]['float_kernel'] else 'NumPy'} kernel; NumPy kernel {rows[n]['numpy_rhs_us']:6.1f} us)  "
            f"RTF {rows[n]['rtf']:7.1f}x  nfev {res.stats['nfev']}  njev {res.stats['njev']}"
        )
    return rows


def _metric_err(rows_a, rows_b):
    """Max relative difference of the summary metrics of two sweep tables (floors near zero)."""
    floors = {
        "distance_m": 1e-4,
        "mean_speed_mps": 1e-4,
        "late_speed_mps": 1e-4,
        "mean_slip": 1e-4,
        "max_slip": 1e-4,
        "max_link_force_N": 1e-2,
        "energy_per_m_J": 1e-2,
    }
    worst = 0.0
    for a, b in zip(rows_a, rows_b):
        keys = dict(floors, **{k: 1e-2 for k in a if k.startswith("final_link_force_")})
        for k, floor in keys.items():
            if a[k] is None or b[k] is None:
                worst = max(worst, 0.0 if a[k] is b[k] else 1.0)
                continue
            worst = max(worst, abs(a[k] - b[k]) / max(abs(a[k]), floor / 1e-3))
    return worst


def bench_sweep(n_xt, n_tow, duration, n_xt_big, report):
    """Sweep throughput of tow6_uniform over terrain.xt x tow.force_N, as cases per second.

    Serial, 2 processes and batched (one process) on the same ``n_xt x n_tow`` cases (the batched
    results are compared with the serial ones); then the batched path's throughput on a larger
    sweep (``n_xt_big x n_tow`` cases, as a batched sweep is used), in one process and in two.
    The speed-ups are cases/s against the serial cases/s.
    """

    def sets_of(nx):
        return [f"terrain.xt=0.6:1.0:{nx}", f"tow.force_N=0:450:{n_tow}", f"simulation.duration_s={duration}"]

    n, n_big = n_xt * n_tow, n_xt_big * n_tow
    out = {"cases": n, "duration_s": duration, "sets": sets_of(n_xt), "big_cases": n_big, "big_sets": sets_of(n_xt_big)}
    tables = {}
    runs = (
        ("serial", n_xt, {}),
        ("2 processes", n_xt, {"jobs": 2}),
        ("batched", n_xt, {"batch": min(n, 100)}),
        (f"batched, {n_big} cases", n_xt_big, {"batch": 100}),
        (f"batched, {n_big} cases, 2 processes", n_xt_big, {"batch": 100, "jobs": 2}),
    )
    for label, nx, kw in runs:
        t0 = time.perf_counter()
        tables[label] = run_sweep(SC / "tow6_uniform.yaml", sets_of(nx), plot=False, progress=False, **kw)
        wall = time.perf_counter() - t0
        m = len(tables[label].rows)
        ok = sum(r["status"] == "ok" for r in tables[label].rows)
        out[label] = {"wall_s": wall, "cases_per_s": m / wall, "ok": ok, "cases": m}
        report(f"  {label:32s} {m / wall:7.1f} cases/s  ({wall:6.2f} s for {m} cases, {ok} ok)")
    base = out["serial"]["cases_per_s"]
    for label, _, _ in runs[1:]:
        out[label]["speedup"] = out[label]["cases_per_s"] / base
    out["batched_big"], out["batched_big_2proc"] = runs[3][0], runs[4][0]
    out["batched_rel_err"] = _metric_err(tables["serial"].rows, tables["batched"].rows)
    report(
        f"  speed-up over serial: 2 processes {out['2 processes']['speedup']:.2f}x, batched "
        f"{out['batched']['speedup']:.2f}x ({n} cases), {out[runs[3][0]]['speedup']:.2f}x ({n_big} cases), "
        f"{out[runs[4][0]]['speedup']:.2f}x ({n_big} cases, 2 processes); batched vs serial metrics: "
        f"max rel. err {out['batched_rel_err']:.2e}"
    )
    return out


_MEMORY_CHILD = r"""
import json, resource, sys, time
sys.path.insert(0, {root!r})
from snoworm.studies.sweep import run_sweep
t0 = time.perf_counter()
tab = run_sweep({scenario!r}, {sets!r}, plot=False, progress=False, batch={batch})
wall = time.perf_counter() - t0
print(json.dumps({{"cases": len(tab), "ok": sum(r["status"] == "ok" for r in tab.rows), "wall_s": wall,
                  "maxrss_kB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}}))
"""


def bench_memory(n_a, n_b, report):
    """Peak RSS of a sweep of n_a x n_b cases (frostyboy_case3, 3 s runs, batched) in a child process."""
    sets = [f"terrain.xt=0.6:1.0:{n_a}", f"mode.speed_mps=1.0:2.5:{n_b}", "simulation.duration_s=3"]
    code = _MEMORY_CHILD.format(root=str(ROOT), scenario=str(SC / "frostyboy_case3.yaml"), sets=sets, batch=500)
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    child = json.loads(p.stdout.strip().splitlines()[-1])
    out = {
        "cases": child["cases"],
        "ok": child["ok"],
        "wall_s": child["wall_s"],
        "peak_MB": child["maxrss_kB"] / 1024,
        "ru_maxrss_children_MB": max(after, before) / 1024,
        "sets": sets,
        "batch": 500,
    }
    report(
        f"  {child['cases']} cases ({child['ok']} ok) in {child['wall_s']:.1f} s "
        f"({child['cases'] / child['wall_s']:.0f} cases/s): peak RSS {out['peak_MB']:.0f} MB"
    )
    return out


def bench_processes(repeats, report):
    """Wall time of whole ``snoworm`` processes (start-up, imports, runs, files), best of ``repeats``."""
    import tempfile

    out = {}
    for key, args in PROCESSES.items():
        best = np.inf
        for _ in range(repeats):
            with tempfile.TemporaryDirectory() as tmp:
                cmd = [str(Path(sys.executable).parent / "snoworm")] + [a.format(out=tmp) for a in args]
                t0 = time.perf_counter()
                subprocess.run(cmd, check=True, capture_output=True, cwd=ROOT)
                best = min(best, time.perf_counter() - t0)
        out[key] = best
        report(
            f"  snoworm {' '.join(args[:1] + [a for a in args[1:] if not a.startswith('/') and a != '{out}' and a != '--out'])}: "
            f"{best:6.2f} s"
        )
    return out


def bench_controllers(repeats, report):
    """Issue 14: a scenario driven by a Python controller, and the step-by-step Simulator."""
    out = {}
    sc = load_scenario(ROOT / "examples" / "controllers" / "tow6_uniform_controller.yaml")
    res, wall = run_timed(sc, repeats)
    out["controller_tow6"] = {
        "wall_s": wall,
        "rtf": sc.simulation.duration_s / wall,
        "nfev": res.stats["nfev"],
        "intervals": res.stats["intervals"],
    }
    report(
        f"  tow6 20 s, 50 Hz Python controller: RTF {out['controller_tow6']['rtf']:6.1f}x  wall {wall:6.3f} s  "
        f"nfev {res.stats['nfev']}  intervals {res.stats['intervals']}"
    )
    # on VODE, which the Simulator keeps across steps (no restart per step; LSODA restarts every step)
    base = load_scenario(SC / "tow6_uniform.yaml", [("simulation.method", "VODE")])
    best = np.inf
    for _ in range(repeats):
        sim = Simulator(base)
        t0 = time.perf_counter()
        sim.reset()
        for k in range(2000):
            sim.step({"wheel_speed_mps": [1.8] * 6} if k == 100 else None, 0.01)
        best = min(best, time.perf_counter() - t0)
    out["simulator_step"] = {"wall_s": best, "rtf": 20.0 / best, "nfev": sim.result().stats["nfev"]}
    report(f"  Simulator.step dt = 10 ms, tow6 20 s: RTF {out['simulator_step']['rtf']:6.1f}x  wall {best:6.3f} s")
    return out


# ---------------------------------------------------------------- reinforcement learning (issue 27)
RL_TARGETS = {
    "rl_single_speedup": (">=", 3.0, "SnowormEnv random actions / the baseline's (steps/s, dt 0.1 s)"),
    "rl_vector64_speedup": (">=", 6.0, "vector env B = 64 / SnowormEnv (env-steps per CPU s)"),
    "rl_vector64_member_err": ("<=", 5e-3, "vector env B = 64: worst member vs rtol 1e-9 (norm. obs.)"),
}
TARGETS.update(RL_TARGETS)


def _rl_rate(env, steps, vector=False):
    """Env-steps per CPU second and per wall second of ``steps`` random-action steps (episodes
    restarted as they end): ``(cpu_rate, wall_rate)``."""
    env.reset(seed=0)
    n = getattr(env, "num_envs", 1)
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        out = env.step(env.action_space.sample())
        if not vector and (out[2] or out[3]):
            env.reset()
    return n * steps / (time.process_time() - c0), n * steps / (time.perf_counter() - t0)


def vector_member_error(sc, batch, steps):
    """The vector environment's accuracy (issue 34): each member's largest deviation (normalised
    observation units, every observation of every step) from the same member solved at rtol 1e-9,
    over ``steps`` periods of random actions from the start (``steps`` x 0.1 s: a 20 s episode for
    200): ``(worst member, median member, nfev default, nfev reference)``."""
    from snoworm.env import SnowormVectorEnv

    acts = np.random.default_rng(1).uniform(-1, 1, (steps, batch, 6)).astype(np.float32)
    runs = []
    for rtol in ("default", 1e-9):
        env = SnowormVectorEnv(batch, sc, dt_s=0.1) if rtol == "default" else SnowormVectorEnv(batch, sc, rtol=rtol)
        obs = [env.reset(seed=0)[0]] + [env.step(a)[0] for a in acts]
        runs.append((np.array(obs, float), env.stats["nfev"]))
    err = np.abs(runs[0][0] - runs[1][0]).max(axis=(0, 2))
    return float(err.max()), float(np.median(err)), runs[0][1], runs[1][1]


def bench_rl(repeats, report, base_ref, steps=200, batch=64):
    """Issues 27 and 34: random-action env-steps/s on tow6_uniform at dt 0.1 s.

    The single-environment target compares ``SnowormEnv`` of ``base_ref`` (exported from git, the
    code users had) with this checkout's, in child processes taking turns
    (:func:`benchmarks.baseline.compare_envs`).  In this process, interleaved (one run of each per
    round, best of ``repeats`` rounds), in CPU time (so that other jobs on the machine do not move the
    ratios; wall rates beside): the old environment's code kept in benchmarks/env_baseline.py on
    today's Simulator (so it gains from the float kernel too), the new SnowormEnv (default: VODE
    restarted when the command changes; and on LSODA), and the vector environment with B = ``batch``
    (``steps / 4`` periods): its default (VODE, each member at rtol 1e-3, a stack at rtol / sqrt(B)),
    at the scenario's rtol (1e-5, the default before issue 34) and on LSODA.  The vector target is
    the default vector environment against the single one, beside its accuracy over a 20 s episode
    (:func:`vector_member_error`)."""
    import tempfile
    import warnings

    warnings.filterwarnings("ignore", module="gymnasium")  # the baseline's unnormalised spaces
    from benchmarks.env_baseline import SnowormEnv as BaselineEnv
    from snoworm.env import SnowormEnv, SnowormVectorEnv

    with tempfile.TemporaryDirectory(prefix="snoworm-baseline-") as tmp:
        base = str(export_tree(base_ref, Path(tmp)))
        against = compare_envs(base, repeats, steps, report)
    sc = load_scenario(SC / "tow6_uniform.yaml")
    envs = {
        "old env code (env_baseline.py) on today's Simulator": (BaselineEnv(sc, dt_s=0.1), False),
        "SnowormEnv (VODE, default)": (SnowormEnv(sc, dt_s=0.1), False),
        "SnowormEnv (method LSODA)": (SnowormEnv(sc, dt_s=0.1, method="LSODA"), False),
        f"SnowormVectorEnv B = {batch} (default: rtol 1e-3 a member)": (SnowormVectorEnv(batch, sc, dt_s=0.1), True),
        f"SnowormVectorEnv B = {batch} (scenario's rtol 1e-5)": (
            SnowormVectorEnv(batch, sc, dt_s=0.1, rtol=None),
            True,
        ),
        f"SnowormVectorEnv B = {batch} (method LSODA)": (SnowormVectorEnv(batch, sc, dt_s=0.1, method="LSODA"), True),
    }
    best = {label: (0.0, 0.0) for label in envs}
    for _ in range(repeats):
        for label, (env, vector) in envs.items():
            cpu, wall = _rl_rate(env, steps // 4 if vector else steps, vector)
            best[label] = (max(best[label][0], cpu), max(best[label][1], wall))
    for label, (cpu, wall) in best.items():
        report(f"  {label:60s} {cpu:8.1f} env-steps/CPU s  {wall:8.1f} env-steps/s")
    labels = list(envs)
    worst, median, nfev, nfev_ref = vector_member_error(sc, batch, steps)
    out = {
        "rates_cpu": {k: v[0] for k, v in best.items()},
        "rates_wall": {k: v[1] for k, v in best.items()},
        "batch": batch,
        "steps": steps,
        "against": dict(against, ref=base_ref),
        "single_speedup": against["speedup_wall"],
        "vector_speedup": best[labels[3]][0] / best[labels[1]][0],
        "vector_speedup_scenario_rtol": best[labels[4]][0] / best[labels[1]][0],
        "vector_member_err": worst,
        "vector_member_err_median": median,
        "vector_nfev": nfev,
        "vector_nfev_reference": nfev_ref,
    }
    report(
        f"  SnowormEnv / {base_ref}'s SnowormEnv: {out['single_speedup']:.2f}x (child processes); vector B = "
        f"{batch} / SnowormEnv (CPU time, in this process): {out['vector_speedup']:.2f}x by default, "
        f"{out['vector_speedup_scenario_rtol']:.2f}x at the scenario's rtol"
    )
    report(
        f"  vector B = {batch}, {steps * 0.1:g} s of random actions against rtol 1e-9: worst member {worst:.2e}, "
        f"median member {median:.2e} (normalised observations); nfev {nfev} against {nfev_ref}"
    )
    return out


# ---------------------------------------------------------------- start-up (issue 16): whole processes
#: whole-process ratio targets: command / its import floor, both timed in the same run
STARTUP_TARGETS = {
    "startup_help_ratio": ("<=", 1.3, "`snoworm --help` / import numpy, yaml, click"),
    "startup_run_ratio": ("<=", 1.2, "`snoworm run --no-plot` / import scipy.integrate"),
}
#: `snoworm run` with plots against `import scipy.integrate, matplotlib.pyplot` is measured and
#: reported, without a target (withdrawn in issue 25: figure quality comes first)
TARGETS.update(STARTUP_TARGETS)


def _snoworm_command():
    """The installed ``snoworm`` script beside this interpreter, else ``python -m snoworm``."""
    script = Path(sys.executable).with_name("snoworm")
    return [str(script)] if script.exists() else [sys.executable, "-m", "snoworm"]


def bench_startup(repeats, report):
    """Whole-process wall times of three commands and of their import floors, interleaved (one of
    each per round, after an untimed warm-up round), best of ``repeats`` rounds."""
    import tempfile

    # installed code as users get it: byte-compiled (an environment with PYTHONDONTWRITEBYTECODE
    # would otherwise compile every module from source at every start)
    subprocess.run(
        [sys.executable, "-m", "compileall", "-q", str(ROOT / "snoworm")], check=True, stdout=subprocess.DEVNULL
    )
    snoworm = _snoworm_command()
    scenario = str(SC / "tow6_uniform.yaml")
    with tempfile.TemporaryDirectory(prefix="snoworm-bench-") as tmp:
        cases = {  # key: (command, floor key)
            "floor_help": ([sys.executable, "-c", "import numpy, yaml, click"], None),
            "help": (snoworm + ["--help"], "floor_help"),
            "floor_run": ([sys.executable, "-c", "import scipy.integrate"], None),
            "run": (snoworm + ["run", scenario, "--no-plot", "--out", f"{tmp}/run"], "floor_run"),
            "floor_run_plots": ([sys.executable, "-c", "import scipy.integrate, matplotlib.pyplot"], None),
            "run_plots": (snoworm + ["run", scenario, "--out", f"{tmp}/plots"], "floor_run_plots"),
        }
        best = {k: np.inf for k in cases}
        for rnd in range(repeats + 1):
            for key, (cmd, _) in cases.items():
                cmd = [f"{c}{rnd}" if c.startswith(tmp) else c for c in cmd]  # a new --out folder each round
                t0 = time.perf_counter()
                subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                if rnd:  # round 0 warms the disk cache and the bytecode
                    best[key] = min(best[key], time.perf_counter() - t0)
    labels = {
        "help": "snoworm --help",
        "run": "snoworm run tow6_uniform.yaml --no-plot --out D",
        "run_plots": "snoworm run tow6_uniform.yaml --out D (3 PNG plots)",
    }
    out = {}
    for key, (cmd, _floor) in cases.items():
        out[key] = {"wall_s": best[key], "command": labels.get(key) or f"python -c {cmd[-1]!r}"}
    for key, (_, floor) in cases.items():
        if floor:
            out[key].update(floor=floor, ratio=best[key] / best[floor])
            report(
                f"  {out[key]['command']:50s} {best[key]:6.3f} s   floor {out[floor]['command']:50s} "
                f"{best[floor]:6.3f} s   ratio {out[key]['ratio']:.2f}"
            )
    return out


def startup_values(rows):
    """The start-up ratios for the target table."""
    return {"startup_help_ratio": rows["help"]["ratio"], "startup_run_ratio": rows["run"]["ratio"]}


def verdict(key, value):
    op, target, _ = TARGETS[key]
    ok = {">=": value >= target, "<=": value <= target, "<": value < target}[op]
    return ("PASS" if ok else "MISS"), f"{op} {target:g}"


# ------------------------------------------------------------------------------ odds (issue 33)
def _km_route():
    """A 1 km route for the odds benchmark: traverse_patch's chain (supervisor: rolling speed and inching gait)
    on X_t 0.8, level, a 5 deg climb of 100 m, 300 m plateau, a 5 deg descent."""
    from snoworm.config.scenario import read_scenario_yaml

    raw, _ = read_scenario_yaml("traverse_patch")
    raw = dict(raw, name="km_route")
    elev = [[0.0, 0.0], [300.0, 0.0], [400.0, 8.7], [700.0, 8.7], [800.0, 0.0], [1000.0, 0.0]]
    raw["terrain"] = {"xt": 0.8, "elevation": elev}
    return raw


def bench_odds(quick, report):
    """Issue 33: ``snoworm odds``.  Steady fidelity: draws of a 1 km route with a random X_t field
    (sd 0.05, correlation 5 m), rolling and inching, ``-j 2``, cold (the inching table computed in the run).
    Transient: the same tow6_uniform cases as an odds study (X_t drawn) and as a plain sweep over the drawn
    values (serial, interleaved, best of two), cases per second."""
    from snoworm.studies.odds import odds, screen

    out = {}
    n = 200 if quick else 1000
    screen._MEMO.clear()
    t0 = time.perf_counter()
    res = odds(
        _km_route(),
        xt_field="sd=0.05,corr=5",
        samples=n,
        strategies=["rolling", "inching"],
        fidelity="steady",
        jobs=2,
        progress=False,
    )
    wall = time.perf_counter() - t0
    out["steady"] = {"draws": n, "wall_s": wall, "text": res.text}
    report(f"  steady, {n} draws x 2 gaits, 1 km, -j 2 (cold): {wall:6.1f} s;  {res.text.splitlines()[0]}")
    if quick:
        out["steady"]["wall_s_1000"] = wall * 1000 / n  # the draws scale linearly; the tables are a fixed cost
    m = 12 if quick else 40
    kw = dict(vary=["terrain.xt=uniform:0.6:1.0"], sets=["simulation.duration_s=10"], samples=m, progress=False)
    best = {"odds": float("inf"), "sweep": float("inf")}
    for _ in range(2):
        t0 = time.perf_counter()
        r = odds(SC / "tow6_uniform.yaml", **kw)
        best["odds"] = min(best["odds"], time.perf_counter() - t0)
        xts = ",".join(repr(row["terrain.xt"]) for row in r.rows)
        t0 = time.perf_counter()
        run_sweep(
            SC / "tow6_uniform.yaml", [f"terrain.xt={xts}", "simulation.duration_s=10"], plot=False, progress=False
        )
        best["sweep"] = min(best["sweep"], time.perf_counter() - t0)
    out["transient"] = {"cases": m, **{f"{k}_s": v for k, v in best.items()}, "ratio": best["sweep"] / best["odds"]}
    report(
        f"  transient, {m} cases of tow6_uniform 10 s: odds {m / best['odds']:.1f} cases/s, sweep "
        f"{m / best['sweep']:.1f} cases/s (ratio {best['sweep'] / best['odds']:.2f})"
    )
    return out


#: the sections of a run, in order (``--only`` picks some)
SECTIONS = (
    "scenarios",
    "scaling",
    "floatlimit",
    "sweep",
    "baseline",
    "memory",
    "processes",
    "controllers",
    "startup",
    "rl",
    "odds",
)


def _values(res) -> dict:
    """The measured value of every target whose section ran."""
    v = {}
    if "scenarios" in res:
        sc = res["scenarios"]
        v.update(
            tow6_uniform_rtf=sc["tow6_uniform"]["rtf"],
            inchworm6_rtf=sc["inchworm6"]["rtf"],
            inchworm6_tight_err=sc["inchworm6"]["tight_scaled_err"],
            steady_rel_err=max(max(r["rel_err_vs_tight"].values()) for r in sc.values() if "rel_err_vs_tight" in r),
        )
    if "scaling" in res:
        v["rhs_n48_over_n6"] = res["scaling"][48]["numpy_rhs_us"] / res["scaling"][6]["numpy_rhs_us"]
    if "sweep" in res:
        sw = res["sweep"]
        v.update(
            sweep_2proc_speedup=sw["2 processes"]["speedup"],
            sweep_batched_speedup=sw[sw["batched_big"]]["speedup"],
            sweep_batched_2proc_speedup=sw[sw["batched_big_2proc"]]["speedup"],
            batched_rel_err=sw["batched_rel_err"],
        )
    if "baseline" in res:
        v["traverse_patch_speedup"] = res["baseline"]["runs"]["traverse_patch"]["speedup_wall"]
        v["inching_sweep_speedup"] = res["baseline"]["inching_sweep"]["speedup"]
    if "memory" in res:
        v["sweep10k_peak_MB"] = res["memory"]["peak_MB"]
    v.update(res.get("processes", {}))
    if "controllers" in res:
        v.update(
            controller_tow6_rtf=res["controllers"]["controller_tow6"]["rtf"],
            simulator_step_rtf=res["controllers"]["simulator_step"]["rtf"],
        )
    if "startup" in res:
        v.update(startup_values(res["startup"]))
    if "rl" in res:
        v.update(rl_values(res["rl"]))
    if "odds" in res:
        st = res["odds"]["steady"]
        v["odds_steady_1000_s"] = st.get("wall_s_1000", st["wall_s"])
        v["odds_transient_throughput"] = res["odds"]["transient"]["ratio"]
    return v


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller sweeps (40 cases, 1,000 for memory), fewer repeats")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results.json"), help="JSON output file")
    ap.add_argument("--only", nargs="+", choices=SECTIONS, help="run only these sections")
    ap.add_argument("--baseline", default="main", help="git ref the speed-ups are measured against (default main)")
    args = ap.parse_args(argv)
    only = set(args.only or SECTIONS)
    lines = []

    def report(s):
        print(s, flush=True)
        lines.append(s)

    cores = os.cpu_count()
    report(
        f"snoworm benchmarks: {platform.python_version()}, numpy {np.__version__}, {cores} cores, "
        f"{'quick' if args.quick else 'full'} run{'' if args.only is None else ' of ' + ', '.join(args.only)}"
    )
    repeats = 2 if args.quick else 3
    res = {"cores": cores, "python": platform.python_version(), "numpy": np.__version__, "quick": args.quick}
    steps = [
        (
            "scenarios",
            "Scenarios (default tolerances; reference: rtol 1e-9, atol_scale 1e-3):",
            lambda: bench_scenarios(repeats, report),
        ),
        (
            "scaling",
            "Cost growth with N (tow6_uniform with N segments, 33.3 N tow per segment, 20 s):",
            lambda: bench_scaling(report, repeats),
        ),
        (
            "floatlimit",
            "Where the float kernel stops paying (whole runs in fresh processes, CPU time):",
            lambda: bench_float_limit(report, repeats),
        ),
        (
            "sweep",
            "Sweep throughput (tow6_uniform over terrain.xt x tow.force_N):",
            lambda: bench_sweep(*((8, 5, 5, 40) if args.quick else (20, 10, 5, 100)), report),
        ),
        (
            "baseline",
            f"Against {args.baseline} (child processes, interleaved; inching sweep "
            f"{'20 cases of 6 s' if args.quick else '100 cases of 30 s'}):",
            lambda: baseline_section(args.baseline, args.quick, report),
        ),
        (
            "memory",
            "Sweep memory (frostyboy_case3 over terrain.xt x mode.speed_mps, batched 500, child process):",
            lambda: bench_memory(*((40, 25) if args.quick else (100, 100)), report),
        ),
        (
            "processes",
            f"Whole processes (best of {1 if args.quick else 2}):",
            lambda: bench_processes(1 if args.quick else 2, report),
        ),
        (
            "controllers",
            "Controllers (issue 14: solver restarted at every control period / step):",
            lambda: bench_controllers(repeats, report),
        ),
        (
            "startup",
            "Start-up (whole processes, byte-compiled, against their import floors, interleaved, best of "
            f"{repeats + 2} rounds):",
            lambda: bench_startup(repeats + 2, report),
        ),
        (
            "rl",
            "Gymnasium environments (issues 27, 34: tow6_uniform, dt 0.1 s, random actions, interleaved, best of "
            f"{repeats} rounds):",
            lambda: bench_rl(repeats, report, args.baseline),
        ),
        (
            "odds",
            "Odds of getting through (issue 33: steady screen of a 1 km route; transient against a plain sweep):",
            lambda: bench_odds(args.quick, report),
        ),
    ]
    for key, title, fn in steps:
        if key in only:
            report(title)
            res[key] = fn()
    values = _values(res)
    if "memory" in res and res["memory"]["cases"] < 10_000:
        report(
            f"  (memory measured on {res['memory']['cases']} cases; rows are ~1 kB each, so 10,000 cases add "
            f"~{(10_000 - res['memory']['cases']) * 1e-3:.0f} MB at most to the figure below)"
        )
    report("")
    report(f"Targets ({cores} cores):")
    res["targets"] = {}
    for key, val in values.items():
        v, t = verdict(key, val)
        res["targets"][key] = {"value": val, "target": t, "verdict": v}
        report(f"  {v}  {TARGETS[key][2]:60s} {val:10.4g}  (target {t})")
    res["report"] = lines
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(res, indent=2, default=float) + "\n")
    print(f"wrote {args.out}")


def rl_values(rows):
    """The RL ratios for the target table."""
    return {
        "rl_single_speedup": rows["single_speedup"],
        "rl_vector64_speedup": rows["vector_speedup"],
        "rl_vector64_member_err": rows["vector_member_err"],
    }


if __name__ == "__main__":
    main()
