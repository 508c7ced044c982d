"""Sweep cases: the grid (or zip) of an axis list, each case with a stable id and key."""

from __future__ import annotations

import hashlib
import itertools
import math
from dataclasses import dataclass

from ...config.schema import ScenarioError
from ...infra.csvwriter import canonical_json
from .spec import MAX_CASES

__all__ = ["SweepCase", "build_cases"]


@dataclass(frozen=True)
class SweepCase:
    """One case: its index in the grid order and one value per axis."""

    index: int
    values: tuple
    case_id: str
    key: str

    def overrides(self, axes):
        return [(a.key, v) for a, v in zip(axes, self.values)]


def build_cases(axes, zip_: bool = False) -> list:
    """All cases of a sweep, in a deterministic order.

    A grid (``itertools.product``, the first axis varying slowest) or, with ``zip_``, the
    element-wise pairing of axes of equal length.  ``case_id`` is the zero-padded index in that
    order; ``key`` is a digest of the keys and values, the identity used for resumption.
    """
    n_cases = len(axes[0].values) if zip_ and axes else math.prod(len(a.values) for a in axes)
    if n_cases > MAX_CASES:
        raise ScenarioError(
            f"--set: the sweep has {n_cases} cases, over the {MAX_CASES} allowed in one sweep; "
            "use fewer values or split the study into several sweeps."
        )
    if zip_:
        lens = {a.key: len(a.values) for a in axes}
        if len(set(lens.values())) > 1:
            detail = ", ".join(f"{k} has {n}" for k, n in lens.items())
            raise ScenarioError(
                f"--zip pairs the values of every --set element by element, so each needs the "
                f"same number of values; {detail}. Make the lengths equal or drop --zip for a grid."
            )
        combos = list(zip(*(a.values for a in axes)))
    else:
        combos = list(itertools.product(*(a.values for a in axes)))
    width = max(4, len(str(len(combos) - 1)))
    cases = []
    for j, vals in enumerate(combos):
        digest = hashlib.sha1(canonical_json([[a.key, v] for a, v in zip(axes, vals)]).encode()).hexdigest()[:12]
        cases.append(SweepCase(j, tuple(vals), f"{j:0{width}d}", digest))
    return cases
