"""The hostile-input battery's machinery: a case, its sandbox, its run and its class (benchmarks/hostile.py)."""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable

#: Classes that are never an expected outcome.
BAD = ("hang", "code_run", "touched_outside", "internal_error", "silent_nonsense")
MAX_MESSAGE_CHARS = 2000

#: Wraps an API case's body: a user-facing exception is exit 2 (SolverError 1), anything else a
#: traceback (exit 3).  ``nonsense(msg)`` in the body flags a wrong result it can see.
HARNESS = r"""
import sys, traceback
def nonsense(msg):
    print("NONSENSE: " + str(msg)); sys.stdout.flush(); sys.exit(0)
_body = {body!r}
try:
    exec(compile(_body, "<case>", "exec"), {{"__name__": "__main__", "nonsense": nonsense}})
except SystemExit:
    raise
except BaseException as exc:
    import snoworm
    user = (snoworm.ScenarioError, snoworm.ResultFileError, snoworm.OutputError)
    try:
        import gymnasium.error
        user = user + (gymnasium.error.Error,)
    except ImportError:
        pass
    tb = traceback.extract_tb(exc.__traceback__)
    origin = tb[-1].filename if tb else ""
    own = "/snoworm/" in origin.replace("\\", "/")
    if isinstance(exc, snoworm.SolverError):
        print(f"SolverError: {{exc}}", file=sys.stderr); sys.exit(1)
    if isinstance(exc, user) or (own and type(exc) in (ValueError, TypeError)):
        print(f"{{type(exc).__name__}}: {{exc}}", file=sys.stderr); sys.exit(2)
    traceback.print_exc(); sys.exit(3)
"""


@dataclass
class Ctx:
    """A case's sandbox: ``base`` (temporary), ``cwd`` = base/work, ``out`` = cwd/out."""

    base: Path
    cwd: Path
    out: Path
    marker: Path
    victim: Path
    mounts: list = field(default_factory=list)

    def fmt(self, s: str) -> str:
        for key in ("out", "cwd", "marker", "base", "victim"):
            s = s.replace("{" + key + "}", str(getattr(self, key)))
        return s


@dataclass
class Case:
    """One hostile case.

    ``args`` (after ``python -m snoworm``) or ``code`` (an API body, run through :data:`HARNESS`)
    or ``runner(ctx) -> dict(rc, stdout, stderr, timed_out, note, nonsense)``; strings are
    formatted with ``{out}``, ``{cwd}``, ``{marker}``, ``{base}``, ``{victim}``.  ``setup(ctx)``
    writes the inputs before the snapshot; ``check(ctx, run) -> str | None`` names a wrong result
    after exit 0.
    """

    surface: str
    name: str
    args: list | None = None
    code: str | None = None
    runner: Callable | None = None
    setup: Callable | None = None
    check: Callable | None = None
    expect: tuple = ("ok", "refused")
    code_may_run: bool = False
    timeout: float = 60.0
    env: dict = field(default_factory=dict)
    serial: bool = False
    ok_rcs: tuple = (0, 1, 2)
    teardown: Callable | None = None
    may_touch: tuple = ()  # paths (relative to the sandbox) the case itself changes on purpose


def sandbox() -> Ctx:
    base = Path(tempfile.mkdtemp(prefix="snoworm-hostile-"))
    cwd = base / "work"
    cwd.mkdir()
    victim = base / "victim.txt"
    victim.write_text("the victim: snoworm must never change this file\n")
    return Ctx(base, cwd, cwd / "out", base / "MARKER", victim)


def snapshot(ctx: Ctx) -> dict:
    """Every path under ``ctx.base`` except ``--out``'s tree and the marker -> (kind, size, mtime, hash)."""
    snap = {}
    for dirpath, dirnames, filenames in os.walk(ctx.base, followlinks=False):
        d = Path(dirpath)
        dirnames[:] = [n for n in dirnames if d / n != ctx.out]
        for n in dirnames + filenames:
            p = d / n
            if p == ctx.marker or p == ctx.out:
                continue
            try:
                st = os.lstat(p)
            except OSError:
                continue
            kind = "dir" if os.path.isdir(p) and not os.path.islink(p) else "file"
            digest = ""
            if kind == "file" and os.path.isfile(p) and not os.path.islink(p) and st.st_size < 64 << 20:
                digest = hashlib.sha256(p.read_bytes()).hexdigest()
            snap[str(p.relative_to(ctx.base))] = (kind, st.st_size if kind == "file" else 0, st.st_mtime_ns, digest)
    return snap


def _diff(before: dict, after: dict) -> str:
    notes = []
    for k in sorted(set(before) | set(after)):
        if k not in after:
            notes.append(f"removed {k}")
        elif k not in before:
            notes.append(f"created {k}")
        elif before[k] != after[k] and before[k][0] == "file":
            notes.append(f"changed {k}")
    return "; ".join(notes)


def spawn(ctx: Ctx, argv: list, env: dict | None = None, timeout: float = 60.0, **kw) -> dict:
    """Run ``argv`` in ``ctx.cwd`` (own process group), killing its group on timeout."""
    full_env = dict(os.environ)
    full_env.update({"PYTHONPATH": str(ROOT), "PYTHONDONTWRITEBYTECODE": "1", "MPLBACKEND": "Agg"})
    full_env.update(env or {})
    t0 = time.monotonic()
    proc = subprocess.Popen(
        argv, cwd=ctx.cwd, env=full_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True, **kw
    )
    try:
        out, err = proc.communicate(timeout=timeout)
        timed_out = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        timed_out = True
    return {
        "rc": proc.returncode,
        "stdout": out.decode(errors="replace"),
        "stderr": err.decode(errors="replace"),
        "timed_out": timed_out,
        "wall_s": time.monotonic() - t0,
    }


def snoworm_argv(ctx: Ctx, args: list) -> list:
    return [PY, "-m", "snoworm", *[ctx.fmt(a) if isinstance(a, str) else a for a in args]]


def api_argv(ctx: Ctx, body: str) -> list:
    return [PY, "-c", HARNESS.format(body=ctx.fmt(body))]


def classify(case: Case, ctx: Ctx, run: dict, note: str) -> tuple[str, str]:
    """The case's class and a note (see benchmarks/hostile.py)."""
    err = run["stderr"]
    if run["timed_out"]:
        return "hang", note
    if ctx.marker.exists() and not case.code_may_run:
        return "code_run", note + " marker: " + ctx.marker.read_text()[:200]
    if run.get("touched"):
        return "touched_outside", run["touched"] + ("; " + note if note else "")
    if "Traceback (most recent call last)" in err or "Fatal Python error" in err or "This is a bug in snoworm" in err:
        return "internal_error", note
    if run["rc"] not in case.ok_rcs:
        return "internal_error", f"exit status {run['rc']}" + ("; " + note if note else "")
    if run.get("nonsense"):
        return "silent_nonsense", run["nonsense"]
    if "NONSENSE:" in run["stdout"]:
        return "silent_nonsense", run["stdout"].split("NONSENSE:", 1)[1].strip()[:600]
    if run["rc"] == 0 or (run["rc"] in case.ok_rcs and run["rc"] not in (1, 2)):
        return "ok", note
    msg = err.strip()
    if not msg:
        return "internal_error", f"exit {run['rc']} without a message"
    if len(_last_message(msg)) > MAX_MESSAGE_CHARS:
        return "internal_error", f"message of {len(_last_message(msg))} characters; " + note
    return ("solver_failure" if run["rc"] == 1 else "refused"), note


def _last_message(err: str) -> str:
    """stderr without progress lines."""
    keep = [ln for ln in err.splitlines() if " % (" not in ln and "elapsed" not in ln]
    return "\n".join(keep)


def run_case(case: Case, keep: bool = False) -> dict:
    """Run one case in a fresh sandbox and classify it."""
    ctx = sandbox()
    note = ""
    try:
        if case.setup:
            case.setup(ctx)
        before = snapshot(ctx)
        if case.runner:
            run = case.runner(ctx)
            run.setdefault("timed_out", False)
            run.setdefault("wall_s", 0.0)
            run.setdefault("stdout", "")
        elif case.code is not None:
            run = spawn(ctx, api_argv(ctx, case.code), case.env, case.timeout)
        else:
            run = spawn(ctx, snoworm_argv(ctx, case.args), case.env, case.timeout)
        after = snapshot(ctx)
        for k in case.may_touch:
            before.pop(k, None)
            after.pop(k, None)
        run["touched"] = _diff(before, after)
        note = run.get("note", "")
        if run["rc"] == 0 and not run["timed_out"] and case.check and not run.get("nonsense"):
            try:
                run["nonsense"] = case.check(ctx, run)
            except Exception as exc:  # noqa: BLE001 - a check that cannot read the result is a finding
                run["nonsense"] = f"check failed: {type(exc).__name__}: {exc}"
        klass, note = classify(case, ctx, run, note)
    except Exception as exc:  # noqa: BLE001 - the battery's own failure is reported, not raised
        run = {"rc": None, "stderr": "", "wall_s": 0.0}
        klass, note = "internal_error", f"battery error: {type(exc).__name__}: {exc}"
    finally:
        if case.teardown:
            try:
                case.teardown(ctx)
            except Exception:  # noqa: BLE001
                pass
        for m in reversed(ctx.mounts):
            subprocess.run(["umount", "-l", str(m)], capture_output=True)
        if not keep:
            shutil.rmtree(ctx.base, ignore_errors=True)
    command = " ".join(case.args) if case.args else (case.code or getattr(case.runner, "__name__", ""))
    tail = "\n".join(_last_message(run.get("stderr", "")).strip().splitlines()[-6:])
    return {
        "surface": case.surface,
        "name": case.name,
        "klass": klass,
        "expect": list(case.expect),
        "good": klass in case.expect and klass not in BAD,
        "rc": run.get("rc"),
        "wall_s": run.get("wall_s", 0.0),
        "command": command,
        "note": note,
        "stderr_tail": tail[-1500:],
    }


# ---------------------------------------------------------------- checks of results read back


def _csv_rows(path: Path) -> list[list[str]]:
    lines = [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    return [ln.split(",") for ln in lines]


def _finite_csv(path: Path) -> str | None:
    rows = _csv_rows(path)
    if len(rows) < 2:
        return f"{path.name} has no data rows"
    for r in rows[1:]:
        for cell in r:
            if cell.strip().lower() in ("nan", "inf", "-inf", "+inf"):
                return f"{path.name} holds {cell}"
    return None


def check_run(ctx: Ctx, run: dict, out: Path | None = None) -> str | None:
    """A run folder: manifest, finite tables and summary."""
    out = out or ctx.out
    if not (out / ".snoworm-manifest.json").is_file():
        return "exit 0 without a manifest in --out"
    for name in ("segments.csv", "links.csv"):
        if (out / name).exists():
            bad = _finite_csv(out / name)
            if bad:
                return bad
        elif name == "segments.csv":
            return "segments.csv missing"
    summary = json.loads((out / "summary.json").read_text())

    def walk(v):
        if isinstance(v, float) and not math.isfinite(v):
            return True
        if isinstance(v, dict):
            return any(walk(x) for x in v.values())
        if isinstance(v, list):
            return any(walk(x) for x in v)
        return False

    if walk(summary):
        return "summary.json holds a non-finite value"
    return None


def check_sweep(ctx: Ctx, run: dict, out: Path | None = None) -> str | None:
    """A sweep folder: complete manifest, one row per planned case, no repeated case."""
    out = out or ctx.out
    man = json.loads((out / ".snoworm-manifest.json").read_text())
    plan = json.loads((out / "sweep.json").read_text())
    rows = _csv_rows(out / "summary.csv")
    header, data = rows[0], rows[1:]
    ids = [r[0] for r in data]
    if len(set(ids)) != len(ids):
        return "summary.csv repeats a case"
    if man.get("status") == "complete" and len(ids) != plan["n_cases"]:
        return f"manifest complete with {len(ids)} of {plan['n_cases']} rows"
    st = header.index("status")
    for r in data:
        if r[st] == "error":
            return f"case {r[0]} recorded as error: {r[header.index('error')][:200]}"
    return None


def check_map(ctx: Ctx, run: dict) -> str | None:
    """A mobility map: a manifest and a CSV without NaN regions."""
    if not (ctx.out / ".snoworm-manifest.json").is_file():
        return "exit 0 without a manifest"
    rows = _csv_rows(ctx.out / "mobility_map.csv")
    if len(rows) < 2:
        return "mobility_map.csv has no rows"
    return None
