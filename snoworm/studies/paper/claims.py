"""Claim types and the run context shared by every report item.

:class:`Claim` (one checked statement), :class:`Variant` (claims re-evaluated under an
alternative reading) and :class:`Section` (one figure or table of the paper); :func:`make_claim`,
the constructor the check functions use (it makes the computed values JSON-friendly); and
:class:`Context`, which runs the shipped scenarios with the report's overrides and caches the runs.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...config.scenario import load_scenario
from ...simulation.driver import simulate
from ..groundtruth import vehicle_model

__all__ = [
    "Claim",
    "Variant",
    "Section",
    "Context",
    "SCENARIO_DIR",
    "QUICK_INCHWORM_DURATION_S",
    "STEADY_WINDOW_S",
    "make_claim",
    "find_claim",
    "start_time_s",
    "steady_mean",
]

#: The shipped scenarios (package data, snoworm/scenarios).
SCENARIO_DIR = Path(__file__).resolve().parents[2] / "scenarios"

#: Simulated duration of the inchworm runs in ``--quick`` mode [s] (about three gait cycles).
QUICK_INCHWORM_DURATION_S = 10.0
#: Length of the window at the end of a run whose mean is taken as the steady state [s].
STEADY_WINDOW_S = 1.0


# ------------------------------------------------------------------------------- data types


@dataclass(frozen=True)
class Claim:
    """One checked statement.

    Attributes
    ----------
    id : str
        Stable identifier, e.g. ``"fig6.link_tensions"``.
    figure : str
        Figure or table of the paper, e.g. ``"Fig 6"``.
    statement : str
        What is claimed (quote or paraphrase, with the paper's section).
    source : {"paper", "model"}
        ``"paper"``: stated in the paper; ``"model"``: a reference-model number (docs/model.md).
    computed : dict
        The computed value(s) the verdict is derived from (SI units in the keys).
    tolerance : str
        The acceptance rule, in words and numbers.
    holds : bool
        Whether the computed values satisfy the rule.
    """

    id: str
    figure: str
    statement: str
    source: str
    computed: dict
    tolerance: str
    holds: bool

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclass
class Variant:
    """The claims of a section re-evaluated under an alternative model reading."""

    label: str
    overrides: dict
    claims: list


@dataclass
class Section:
    """One figure or table of the paper: what it states, what was computed, the claims."""

    key: str
    title: str
    paper_says: str
    scenarios: list = field(default_factory=list)
    claims: list = field(default_factory=list)
    figures: list = field(default_factory=list)
    tables: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    variants: list = field(default_factory=list)
    wall_time_s: float = 0.0


def make_claim(id, figure, statement, computed, tolerance, holds, source="paper") -> Claim:
    """A :class:`Claim` with ``computed`` made JSON-friendly (see :func:`_plain`) and ``holds`` a bool."""
    return Claim(id, figure, statement, source, _plain(computed), tolerance, bool(holds))


def _plain(obj):
    """JSON-friendly copy: numpy scalars/arrays to floats/lists, floats rounded to 6 significant digits."""
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [_plain(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if not math.isfinite(v) or v == 0 else float(f"{v:.6g}")
    return obj


def find_claim(sections, claim_id) -> Claim:
    """The claim with id ``claim_id`` among the sections' main claims (KeyError if absent)."""
    for s in sections:
        for c in s.claims:
            if c.id == claim_id:
                return c
    raise KeyError(claim_id)


# ------------------------------------------------------------------------------- context


class Context:
    """What the item functions share: mode, overrides, output directory, a cache of runs.

    Parameters
    ----------
    quick : bool
        Shorten the inchworm runs to :data:`QUICK_INCHWORM_DURATION_S`.
    model : dict, optional
        Terrain-model coefficients replacing the parameter set's, e.g. ``{"peak_exponent_d": 1}``;
        applied to every scenario (``terrain.model.<name>``) and to the steady-state model.
    scenario_overrides : dict of str -> list of str, optional
        Extra dotted-key overrides per scenario name, e.g.
        ``{"tow6_uniform": ["tow.force_N=300"]}`` (used by the tests to break a claim).
    out_dir : str or Path, optional
        Directory for figures; ``None`` draws nothing.
    plot_format : {"png", "pdf", "svg"}
        File format of the figures (:func:`snoworm.plotting.save`; PNG at 200 dpi).
    figure_size : str, optional
        Print size of the figures: ``"column"``, ``"page"`` (default) or ``"WxH"`` inches.
    """

    def __init__(
        self, quick=False, model=None, scenario_overrides=None, out_dir=None, plot_format="png", figure_size=None
    ):
        self.quick = bool(quick)
        self.model = dict(model or {})
        self.scenario_overrides = {k: list(v) for k, v in (scenario_overrides or {}).items()}
        self.out_dir = Path(out_dir) if out_dir is not None else None
        self.plot_format = str(plot_format)
        self.figure_size = figure_size
        self._runs = {}

    def child(self, model=None, plot=False) -> Context:
        """A context with extra terrain-model overrides (alternative readings), sharing nothing."""
        m = dict(self.model)
        m.update(model or {})
        return Context(
            self.quick, m, self.scenario_overrides, self.out_dir if plot else None, self.plot_format, self.figure_size
        )

    def overrides(self, name, extra=()) -> list:
        ov = [f"terrain.model.{k}={v}" for k, v in self.model.items()]
        return ov + list(self.scenario_overrides.get(name, [])) + list(extra)

    def run(self, name, extra=()):
        """Simulate the shipped scenario ``name`` with the context's overrides (memoised)."""
        key = (name, tuple(self.overrides(name, extra)))
        if key not in self._runs:
            self._runs[key] = simulate(load_scenario(SCENARIO_DIR / f"{name}.yaml", list(key[1])))
        return self._runs[key]

    def put(self, name, extra, result):
        """Memoise ``result`` as :meth:`run` ``(name, extra)`` (a run computed elsewhere, e.g. in a worker)."""
        self._runs[(name, tuple(self.overrides(name, extra)))] = result

    def args(self) -> tuple:
        """The constructor's arguments: ``Context(*ctx.args())`` is a context with the same settings
        and an empty cache (how worker processes get theirs)."""
        return self.quick, self.model, self.scenario_overrides, self.out_dir, self.plot_format, self.figure_size

    def vehicle(self):
        """``(SegmentConfig, TerrainParams)`` of FrostyBoy with the context's model overrides."""
        seg, tp = vehicle_model("frostyboy")
        return seg, dataclasses.replace(tp, **self.model) if self.model else tp

    def figure(self, name):
        """Path of figure ``name`` (its suffix replaced by :attr:`plot_format`) in the output
        directory, or ``None`` when not plotting."""
        return None if self.out_dir is None else (self.out_dir / name).with_suffix("." + self.plot_format)


def start_time_s(res) -> float:
    """Earliest controller start time of a run's mode [s] (a scalar or one per segment)."""
    return float(np.min(res.scenario.mode.start_time_s))


def steady_mean(res, group, key, window_s=STEADY_WINDOW_S):
    """Mean of a per-segment or per-link series over the last ``window_s`` of a run."""
    data = getattr(res, group)[key]
    return data[res.t >= res.t[-1] - window_s].mean(0)
