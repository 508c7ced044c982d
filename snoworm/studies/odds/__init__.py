"""The odds of getting through: uncertain snow, Monte Carlo / quasi-Monte Carlo draws, P(go) with
Wilson intervals, Sobol indices (``snoworm odds``, :func:`snoworm.odds`; docs/odds.md).

Modules, in data-flow order (highest first in the layer contract)
-----------------------------------------------------------------
:mod:`.run`
    :func:`odds`: the plan (scenario, inputs, strategies, draws), the draws on the sweep's executors
    (or the steady screen), ``samples.csv`` appended as draws finish (resumable), ``odds.json``, figures.
:mod:`.screen`
    ``--fidelity steady``: each route element at its steady state (rolling tables, the inching table).
:mod:`.outcome`
    One draw: strategy -> mode, the drawn scenario with its X_t field, the run, its outcome and the stop verdict.
:mod:`.sampling` | :mod:`.stats`
    The draws (random, Sobol', Latin hypercube; Saltelli's design) | Wilson intervals, percentiles, Sobol indices.
:mod:`.inputs`
    Distributions, ``--vary``, the X_t field, calibrated coefficients, the ``uncertainty:`` section.
"""

from .inputs import DISTRIBUTIONS, CalibrationInput, Distribution, ScalarInput, Uncertainty, XtField
from .outcome import OUTCOME_COLUMNS, STRATEGIES
from .run import FIDELITIES, OddsResult, load_odds, odds
from .sampling import METHODS, design
from .stats import sobol, wilson

__all__ = [
    "odds",
    "OddsResult",
    "load_odds",
    "FIDELITIES",
    "METHODS",
    "STRATEGIES",
    "OUTCOME_COLUMNS",
    "DISTRIBUTIONS",
    "Distribution",
    "ScalarInput",
    "XtField",
    "CalibrationInput",
    "Uncertainty",
    "design",
    "wilson",
    "sobol",
]
