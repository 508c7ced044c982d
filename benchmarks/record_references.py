"""Re-record the regression references of the test suite (run from the repository root).

    python benchmarks/record_references.py summaries   # tests/data/reference_summaries.json
    python benchmarks/record_references.py tight       # tests/data/tight_reference.json (minutes)
    python benchmarks/record_references.py tight --only inchworm6 inchworm2

``summaries``: every shipped scenario at its own settings; tests/test_reference_summaries.py
holds every change to it (tolerances from the solver tolerance and each quantity's physical
scale, see its docstring).  Re-record it only for a deliberate numerical change, and say so
in the commit.  ``tight``: every shipped scenario at rtol 1e-9 and 1e-3 times the default
absolute tolerances with LSODA, whatever its YAML says; tests/test_tight_reference.py holds
the shipped settings within half their 1e-3 promise of it.  Re-record it only when the model changes.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from snoworm import load_scenario, simulate  # noqa: E402
from tests.reference_quantities import quantities  # noqa: E402
from tests.test_tight_reference import TIGHT_SETTINGS  # noqa: E402

DATA = ROOT / "tests" / "data"
SC = ROOT / "scenarios"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("which", choices=("summaries", "tight"))
    ap.add_argument("--only", nargs="*", help="re-record only these scenarios (others kept)")
    a = ap.parse_args(argv)
    out = DATA / ("reference_summaries.json" if a.which == "summaries" else "tight_reference.json")
    data = json.loads(out.read_text()) if out.exists() else {}
    old = json.loads(json.dumps(data))
    names = a.only or sorted(p.stem for p in SC.glob("*.yaml"))
    for name in names:
        t0 = time.perf_counter()
        if a.which == "summaries":
            data[name] = quantities(simulate(load_scenario(SC / f"{name}.yaml")))
        else:
            res = simulate(load_scenario(SC / f"{name}.yaml", TIGHT_SETTINGS))
            data[name] = dict(quantities(res), settings=[list(s) for s in TIGHT_SETTINGS])
        if name in old:  # keep the file's key order (small diffs)
            data[name] = {k: data[name][k] for k in [*old[name], *data[name]] if k in data[name]}
        print(f"{name}: {time.perf_counter() - t0:.1f} s", flush=True)
    out.write_text(json.dumps(dict(sorted(data.items())), indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
