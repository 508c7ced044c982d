"""Hostile-input battery (issue 30): snoworm against malformed files, folders and calls.

Usage (from the repository root; needs root for the full-disk and read-only surfaces)::

    python benchmarks/hostile.py --out DIR [--only SURFACE ...] [--jobs 2] [--list]

Not part of the pytest suite (a full run takes ~10 minutes on 2 cores).  Each case runs in its own
subprocess (``python -m snoworm ...`` or ``python -c`` for API cases) with a timeout, in a fresh
temporary folder ``CASE/work`` (the working folder, ``--out`` is ``CASE/work/out``), beside a
victim file ``CASE/victim.txt``.  After the case every file outside ``--out`` is compared with the
snapshot taken before (content, size, mtime), and a marker file is looked for: controller code
planted where it must not run writes it when imported.

Each case gets one class, in this order of precedence:

``hang``             the timeout (60 s unless the case says otherwise) was reached
``code_run``         the marker exists after a case that must not run that code
``touched_outside``  a file or folder outside ``--out`` was created, changed or removed
``internal_error``   a traceback on stderr, an exit status other than 0/1/2 (130/143 for the
                     signal cases), a Python exception not meant for users (API cases: anything
                     but ScenarioError, ResultFileError, OutputError, SolverError, gymnasium's
                     errors, and a ValueError/TypeError raised by snoworm's own code), or a
                     refusal whose message is over 2 000 characters
``silent_nonsense``  exit 0 but a result the case can check is wrong or missing (NaN or inf
                     written, rows lost or repeated, a sweep claiming complete without its rows,
                     a hostile value accepted that must not be, a second command clobbering a
                     folder another one holds)
``solver_failure``   exit 1 with a message
``refused``          exit 2 with a message and no traceback
``ok``               exit 0 and the checks passed

A case also lists the classes that are *expected* of it (e.g. ``refused`` for a malformed route
file, ``ok``/``refused`` where both are right).  The report (stdout, ``DIR/report.txt`` and
``DIR/report.json``) gives the counts per surface and class, then every case whose class is not
expected, with its command, exit status and the tail of its stderr: those are the ones to look at
by hand.  ``hang``, ``code_run``, ``touched_outside``, ``internal_error`` and ``silent_nonsense``
are never expected.  Exit status 0 when every case got an expected class, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from hostile_cases import SURFACES  # noqa: E402
from hostile_core import BAD, run_case  # noqa: E402


def main(argv=None) -> int:
    """Run the battery; see the module docstring."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, type=Path, help="folder for report.txt and report.json")
    ap.add_argument("--only", nargs="+", choices=sorted(SURFACES), help="run only these surfaces")
    ap.add_argument("--jobs", type=int, default=2, help="cases run at once (default 2)")
    ap.add_argument("--name", help="run only the cases whose name contains this text")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    ap.add_argument("--keep", action="store_true", help="keep the cases' temporary folders")
    args = ap.parse_args(argv)
    cases = []
    for surface in args.only or sorted(SURFACES):
        cases += SURFACES[surface]()
    if args.name:
        cases = [c for c in cases if args.name in c.name]
    if args.list:
        for c in cases:
            print(f"{c.surface:12s} {c.name}")
        print(f"{len(cases)} cases")
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    results = []
    # serial cases (mounts, signals, concurrency timing) after the parallel ones
    parallel = [c for c in cases if not c.serial]
    serial = [c for c in cases if c.serial]
    with ThreadPoolExecutor(max(1, args.jobs)) as pool:
        for r in pool.map(lambda c: run_case(c, keep=args.keep), parallel):
            results.append(r)
            _progress(r, len(results), len(cases))
    for c in serial:
        r = run_case(c, keep=args.keep)
        results.append(r)
        _progress(r, len(results), len(cases))
    report = _report(results, time.monotonic() - t0)
    print(report)
    (args.out / "report.txt").write_text(report)
    (args.out / "report.json").write_text(json.dumps(results, indent=1))
    return 0 if all(r["good"] for r in results) else 1


def _progress(r, k, n):
    mark = "" if r["good"] else "   <-- " + r["klass"]
    print(f"[{k}/{n}] {r['surface']}/{r['name']}: {r['klass']} ({r['wall_s']:.1f} s){mark}", file=sys.stderr)


def _report(results, wall_s) -> str:
    classes = ["ok", "refused", "solver_failure", *BAD]
    counts = defaultdict(Counter)
    for r in results:
        counts[r["surface"]][r["klass"]] += 1
    lines = [f"{len(results)} cases in {wall_s:.0f} s", ""]
    lines.append(f"{'surface':14s}" + "".join(f"{c[:10]:>11s}" for c in classes) + f"{'total':>7s}{'unexp':>7s}")
    for s in sorted(counts):
        unexp = sum(1 for r in results if r["surface"] == s and not r["good"])
        row = "".join(f"{counts[s][c]:11d}" for c in classes)
        lines.append(f"{s:14s}{row}{sum(counts[s].values()):7d}{unexp:7d}")
    tot = Counter()
    for s in counts:
        tot.update(counts[s])
    unexp = sum(1 for r in results if not r["good"])
    lines.append(f"{'TOTAL':14s}" + "".join(f"{tot[c]:11d}" for c in classes) + f"{len(results):7d}{unexp:7d}")
    bad = [r for r in results if not r["good"]]
    if bad:
        lines += ["", "Cases whose class is not expected:"]
    for r in bad:
        lines.append(f"\n* {r['surface']}/{r['name']}: {r['klass']} (expected {', '.join(r['expect'])}); rc {r['rc']}")
        lines.append(f"  command: {r['command'][:300]}")
        if r["note"]:
            lines.append(f"  note: {r['note'][:600]}")
        if r["stderr_tail"]:
            lines.append("  stderr: " + r["stderr_tail"].replace("\n", "\n          "))
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
