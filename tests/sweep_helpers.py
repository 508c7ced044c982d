"""Shared constants and helpers of the sweep tests (tests/test_sweep_*.py)."""

from __future__ import annotations

import csv
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TOW6 = str(ROOT / "scenarios" / "tow6_uniform.yaml")
SHORT = "simulation.duration_s=6"
#: 4 cases: a 2 x 2 grid, one of them immobilised-free, all fast (6 s simulated each)
SMALL = ["terrain.xt=0.7,0.9", "tow.force_N=0,200", SHORT]


def comparable(table):
    """Rows without the wall time (the only column allowed to differ between executors)."""
    return [{k: v for k, v in r.items() if k != "wall_time_s"} for r in table.rows]


def csv_rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))
