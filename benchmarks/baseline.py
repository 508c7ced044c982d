"""Speed-ups against another version of snoworm measured in the same benchmark run (issue 25).

The baseline is a git ref of this repository (``main`` by default), exported with ``git archive``
into a temporary folder (the repository is only read).  Each measurement runs in a child
process that imports either the baseline tree or this checkout, and the children alternate
(baseline, current, baseline, current, ...), so a drift of the shared machine's speed weighs on
both sides alike.  Each side runs its own scenario files: the baseline's settings are "today's".
"""

from __future__ import annotations

import json
import subprocess
import sys
import tarfile
import tempfile
from io import BytesIO
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_RUN_CHILD = r"""
import json, sys, time
sys.path.insert(0, {tree!r})
import snoworm
from snoworm import load_scenario, simulate
assert snoworm.__file__.startswith({tree!r}), snoworm.__file__
sc = load_scenario({tree!r} + "/snoworm/scenarios/{name}.yaml")
simulate(sc)                                    # warm-up: imports, generated code, caches
out = []
for _ in range({repeats}):
    w0, c0 = time.perf_counter(), time.process_time()
    res = simulate(sc)
    out.append((time.perf_counter() - w0, time.process_time() - c0))
print(json.dumps({{"wall_s": min(w for w, _ in out), "cpu_s": min(c for _, c in out), "nfev": res.stats["nfev"],
                  "duration_s": sc.simulation.duration_s}}))
"""

_SWEEP_CHILD = r"""
import json, sys, time
sys.path.insert(0, {tree!r})
import snoworm
from snoworm import run_sweep   # the public name: any version of the tree, before or after the layout
assert snoworm.__file__.startswith({tree!r}), snoworm.__file__
t0 = time.perf_counter()
tab = run_sweep({tree!r} + "/snoworm/scenarios/inchworm6.yaml", {sets!r}, plot=False, progress=False, jobs={jobs})
wall = time.perf_counter() - t0
print(json.dumps({{"wall_s": wall, "cases": len(tab.rows), "ok": sum(r["status"] == "ok" for r in tab.rows)}}))
"""

_ENV_CHILD = r"""
import json, sys, time, warnings
sys.path.insert(0, {tree!r})
warnings.filterwarnings("ignore", module="gymnasium")  # the old environment's unnormalised spaces
import snoworm
from snoworm import load_scenario
from snoworm.env import SnowormEnv
assert snoworm.__file__.startswith({tree!r}), snoworm.__file__
env = SnowormEnv(load_scenario({tree!r} + "/snoworm/scenarios/tow6_uniform.yaml"), dt_s=0.1)

def rate(steps):
    env.reset(seed=0)
    env.action_space.seed(0)  # explicitly: the environment before issue 27 did not seed it in reset
    w0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        out = env.step(env.action_space.sample())
        if out[2] or out[3]:
            env.reset()
    return steps / (time.perf_counter() - w0), steps / (time.process_time() - c0)

rate(20)                                        # warm-up: imports, generated code, caches
wall, cpu = rate({steps})
print(json.dumps({{"steps_per_s_wall": wall, "steps_per_s_cpu": cpu}}))
"""


def export_tree(ref: str, dest: Path) -> Path:
    """``git archive`` of ``ref``'s ``snoworm`` package into ``dest`` (returns ``dest``)."""
    data = subprocess.run(
        ["git", "-C", str(ROOT), "archive", "--format=tar", ref, "snoworm"], check=True, capture_output=True
    ).stdout
    with tarfile.open(fileobj=BytesIO(data)) as tar:
        tar.extractall(dest)
    return dest


def _child(code: str, cwd: str) -> dict:
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=cwd)
    if p.returncode:
        raise RuntimeError(f"benchmark child failed: {p.stderr[-2000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def _best_of_turns(base: str, rounds: int, code, keep) -> tuple:
    """``(baseline, current)``: each side's child process (source ``code(tree)``) run ``rounds``
    times, the two sides taking turns; ``keep(best, new)`` merges a side's results into its best."""
    best = {"baseline": None, "current": None}
    for _ in range(rounds):
        for side, tree in (("baseline", base), ("current", str(ROOT))):
            r = _child(code(tree), tree)
            best[side] = r if best[side] is None else keep(best[side], r)
    return best["baseline"], best["current"]


def compare_runs(base: str, names, rounds: int, repeats: dict, report) -> dict:
    """Best wall and CPU time of each scenario on the baseline tree and this checkout, interleaved."""
    out = {}
    for name in names:
        b, c = _best_of_turns(
            base,
            rounds,
            lambda tree, name=name: _RUN_CHILD.format(tree=tree, name=name, repeats=repeats.get(name, 1)),
            lambda old, r: dict(r, wall_s=min(old["wall_s"], r["wall_s"]), cpu_s=min(old["cpu_s"], r["cpu_s"])),
        )
        out[name] = {
            "baseline": b,
            "current": c,
            "speedup_wall": b["wall_s"] / c["wall_s"],
            "speedup_cpu": b["cpu_s"] / c["cpu_s"],
            "rtf_wall": c["duration_s"] / c["wall_s"],
            "rtf_cpu": c["duration_s"] / c["cpu_s"],
        }
        report(
            f"  {name:16s} baseline {b['wall_s']:7.3f} s wall {b['cpu_s']:7.3f} s CPU (nfev {b['nfev']})   "
            f"current {c['wall_s']:7.3f} s wall {c['cpu_s']:7.3f} s CPU (nfev {c['nfev']})   speed-up "
            f"{out[name]['speedup_wall']:.2f}x wall, {out[name]['speedup_cpu']:.2f}x CPU; current "
            f"{out[name]['rtf_wall']:.1f}x real time (wall)"
        )
    return out


def compare_envs(base: str, rounds: int, steps: int, report) -> dict:
    """Random-action env-steps/s of ``SnowormEnv`` on tow6_uniform (dt 0.1 s) in the baseline tree
    and in this checkout, each in child processes taking turns, best of ``rounds`` (issue 27's
    single-environment target: the environment as users had it, on the code they had)."""
    b, c = _best_of_turns(
        base,
        rounds,
        lambda tree: _ENV_CHILD.format(tree=tree, steps=steps),
        lambda old, r: {k: max(old[k], r[k]) for k in r},
    )
    out = {
        "baseline": b,
        "current": c,
        "speedup_wall": c["steps_per_s_wall"] / b["steps_per_s_wall"],
        "speedup_cpu": c["steps_per_s_cpu"] / b["steps_per_s_cpu"],
    }
    report(
        f"  SnowormEnv in child processes: baseline {b['steps_per_s_wall']:6.1f} env-steps/s wall "
        f"({b['steps_per_s_cpu']:6.1f} CPU), current {c['steps_per_s_wall']:6.1f} wall ({c['steps_per_s_cpu']:6.1f} "
        f"CPU): {out['speedup_wall']:.2f}x wall, {out['speedup_cpu']:.2f}x CPU"
    )
    return out


def compare_inching_sweep(base: str, n_xt: int, n_tow: int, duration, report, chunks: int = 5) -> dict:
    """inchworm6 over terrain.xt x tow.force_N: the baseline serial against this checkout serial and
    with ``-j 2`` (and the baseline with ``-j 2``, for the machine's parallel capacity at the time).
    The X_t values are split into ``chunks`` sweeps run in turn by the four sides
    (interleaved, so the machine's drift weighs on each alike); cases/s over all chunks."""
    xts = [round(0.2 + 0.15 * k / (n_xt - 1), 10) for k in range(n_xt)]
    tail = [f"tow.force_N=0:90:{n_tow}"] + ([f"simulation.duration_s={duration}"] if duration is not None else [])
    # the baseline with -j 2 too: what two processes give on the machine as it is loaded now
    sides = (
        ("baseline serial", base, 1),
        ("current serial", str(ROOT), 1),
        ("current -j 2", str(ROOT), 2),
        ("baseline -j 2", base, 2),
    )
    out = {"sets": [f"terrain.xt=0.2:0.35:{n_xt}"] + tail, "cases": n_xt * n_tow, "chunks": chunks}
    tot = {label: {"wall_s": 0.0, "cases": 0, "ok": 0} for label, _, _ in sides}
    for c in range(chunks):
        sets = ["terrain.xt=" + ",".join(str(x) for x in xts[c::chunks])] + tail
        order = sides[c % len(sides) :] + sides[: c % len(sides)]  # rotate who goes first
        for label, tree, jobs in order:
            r = _child(_SWEEP_CHILD.format(tree=tree, sets=sets, jobs=jobs), tree)
            for k in ("wall_s", "cases", "ok"):
                tot[label][k] += r[k]
    for label, _, _ in sides:
        r = out[label] = dict(tot[label], cases_per_s=tot[label]["cases"] / tot[label]["wall_s"])
        report(
            f"  inchworm6 sweep, {label:16s} {r['cases_per_s']:6.2f} cases/s ({r['wall_s']:6.1f} s for "
            f"{r['cases']} cases, {r['ok']} ok; {chunks} interleaved chunks)"
        )
    out["speedup_serial"] = out["current serial"]["cases_per_s"] / out["baseline serial"]["cases_per_s"]
    out["speedup"] = out["current -j 2"]["cases_per_s"] / out["baseline serial"]["cases_per_s"]
    out["baseline_2proc"] = out["baseline -j 2"]["cases_per_s"] / out["baseline serial"]["cases_per_s"]
    report(
        f"  against the baseline's serial throughput: current serial {out['speedup_serial']:.2f}x, "
        f"current -j 2 {out['speedup']:.2f}x (baseline -j 2: {out['baseline_2proc']:.2f}x, the machine's "
        "parallel capacity at this load)"
    )
    return out


def baseline_section(ref: str, quick: bool, report) -> dict:
    """Every baseline comparison of the benchmark (scenarios interleaved, then the inching sweep)."""
    with tempfile.TemporaryDirectory(prefix="snoworm-baseline-") as tmp:
        base = str(export_tree(ref, Path(tmp)))
        rounds = 2 if quick else 3
        runs = compare_runs(
            base, ("inchworm6", "tow6_uniform", "traverse_patch"), rounds, {"tow6_uniform": 10, "inchworm6": 2}, report
        )
        sweep = compare_inching_sweep(base, *((4, 5, 6) if quick else (10, 10, None)), report, chunks=2 if quick else 5)
    return {"ref": ref, "runs": runs, "inching_sweep": sweep}
